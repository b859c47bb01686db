"""Compiled per-knot functions (gdimitate.retarget.codegen): compiled once into the cache
folder, loaded afterwards without building or compiling, nothing written to the working
folder, the same numbers as CasADi's virtual machine; no C compiler → the virtual machine with
one warning."""

from __future__ import annotations

import os
import warnings

import casadi as ca
import numpy as np
import pytest

from gdimitate.retarget import codegen


def _functions() -> list[ca.Function]:
    x = ca.SX.sym("x", 3)
    y = ca.vertcat(ca.sin(x[0]) * x[1], x[2] ** 3 - x[0])
    return [ca.Function("val", [x], [y]), ca.Function("dval", [x], [ca.jacobian(y, x)])]


def test_compiled_once_then_loaded(tmp_path, monkeypatch):
    cache, work = tmp_path / "cache", tmp_path / "work"
    work.mkdir()
    monkeypatch.setenv(codegen.ENV, str(cache))
    monkeypatch.chdir(work)
    if codegen._compiler() is None:
        pytest.skip("no C compiler on this machine")
    n = codegen.COMPILE_COUNT
    key = f"test-{os.getpid()}-{np.random.default_rng().integers(1 << 30)}"
    funs, compiled = codegen.compiled_functions(key, _functions)
    assert compiled and codegen.COMPILE_COUNT == n + 1
    assert list(work.iterdir()) == []  # nothing in the working folder
    assert any(p.suffix == ".so" for p in cache.iterdir())

    def must_not_build():
        raise AssertionError("a cached library must be loaded, not rebuilt")

    again, compiled2 = codegen.compiled_functions(key, must_not_build)
    assert compiled2 and codegen.COMPILE_COUNT == n + 1
    ref = {f.name(): f for f in _functions()}
    x = np.array([0.3, -1.2, 0.7])
    for name in ("val", "dval"):
        np.testing.assert_allclose(np.array(again[name](x)), np.array(ref[name](x)),
                                   rtol=1e-14, atol=1e-15)


def test_no_compiler_falls_back_with_one_warning(tmp_path, monkeypatch):
    monkeypatch.setenv(codegen.ENV, str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    monkeypatch.setattr(codegen, "_WARNED", False)
    with pytest.warns(codegen.SlowDerivativesWarning, match="virtual machine"):
        funs, compiled = codegen.compiled_functions("nocc-a", _functions)
    assert not compiled
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # said once, not again
        codegen.compiled_functions("nocc-b", _functions)
    x = np.array([0.1, 0.2, 0.3])
    np.testing.assert_allclose(np.array(funs["val"](x)).ravel(),
                               [np.sin(0.1) * 0.2, 0.3**3 - 0.1], rtol=1e-14)


def test_cache_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv(codegen.ENV, str(tmp_path / "c"))
    assert codegen.cache_dir() == tmp_path / "c"
    monkeypatch.delenv(codegen.ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert codegen.cache_dir() == tmp_path / "xdg" / "gdimitate"


def test_source_digest_covers_every_module_the_compiled_expressions_import():
    """The compiled-derivative cache key digests the source of the modules the per-knot
    expressions are written in; a module they import from gdimitate but the digest leaves out
    (the cone rows moved to gdimitate/contact.py once) would let an edit load a stale library."""
    import ast
    from pathlib import Path

    from gdimitate.retarget import problem

    root = Path(problem.__file__).parents[1]  # gdimitate/
    digested = set()
    for mod in problem.SOURCE_MODULES:
        p = Path(mod.__file__)
        digested |= set(p.parent.rglob("*.py")) if p.name == "__init__.py" else {p}
    writers = [root / "retarget" / "knot.py",
               root / "symbolic.py", *(root / "retarget" / "parts").glob("*.py")]
    missing = set()
    for f in writers:
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = f.parent
                for _ in range(node.level - 1):
                    base = base.parent
                parts = (node.module or "").split(".") if node.module else []
                target = base.joinpath(*parts)
                names = [target / f"{a.name}.py" for a in node.names] if not parts else []
                for cand in [target.with_suffix(".py"), target / "__init__.py", *names]:
                    if cand.exists() and cand.resolve() not in {d.resolve() for d in digested}:
                        missing.add(str(cand.relative_to(root)))
    missing.discard("errors.py")  # exception classes only: nothing of an expression
    assert not missing, f"imported by the compiled expressions but not digested: {missing}"
