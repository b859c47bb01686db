"""The self-adjusting adaptor: tune a Matsuoka network to entrain to and replay joint targets.

Given targets ``(T, n)`` on ``t`` (e.g. an adapted gait, radians), :func:`self_adjust`:

1. fits a periodic teaching signal (:func:`~gdimitate.oscillator.teaching.fit_teacher`: a
   common-fundamental Fourier series, so a 2-stride clip can be repeated smoothly);
2. per joint: time constants from Matsuoka's closed form for the teacher's frequency
   (``tau_r/tau_a`` = ``ratio``), ``s`` from the closed-form amplitude so that each
   oscillator's amplitude matches its joint's, and the input gain ``k`` as the smallest gain
   whose 1:1 Arnold tongue (:func:`~gdimitate.oscillator.tongue.arnold_tongue`) spans
   ``±lock_margin`` around the free frequency;
3. couples joints whose fundamentals are roughly in anti-phase (e.g. left/right legs) by
   inhibition ``W_ij = coupling_gain·s_i/(s_j·n_i)``, ``n_i`` the number of joint i's
   anti-phase partners (mutual inhibition can only favour anti-phase; other relations are
   held because all oscillators share one intrinsic frequency). Dividing by ``n_i`` bounds
   the inhibition a joint receives by ``coupling_gain`` whatever the network's size: a pair
   of legs is coupled as before, while a whole-body network (G1: 35 signals, up to 20
   anti-phase partners each) would otherwise inhibit some of its oscillators to a standstill;
4. measures the coupled network's free frequency while it is on the taught phase pattern,
   then drives it with the teacher while adapting its frequency
   (:func:`~gdimitate.oscillator.adaptive.adapt_frequency`), and lets it run free;
5. fits a linear read-out ``q_j = offset_j + gain_j · features`` by least squares on the
   middle third of the entrained window and evaluates it on the last third. Features per
   oscillator are ``(x_e, x_f, v_e, v_f, y_e, y_f)``; ``readout="network"`` (default) uses
   those of all oscillators, ``"own"`` only the joint's own, ``"output"`` only its ``y``
   (the paper's output gain/offset).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, NamedTuple

import numpy as np

from ..errors import OscillatorError
from ..safety import MAX_CYCLES, MAX_HARMONICS, check_count, check_positive, check_steps
from .adaptive import adapt_frequency
from .analysis import measured_frequency
from .bank import MatsuokaBank
from .closed_form import natural_amplitude
from .params import MatsuokaParams
from .teaching import FourierTeacher, check_targets, fit_teacher
from .tongue import arnold_tongue

__all__ = ["SelfAdjustResult", "self_adjust", "state_features"]

Readout = Literal["network", "own", "output"]

#: Largest |target| accepted: beyond it the squares in the read-out fit and the error measures
#: overflow float64 (whose largest square root is 1.3e154).
MAX_TARGET = 1e100


def state_features(states: np.ndarray, readout: Readout) -> np.ndarray:
    """Read-out features from states ``(4, T, n)`` → ``(T, n, m)`` (``m`` per joint).

    ``network``: ``m = 6n`` (all oscillators' x_e, x_f, v_e, v_f, y_e, y_f); ``own``: ``m = 6``;
    ``output``: ``m = 1`` (y = y_e − y_f).
    """
    xe, xf, ve, vf = states
    ye, yf = np.maximum(xe, 0.0), np.maximum(xf, 0.0)
    if readout == "output":
        return (ye - yf)[..., None]
    own = np.stack([xe, xf, ve, vf, ye, yf], axis=-1)  # (T, n, 6)
    if readout == "own":
        return own
    if readout == "network":
        T, n, _ = own.shape
        return np.broadcast_to(own.reshape(T, 1, 6 * n), (T, n, 6 * n))
    raise OscillatorError(f"readout must be 'network', 'own' or 'output', got {readout!r}")


def _x0_pattern(phase: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Initial state ``(4, n)`` putting joint j's extensor ahead when its fundamental leads."""
    x0 = np.zeros((4, phase.size))
    x0[0] = 0.1 * s * np.maximum(np.cos(phase), 0) + 1e-3 * s
    x0[1] = 0.1 * s * np.maximum(-np.cos(phase), 0)
    return x0


@dataclass(frozen=True)
class SelfAdjustResult:
    """A tuned network that replays the taught targets; see :func:`self_adjust`.

    Attributes:
        joint_names: ``n`` names.
        params: tuned :class:`MatsuokaParams`, shape ``(n,)``, time constants at the learned
            frequency.
        coupling: ``(n, n)`` inhibitory coupling.
        gain: ``(n, m)`` read-out gains; offset: ``(n,)`` read-out offsets [rad].
        readout: feature set (see :func:`state_features`).
        frequency: learned intrinsic frequency [Hz]; the network runs free at it.
        teacher: the periodic teaching signal (targets' Fourier series).
        input_offset, input_scale: ``(n,)``; the input is ``g = (teacher − offset)/scale``.
        x0: ``(4, n)`` state at the end of teaching (replay starts there).
        frequency_history: ``(C,)`` intrinsic frequency after each adaptation cycle [Hz].
        report: per joint ``{nrmse_entrained, nrmse_free, freq_error_after,
            frequency_after_hz, teacher_fit_nrmse}`` (errors as fractions; nRMSE = RMS error
            / the target's peak-to-peak).
    """

    joint_names: tuple[str, ...]
    params: MatsuokaParams
    coupling: np.ndarray
    gain: np.ndarray
    offset: np.ndarray
    readout: str
    frequency: float
    teacher: FourierTeacher
    input_offset: np.ndarray
    input_scale: np.ndarray
    x0: np.ndarray
    frequency_history: np.ndarray
    report: dict[str, dict[str, float]] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    def bank(self) -> MatsuokaBank:
        """The tuned network as a bank of shape ``(n,)``."""
        return MatsuokaBank(self.params, self.coupling, shape=(self.n,))

    def teaching_input(self, t: np.ndarray) -> np.ndarray:
        """The normalised teaching input ``g (T, n)`` on ``t`` [s]."""
        return (self.teacher(np.asarray(t, dtype=float)) - self.input_offset) / self.input_scale

    def read_out(self, states: np.ndarray) -> np.ndarray:
        """Joint trajectories ``(T, n)`` [rad] from states ``(4, T, n)``."""
        F = state_features(states, self.readout)  # type: ignore[arg-type]
        return np.einsum("tjm,jm->tj", F, self.gain) + self.offset

    def replay(
        self, t_out: np.ndarray, teach_until: float | None = None, *, dt: float = 1e-3
    ) -> np.ndarray:
        """Replay the taught motion on ``t_out (T_out,)`` [s] → ``(T_out, n)`` [rad].

        ``teach_until=None``: run free from the state reached at the end of teaching
        (``t_out[0]`` is that instant). ``teach_until=τ``: start from a small state at
        ``t_out[0]``, drive with the teacher for ``t < τ``, then run free (the phase is then
        tied to the teacher's clock ``t``). Integrated on a ``dt`` grid and interpolated.
        """
        t_out = np.asarray(t_out, dtype=float)
        if t_out.ndim != 1 or t_out.size < 2 or not np.all(np.isfinite(t_out)) \
                or np.any(np.diff(t_out) <= 0):
            raise OscillatorError("t_out must be 1-D, finite, strictly increasing, with >= 2 "
                                  "points")
        dt = check_positive("dt", dt, error=OscillatorError)
        steps = check_steps(np.ceil((t_out[-1] - t_out[0]) / dt), "replay")
        t = t_out[0] + dt * np.arange(steps + 1)
        bank = self.bank()
        if teach_until is None:
            tr = bank.simulate(t, None, self.x0)
        else:
            g = np.where((t < teach_until)[:, None], self.teaching_input(t), 0.0)
            x0 = _x0_pattern(self.teacher.fundamental_phase(), np.asarray(self.params.s))
            tr = bank.simulate(t, g, x0)
        states = tr.states()
        fine = np.stack(
            [[np.interp(t_out, t, states[a, :, j]) for j in range(self.n)] for a in range(4)]
        )  # (4, n, T_out)
        out = self.read_out(np.moveaxis(fine, -1, 1))
        if not np.all(np.isfinite(out)):
            raise OscillatorError("the replay is not finite (overflow): the network's scale "
                                  "is too large; rescale the targets (e.g. to radians)")
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (round-trips through :meth:`from_dict`)."""
        return {
            "kind": "gdimitate.oscillator.SelfAdjustResult",
            "joint_names": list(self.joint_names),
            "params": self.params.to_dict(),
            "coupling": self.coupling.tolist(),
            "gain": self.gain.tolist(),
            "offset": self.offset.tolist(),
            "readout": self.readout,
            "frequency": self.frequency,
            "teacher": self.teacher.to_dict(),
            "input_offset": self.input_offset.tolist(),
            "input_scale": self.input_scale.tolist(),
            "x0": self.x0.tolist(),
            "frequency_history": self.frequency_history.tolist(),
            "report": self.report,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SelfAdjustResult:
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(
                joint_names=tuple(d["joint_names"]),
                params=MatsuokaParams.from_dict(d["params"]),
                coupling=np.asarray(d["coupling"], dtype=float),
                gain=np.asarray(d["gain"], dtype=float),
                offset=np.asarray(d["offset"], dtype=float),
                readout=str(d["readout"]),
                frequency=float(d["frequency"]),
                teacher=FourierTeacher.from_dict(d["teacher"]),
                input_offset=np.asarray(d["input_offset"], dtype=float),
                input_scale=np.asarray(d["input_scale"], dtype=float),
                x0=np.asarray(d["x0"], dtype=float),
                frequency_history=np.asarray(d["frequency_history"], dtype=float),
                report={k: dict(v) for k, v in d["report"].items()},
            )
        except KeyError as e:
            raise OscillatorError(f"SelfAdjustResult.from_dict: missing key {e}") from None

    def to_json(self) -> str:
        """:meth:`to_dict` as a JSON string."""
        return json.dumps(self.to_dict())


def _choose_gain(unit1: MatsuokaParams, margin: float) -> float:
    """Smallest input gain (s = 1, unit-amplitude sine) locking at free·(1 ± margin)."""
    gains = np.geomspace(0.02, 2.0, 24)
    from .analysis import free_running_frequency

    f_free = float(np.ravel(free_running_frequency(unit1))[0])
    at = arnold_tongue(unit1, f_free * np.array([1 - margin, 1 + margin]), gains, periods=30)
    ok = np.flatnonzero(at.locked.all(axis=1))
    if ok.size == 0:
        raise OscillatorError(
            f"no input gain up to {gains[-1]} locks the oscillator over ±{margin:.0%}; "
            "lower lock_margin or pass input_gain"
        )
    return float(gains[ok[0]])


def _fit_readout(F: np.ndarray, ref: np.ndarray, ridge: float) -> tuple[np.ndarray, np.ndarray]:
    """Per joint ridge least squares ``ref[:, j] ≈ F[:, j] @ gain_j + offset_j``."""
    n, m = F.shape[1], F.shape[2]
    gain = np.empty((n, m))
    offset = np.empty(n)
    for j in range(n):
        A = np.column_stack([F[:, j], np.ones(F.shape[0])])
        scale = np.sqrt(np.mean(A**2, axis=0)) + 1e-300
        As = A / scale
        lhs = As.T @ As + ridge * A.shape[0] * np.eye(m + 1)
        c = np.linalg.solve(lhs, As.T @ ref[:, j]) / scale
        gain[j], offset[j] = c[:-1], c[-1]
    return gain, offset


def _check_options(*, harmonics, frequency, initial_frequency, ratio, b, w, input_gain,
                   lock_margin, coupling_gain, readout, teach_cycles, free_cycles, adapt_rate,
                   dt, ridge) -> None:
    """Validate :func:`self_adjust`'s options before any work (OscillatorError names the
    option; ResourceLimitError states a bound of :mod:`gdimitate.safety`)."""
    E = OscillatorError
    check_count("harmonics", harmonics, 1, MAX_HARMONICS, E)
    check_count("teach_cycles", teach_cycles, 9, MAX_CYCLES, E)
    check_count("free_cycles", free_cycles, 3, MAX_CYCLES, E)
    for name, v in (("frequency", frequency), ("initial_frequency", initial_frequency)):
        if v is not None:
            check_positive(name, v, error=E)
    ratio = check_positive("ratio (tau_r/tau_a)", ratio, error=E)
    b = check_positive("b", b, zero=True, error=E)
    w = check_positive("w", w, error=E)
    if not 1 + ratio < w < 1 + b:
        raise E(f"ratio = {ratio:g}, b = {b:g}, w = {w:g} cannot oscillate: Matsuoka's "
                f"condition needs 1 + ratio < w < 1 + b, i.e. {1 + ratio:g} < w < {1 + b:g}")
    if input_gain is not None:
        check_positive("input_gain", input_gain, zero=True, error=E)
    if not check_positive("lock_margin", lock_margin, error=E) < 1:
        raise E(f"lock_margin must be in (0, 1); got {lock_margin!r}")
    check_positive("coupling_gain", coupling_gain, zero=True, error=E)
    if readout not in ("network", "own", "output"):
        raise E(f"readout must be 'network', 'own' or 'output', got {readout!r}")
    if not check_positive("adapt_rate", adapt_rate, error=E) <= 1:
        raise E(f"adapt_rate must be in (0, 1]; got {adapt_rate!r}")
    check_positive("dt", dt, error=E)
    check_positive("ridge", ridge, zero=True, error=E)


def self_adjust(
    t: np.ndarray,
    targets: np.ndarray,
    *,
    joint_names: Sequence[str] | None = None,
    harmonics: int = 8,
    frequency: float | None = None,
    initial_frequency: float | None = None,
    ratio: float = 0.5,
    b: float = 2.5,
    w: float = 2.5,
    input_gain: float | None = None,
    lock_margin: float = 0.15,
    coupling_gain: float = 0.2,
    readout: Readout = "network",
    teach_cycles: int = 30,
    free_cycles: int = 12,
    adapt_rate: float = 0.5,
    dt: float = 1e-3,
    ridge: float = 1e-4,
) -> SelfAdjustResult:
    """Tune a Matsuoka network so that its entrained output follows ``targets`` (see module).

    Args:
        t: ``(T,)`` [s]; targets: ``(T, n)`` [rad] (any periodic-ish joint trajectories).
        joint_names: ``n`` names (default ``joint0..``).
        harmonics: Fourier harmonics of the teaching signal.
        frequency: teacher's fundamental [Hz] (default: estimated from the targets).
        initial_frequency: where frequency adaptation starts [Hz] (default: the teacher's).
        ratio, b, w: ``tau_r/tau_a``, adaptation and mutual-inhibition gains of every joint.
        input_gain: ``k`` relative to ``s`` (default: chosen from the Arnold tongue to lock
            over ``±lock_margin``).
        coupling_gain: total inhibition a joint receives from its anti-phase partners
            (relative to ``s``; shared equally among them).
        readout: ``"network"``, ``"own"`` or ``"output"`` (see :func:`state_features`).
        teach_cycles: adaptation cycles with input; free_cycles: cycles after it stops
            (frequency error is measured over cycles 2..free_cycles after the stop).
        adapt_rate: η of the frequency adaptation. dt: integration step [s].
        ridge: Tikhonov weight (relative to the feature scale) of the read-out fit.

    Returns:
        :class:`SelfAdjustResult` with ``.report`` per joint.

    Raises:
        OscillatorError: a bad option (NaN, zero or negative where it must be positive, a
            ratio/b/w without a limit cycle), targets that cannot be taught (constant,
            too short) or whose scale overflows the integration.
        ResourceLimitError: more than :data:`~gdimitate.safety.MAX_HARMONICS` harmonics or
            :data:`~gdimitate.safety.MAX_CYCLES` cycles, or a run of more than
            :data:`~gdimitate.safety.MAX_SIM_STEPS` steps (checked before integrating).
    """
    t, x = check_targets(t, targets)
    names = _joint_names(joint_names, x)
    _check_options(harmonics=harmonics, frequency=frequency, initial_frequency=initial_frequency,
                   ratio=ratio, b=b, w=w, input_gain=input_gain, lock_margin=lock_margin,
                   coupling_gain=coupling_gain, readout=readout, teach_cycles=teach_cycles,
                   free_cycles=free_cycles, adapt_rate=adapt_rate, dt=dt, ridge=ridge)
    teacher = fit_teacher(t, x, harmonics=harmonics, frequency=frequency)
    fT = teacher.frequency
    check_steps((22 + teach_cycles + free_cycles) / (min(fT, initial_frequency or fT) * dt),
                f"self_adjust at {fT:.3g} Hz with dt = {dt:g} s")
    net = _network(teacher, ratio=ratio, b=b, w=w, input_gain=input_gain,
                   lock_margin=lock_margin, coupling_gain=coupling_gain)
    run, f_unit = _entrain(net, teacher, initial_frequency=initial_frequency or fT,
                           teach_cycles=teach_cycles, free_cycles=free_cycles,
                           adapt_rate=adapt_rate, dt=dt)
    fit = _fit_aligned_readout(run, teacher, readout, ridge)
    if not (np.all(np.isfinite(fit.gain)) and np.all(np.isfinite(fit.offset))):
        raise OscillatorError("the read-out fit overflowed (targets' amplitude up to "
                              f"{np.max(net.amp):.3g}); rescale the targets (e.g. to radians)")
    n = len(names)
    result = SelfAdjustResult(
        joint_names=names, params=net.unit.time_scaled(f_unit / run.frequency),
        coupling=np.zeros((n, n)) if net.coupling is None else net.coupling,
        gain=fit.gain, offset=fit.offset, readout=readout, frequency=run.frequency,
        teacher=teacher, input_offset=net.mean, input_scale=net.amp, x0=run.final_teach_state,
        frequency_history=run.history_f,
    )
    return dataclasses.replace(result, report=_report(result, run, fit, net.unit, fT))


def _joint_names(joint_names: Sequence[str] | None, x: np.ndarray) -> tuple[str, ...]:
    """The ``n`` joint names of targets ``x`` ``(T, n)`` (default ``joint0..``); refuses a
    wrong count and targets whose scale overflows the fit (OscillatorError)."""
    n = x.shape[1]
    names = tuple(joint_names) if joint_names is not None else tuple(f"joint{j}" for j in range(n))
    if len(names) != n:
        raise OscillatorError(f"{len(names)} joint_names for {n} target columns")
    if np.max(np.abs(x)) > MAX_TARGET:
        raise OscillatorError(f"targets reach {np.max(np.abs(x)):.3g}; beyond {MAX_TARGET:g} "
                              "the fit's float64 arithmetic overflows: rescale them (radians)")
    return names


class _Network(NamedTuple):
    """The network before frequency adaptation (:func:`_network`)."""

    unit: MatsuokaParams  # per joint: time constants for the teacher's frequency, s, k
    s: np.ndarray  # (n,) tonic input: each oscillator's amplitude matches its joint's
    coupling: np.ndarray | None  # (n, n) inhibition between anti-phase joints, None if none
    mean: np.ndarray  # (n,) the teacher's mean over one period [rad]
    amp: np.ndarray  # (n,) the teacher's half peak-to-peak over one period [rad]
    phase: np.ndarray  # (n,) the teacher's fundamental phases [rad]


def _network(teacher: FourierTeacher, *, ratio: float, b: float, w: float,
             input_gain: float | None, lock_margin: float, coupling_gain: float) -> _Network:
    """Steps 2–3 of the module docstring: per joint closed-form time constants for the
    teacher's frequency and ``s`` for its amplitude, the input gain (Arnold tongue unless
    given), and inhibition between anti-phase joints."""
    fT = teacher.frequency
    one = teacher(np.linspace(0, 1 / fT, 2000, endpoint=False))
    mean = one.mean(axis=0)
    amp = np.ptp(one, axis=0) / 2
    if not (np.all(np.isfinite(one)) and np.all(np.isfinite(amp))):
        raise OscillatorError("the targets' scale overflows the teaching signal; rescale them")
    # per joint: closed-form time constants for fT, s for the amplitude
    tau_a = np.sqrt(((ratio + 1) * b - ratio * w) / (ratio * w)) / (2 * np.pi * fT)
    unit1 = MatsuokaParams(tau_r=ratio * tau_a, tau_a=tau_a, b=b, w=w, s=1.0)
    s = amp / float(natural_amplitude(unit1))
    k_rel = _choose_gain(unit1, lock_margin) if input_gain is None else float(input_gain)
    unit = MatsuokaParams(tau_r=ratio * tau_a, tau_a=tau_a, b=b, w=w, s=s, k=k_rel * s)
    phase = teacher.fundamental_phase()
    anti = np.cos(phase[:, None] - phase[None, :]) < -0.5
    partners = np.maximum(anti.sum(axis=1), 1)[:, None]
    W = np.where(anti, coupling_gain * s[:, None] / (s[None, :] * partners), 0.0)
    return _Network(unit, s, W if W.any() else None, mean, amp, phase)


def _entrain(net: _Network, teacher: FourierTeacher, *, initial_frequency: float,
             teach_cycles: int, free_cycles: int, adapt_rate: float, dt: float):
    """Step 4: the coupled network's free frequency on the taught phase pattern (at time
    scale 1, per joint: groups not coupled to each other may run at different frequencies),
    then the teacher driving it while its frequency adapts, then a free run. Returns
    ``(run, f_unit)``: the :func:`adapt_frequency` run and the free frequencies [Hz]."""
    fT = teacher.frequency

    def g_of(tt: np.ndarray) -> np.ndarray:
        return (teacher(tt) - net.mean) / net.amp

    x0 = _x0_pattern(net.phase, net.s)
    cal = adapt_frequency(net.unit, net.coupling, fT, g_of, initial_frequency=fT,
                          teach_cycles=6, free_cycles=16, dt=dt, rate=1e-9, x0=x0)
    f_unit = measured_frequency(cal.t, cal.y, start=cal.teach_until + 4 / fT)
    if not np.all(np.isfinite(f_unit)):
        raise OscillatorError(f"the network did not oscillate freely (frequencies {f_unit})")
    run = adapt_frequency(net.unit, net.coupling, f_unit, g_of,
                          initial_frequency=initial_frequency, teach_cycles=teach_cycles,
                          free_cycles=free_cycles, dt=dt, rate=adapt_rate, x0=x0)
    if not np.all(np.isfinite(run.states)):
        raise OscillatorError("the network's states overflowed (s = "
                              f"{np.max(net.s):.3g}); rescale the targets (e.g. to radians)")
    return run, f_unit


class _Readout(NamedTuple):
    """The read-out fitted on an adaptation run (:func:`_fit_aligned_readout`)."""

    gain: np.ndarray  # (n, m)
    offset: np.ndarray  # (n,)
    shift: float  # [s] the free run's common time shift onto the teacher
    ref: np.ndarray  # (T, n) the teacher on the run's time axis
    ref_free: np.ndarray  # (T, n) the teacher shifted by ``shift``
    ptp: np.ndarray  # (n,) the teacher's peak-to-peak in the fit window
    entrained: np.ndarray  # (T,) bool: the evaluation window while entrained (last third)
    free: np.ndarray  # (T,) bool: the free evaluation window (after free cycle 6)


def _fit_aligned_readout(run, teacher: FourierTeacher, readout: Readout,
                         ridge: float) -> _Readout:
    """Step 5: fit on the middle third of teaching; align the free run to the teacher by one
    common time shift; refit on both (entrained middle third + free cycles 2..6)."""
    tt = run.t
    T_end = run.teach_until
    P = 1.0 / teacher.frequency
    fit_w = (tt >= T_end / 3) & (tt < 2 * T_end / 3)
    ev_w = (tt >= 2 * T_end / 3) & (tt <= T_end)
    free_fit = (tt > T_end + 2 * P) & (tt <= T_end + 6 * P)
    free_ev = tt > T_end + 6 * P
    F = state_features(run.states, readout)
    ref = teacher(tt)
    ptp = np.ptp(ref[fit_w], axis=0)
    gain, offset = _fit_readout(F[fit_w], ref[fit_w], ridge)
    q0 = np.einsum("tjm,jm->tj", F[free_fit], gain) + offset
    shifts = np.linspace(0.0, P, 200, endpoint=False)
    cost = [np.mean(((q0 - teacher(tt[free_fit] + d)) / ptp) ** 2) for d in shifts]
    shift = float(shifts[int(np.argmin(cost))])
    ref_free = teacher(tt + shift)
    both = fit_w | free_fit
    target = np.where(free_fit[:, None], ref_free, ref)
    gain, offset = _fit_readout(F[both], target[both], ridge)
    return _Readout(gain, offset, shift, ref, ref_free, ptp, ev_w, free_ev)


def _report(result: SelfAdjustResult, run, fit: _Readout, unit: MatsuokaParams,
            fT: float) -> dict[str, dict[str, float]]:
    """Per joint: tracking nRMSE entrained and free, the frequency after the input stops,
    the teacher's fit; OscillatorError where any of it is not finite."""
    q = result.read_out(run.states)
    f_after = measured_frequency(run.t, run.y, start=run.teach_until + 2 / run.frequency)
    ev_w, free_ev, ref, ref_free, ptp = fit.entrained, fit.free, fit.ref, fit.ref_free, fit.ptp
    report = {}
    for j, name in enumerate(result.joint_names):
        report[name] = {
            "nrmse_entrained": float(np.sqrt(np.mean((q[ev_w, j] - ref[ev_w, j]) ** 2)) / ptp[j]),
            "nrmse_free": float(
                np.sqrt(np.mean((q[free_ev, j] - ref_free[free_ev, j]) ** 2)) / ptp[j]
            ),
            "shift_after_s": fit.shift,
            "freq_error_after": float(abs(f_after[j] / fT - 1)),
            "frequency_after_hz": float(f_after[j]),
            "teacher_frequency_hz": float(fT),
            "teacher_fit_nrmse": float(result.teacher.fit_nrmse[j]),
            "input_gain_k": float(unit.k[j]) if np.ndim(unit.k) else float(unit.k),
        }
    bad = [f"{j}.{k}" for j, r in report.items() for k, v in r.items() if not np.isfinite(v)]
    if bad:
        raise OscillatorError(f"the tuned network's output is not finite ({bad[:4]}); the "
                              "targets cannot be replayed as given")
    return report
