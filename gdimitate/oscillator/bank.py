"""A bank of Matsuoka oscillators of shape ``(*batch, n)`` and its integration (docs/design.md §7).

Per oscillator i (extensor e, flexor f), with y = max(x, 0) and W the ``(n, n)`` coupling::

    T_r·ẋ_e + x_e = −w·y_f − Σ_j W_ij·y_e,j − b·v_e − k·[g]⁺ + s
    T_a·v̇_e + v_e = y_e
    T_r·ẋ_f + x_f = −w·y_e − Σ_j W_ij·y_f,j − b·v_f − k·[g]⁻ + s
    T_a·v̇_f + v_f = y_f
    output y = y_e − y_f

The coupling term ``Σ_j W_ij·y_j`` of docs/design.md §7 is read neuron-wise: the extensor of i is
inhibited by the extensors of the other oscillators and the flexor by the flexors, so an
inhibitory ``W_ij > 0`` pulls oscillators i and j towards anti-phase. The ``n`` oscillators of
one batch element are coupled; batch elements are independent copies.

Integration is classical fixed-step RK4 on the given time grid (steps may vary); the input
``g`` is linearly interpolated to the half step. Accuracy (measured by the tests against
``scipy.integrate.solve_ivp`` with DOP853 at rtol = atol = 1e-12, docs/design.md's example
parameters
T_r 0.1 s, T_a 0.2 s, b = w = 2.5): max |Δy| = 3.4e-5 over 20 s at dt = 1 ms (1.6e-4 at
2 ms). The kinks of max(x, 0) break RK4's fourth order; the error is mostly a slowly growing
phase drift. Keep dt ≤ tau_r/100 for |Δy| ≲ 1e-4 over tens of periods.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..errors import OscillatorError, TimeGridError
from ..safety import check_array_size
from . import _kernel
from .params import MatsuokaParams, validate_coupling, validate_params, validate_step

__all__ = ["MatsuokaBank", "Trace", "OscillatorTimeGridError", "default_x0"]


class OscillatorTimeGridError(OscillatorError, TimeGridError):
    """A time grid that is not 1-D, finite and strictly increasing with at least two points."""


@dataclass(frozen=True, eq=False)
class Trace:
    """Result of :meth:`MatsuokaBank.simulate`; every state array is ``(T, *batch, n)``.

    Attributes:
        t: time grid ``(T,)`` [s].
        x_e, x_f: membrane states of the extensor and flexor neurons (``None`` if not recorded).
        v_e, v_f: adaptation states (``None`` if not recorded).
        y: output ``y_e − y_f``.
        final: state at ``t[-1]``, ``(4, *batch, n)`` in the order ``(x_e, x_f, v_e, v_f)``;
            pass it as ``x0`` to continue a simulation.
    """

    t: np.ndarray
    x_e: np.ndarray | None
    x_f: np.ndarray | None
    v_e: np.ndarray | None
    v_f: np.ndarray | None
    y: np.ndarray
    final: np.ndarray

    @property
    def y_e(self) -> np.ndarray:
        """Extensor output max(x_e, 0), ``(T, *batch, n)``."""
        return np.maximum(self._need("x_e"), 0.0)

    @property
    def y_f(self) -> np.ndarray:
        """Flexor output max(x_f, 0), ``(T, *batch, n)``."""
        return np.maximum(self._need("x_f"), 0.0)

    def states(self) -> np.ndarray:
        """All four states stacked, ``(4, T, *batch, n)`` in the order (x_e, x_f, v_e, v_f)."""
        return np.stack([self._need(f) for f in ("x_e", "x_f", "v_e", "v_f")])

    def _need(self, name: str) -> np.ndarray:
        v = getattr(self, name)
        if v is None:
            raise OscillatorError(f"trace has no {name}: simulate with record='all'")
        return v


def default_x0(params: MatsuokaParams, shape: tuple[int, ...]) -> np.ndarray:
    """The default initial state ``(4, *shape)``: ``x_e = 0.1·s``, ``x_f = v_e = v_f = 0``.

    Small and asymmetric (so the oscillation starts at once, away from the unstable
    equilibrium) and proportional to ``s`` (so the scaling invariance in ``s`` holds exactly).
    """
    x0 = np.zeros((4, *shape))
    x0[0] = 0.1 * np.broadcast_to(params.s, shape)
    return x0


def _rhs(state, g, p: MatsuokaParams, W: np.ndarray, has_coupling: bool):
    """Derivative of ``state (4, *batch, n)``; ``g`` broadcastable to ``(*batch, n)`` or None."""
    xe, xf, ve, vf = state
    ye = np.maximum(xe, 0.0)
    yf = np.maximum(xf, 0.0)
    dxe = p.s - xe - p.w * yf - p.b * ve
    dxf = p.s - xf - p.w * ye - p.b * vf
    if has_coupling:
        dxe = dxe - ye @ W.T
        dxf = dxf - yf @ W.T
    if g is not None:
        dxe = dxe - p.k * np.maximum(g, 0.0)
        dxf = dxf - p.k * np.maximum(-g, 0.0)
    return np.stack([dxe / p.tau_r, dxf / p.tau_r, (ye - ve) / p.tau_a, (yf - vf) / p.tau_a])


def _rk4_numpy(t, g, p, W, x0, rec_all):
    """NumPy reference RK4 (the definition the compiled kernel is tested against)."""
    T = t.shape[0]
    has_c = bool(np.any(W))
    out = np.empty((T, *x0.shape)) if rec_all else None
    y = np.empty((T, *x0.shape[1:]))
    x = x0.copy()
    y[0] = np.maximum(x[0], 0) - np.maximum(x[1], 0)
    if rec_all:
        out[0] = x
    for k in range(T - 1):
        h = t[k + 1] - t[k]
        g0 = g1 = gm = None
        if g is not None:
            g0, g1 = g[k], g[k + 1]
            gm = 0.5 * (g0 + g1)
        k1 = _rhs(x, g0, p, W, has_c)
        k2 = _rhs(x + 0.5 * h * k1, gm, p, W, has_c)
        k3 = _rhs(x + 0.5 * h * k2, gm, p, W, has_c)
        k4 = _rhs(x + h * k3, g1, p, W, has_c)
        x = x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        y[k + 1] = np.maximum(x[0], 0) - np.maximum(x[1], 0)
        if rec_all:
            out[k + 1] = x
    return y, out, x


def _rk4_compiled(t, g, p, W, x0, rec_all):
    """Reshape to the kernel's ``(n, B)`` layout, run it, reshape back."""
    shape = x0.shape[1:]
    coupled = bool(np.any(W))
    n = shape[-1] if coupled else 1  # uncoupled: every oscillator is an independent copy
    B = int(np.prod(shape, dtype=int)) // n
    T = t.shape[0]

    def to_nb(a, lead):  # (*lead, *batch, n) -> (*lead, n, B)
        a = a.reshape(*lead, B, n)
        # writable as well as contiguous: numba compiles a read-only array (a broadcast
        # view's) as another type, and so the whole kernel again (47 s on 2 cores)
        return np.require(np.swapaxes(a, -1, -2), requirements=["C", "W"])

    P = np.stack(
        [1.0 / p.tau_r, 1.0 / p.tau_a, p.b, p.w, p.s, p.k]
    )  # (6, *batch, n)
    P = to_nb(P, (6,))
    xs = to_nb(x0, (4,))
    has_g = g is not None
    gk = to_nb(g, (T,)) if has_g else np.zeros((1, n, 1))
    Y = np.empty((T, n, B))
    rec = (T, n, B) if rec_all else (1, 1, 1)
    XE, XF, VE, VF = (np.empty(rec) for _ in range(4))
    final = np.empty((4, n, B))
    tc = np.require(t, requirements=["C", "W"])
    run = _kernel.kernel(coupled, B)
    _kernel.announce_first_compile(run)
    if coupled:
        run(tc, gk, has_g, P, np.require(W, requirements=["C", "W"]), xs, rec_all, Y, XE, XF,
            VE, VF, final)
    else:
        run(tc, gk, has_g, P, xs, rec_all, Y, XE, XF, VE, VF, final)

    def back(a, lead):  # (*lead, n, B) -> (*lead, *batch, n)
        return np.swapaxes(a, -1, -2).reshape(*lead, *shape)

    out = np.stack([back(a, (T,)) for a in (XE, XF, VE, VF)], axis=1) if rec_all else None
    return back(Y, (T,)), out, back(final, (4,))


class MatsuokaBank:
    """Matsuoka oscillators of shape ``(*batch, n)``: ``n`` coupled ones, copied over ``batch``.

    Args:
        params: :class:`MatsuokaParams`; fields broadcast to the bank shape.
        coupling: ``(n, n)`` inhibitory coupling ``W_ij >= 0`` with zero diagonal (``None``: no
            coupling).
        shape: bank shape ``(*batch, n)``; default: the parameters' broadcast shape, with the
            last axis taken from ``coupling`` where that is larger, and ``(1,)`` for scalars.

    Raises:
        OscillatorError (or its subclass NoOscillationError): invalid parameters or coupling,
        naming the first offending oscillator.
    """

    def __init__(
        self,
        params: MatsuokaParams,
        coupling: np.ndarray | None = None,
        *,
        shape: tuple[int, ...] | None = None,
    ):
        if not isinstance(params, MatsuokaParams):
            raise OscillatorError(f"params must be MatsuokaParams, got {type(params).__name__}")
        if shape is None:
            shape = params.shape or (1,)
            if coupling is not None:
                n = np.shape(coupling)[0] if np.ndim(coupling) == 2 else 1
                if shape[-1] == 1 and n > 1:
                    shape = (*shape[:-1], n)
        try:
            shape = tuple(int(d) for d in shape)
        except (TypeError, ValueError, OverflowError):
            raise OscillatorError(f"bank shape must be a tuple of integers: {shape!r}") from None
        if len(shape) == 0 or min(shape) < 1:
            raise OscillatorError(f"bank shape must be (*batch, n) with positive sizes: {shape}")
        check_array_size(f"MatsuokaBank of shape {shape} (4 states each)", (4, *shape))
        self.shape: tuple[int, ...] = shape
        self.params: MatsuokaParams = validate_params(params, shape)
        n = shape[-1]
        self.coupling: np.ndarray = (
            np.zeros((n, n)) if coupling is None else validate_coupling(coupling, n)
        )

    @property
    def n(self) -> int:
        """Number of coupled oscillators (last axis)."""
        return self.shape[-1]

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """Shape of the independent copies."""
        return self.shape[:-1]

    @property
    def size(self) -> int:
        """Total number of oscillators."""
        return int(np.prod(self.shape))

    def simulate(
        self,
        t: np.ndarray,
        g: np.ndarray | None = None,
        x0: np.ndarray | None = None,
        *,
        backend: Literal["auto", "numba", "numpy"] = "auto",
        record: Literal["all", "y"] = "all",
    ) -> Trace:
        """Integrate the bank with fixed-step RK4 on the grid ``t``.

        Args:
            t: time grid ``(T,)`` [s], strictly increasing, T >= 2 (steps may vary).
            g: external input ``(T, *batch, n)`` (or broadcastable to it), linearly
                interpolated between grid points; ``None`` = no input.
            x0: initial state ``(4, *batch, n)`` (or broadcastable) in the order
                ``(x_e, x_f, v_e, v_f)``; ``None`` = :func:`default_x0`.
            backend: ``"numba"`` compiled kernel, ``"numpy"`` reference, ``"auto"`` = numba
                when available. The two agree to round-off.
            record: ``"all"`` keeps every state; ``"y"`` keeps only the output (memory).

        Returns:
            :class:`Trace` with arrays ``(T, *batch, n)``.

        Raises:
            OscillatorTimeGridError: bad ``t``. StepTooLargeError: a step > 0.5·tau_r.
            OscillatorError: wrong shapes, NaN/inf in ``g`` or ``x0``, unknown options.
        """
        t = _check_t(t)
        T = t.shape[0]
        check_array_size(f"a {T}-step run of a bank of shape {self.shape}",
                         (T, 4 if record == "all" else 1, *self.shape))
        validate_step(self.params, float(np.max(np.diff(t))), self.shape)
        if g is not None:
            g = _check_array("g", g, (T, *self.shape), lead="time step")
        if x0 is None:
            x0 = default_x0(self.params, self.shape)
        else:
            x0 = _check_array("x0", x0, (4, *self.shape), lead="state")
        if record not in ("all", "y"):
            raise OscillatorError(f"record must be 'all' or 'y', got {record!r}")
        if backend not in ("auto", "numba", "numpy"):
            raise OscillatorError(f"backend must be 'auto', 'numba' or 'numpy', got {backend!r}")
        if backend == "numba" and not _kernel.HAVE_NUMBA:  # pragma: no cover
            raise OscillatorError("backend='numba' needs numba installed")
        use_numba = backend == "numba" or (backend == "auto" and _kernel.HAVE_NUMBA)
        rec_all = record == "all"
        run = _rk4_compiled if use_numba else _rk4_numpy
        y, states, final = run(t, g, self.params, self.coupling, x0, rec_all)
        if rec_all:
            xe, xf, ve, vf = (states[:, i] for i in range(4))
        else:
            xe = xf = ve = vf = None
        return Trace(t=t, x_e=xe, x_f=xf, v_e=ve, v_f=vf, y=y, final=final)


def _check_t(t) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.shape[0] < 2:
        raise OscillatorTimeGridError(f"t must be 1-D with at least 2 points, got shape {t.shape}")
    if not np.isfinite(t).all():
        raise OscillatorTimeGridError(f"t[{int(np.argmax(~np.isfinite(t)))}] is NaN or infinite")
    d = np.diff(t)
    if (d <= 0).any():
        i = int(np.argmax(d <= 0))
        raise OscillatorTimeGridError(
            f"t must be strictly increasing: t[{i}] = {t[i]:g} >= t[{i + 1}] = {t[i + 1]:g}"
        )
    return t


def _check_array(name: str, a, shape: tuple[int, ...], lead: str) -> np.ndarray:
    try:
        a = np.asarray(a, dtype=float)
    except (TypeError, ValueError):
        raise OscillatorError(f"{name} must be a numeric array") from None
    try:
        a = np.broadcast_to(a, shape)
    except ValueError:
        raise OscillatorError(
            f"{name} has shape {a.shape}; expected {shape} (or broadcastable to it)"
        ) from None
    bad = ~np.isfinite(a)
    if bad.any():
        idx = tuple(int(v) for v in np.argwhere(bad)[0])
        raise OscillatorError(
            f"{name} is NaN or infinite at {lead} {idx[0]}, oscillator {idx[1:]}"
        )
    return a
