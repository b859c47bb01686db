"""Frequency adaptation of a Matsuoka network (in the spirit of adaptive-frequency oscillators).

An adaptive-frequency oscillator (Righetti, Buchli & Ijspeert 2006) carries its intrinsic
frequency ω as a state that moves towards the frequency it is being driven at and keeps it
when the drive stops. A Matsuoka network has no frequency parameter, but its period scales
*exactly* with its time constants: at time scale λ (``tau_r, tau_a`` multiplied by λ) a network
whose free frequency is ``f_unit`` at λ = 1 runs at ``f_unit/λ``. We therefore carry ω, set
``λ = f_unit/ω``, and after each cycle of the driven network move ω towards the frequency it
actually ran at (the mean of the last crossing intervals of its outputs)::

    ω ← ω + η·(1/P_observed − ω)

While the network is 1:1 locked to the teacher, P_observed is the teacher's period, so ω
converges geometrically (rate 1 − η) to the teacher's frequency; when the input stops, λ stays
and the network keeps that frequency. This is a cycle-by-cycle (discrete) adaptation rule, not
Righetti's continuous Hebbian one: it needs the drive to lock (the input gain is chosen from an
Arnold tongue for that), and in exchange it has no bias from an approximate phase-response
estimate.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import OscillatorError
from .analysis import crossing_times
from .bank import MatsuokaBank
from .params import MatsuokaParams

__all__ = ["AdaptiveRun", "adapt_frequency"]


@dataclass(frozen=True)
class AdaptiveRun:
    """Result of :func:`adapt_frequency`.

    Attributes:
        t: time grid ``(T,)`` [s].
        states: ``(4, T, n)`` states (x_e, x_f, v_e, v_f).
        y: ``(T, n)`` outputs.
        frequency: learned intrinsic frequency [Hz] at the end of teaching.
        history_t, history_f: ``(C,)`` times [s] and intrinsic frequency [Hz] per update.
        teach_until: time [s] at which the input stopped.
        final_teach_state: ``(4, n)`` state at ``teach_until``.
    """

    t: np.ndarray
    states: np.ndarray
    y: np.ndarray
    frequency: float
    history_t: np.ndarray
    history_f: np.ndarray
    teach_until: float
    final_teach_state: np.ndarray


def adapt_frequency(
    unit: MatsuokaParams,
    coupling: np.ndarray | None,
    unit_frequency: float | np.ndarray,
    teacher: Callable[[np.ndarray], np.ndarray],
    *,
    initial_frequency: float,
    teach_cycles: int,
    free_cycles: int,
    dt: float = 1e-3,
    rate: float = 0.5,
    x0: np.ndarray | None = None,
) -> AdaptiveRun:
    """Drive an ``n``-oscillator network by ``teacher`` while adapting its time scale, then
    let it run free.

    Args:
        unit: network parameters ``(n,)`` at time scale 1.
        coupling: ``(n, n)`` coupling (or None).
        unit_frequency: free frequency [Hz] of the network at time scale 1 (measured), scalar
            or per oscillator ``(n,)`` (uncoupled groups of a network can differ).
        teacher: ``g(t (T,)) -> (T, n)`` input (already scaled for the input gain ``k``).
        initial_frequency: starting intrinsic frequency ω [Hz].
        teach_cycles: number of adaptation cycles (segments of one intrinsic period).
        free_cycles: cycles (at the learned frequency) to run after the input stops.
        dt: integration step [s].
        rate: η in (0, 1].
        x0: initial state ``(4, n)``; default the bank's.
    """
    if not 0 < rate <= 1:
        raise OscillatorError(f"adaptation rate must be in (0, 1], got {rate}")
    unit_frequency = np.asarray(unit_frequency, dtype=float)
    if initial_frequency <= 0 or np.any(unit_frequency <= 0):
        raise OscillatorError("frequencies must be > 0 Hz")
    n = unit.shape[-1] if unit.shape else 1
    omega = float(initial_frequency)
    x = x0
    ts: list[np.ndarray] = []
    st: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    hist_t, hist_f = [], []
    t0 = 0.0
    t_all = np.empty(0)
    y_all = np.empty((0, n))
    for _ in range(int(teach_cycles)):
        steps = max(int(round(1.0 / (omega * dt))), 2)
        t = t0 + dt * np.arange(steps + 1)
        bank = MatsuokaBank(unit.time_scaled(unit_frequency / omega), coupling, shape=(n,))
        tr = bank.simulate(t, teacher(t), x)
        x = tr.final
        keep = slice(None) if not ts else slice(1, None)
        ts.append(t[keep])
        st.append(tr.states()[:, keep])
        ys.append(tr.y[keep])
        t_all = np.concatenate([t_all, t[keep]])
        y_all = np.concatenate([y_all, tr.y[keep]])
        t0 = t[-1]
        periods = _last_periods(t_all, y_all)
        if periods is not None:
            omega += rate * (1.0 / float(np.mean(periods)) - omega)
        hist_t.append(t0)
        hist_f.append(omega)
    teach_until = t0
    if x is None:  # no teaching cycle ran and no start state was given
        raise OscillatorError("adapt_frequency needs teach_cycles >= 1 or x0")
    final_teach = x.copy()
    if free_cycles > 0:
        for out, part in zip((ts, st, ys), _free_run(unit, coupling, unit_frequency, omega, x,
                                                     t0, free_cycles, dt), strict=True):
            out.append(part)
    return AdaptiveRun(
        t=np.concatenate(ts),
        states=np.concatenate(st, axis=1),
        y=np.concatenate(ys),
        frequency=omega,
        history_t=np.asarray(hist_t),
        history_f=np.asarray(hist_f),
        teach_until=teach_until,
        final_teach_state=final_teach,
    )


def _free_run(unit: MatsuokaParams, coupling: np.ndarray | None,
              unit_frequency: np.ndarray, omega: float, x: np.ndarray, t0: float,
              free_cycles: int, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``free_cycles`` cycles at intrinsic frequency ``omega`` [Hz] without input from state
    ``x`` ``(4, n)`` at ``t0`` [s]: ``(t (S,), states (4, S, n), y (S, n))``, the start left
    out."""
    n = unit.shape[-1] if unit.shape else 1
    bank = MatsuokaBank(unit.time_scaled(unit_frequency / omega), coupling, shape=(n,))
    t = t0 + dt * np.arange(int(round(free_cycles / (omega * dt))) + 1)
    tr = bank.simulate(t, None, x)
    return t[1:], tr.states()[:, 1:], tr.y[1:]


def _last_periods(t: np.ndarray, y: np.ndarray) -> list[float] | None:
    """Per column of ``y`` ``(T, n)`` on ``t`` ``(T,)`` [s], the last period [s] (between its
    last two upward zero crossings); None until every column has two crossings."""
    periods = []
    for j in range(y.shape[1]):
        c = crossing_times(t, y[:, j])
        if c.size >= 2:
            periods.append(c[-1] - c[-2])
    return periods if len(periods) == y.shape[1] else None
