"""Issue 38: the documentation site builds with ``mkdocs build --strict`` (mkdocs.yml at the
root: mkdocs-material, mkdocstrings from the docstrings), so a broken link, anchor, included
file or API reference fails the suite; every public name of ``gdimitate.__all__`` is in the API
reference (docs/reference/index.md) with its docstring, in the built page."""

from __future__ import annotations

import html
import importlib
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest
import yaml

import gdimitate
from tests.helpers import ROOT

REFERENCE = ROOT / "docs" / "reference" / "index.md"


def _mkdocs_build(config: Path, site: Path) -> subprocess.CompletedProcess[str]:
    """``mkdocs build --strict`` of ``config`` into ``site``, run from the repository root
    (the snippets' base path: README-side files such as CHANGELOG.md are included from it)."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                           "-f", str(config), "-d", str(site)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})


def _directives() -> list[str]:
    """The objects the reference page documents (``::: path`` lines), in order."""
    return re.findall(r"^::: (\S+)\s*$", REFERENCE.read_text(), re.MULTILINE)


def _resolve(path: str) -> object:
    """The object named by a dotted ``path`` (a module, or an attribute of one)."""
    try:
        return importlib.import_module(path)
    except ImportError:
        module, _, name = path.rpartition(".")
        return getattr(importlib.import_module(module), name)


def _public() -> dict[str, str]:
    """Public name → the reference's path for it (the object's own home)."""
    found: dict[str, str] = {}
    for path in _directives():
        obj = _resolve(path)
        for name in gdimitate.__all__:
            public = getattr(gdimitate, name)
            if obj is public and path.rsplit(".", 1)[-1] == name or (
                    isinstance(public, types.ModuleType) and path == public.__name__):
                found[name] = path
    return found


def _doc(name: str, path: str) -> str:
    """The docstring the reference shows for public ``name``: the object's own, or for a module
    attribute (an instance, e.g. ``HUMAN_GAIT``) the string literal right after its
    assignment, as mkdocstrings reads it."""
    obj = getattr(gdimitate, name)
    if isinstance(obj, (type, types.ModuleType)) or callable(obj):
        return obj.__doc__ or ""
    module, _, attr = path.rpartition(".")
    source = Path(importlib.import_module(module).__file__).read_text()
    m = re.search(rf"^{attr} = .*\n\"\"\"(.*?)\"\"\"", source, re.MULTILINE | re.DOTALL)
    return m.group(1) if m else ""


def test_every_public_module_has_a_page_with_its_own_public_names():
    """docs/reference/<module>.md (written by docs/make_reference.py) documents every name of
    the module's ``__all__``: ``gd.sim.simulate``, ``gd.gait.human_walk_3d`` … are what a
    user calls after ``gd.adapt``."""
    for name in gdimitate.__all__:
        module = getattr(gdimitate, name)
        if not isinstance(module, types.ModuleType):
            continue
        page = ROOT / "docs" / "reference" / f"{name}.md"
        assert page.exists(), f"{page} missing: run python docs/make_reference.py"
        documented = {p.rsplit(".", 1)[-1] for p in
                      re.findall(r"^::: (\S+)\s*$", page.read_text(), re.MULTILINE)}
        missing = sorted(set(module.__all__) - documented)
        assert missing == [], f"{name}: run python docs/make_reference.py ({missing})"


def _first_line(doc: str | None) -> str:
    return (doc or "").strip().split("\n\n")[0].split("\n")[0].strip()


def test_the_readme_is_a_guide_and_the_design_page_no_log():
    """Issue 38: the README ≤ 12 KB (it was 82 KB, three generations of benchmark tables) and
    docs/design.md ≤ 25 KB (it was 84 KB, three quarters measurement logs): measurements go to
    benchmarks/RESULTS.md, the user guide to docs/guide/, history to CHANGELOG.md."""
    assert len((ROOT / "README.md").read_bytes()) <= 12 * 1024
    assert len((ROOT / "docs" / "design.md").read_bytes()) <= 25 * 1024


def test_every_public_name_is_in_the_api_reference_with_a_docstring():
    found = _public()
    assert sorted(set(gdimitate.__all__) - set(found)) == []
    assert [name for name, path in found.items() if not _first_line(_doc(name, path))] == []


def _text(fragment: str) -> str:
    """Rendered HTML as plain text: tags and markup characters dropped, entities decoded,
    spaces collapsed."""
    text = html.unescape(re.sub(r"<[^>]+>", " ", fragment))
    return " ".join(re.sub(r"[`*~]|:\w+:", "", text).split())


def _plain(doc_line: str) -> str:
    """A docstring line as the page shows its words: reST roles as the site's Griffe
    extension (docs/hooks/rst_roles.py) writes them, markup characters dropped."""
    line = re.sub(r":(?:py:)?\w+:`(~?)([^`]+)`",
                  lambda m: m.group(2).rsplit(".", 1)[-1] if m.group(1) else m.group(2),
                  doc_line)
    return " ".join(re.sub(r"[`*~]", "", line).split())




@pytest.mark.slow
def test_the_site_builds_strictly_with_every_public_name_and_its_docstring(tmp_path):
    r = _mkdocs_build(ROOT / "mkdocs.yml", tmp_path / "site")
    assert r.returncode == 0, r.stderr[-3000:]
    page = (tmp_path / "site" / "reference" / "index.html").read_text()
    for name, path in _public().items():
        i = page.find(f'id="{path}"')
        assert i >= 0, f"{name}: no entry {path} in the built reference"
        first = _plain(_first_line(_doc(name, path)))
        assert first, f"{name} has no docstring"
        entry = _text(page[i:i + 20000]).replace(" ", "")
        assert first[:60].replace(" ", "") in entry, f"{name}: docstring not on the page"


#: Broken things a strict build must refuse: a page name → its text.
BROKEN = {
    "link": "[missing](no-such-page.md)",
    "anchor": "[missing](#no-such-heading)",
    "api": "::: gdimitate.no_such_name",
    "include": '--8<-- "NO_SUCH_FILE.md"',
}


def _one_page_site(tmp_path: Path, extra: str = "") -> Path:
    """The project's own configuration (its plugins, validation and strictness) on a one-page
    site whose page has a working link, anchor and API entry, and ``extra``."""
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text())
    docs = tmp_path / "docs"
    docs.mkdir()
    config.update(docs_dir=str(docs), nav=[{"Home": "index.md"}])
    python = config["plugins"][1]["mkdocstrings"]["handlers"]["python"]
    python["paths"] = [str(ROOT)]
    python["options"]["extensions"] = [str(ROOT / e) for e in python["options"]["extensions"]]
    (tmp_path / "mkdocs.yml").write_text(yaml.safe_dump(config))
    (docs / "index.md").write_text("# Home\n\n## A heading\n\n[fine](#a-heading)\n\n"
                                   f"::: gdimitate.adaptation.adaptor.adapt\n\n{extra}\n")
    return tmp_path / "mkdocs.yml"


@pytest.mark.slow
def test_the_one_page_site_builds(tmp_path):
    r = _mkdocs_build(_one_page_site(tmp_path), tmp_path / "site")
    assert r.returncode == 0, r.stderr[-2000:]


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(BROKEN))
def test_a_broken_reference_fails_the_build(tmp_path, kind):
    """The page of test_the_one_page_site_builds with one broken reference added fails."""
    r = _mkdocs_build(_one_page_site(tmp_path, BROKEN[kind]), tmp_path / "site")
    assert r.returncode != 0, f"a broken {kind} passed the strict build"


def test_every_cited_design_section_exists():
    """Code, tests, benchmarks and pages cite ``docs/design.md §N``; when design.md was cut to
    its design (issue 38) two citations pointed at sections it never had (§16, §17). Every
    cited number is a ``## N.`` heading of design.md."""
    sections = set(re.findall(r"^## (\d+)\.", (ROOT / "docs" / "design.md").read_text(),
                              re.MULTILINE))
    cite = re.compile(r"design\.md\)?\s*((?:§\s?\d+(?:,\s*)?)+)")
    missing = []
    for folder in ("gdimitate", "tests", "benchmarks", "docs", "notebooks"):
        for path in (ROOT / folder).rglob("*"):
            if path.suffix not in (".py", ".md", ".ipynb") or "site" in path.parts:
                continue
            for m in cite.finditer(path.read_text(errors="replace")):
                missing += [f"{path.relative_to(ROOT)}: §{n}"
                            for n in re.findall(r"\d+", m.group(1)) if n not in sections]
    assert not missing, missing
