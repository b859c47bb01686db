"""The RK4 bank against an independent scipy integration, its exact invariances, the compiled
kernel against the NumPy reference, batch against loop, and input validation."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from gdimitate.errors import OscillatorError, TimeGridError
from gdimitate.oscillator import (
    MatsuokaBank,
    MatsuokaParams,
    NoOscillationError,
    OscillatorWarning,
    StepTooLargeError,
    _kernel,
)

P0 = MatsuokaParams(tau_r=0.1, tau_a=0.2, b=2.5, w=2.5, s=1.0)


def reference(p: dict, W: np.ndarray, g, x0: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Independent implementation of docs/design.md §7 for n coupled oscillators; returns y (T,
    n)."""
    n = W.shape[0]

    def f(tt, z):
        xe, xf, ve, vf = z.reshape(4, n)
        ye, yf = np.maximum(xe, 0), np.maximum(xf, 0)
        gg = g(tt) if g is not None else np.zeros(n)
        dxe = (-xe - p["w"] * yf - W @ ye - p["b"] * ve - p["k"] * np.maximum(gg, 0) + p["s"])
        dxf = (-xf - p["w"] * ye - W @ yf - p["b"] * vf - p["k"] * np.maximum(-gg, 0) + p["s"])
        return np.concatenate([dxe / p["tau_r"], dxf / p["tau_r"],
                               (ye - ve) / p["tau_a"], (yf - vf) / p["tau_a"]])

    sol = solve_ivp(f, (t[0], t[-1]), x0.ravel(), method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=t)
    xe, xf = sol.y[:n], sol.y[n:2 * n]
    return (np.maximum(xe, 0) - np.maximum(xf, 0)).T


def test_free_oscillator_matches_solve_ivp_over_20s():
    t = np.arange(0, 20 + 5e-4, 1e-3)
    tr = MatsuokaBank(P0).simulate(t)
    y_ref = reference(dict(tau_r=0.1, tau_a=0.2, b=2.5, w=2.5, s=1.0, k=0.0), np.zeros((1, 1)),
                      None, np.array([0.1, 0, 0, 0]), t)
    err = np.max(np.abs(tr.y - y_ref))
    assert err <= 1e-4, err  # measured 3.4e-5


def test_coupled_driven_pair_matches_solve_ivp():
    t = np.arange(0, 10 + 5e-4, 1e-3)
    W = np.array([[0, 0.4], [0.7, 0]])
    p = P0.replace(k=0.3)
    x0 = np.array([[0.1, 0.0], [0.0, 0.05], [0, 0], [0, 0]])

    def g(tt):
        return np.array([np.sin(2 * np.pi * 1.0 * tt), 0.5 * np.cos(2 * np.pi * 1.3 * tt)])

    tr = MatsuokaBank(p, W).simulate(t, g(t).T, x0)
    y_ref = reference(dict(tau_r=0.1, tau_a=0.2, b=2.5, w=2.5, s=1.0, k=0.3), W, g, x0, t)
    assert np.max(np.abs(tr.y - y_ref)) <= 1e-4


def test_trace_fields_and_shapes():
    t = np.linspace(0, 1, 101)
    tr = MatsuokaBank(P0, shape=(2, 3)).simulate(t)
    for name in ("x_e", "x_f", "v_e", "v_f", "y"):
        assert getattr(tr, name).shape == (101, 2, 3)
    assert tr.final.shape == (4, 2, 3)
    np.testing.assert_array_equal(tr.y, tr.y_e - tr.y_f)
    np.testing.assert_array_equal(tr.final, tr.states()[:, -1])


def test_numba_kernel_equals_numpy_reference_coupled_and_uncoupled():
    rng = np.random.default_rng(0)
    t = np.arange(0, 3, 1e-3)
    W = np.array([[0, 0.3, 0.1], [0.2, 0, 0], [0, 0.5, 0]])
    p = P0.replace(tau_r=rng.uniform(0.08, 0.12, (2, 3)), k=0.4)
    g = np.sin(2 * np.pi * 1.1 * t)[:, None, None] * rng.uniform(0.5, 1.5, (2, 3))
    for coupling in (W, None):
        bank = MatsuokaBank(p, coupling)
        a = bank.simulate(t, g, backend="numba")
        b = bank.simulate(t, g, backend="numpy")
        np.testing.assert_allclose(a.states(), b.states(), rtol=0, atol=1e-11)
        np.testing.assert_allclose(a.y, b.y, rtol=0, atol=1e-11)


def test_continuing_from_final_state_equals_one_run():
    t = np.arange(0, 4, 1e-3)
    bank = MatsuokaBank(P0, shape=(3,))
    whole = bank.simulate(t)
    first = bank.simulate(t[:2000])
    second = bank.simulate(t[1999:], x0=first.final)
    np.testing.assert_allclose(second.y, whole.y[1999:], atol=1e-13)


def test_scaling_s_scales_every_state_exactly():
    t = np.arange(0, 5, 1e-3)
    a = MatsuokaBank(P0).simulate(t)
    b = MatsuokaBank(P0.replace(s=3.7)).simulate(t)  # default x0 ∝ s
    np.testing.assert_allclose(b.states(), 3.7 * a.states(), rtol=1e-12, atol=1e-12)


def test_scaling_time_constants_scales_time_exactly():
    lam = 2.5
    t = np.arange(0, 4, 1e-3)
    a = MatsuokaBank(P0).simulate(t)
    b = MatsuokaBank(P0.time_scaled(lam)).simulate(lam * t)  # same steps in scaled time
    np.testing.assert_allclose(b.states(), a.states(), rtol=0, atol=1e-12)


@settings(max_examples=15, deadline=None)
@given(
    batch=st.lists(st.integers(1, 3), min_size=0, max_size=2),
    n=st.integers(1, 3),
    seed=st.integers(0, 2**31 - 1),
    coupled=st.booleans(),
)
def test_batch_equals_loop(batch, n, seed, coupled):
    rng = np.random.default_rng(seed)
    shape = (*batch, n)
    ratio = rng.uniform(0.2, 0.5, shape)
    tau_a = rng.uniform(0.15, 0.4, shape)
    b = rng.uniform(1.5, 3.0, shape)
    w = (1 + ratio) + rng.uniform(0.1, 0.9, shape) * (b - ratio)
    p = MatsuokaParams(tau_r=ratio * tau_a, tau_a=tau_a, b=b, w=w, s=rng.uniform(0.5, 2, shape),
                       k=rng.uniform(0, 0.5, shape))
    W = rng.uniform(0, 0.5, (n, n)) * (1 - np.eye(n)) if coupled else None
    t = np.arange(0, 0.6, 1e-3)
    g = rng.normal(size=(1, *shape)) * np.sin(2 * np.pi * t)[(slice(None),) + (None,) * len(shape)]
    x0 = rng.uniform(-0.2, 0.2, (4, *shape))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OscillatorWarning)
        whole = MatsuokaBank(p, W, shape=shape).simulate(t, g, x0)
        for idx in np.ndindex(*batch):
            sub = MatsuokaParams(**{f: getattr(p, f)[idx] for f in ("tau_r", "tau_a", "b", "w",
                                                                      "s", "k")})
            one = MatsuokaBank(sub, W, shape=(n,)).simulate(t, g[(slice(None), *idx)],
                                                            x0[(slice(None), *idx)])
            np.testing.assert_allclose(whole.y[(slice(None), *idx)], one.y, rtol=0, atol=1e-12)
            np.testing.assert_allclose(whole.final[(slice(None), *idx)], one.final, atol=1e-12)


@pytest.mark.parametrize(
    "kw, exc, words",
    [
        (dict(w=1.2), NoOscillationError, ["(1, 2)", "cannot oscillate"]),  # w < 1 + tr/ta
        (dict(w=3.6), NoOscillationError, ["cannot oscillate", "w = 3.6"]),  # w > 1 + b
        (dict(tau_r=-0.1), OscillatorError, ["tau_r", "> 0"]),
        (dict(tau_a=0.0), OscillatorError, ["tau_a", "> 0"]),
        (dict(s=0.0), OscillatorError, ["s = 0"]),
        (dict(k=-1.0), OscillatorError, ["k = -1"]),
        (dict(b=np.nan), OscillatorError, ["NaN"]),
    ],
)
def test_bad_parameters_raise_naming_the_oscillator(kw, exc, words):
    field, value = next(iter(kw.items()))
    arr = np.full((2, 3), getattr(P0, field), dtype=float)
    arr[1, 2] = value
    with pytest.raises(exc) as info, warnings.catch_warnings():
        warnings.simplefilter("ignore", OscillatorWarning)
        MatsuokaBank(P0.replace(**{field: arr}))
    assert "oscillator (1, 2)" in str(info.value)
    for word in words:
        assert word in str(info.value)


def test_step_too_large_and_doubtful_ratio():
    with pytest.raises(StepTooLargeError, match="tau_r"):
        MatsuokaBank(P0).simulate(np.arange(0, 1, 0.06))
    with pytest.warns(OscillatorWarning, match="accuracy"):
        MatsuokaBank(P0).simulate(np.arange(0, 1, 0.01))
    with pytest.warns(OscillatorWarning, match="tau_r/tau_a"):
        MatsuokaBank(P0.replace(tau_r=0.15, tau_a=0.2, w=2.0))


def test_bad_shapes_and_values_raise():
    bank = MatsuokaBank(P0, shape=(2, 3))
    t = np.linspace(0, 0.1, 101)
    with pytest.raises(OscillatorError, match="shape"):
        bank.simulate(t, g=np.zeros((101, 3, 2)))
    with pytest.raises(OscillatorError, match="expected"):
        bank.simulate(t, x0=np.zeros((3, 2, 3)))
    g = np.zeros((101, 2, 3))
    g[5, 1, 0] = np.nan
    with pytest.raises(OscillatorError, match=r"time step 5, oscillator \(1, 0\)"):
        bank.simulate(t, g=g)
    with pytest.raises(TimeGridError, match="increasing"):
        bank.simulate(t[::-1])
    with pytest.raises(OscillatorError, match="diagonal"):
        MatsuokaBank(P0, np.eye(2))
    with pytest.raises(OscillatorError, match=">= 0"):
        MatsuokaBank(P0, np.array([[0, -1.0], [0, 0]]))
    with pytest.raises(OscillatorError, match="broadcast"):
        MatsuokaParams(tau_r=np.ones(3), tau_a=np.ones(2))
    with pytest.raises(OscillatorError, match="record"):
        bank.simulate(t, record="x")


def test_a_first_numba_compile_is_announced(tmp_path, capsys, monkeypatch):
    """A fresh install's first run compiled the oscillator kernels for 1–2 min in silence. A
    real cache=True numba function in a new module: before its first call there is no cache
    index on disk, so the call is announced (once); after it, the index exists and a fresh
    dispatcher of the same function is not announced."""
    import importlib.util

    src = tmp_path / "fresh_kernel.py"
    src.write_text("import numba\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n")

    def load():
        spec = importlib.util.spec_from_file_location("fresh_kernel", src)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod.twice

    f = load()
    assert _kernel.first_compile(f)
    monkeypatch.setattr(_kernel, "_ANNOUNCED", False)
    _kernel.announce_first_compile(f)
    _kernel.announce_first_compile(f)
    assert capsys.readouterr().err.count("compiling the oscillator network's kernels") == 1
    assert f(21) == 42  # compiles and writes numba's cache next to the module
    assert not _kernel.first_compile(f)  # compiled in this process
    assert not _kernel.first_compile(load())  # a fresh dispatcher finds the cache on disk


def test_both_builds_equal_the_reference_and_read_only_inputs_compile_nothing_new():
    """The serial build runs one chunk of copies, the parallel one more than one chunk (the
    same definition compiled twice); both equal the NumPy reference. Inputs that are read-only
    views (a broadcast ``g``) are the same numba type as writable ones: a read-only array was a
    second compile of the whole kernel (47 s on 2 cores in a fresh install's first demo)."""
    rng = np.random.default_rng(1)
    t = np.arange(0, 0.2, 1e-3)
    W = np.array([[0, 0.3], [0.2, 0]])
    for copies in (3, _kernel.CHUNK + 5):
        p = P0.replace(tau_r=rng.uniform(0.08, 0.12, (copies, 2)), k=0.4)
        g = np.broadcast_to(np.sin(2 * np.pi * 1.1 * t)[:, None, None], (t.size, copies, 2))
        assert not g.flags.writeable
        for coupling in (W, None):
            run = _kernel.kernel(coupling is not None, copies if coupling is not None
                                 else 2 * copies)
            assert run is ((_kernel.rk4_numba if coupling is not None else
                            _kernel.rk4_uncoupled_numba) if copies > _kernel.CHUNK else
                           (_kernel.rk4_numba_serial if coupling is not None else
                            _kernel.rk4_uncoupled_numba_serial))
            bank = MatsuokaBank(p, coupling)
            a = bank.simulate(t, g, backend="numba")
            b = bank.simulate(t, g, backend="numpy")
            np.testing.assert_allclose(a.y, b.y, rtol=0, atol=1e-11)
            a2 = bank.simulate(t, np.ascontiguousarray(g), backend="numba")
            np.testing.assert_array_equal(a2.y, a.y)
            assert len(run.signatures) == 1
