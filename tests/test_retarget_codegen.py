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
