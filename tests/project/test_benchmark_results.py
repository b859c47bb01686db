"""Issue 38: the measured tables in benchmarks/RESULTS.md are written by the benchmarks
themselves (``--results``, benchmarks/results.py): every block of the file names a script that
writes it, and a run replaces its block — only its block — with what it printed, under the
command that produced it."""

from __future__ import annotations

import importlib.util
import re
import sys

from tests.helpers import ROOT

BENCHMARKS = ROOT / "benchmarks"


def _results():
    """benchmarks/results.py as a module (the benchmarks are scripts, not a package)."""
    spec = importlib.util.spec_from_file_location("results", BENCHMARKS / "results.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_block_is_written_by_its_benchmark():
    names = re.findall(r"^<!-- results: (\w+) -->$", (BENCHMARKS / "RESULTS.md").read_text(),
                       re.MULTILINE)
    assert {"adaptor", "corpus", "oscillator_bank", "batch", "import_time", "streaming", "peers",
            "walk_push", "walk_frequency"} <= set(names)
    for name in names:
        script = (BENCHMARKS / f"{name}.py").read_text()
        assert f'recording("{name}", "--results" in sys.argv[1:])' in script, name
        assert "add_flag(" in script, name
        assert len(_results().block(name).findall((BENCHMARKS / "RESULTS.md").read_text())) == 1


def test_a_run_replaces_its_own_block_only(tmp_path, monkeypatch, capsys):
    results = _results()
    path = tmp_path / "RESULTS.md"
    path.write_text("# Results\n\n## A\n\n<!-- results: a -->\nold a\n<!-- /results: a -->\n\n"
                    "## B\n\n<!-- results: b -->\nold b\n<!-- /results: b -->\n")
    monkeypatch.setattr(sys, "argv", ["benchmarks/a.py", "--robots", "g1", "--results"])
    with results.recording("a", True, path):
        print("load 1.0")
        print("| robot | s |\n|---|---|\n| g1 | 1.5 |")
    text = path.read_text()
    assert "old a" not in text and "old b" in text
    block = results.block("a").search(text).group(2)
    assert block.startswith("Written by `python benchmarks/a.py --robots g1 --results` on ")
    assert "```text\nload 1.0\n```\n\n| robot | s |\n|---|---|\n| g1 | 1.5 |\n" in block
    assert "| g1 | 1.5 |" in capsys.readouterr().out  # still printed
    with results.recording("c", True, path):  # a block the file lacks is appended
        print("new")
    assert results.block("c").search(path.read_text()).group(2).endswith("```text\nnew\n```\n")
    with results.recording("a", False, path):  # without --results nothing is written
        print("not kept")
    assert "not kept" not in path.read_text()
