"""Issue 34: the README runs as written; issue 38: so does every page of the documentation.
Every ```python block of README.md and of docs/**/*.md runs, page by page, each page's blocks
in order in one namespace of their own (later blocks use what earlier ones defined, as a
reader following the page would; a page never sees another page's names or files), in a
private working folder per page; a block that begins with ``# placeholder`` (it needs the
reader's own files) is skipped, and the test names the skipped blocks so that none is skipped
by accident. The README's API block once opened ``subject.osim`` and ``clip.bvh``, files that
do not exist, and its gait-lab block a C3D that did not ship.

All pages run in one interpreter (one subprocess, each page in a fresh namespace and folder),
so the engines are imported and each robot's compiled problem loaded once for all pages: the
test's wall time is that of the blocks, not of one interpreter start per page."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers import ROOT

README = ROOT / "README.md"
#: The blocks skipped as placeholders: (page, the section they are in).
PLACEHOLDERS = {
    ("docs/guide/your-robot.md", "Your own robot"),
    ("docs/batch.md", "Batches: a folder of demonstrations, on one machine or a cluster"),
}
#: Files some pages write (in their own folder) that the test checks were written.
WRITTEN = {
    "README.md": {"g1_walk.csv"},
    "docs/guide/gait-lab.md": {"subject01_walk1.c3d", "g1_walk.pkl"},
    "docs/guide/viewing.md": {"walk.html"},
}


def pages() -> list[Path]:
    """README.md and every markdown page under docs/, in a fixed order."""
    return [README] + sorted((ROOT / "docs").rglob("*.md"))


def _blocks(page: Path) -> list[tuple[str, str]]:
    """``(section, code)`` of every python block of ``page``, in order; the section is the
    last heading of level 1 or 2 above the block."""
    section, out = "", []
    for m in re.finditer(r"^##? ([^\n]+)$|^```python\n(.*?)^```", page.read_text(),
                         re.MULTILINE | re.DOTALL):
        if m.group(1):
            section = m.group(1).strip()
        else:
            out.append((section, m.group(2)))
    return out


def _rel(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


def _placeholder(code: str) -> bool:
    return code.lstrip().startswith("# placeholder")


def test_the_placeholders_are_the_ones_named():
    skipped = {(_rel(p), s) for p in pages() for s, code in _blocks(p) if _placeholder(code)}
    assert skipped == PLACEHOLDERS
    assert sum(len(_blocks(p)) for p in pages()) > len(skipped)
    for page in WRITTEN:  # the pages whose outputs are checked have blocks that run
        assert any(not _placeholder(c) for _, c in _blocks(ROOT / page)), page


#: Runs each page's code in a fresh namespace and folder; prints what each page took.
DRIVER = """\
import os, sys, time, traceback
import matplotlib
matplotlib.use("Agg")
root = os.getcwd()
for page, folder, code in PAGES:
    os.makedirs(folder)
    os.chdir(folder)
    t0 = time.perf_counter()
    try:
        exec(compile(code, page, "exec"), {"__name__": "__main__"})
    except BaseException:
        traceback.print_exc()
        sys.exit(f"{page}: a code block failed (above)")
    finally:
        os.chdir(root)
    print(f"{page}: {time.perf_counter() - t0:.1f} s", flush=True)
"""


def _page_code(page: Path) -> str:
    """The runnable blocks of ``page`` as one script, each block marked by its section."""
    return "\n".join(f"# --- {s}\n{c}" for s, c in _blocks(page) if not _placeholder(c))


@pytest.mark.slow
def test_every_code_block_of_the_readme_and_the_docs_runs(tmp_path):
    runnable = [(_rel(p), f"page{i}", _page_code(p)) for i, p in enumerate(pages())
                if _page_code(p).strip()]
    script = tmp_path / "pages.py"
    script.write_text(f"PAGES = {runnable!r}\n" + DRIVER)
    r = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                       text=True, timeout=900, env={**os.environ, "MPLBACKEND": "Agg"})
    print("".join(line + "\n" for line in r.stdout.splitlines() if ".md: " in line))
    assert r.returncode == 0, r.stderr[-3000:]
    folders = {page: tmp_path / folder for page, folder, _ in runnable}
    for page, files in WRITTEN.items():
        written = {p.name for p in folders[page].iterdir()}
        assert files <= written, (page, written)


def _make_readme_output():
    """docs/make_readme_output.py as a module (it is a script, not part of the package)."""
    path = ROOT / "docs" / "make_readme_output.py"
    spec = importlib.util.spec_from_file_location("make_readme_output", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_printed_demo_block_is_regenerated_not_pasted():
    """Issue 34: the README's printed `gdimitate demo` block was stale (42 iterations and
    0.8 cm slip where a fresh run printed 32 and 0.3 cm). The block is now written by
    docs/make_readme_output.py from a fresh run, which also stores that run's summary.json
    (docs/output/demo_summary.json): the block must be, line for line, the table the current
    printing code renders from that file — labels, numbers and their formatting — so a change
    of the printed table fails here until the script is run again. The stored run is demo's
    default story: the shipped stride, G1, the optimal adaptor."""
    from gdimitate.apps.demo import DEFAULT_IMITATOR, default_demonstration, summary_table

    script = _make_readme_output()
    summary = json.loads((ROOT / "docs" / "output" / "demo_summary.json").read_text())
    block = script.output_block("demo")
    table = summary_table(summary, script.DEMO_OUT).splitlines()
    assert block[:len(table)] == table
    ok = summary["verdict"]["ok"] and not summary["simulation"]["fell"]
    assert len(block) == len(table) + (0 if ok else 1)  # + "result written, but …: exit 3"
    assert summary["imitator"] == DEFAULT_IMITATOR and summary["method"] == "optimal"
    _, stride, _ = default_demonstration()
    assert summary["frames"] == stride.T
    assert summary["duration_s"] == pytest.approx(stride.t[-1] - stride.t[0], abs=1e-12)
