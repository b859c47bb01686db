"""Matsuoka oscillator parameters and their validation (docs/design.md §7).

One oscillator has an extensor and a flexor neuron with membrane time constant ``tau_r`` [s],
adaptation time constant ``tau_a`` [s], self-inhibition (adaptation) gain ``b``, mutual
inhibition ``w``, tonic input ``s`` and input gain ``k``. Every field broadcasts to the bank's
shape ``(*batch, n)``, so one :class:`MatsuokaParams` can describe a whole parameter sweep.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import OscillatorError

__all__ = [
    "MatsuokaParams",
    "NoOscillationError",
    "StepTooLargeError",
    "OscillatorWarning",
    "validate_params",
    "validate_coupling",
    "validate_step",
    "FIELDS",
]

FIELDS = ("tau_r", "tau_a", "b", "w", "s", "k")

#: Range of ``tau_r / tau_a`` in which the paper reports stable oscillation; outside it we warn.
RATIO_RANGE = (0.1, 0.5)
#: An RK4 step above ``tau_r * STEP_ERROR`` is refused; above ``tau_r * STEP_WARN`` we warn.
STEP_ERROR = 0.5
STEP_WARN = 0.05


class NoOscillationError(OscillatorError):
    """Parameters for which the oscillator has no limit cycle (Matsuoka's condition fails)."""


class StepTooLargeError(OscillatorError):
    """An integration step too large for the oscillator's time constants."""


class OscillatorWarning(UserWarning):
    """A doubtful but legal oscillator setting (e.g. ``tau_r/tau_a`` outside 0.1–0.5)."""


def _as_field(name: str, value: Any) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise OscillatorError(f"MatsuokaParams.{name} must be numeric, got {value!r}") from None
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class MatsuokaParams:
    """Parameters of Matsuoka oscillators; each field a scalar or an array broadcasting to the
    bank's shape ``(*batch, n)``.

    Attributes:
        tau_r: rise (membrane) time constant T_r [s], > 0.
        tau_a: adaptation time constant T_a [s], > 0.
        b: adaptation gain (dimensionless), ≥ 0.
        w: extensor–flexor mutual inhibition; oscillates for ``1 + tau_r/tau_a < w < 1 + b``.
        s: tonic input (sets the amplitude; every state scales with it), > 0.
        k: gain of the external input ``g`` (0 = free running), ≥ 0.

    The defaults are docs/design.md §7's example (free frequency ≈ 1.12 Hz).
    """

    tau_r: Any = 0.1
    tau_a: Any = 0.2
    b: Any = 2.5
    w: Any = 2.5
    s: Any = 1.0
    k: Any = 0.0

    def __post_init__(self) -> None:
        for name in FIELDS:
            object.__setattr__(self, name, _as_field(name, getattr(self, name)))
        try:
            np.broadcast_shapes(*(getattr(self, f).shape for f in FIELDS))
        except ValueError:
            shapes = {f: getattr(self, f).shape for f in FIELDS}
            raise OscillatorError(f"MatsuokaParams fields do not broadcast: {shapes}") from None

    @property
    def shape(self) -> tuple[int, ...]:
        """Broadcast shape of the fields (``()`` when all are scalars)."""
        return np.broadcast_shapes(*(getattr(self, f).shape for f in FIELDS))

    @property
    def ratio(self) -> np.ndarray:
        """``tau_r / tau_a`` (broadcast shape)."""
        return self.tau_r / self.tau_a

    def broadcast_to(self, shape: Sequence[int]) -> MatsuokaParams:
        """The same parameters with every field a full array of ``shape``."""
        shape = tuple(int(d) for d in shape)
        try:
            return MatsuokaParams(
                **{f: np.broadcast_to(getattr(self, f), shape).copy() for f in FIELDS}
            )
        except ValueError:
            raise OscillatorError(
                f"parameters of shape {self.shape} do not broadcast to the bank shape {shape}"
            ) from None

    def replace(self, **changes: Any) -> MatsuokaParams:
        """A copy with some fields replaced (``dataclasses.replace``)."""
        return dataclasses.replace(self, **changes)

    def time_scaled(self, factor: Any) -> MatsuokaParams:
        """Both time constants multiplied by ``factor``: the period scales by exactly ``factor``."""
        factor = np.asarray(factor, dtype=float)
        return self.replace(tau_r=self.tau_r * factor, tau_a=self.tau_a * factor)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (floats or nested lists)."""
        return {f: getattr(self, f).tolist() for f in FIELDS}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> MatsuokaParams:
        """Inverse of :meth:`to_dict`."""
        missing = [f for f in FIELDS if f not in data]
        if missing:
            raise OscillatorError(f"MatsuokaParams.from_dict: missing fields {missing}")
        return cls(**{f: data[f] for f in FIELDS})

    def __repr__(self) -> str:
        def show(a: np.ndarray) -> str:
            return f"{float(a):g}" if a.ndim == 0 else f"array{a.shape}"

        inner = ", ".join(f"{f}={show(getattr(self, f))}" for f in FIELDS)
        return f"MatsuokaParams({inner})"


def _where(mask: np.ndarray, shape: tuple[int, ...]) -> str:
    """'oscillator (i, j)' for the first True in ``mask`` plus a count."""
    idx = np.argwhere(mask)
    first = tuple(int(v) for v in idx[0]) if mask.ndim else ()
    n = int(mask.sum())
    more = f" (and {n - 1} more)" if n > 1 else ""
    return f"oscillator {first if len(shape) != 1 else first[0]}{more}"


def validate_params(
    params: MatsuokaParams,
    shape: Sequence[int],
    dt: float | None = None,
    *,
    coupling: np.ndarray | None = None,
) -> MatsuokaParams:
    """Check parameters for a bank of ``shape`` and return them broadcast to that shape.

    Raises:
        OscillatorError: NaN/inf, non-positive time constants or ``s``, negative ``b``/``k``,
            fields that do not broadcast, a bad coupling matrix.
        NoOscillationError: ``w`` outside ``(1 + tau_r/tau_a, 1 + b)``.
        StepTooLargeError: ``dt > 0.5 * tau_r`` (RK4 then misses the fast dynamics).

    Warns:
        OscillatorWarning: ``tau_r/tau_a`` outside 0.1–0.5, or ``dt > 0.05 * tau_r``.

    Each message names the first offending oscillator index and the count.
    """
    shape = tuple(int(d) for d in shape)
    p = params.broadcast_to(shape)
    for f in FIELDS:
        bad = ~np.isfinite(getattr(p, f))
        if bad.any():
            raise OscillatorError(f"{_where(bad, shape)}: {f} is NaN or infinite")
    for f in ("tau_r", "tau_a", "s"):
        bad = getattr(p, f) <= 0
        if bad.any():
            v = getattr(p, f)[tuple(np.argwhere(bad)[0])]
            raise OscillatorError(f"{_where(bad, shape)}: {f} = {v:g} must be > 0")
    for f in ("b", "k"):
        bad = getattr(p, f) < 0
        if bad.any():
            v = getattr(p, f)[tuple(np.argwhere(bad)[0])]
            raise OscillatorError(f"{_where(bad, shape)}: {f} = {v:g} must be >= 0")
    lo = 1.0 + p.tau_r / p.tau_a
    hi = 1.0 + p.b
    bad = ~((p.w > lo) & (p.w < hi))
    if bad.any():
        i = tuple(np.argwhere(bad)[0])
        raise NoOscillationError(
            f"{_where(bad, shape)} cannot oscillate: needs 1 + tau_r/tau_a < w < 1 + b, i.e. "
            f"{lo[i]:g} < w < {hi[i]:g}, but w = {p.w[i]:g}"
            + (" (the interval is empty: raise b or lower tau_r/tau_a)" if lo[i] >= hi[i] else "")
        )
    ratio = p.ratio
    odd = (ratio < RATIO_RANGE[0]) | (ratio > RATIO_RANGE[1])
    if odd.any():
        i = tuple(np.argwhere(odd)[0])
        warnings.warn(
            f"{_where(odd, shape)}: tau_r/tau_a = {ratio[i]:.3g} is outside "
            f"{RATIO_RANGE[0]}–{RATIO_RANGE[1]}, where stable oscillation and the closed-form "
            "frequency are established",
            OscillatorWarning,
            stacklevel=3,
        )
    if dt is not None:
        validate_step(p, dt, shape)
    if coupling is not None:
        validate_coupling(coupling, shape[-1] if shape else 1)
    return p


def validate_step(params: MatsuokaParams, dt: float, shape: Sequence[int]) -> None:
    """Refuse an RK4 step ``dt`` [s] above ``0.5·tau_r`` (StepTooLargeError); warn above
    ``0.05·tau_r`` (OscillatorWarning). ``params`` must broadcast to ``shape``."""
    shape = tuple(int(d) for d in shape)
    dt = float(dt)
    tau_r = np.broadcast_to(params.tau_r, shape)
    too = dt > STEP_ERROR * tau_r
    if too.any():
        i = tuple(np.argwhere(too)[0])
        raise StepTooLargeError(
            f"{_where(too, shape)}: step dt = {dt:g} s is too large for tau_r = "
            f"{tau_r[i]:g} s (need dt <= {STEP_ERROR} * tau_r; use a finer time grid)"
        )
    doubt = dt > STEP_WARN * tau_r
    if doubt.any():
        i = tuple(np.argwhere(doubt)[0])
        warnings.warn(
            f"{_where(doubt, shape)}: step dt = {dt:g} s exceeds {STEP_WARN} * tau_r = "
            f"{STEP_WARN * tau_r[i]:g} s; RK4 accuracy will be poor",
            OscillatorWarning,
            stacklevel=3,
        )


def validate_coupling(coupling: Any, n: int) -> np.ndarray:
    """Check an inter-oscillator coupling matrix: ``(n, n)``, finite, ``>= 0``, zero diagonal."""
    W = np.asarray(coupling, dtype=float)
    if W.shape != (n, n):
        raise OscillatorError(f"coupling must have shape ({n}, {n}) for n = {n}, got {W.shape}")
    if not np.isfinite(W).all():
        i, j = np.argwhere(~np.isfinite(W))[0]
        raise OscillatorError(f"coupling[{i}, {j}] (oscillator {i} from {j}) is NaN or infinite")
    if (W < 0).any():
        i, j = np.argwhere(W < 0)[0]
        raise OscillatorError(
            f"coupling[{i}, {j}] = {W[i, j]:g} (oscillator {i} from {j}) must be >= 0 (inhibition)"
        )
    if np.any(np.diag(W) != 0):
        i = int(np.flatnonzero(np.diag(W) != 0)[0])
        raise OscillatorError(f"coupling[{i}, {i}] = {W[i, i]:g}: the diagonal must be zero")
    return W
