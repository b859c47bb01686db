"""Closed-form frequency and amplitude of a free Matsuoka oscillator (Matsuoka 2011, docs/design.md
§7).

K. Matsuoka, "Analysis of a neural oscillator", Biol. Cybern. 104 (2011) 297–304:

    ω_n ≈ (1/T_a)·sqrt(((T_r + T_a)·b − T_r·w) / (T_r·w))
    A   ≈ s / (2K − 1 + (2/π)(w + b)·arcsin K),   K = (T_r + T_a)/(T_a·w)

Both are approximations. The frequency is the linearised one at the oscillation onset, so it
is best for ``w`` near the lower end of ``(1 + T_r/T_a, 1 + b)``. Measured here with the RK4
bank (tests hold these): for ``T_r/T_a`` in 0.3–0.5 and ``b`` in 1–3, the error is below 2 %
while ``w`` lies in the lower quarter of its interval (e.g. 0.4 % for docs/design.md's example
T_r 0.1, T_a 0.2, b = w = 2.5; 2.5 % for T_r/T_a = 0.3 with b = w = 2.5), and grows to tens of
percent as ``w → 1 + b``; below T_r/T_a = 0.3 it degrades (−7 % at 0.2, −22 % at 0.1 for
b = w = 2.5). ``A`` is the half peak-to-peak amplitude of ``x_e`` (and ``x_f``), good to
about 2 % for T_r/T_a ≥ 0.3 in the same region. Where accuracy matters, measure
(:func:`~gdimitate.oscillator.analysis.free_running_frequency`) and rescale both time
constants: the period scales with them exactly.
"""

from __future__ import annotations

import numpy as np

from ..errors import OscillatorError
from .params import MatsuokaParams

__all__ = ["natural_frequency", "natural_amplitude", "tau_r_for_frequency"]


def natural_frequency(params: MatsuokaParams) -> np.ndarray:
    """Matsuoka's closed-form natural frequency ω_n/(2π) [Hz], shape ``params.shape``.

    Uses ``tau_r, tau_a, b, w`` (not ``s``, ``k``). NaN where the radicand is negative.
    """
    tr, ta, b, w = params.tau_r, params.tau_a, params.b, params.w
    rad = ((tr + ta) * b - tr * w) / (tr * w)
    with np.errstate(invalid="ignore"):
        return np.sqrt(rad) / ta / (2.0 * np.pi)


def natural_amplitude(params: MatsuokaParams) -> np.ndarray:
    """Matsuoka's closed-form amplitude: half the peak-to-peak of ``x_e`` (same units as ``s``).

    NaN where ``K = (tau_r + tau_a)/(tau_a·w) > 1`` (no oscillation).
    """
    tr, ta, b, w, s = params.tau_r, params.tau_a, params.b, params.w, params.s
    K = (tr + ta) / (ta * w)
    with np.errstate(invalid="ignore"):
        return s / (2.0 * K - 1.0 + (2.0 / np.pi) * (w + b) * np.arcsin(K))


def tau_r_for_frequency(frequency: float | np.ndarray, params: MatsuokaParams) -> np.ndarray:
    """Inverse design: the ``tau_r`` [s] whose closed-form frequency is ``frequency`` [Hz],
    with ``tau_a, b, w`` taken from ``params`` (its ``tau_r`` is ignored).

    Solving ω² T_a² T_r w = (T_r + T_a) b − T_r w for T_r gives
    ``T_r = T_a·b / (w·(1 + (ω T_a)²) − b)``.

    Raises:
        OscillatorError: ``frequency <= 0``, or no ``tau_r > 0`` gives that frequency, or the
            resulting ``tau_r`` violates the oscillation condition ``w > 1 + tau_r/tau_a``
            (the message names the first such oscillator and the reachable range).
    """
    f = np.asarray(frequency, dtype=float)
    if not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise OscillatorError(f"frequency must be finite and > 0 Hz, got {frequency!r}")
    ta, b, w = params.tau_a, params.b, params.w
    om = 2.0 * np.pi * f
    den = w * (1.0 + (om * ta) ** 2) - b
    with np.errstate(divide="ignore", invalid="ignore"):
        tr = np.where(den > 0, ta * b / den, np.nan)
        ok = (den > 0) & (w > 1.0 + tr / ta)
    if not np.all(ok):
        shape = np.broadcast_shapes(f.shape, np.shape(ta), np.shape(b), np.shape(w))
        bad = np.broadcast_to(~ok, shape)
        i = tuple(int(v) for v in np.argwhere(bad)[0])
        ta_i, b_i, w_i = (float(np.broadcast_to(a, shape)[i]) for a in (ta, b, w))
        # frequency at the largest admissible tau_r (w = 1 + tau_r/tau_a) is the lowest reachable
        tr_max = (w_i - 1.0) * ta_i
        f_min = np.sqrt(((tr_max + ta_i) * b_i - tr_max * w_i) / (tr_max * w_i)) / ta_i / 2 / np.pi
        raise OscillatorError(
            f"oscillator {i}: no tau_r gives {float(np.broadcast_to(f, shape)[i]):g} Hz with "
            f"tau_a = {ta_i:g}, b = {b_i:g}, w = {w_i:g}; reachable frequencies are above "
            f"{f_min:.4g} Hz (raise tau_a to lower them)"
        )
    return tr
