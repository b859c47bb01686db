"""1:1 Arnold tongue of a Matsuoka oscillator: locking region over input frequency × gain.

The whole grid runs as **one** bank of shape ``(G, F, 1)`` (one oscillator per cell, gain
``k`` along the first axis, input frequency along the second), driven by sinusoids
``g = amplitude·sin(2π f t)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..errors import OscillatorError
from .analysis import frequency_ratio, phase_locking_value
from .bank import MatsuokaBank
from .params import MatsuokaParams

__all__ = ["ArnoldTongue", "arnold_tongue"]


@dataclass(frozen=True)
class ArnoldTongue:
    """Result of :func:`arnold_tongue`.

    Attributes:
        frequencies: input frequencies ``(F,)`` [Hz].
        gains: input gains ``k`` ``(G,)``.
        locked: ``(G, F)`` bool, 1:1 locked after the transient.
        ratio: ``(G, F)`` measured output/input frequency ratio.
        plv: ``(G, F)`` phase-locking value.
        free_frequency: measured free-running frequency [Hz] of the oscillator (k = 0).
    """

    frequencies: np.ndarray
    gains: np.ndarray
    locked: np.ndarray
    ratio: np.ndarray
    plv: np.ndarray
    free_frequency: float

    def locking_range(self) -> np.ndarray:
        """``(G, 2)`` lowest and highest locked frequency [Hz] of the contiguous locked run
        that contains (or is nearest to) the free frequency; NaN rows where nothing locks."""
        out = np.full((self.gains.size, 2), np.nan)
        f = self.frequencies
        centre = int(np.argmin(np.abs(f - self.free_frequency)))
        for i, row in enumerate(self.locked):
            if not row.any():
                continue
            idx = np.flatnonzero(row)
            c = idx[np.argmin(np.abs(idx - centre))]
            lo = c
            while lo > 0 and row[lo - 1]:
                lo -= 1
            hi = c
            while hi < row.size - 1 and row[hi + 1]:
                hi += 1
            out[i] = f[lo], f[hi]
        return out


def arnold_tongue(
    params: MatsuokaParams,
    frequencies: np.ndarray,
    gains: np.ndarray,
    *,
    amplitude: float = 1.0,
    periods: float = 40.0,
    dt: float | None = None,
    ratio_tol: float = 0.005,
    plv_min: float = 0.95,
    backend: Literal["auto", "numba", "numpy"] = "auto",
) -> ArnoldTongue:
    """Compute the 1:1 locking region over ``frequencies (F,)`` [Hz] × ``gains (G,)``.

    Args:
        params: parameters of one oscillator (scalar fields; its ``k`` is replaced by ``gains``).
        frequencies: input frequencies [Hz], > 0.
        gains: input gains ``k >= 0``.
        amplitude: amplitude of the sinusoidal input.
        periods: simulated duration in periods of the slowest of input and free oscillation;
            the first half is discarded as transient.
        dt: step [s]; default ``min(tau_r/40, 1/(200·max f))``.
        ratio_tol, plv_min: locked ⇔ ``|ratio − 1| < ratio_tol`` and ``plv > plv_min``.
            (A run of ``periods/2`` cycles cannot resolve a detuning much below
            ``1/(periods/2)``: cells right at the tongue's edge may be misclassified.)

    Returns:
        :class:`ArnoldTongue`.
    """
    f = np.asarray(frequencies, dtype=float).ravel()
    k = np.asarray(gains, dtype=float).ravel()
    if f.size == 0 or k.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise OscillatorError("frequencies must be a non-empty array of finite values > 0 Hz")
    if params.shape not in ((), (1,)):
        raise OscillatorError(f"arnold_tongue takes one oscillator's params, got {params.shape}")
    from .analysis import free_running_frequency

    base = params.replace(k=0.0)
    f_free = float(np.ravel(free_running_frequency(base))[0])
    scalars = {n: np.ravel(v)[0] for n, v in base.to_dict().items() if n != "k"}
    p = MatsuokaParams(**scalars, k=k[:, None, None])
    shape = (k.size, f.size, 1)
    bank = MatsuokaBank(p, shape=shape)
    if dt is None:
        dt = min(float(np.ravel(params.tau_r)[0]) / 40.0, 1.0 / (200.0 * f.max()))
    duration = periods / min(f.min(), f_free)
    t = np.arange(0.0, duration + dt / 2, dt)
    g = amplitude * np.sin(2 * np.pi * f[None, :] * t[:, None])[:, None, :, None]
    tr = bank.simulate(t, g, record="y", backend=backend)
    start = duration / 2
    y = tr.y[..., 0]
    gg = np.broadcast_to(g[..., 0], y.shape)
    ratio = frequency_ratio(t, y, gg, start=start)
    plv = phase_locking_value(t, y, gg, start=start)
    locked = (np.abs(ratio - 1.0) < ratio_tol) & (plv > plv_min)
    return ArnoldTongue(f, k, locked, ratio, plv, f_free)
