"""Periodic teaching signals from short clips: frequency estimate and Fourier-series fit.

A demonstration clip is often only a couple of cycles long (the shipped walk: ~2 strides in
2.5 s) — too short for an oscillator to lock and for frequency adaptation to converge. We fit
a truncated Fourier series ``x(t) ≈ c_0 + Σ_{h=1..H} a_h cos(2πhft) + b_h sin(2πhft)`` with a
common fundamental ``f`` to all joints by least squares; ``f`` minimises the fit residual
(golden-section search around the spectral peak). The series is smooth, exactly periodic, and
can be evaluated on any time grid as a teaching signal.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from ..errors import OscillatorError
from ..safety import MAX_HARMONICS, check_count

__all__ = ["FourierTeacher", "fit_teacher", "check_targets"]


def check_targets(t: Any, targets: Any) -> tuple[np.ndarray, np.ndarray]:
    """Validate ``t (T,)`` strictly increasing and ``targets (T, n)`` finite; return floats."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(targets, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if t.ndim != 1 or x.ndim != 2 or x.shape[0] != t.shape[0] or t.shape[0] < 8:
        raise OscillatorError(
            f"need t (T,) and targets (T, n) with T >= 8; got {t.shape} and {np.shape(targets)}"
        )
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise OscillatorError("t must be finite and strictly increasing")
    bad = ~np.isfinite(x)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise OscillatorError(f"targets are NaN or infinite at sample {i}, joint {j}")
    flat = np.ptp(x, axis=0) <= 1e-12
    if flat.any():
        raise OscillatorError(f"joint {int(np.argmax(flat))} is constant: nothing to oscillate")
    return t, x


@dataclass(frozen=True)
class FourierTeacher:
    """A periodic signal ``(T, n)`` given by its Fourier series.

    Attributes:
        frequency: fundamental [Hz].
        coeffs: ``(1 + 2H, n)``: mean, then (cos, sin) pairs of harmonics 1..H [target units].
        fit_nrmse: ``(n,)`` RMS residual of the fit on the clip / the clip's peak-to-peak.
    """

    frequency: float
    coeffs: np.ndarray
    fit_nrmse: np.ndarray

    @property
    def harmonics(self) -> int:
        """Number of harmonics H."""
        return (self.coeffs.shape[0] - 1) // 2

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """Evaluate on ``t (T,)`` [s] → ``(T, n)``."""
        return _basis(np.asarray(t, dtype=float), self.frequency, self.harmonics) @ self.coeffs

    def fundamental_phase(self) -> np.ndarray:
        """``(n,)`` phase [rad] of each joint's first harmonic, as in cos(2πft − φ)."""
        return np.arctan2(self.coeffs[2], self.coeffs[1])

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {
            "frequency": self.frequency,
            "coeffs": self.coeffs.tolist(),
            "fit_nrmse": self.fit_nrmse.tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FourierTeacher:
        """Inverse of :meth:`to_dict`."""
        return cls(float(d["frequency"]), np.asarray(d["coeffs"]), np.asarray(d["fit_nrmse"]))


def _basis(t: np.ndarray, f: float, H: int) -> np.ndarray:
    h = np.arange(1, H + 1)
    arg = 2 * np.pi * f * t[:, None] * h[None, :]
    out = np.empty((t.size, 1 + 2 * H))
    out[:, 0] = 1.0
    out[:, 1::2] = np.cos(arg)
    out[:, 2::2] = np.sin(arg)
    return out


def fit_teacher(
    t: np.ndarray,
    targets: np.ndarray,
    *,
    harmonics: int = 8,
    frequency: float | None = None,
) -> FourierTeacher:
    """Fit a common-fundamental Fourier series to ``targets (T, n)`` on ``t (T,)``.

    Args:
        harmonics: H, number of harmonics (limited to what the clip's sampling resolves).
        frequency: fundamental [Hz]; default: the residual-minimising one near the spectral
            peak (the clip must hold at least about one cycle).
    """
    t, x = check_targets(t, targets)
    H = check_count("harmonics", harmonics, 1, MAX_HARMONICS, OscillatorError)
    if 2 * H + 1 > t.size:
        raise OscillatorError(f"harmonics = {H} needs at least {2 * H + 1} samples (the fit has "
                              f"{2 * H + 1} coefficients per joint); the clip has {t.size}")

    def resid(f: float, h: int = H) -> float:
        A = _basis(t, f, h)
        c = np.linalg.lstsq(A, x, rcond=None)[0]
        r = (x - A @ c) / np.ptp(x, axis=0)
        return float(np.mean(r**2))

    if frequency is None:
        # coarse: best single sinusoid (immune to sub-harmonics) from 0.8 cycles per clip up to
        # a tenth of the sampling rate; fine: full series within ±15 % of it
        span = t[-1] - t[0]
        grid = np.geomspace(0.8 / span, 0.1 / np.median(np.diff(t)), 400)
        f1 = grid[int(np.argmin([resid(f, 1) for f in grid]))]
        fine = np.linspace(0.85 * f1, 1.15 * f1, 61)
        i = int(np.argmin([resid(f) for f in fine]))
        lo, hi = fine[max(i - 1, 0)], fine[min(i + 1, fine.size - 1)]
        frequency = float(
            minimize_scalar(resid, bounds=(lo, hi), method="bounded", options={"xatol": 1e-7}).x
        )
    f = float(frequency)
    if not np.isfinite(f) or f <= 0:
        raise OscillatorError(f"frequency must be > 0 Hz, got {frequency!r}")
    A = _basis(t, f, H)
    c = np.linalg.lstsq(A, x, rcond=None)[0]
    nrmse = np.sqrt(np.mean((x - A @ c) ** 2, axis=0)) / np.ptp(x, axis=0)
    return FourierTeacher(f, c, nrmse)
