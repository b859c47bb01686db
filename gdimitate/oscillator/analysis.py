"""Measurements on oscillator traces: frequency, spectrum, phase plane, entrainment.

Signals are arrays ``(T, *cols)`` with time first on a grid ``t (T,)`` [s]; every measure is
taken per column and returns an array of shape ``cols`` (frequencies in Hz, phases in rad).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
from scipy.signal import hilbert

from ..errors import OscillatorError
from .closed_form import natural_frequency
from .params import MatsuokaParams

__all__ = [
    "Spectrum",
    "PhasePlane",
    "Entrainment",
    "crossing_times",
    "measured_frequency",
    "spectrum",
    "phase_plane",
    "relative_phase",
    "phase_locking_value",
    "frequency_ratio",
    "time_to_lock",
    "entrainment",
    "free_running_frequency",
]


class Spectrum(NamedTuple):
    """One-sided amplitude spectrum: ``freq (F,)`` [Hz], ``amplitude (F, *cols)``."""

    freq: np.ndarray
    amplitude: np.ndarray


class PhasePlane(NamedTuple):
    """Two coordinates of a trajectory, each ``(T, *cols)``, with their labels."""

    x: np.ndarray
    v: np.ndarray
    labels: tuple[str, str]


@dataclass(frozen=True)
class Entrainment:
    """Entrainment of an output ``y`` by an input ``g`` (arrays of shape ``cols``).

    Attributes:
        ratio: measured frequency of y / measured frequency of g (1 = 1:1 locking).
        plv: phase-locking value in [0, 1] of the Hilbert phases.
        phase: mean phase of y's upward zero crossings after g's [rad, (−π, π]].
        locked: ``|ratio − 1| < ratio_tol`` and ``plv > plv_min``.
        time_to_lock: time [s] after which the crossing phase stays within ``phase_tol`` of
            its final value (NaN when not locked).
    """

    ratio: np.ndarray
    plv: np.ndarray
    phase: np.ndarray
    locked: np.ndarray
    time_to_lock: np.ndarray


def _prep(t, y, start):
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or y.shape[:1] != t.shape:
        raise OscillatorError(f"signal of shape {y.shape} does not match t of shape {t.shape}")
    if start is not None:
        keep = t >= start
        t, y = t[keep], y[keep]
    if t.shape[0] < 3:
        raise OscillatorError("need at least 3 samples after `start`")
    return t, y


def crossing_times(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Upward zero-crossing times [s] of a 1-D signal ``y (T,)``, linearly interpolated."""
    t, y = _prep(t, y, None)
    i = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    return t[i] + (t[i + 1] - t[i]) * (-y[i]) / (y[i + 1] - y[i])


def measured_frequency(
    t: np.ndarray,
    y: np.ndarray,
    *,
    method: Literal["zero_crossing", "fft"] = "zero_crossing",
    start: float | None = None,
) -> np.ndarray:
    """Frequency [Hz] of each column of ``y (T, *cols)``; the mean is removed first.

    ``zero_crossing``: (number of upward crossings − 1) / (time between first and last),
    crossings linearly interpolated (NaN with fewer than 2 crossings). ``fft``: peak of the
    Hann-windowed spectrum refined by a parabola through the log-magnitudes (uniform ``t``).
    ``start`` [s] drops the transient before it.
    """
    t, y = _prep(t, y, start)
    y = y - y.mean(axis=0)
    if method == "fft":
        sp = spectrum(t, y)
        a = np.log(sp.amplitude[1:] + 1e-300)  # skip DC
        k = np.argmax(a, axis=0)
        k = np.clip(k, 1, a.shape[0] - 2)
        am, a0, ap = (np.take_along_axis(a, (k + d)[None], 0)[0] for d in (-1, 0, 1))
        den = am - 2 * a0 + ap
        delta = np.where(den != 0, 0.5 * (am - ap) / np.where(den != 0, den, 1), 0.0)
        df = sp.freq[1] - sp.freq[0]
        return sp.freq[1:][k] + delta * df
    if method != "zero_crossing":
        raise OscillatorError(f"method must be 'zero_crossing' or 'fft', got {method!r}")
    up = (y[:-1] < 0) & (y[1:] >= 0)
    tt = t[:-1].reshape(-1, *([1] * (y.ndim - 1)))
    dt = np.diff(t).reshape(tt.shape)
    with np.errstate(invalid="ignore", divide="ignore"):
        tc = np.where(up, tt + dt * (-y[:-1]) / (y[1:] - y[:-1]), np.nan)
        count = up.sum(axis=0)
        span = np.nanmax(np.where(up, tc, -np.inf), axis=0) - np.nanmin(
            np.where(up, tc, np.inf), axis=0
        )
        return np.where(count >= 2, (count - 1) / span, np.nan)


def spectrum(t: np.ndarray, y: np.ndarray) -> Spectrum:
    """Hann-windowed one-sided amplitude spectrum of ``y (T, *cols)`` on a uniform grid."""
    t, y = _prep(t, y, None)
    dt = np.diff(t)
    if np.ptp(dt) > 1e-6 * dt.mean():
        raise OscillatorError("spectrum needs a uniform time grid")
    win = np.hanning(t.shape[0]).reshape(-1, *([1] * (y.ndim - 1)))
    Y = np.fft.rfft((y - y.mean(axis=0)) * win, axis=0)
    amp = 2.0 * np.abs(Y) / win.sum()
    return Spectrum(np.fft.rfftfreq(t.shape[0], dt.mean()), amp)


def phase_plane(trace, kind: Literal["output", "neurons", "adaptation"] = "output") -> PhasePlane:
    """Phase-plane coordinates of a :class:`~gdimitate.oscillator.bank.Trace`.

    ``output``: (y, dy/dt); ``neurons``: (x_e, x_f); ``adaptation``: (x_e − x_f, v_e − v_f).
    """
    if kind == "output":
        return PhasePlane(trace.y, np.gradient(trace.y, trace.t, axis=0), ("y", "dy/dt [1/s]"))
    if kind == "neurons":
        return PhasePlane(trace._need("x_e"), trace._need("x_f"), ("x_e", "x_f"))
    if kind == "adaptation":
        return PhasePlane(
            trace._need("x_e") - trace._need("x_f"),
            trace._need("v_e") - trace._need("v_f"),
            ("x_e − x_f", "v_e − v_f"),
        )
    raise OscillatorError(f"kind must be 'output', 'neurons' or 'adaptation', got {kind!r}")


def relative_phase(t: np.ndarray, y: np.ndarray, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Phase of ``y`` after ``g`` from upward zero crossings (1-D signals ``(T,)``).

    For each cycle ``[t_g,k, t_g,k+1)`` of g holding exactly one upward crossing ``t_y`` of y,
    phase = 2π (t_y − t_g,k) / (t_g,k+1 − t_g,k), wrapped to (−π, π]; NaN otherwise.
    Returns ``(t_g,k (K,), phase (K,))``. Means are removed first.
    """
    t, y = _prep(t, y, None)
    _, g = _prep(t, g, None)
    ty = crossing_times(t, y - y.mean())
    tg = crossing_times(t, g - g.mean())
    if tg.size < 2:
        return tg[:0], tg[:0]
    lo, hi = tg[:-1], tg[1:]
    first = np.searchsorted(ty, lo)
    last = np.searchsorted(ty, hi)
    ok = (last - first) == 1
    tyk = ty[np.minimum(first, max(ty.size - 1, 0))] if ty.size else np.full(lo.shape, np.nan)
    ph = 2 * np.pi * (tyk - lo) / (hi - lo)
    ph = np.where(ok, np.angle(np.exp(1j * ph)), np.nan)
    return lo, ph


def phase_locking_value(
    t: np.ndarray,
    y: np.ndarray,
    g: np.ndarray,
    *,
    start: float | None = None,
    method: Literal["crossing", "hilbert"] = "crossing",
) -> np.ndarray:
    """Phase-locking value in [0, 1] of ``y (T, *cols)`` to ``g`` (broadcastable), per column.

    ``crossing`` (default): |mean exp(iφ_k)| of the stroboscopic crossing phases of
    :func:`relative_phase` (cycles without exactly one crossing count as 0) — exactly 1 for a
    locked periodic response whatever its waveform. ``hilbert``: |mean exp(i(φ_y − φ_g))| of
    the analytic-signal phases (below 1 even when locked if the waveforms differ).
    """
    y = np.asarray(y, dtype=float)
    g = np.broadcast_to(np.asarray(g, dtype=float), y.shape)
    _, g = _prep(t, g, start)
    t, y = _prep(t, y, start)
    if method == "hilbert":
        py = np.angle(hilbert(y - y.mean(axis=0), axis=0))
        pg = np.angle(hilbert(g - g.mean(axis=0), axis=0))
        return np.abs(np.mean(np.exp(1j * (py - pg)), axis=0))
    if method != "crossing":
        raise OscillatorError(f"method must be 'crossing' or 'hilbert', got {method!r}")
    out = np.zeros(y.shape[1:])
    for idx in np.ndindex(*y.shape[1:]):
        col = (slice(None), *idx)
        _, ph = relative_phase(t, y[col], g[col])
        if ph.size:
            out[idx] = np.abs(np.nansum(np.exp(1j * ph)) / ph.size)
    return out


def frequency_ratio(
    t: np.ndarray, y: np.ndarray, g: np.ndarray, *, start: float | None = None
) -> np.ndarray:
    """Measured frequency of ``y`` over that of ``g`` (zero crossings), per column."""
    g = np.broadcast_to(g, np.shape(y))
    return measured_frequency(t, y, start=start) / measured_frequency(t, g, start=start)


def time_to_lock(
    t: np.ndarray, y: np.ndarray, g: np.ndarray, *, phase_tol: float = 0.1
) -> float:
    """Time [s] from which the crossing phase (:func:`relative_phase`) stays within
    ``phase_tol`` [rad] of its final value; NaN when the last cycles are not locked."""
    tk, ph = relative_phase(t, y, g)
    if ph.size < 3 or not np.isfinite(ph[-1]):
        return float("nan")
    dev = np.abs(np.angle(np.exp(1j * (ph - ph[-1]))))
    bad = ~(dev <= phase_tol)
    if bad[-3:].any():
        return float("nan")
    k = np.flatnonzero(bad)
    return float(tk[k[-1] + 1] - t[0]) if k.size else float(tk[0] - t[0])


def entrainment(
    t: np.ndarray,
    y: np.ndarray,
    g: np.ndarray,
    *,
    start: float | None = None,
    ratio_tol: float = 0.01,
    plv_min: float = 0.9,
    phase_tol: float = 0.1,
) -> Entrainment:
    """All entrainment measures of ``y (T, *cols)`` by ``g`` (broadcastable), see
    :class:`Entrainment`; ``start`` [s] drops the transient for ratio, PLV and phase."""
    y = np.asarray(y, dtype=float)
    g = np.broadcast_to(np.asarray(g, dtype=float), y.shape)
    ratio = frequency_ratio(t, y, g, start=start)
    plv = phase_locking_value(t, y, g, start=start)
    cols = y.shape[1:]
    phase = np.full(cols, np.nan)
    ttl = np.full(cols, np.nan)
    keep = np.asarray(t) >= (start if start is not None else -np.inf)
    for idx in np.ndindex(*cols):
        col = (slice(None), *idx)
        _, ph = relative_phase(np.asarray(t)[keep], y[col][keep], g[col][keep])
        if ph.size and np.isfinite(ph).any():
            phase[idx] = np.angle(np.nanmean(np.exp(1j * ph)))
        ttl[idx] = time_to_lock(t, y[col], g[col], phase_tol=phase_tol)
    locked = (np.abs(ratio - 1) < ratio_tol) & (plv > plv_min)
    return Entrainment(ratio, plv, phase, locked, ttl)


def free_running_frequency(
    params: MatsuokaParams,
    coupling: np.ndarray | None = None,
    *,
    periods: float = 40.0,
    dt: float | None = None,
    shape: tuple[int, ...] | None = None,
) -> np.ndarray:
    """Frequency [Hz] of the free bank measured by simulation (zero crossings of ``y``).

    Simulates ``periods`` closed-form periods (the first third discarded) with
    ``dt = min(tau_r)/50`` unless given. Returns an array of the bank shape.
    """
    from .bank import MatsuokaBank  # local: bank imports nothing from here

    bank = MatsuokaBank(params, coupling, shape=shape)
    p = bank.params
    f0 = natural_frequency(p)
    f_lo = float(np.nanmin(np.where(np.isfinite(f0), f0, np.nan))) if np.isfinite(f0).any() else 1.0
    dt = float(np.min(p.tau_r)) / 50.0 if dt is None else float(dt)
    duration = periods / f_lo
    t = np.arange(0.0, duration + dt / 2, dt)
    tr = bank.simulate(t, record="y")
    return measured_frequency(t, tr.y, start=duration / 3)
