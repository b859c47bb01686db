"""From an adapted motion to a central pattern generator and back: entrain and replay.

:func:`entrain` teaches one Matsuoka network (:func:`gdimitate.oscillator.self_adjust`, one
shared frequency) the whole body of a robot's motion — every actuated 1-DoF joint, and the
floating base as periodic signals (its position with the mean walking velocity removed, its
orientation as a rotation vector about the first frame's) — and lets it run free after the
teaching input stops. The replay is a new :class:`~gdimitate.model.motion.Motion` of the same robot
in the same joint order: the base advances at the taught mean velocity plus the network's
periodic part; stance is read from the replayed feet (the lower sole is in stance).

The frequency taught is the stride's: 1 / the mean interval between successive touchdowns of
the same foot in the motion's contact schedule (:func:`stride_frequency`) — so a
demonstration and its adaptation (which keeps the schedule) give the same answer; without
two touchdowns of a foot, the teaching signal's own estimate. A poor teacher fit (nRMSE above
:data:`TEACHER_FIT_WARN`) is an :class:`~gdimitate.oscillator.OscillatorWarning` naming the
signal. The free-running replay is checked against the target (:class:`ReplayCheck`: every
signal's cycle rate and amplitude over :data:`CHECK_STRIDES` strides).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InvalidInputError, ResourceLimitError
from ..model.kinematics import kinematic_contact, robot_motion
from ..model.motion import Motion
from ..model.robot import PLANAR_BASE, Robot
from ..safety import (
    MAX_MOTION_DURATION_S,
    MAX_OUTPUT_SAMPLES,
    check_positive,
    check_time_axis,
)
from . import OscillatorWarning, SelfAdjustResult, self_adjust

__all__ = ["CPGReplay", "ReplayCheck", "entrain", "BodySignals", "body_signals",
           "stride_frequency"]

#: A teaching signal whose Fourier fit leaves an nRMSE above this on some signal is a poor
#: one (the clip is not periodic at the stride frequency): warned, with the number.
TEACHER_FIT_WARN = 0.10
#: A signal whose range over the clip is below this [rad or m] is held still (an unmapped
#: joint the adaptor keeps near its rest pose): its teacher fit is not warned about …
HELD_RANGE = 0.02
#: … nor that of a joint whose range is below this share of the largest joint's (G1's
#: unmapped arm joints wander within their ±0.1 rad band, 0.2 rad, against the legs' ~1 rad):
#: a small, non-rhythmic signal the replay carries as well as it can (the replay check still
#: measures it), not the rhythm the user teaches.
HELD_SHARE = 0.25
#: The replay check: every signal's cycle rate within this fraction of the target's …
REPLAY_FREQUENCY_TOL = 0.05
#: … and its amplitude (half the peak-to-peak) within this fraction of the target's.
REPLAY_AMPLITUDE_TOL = 0.25
#: Strides of free running the replay check measures.
CHECK_STRIDES = 4


def stride_frequency(motion: Motion) -> float | None:
    """The stride frequency [Hz] of ``motion``: 1 / the mean interval between successive
    touchdowns (stance starts) of the same foot in ``motion.contact``, over both feet. A clip
    in which no foot touches down twice but that is one closed cycle — every foot's contact
    at the last frame what it was at the first, with one stance and one swing in between
    (exactly two changes), as a clip from a heel strike to the same foot's next heel strike
    is — is one stride: 1 / its duration. None otherwise."""
    gaps: list[float] = []
    closed = bool(motion.contact)
    for c in motion.contact.values():
        c = np.asarray(c, bool)
        down = np.flatnonzero(~c[:-1] & c[1:]) + 1
        gaps += list(np.diff(motion.t[down]))
        closed &= bool(c[0] == c[-1]) and int(np.sum(c[1:] != c[:-1])) == 2
    if gaps:
        return 1.0 / float(np.mean(gaps))
    span = float(motion.t[-1] - motion.t[0])
    return 1.0 / span if closed and span > 0 else None


@dataclass(frozen=True)
class ReplayCheck:
    """The free-running replay against its target, over :data:`CHECK_STRIDES` strides from
    the end of teaching.

    ``target_frequency_hz``: the stride frequency taught; ``learned_frequency_hz``: the
    network's; per signal (``signals``): ``frequency_error`` — |its oscillator's frequency
    while running free (zero crossings of its output) / the target − 1| — and
    ``amplitude_ratio`` — the replay's peak-to-peak / the teaching signal's (the periodic
    signal taught; how well that fits the motion is the teacher fit, warned about
    separately); ``worst_frequency``/``worst_amplitude``: the signal furthest off;
    ``passed``: every frequency error ≤ :data:`REPLAY_FREQUENCY_TOL` and every ratio within
    1 ± :data:`REPLAY_AMPLITUDE_TOL`."""

    target_frequency_hz: float
    learned_frequency_hz: float
    signals: dict[str, dict[str, float]]

    @property
    def worst_frequency(self) -> tuple[str, float]:
        """``(signal, frequency error)`` of the signal furthest off (NaN counts as worst)."""
        return max(((n, v["frequency_error"]) for n, v in self.signals.items()),
                   key=lambda kv: np.inf if not np.isfinite(kv[1]) else kv[1])

    @property
    def worst_amplitude(self) -> tuple[str, float]:
        """``(signal, amplitude ratio)`` of the signal furthest from 1."""
        return max(((n, v["amplitude_ratio"]) for n, v in self.signals.items()),
                   key=lambda kv: abs(np.log(max(kv[1], 1e-12))))

    @property
    def passed(self) -> bool:
        """Every signal within both tolerances."""
        f = self.worst_frequency[1]
        a = self.worst_amplitude[1]
        return bool(np.isfinite(f) and f <= REPLAY_FREQUENCY_TOL
                    and abs(a - 1) <= REPLAY_AMPLITUDE_TOL)

    def line(self) -> str:
        """One console line."""
        (fn, fe), (an, ar) = self.worst_frequency, self.worst_amplitude
        return (f"replay check ({CHECK_STRIDES} strides free-running): learned "
                f"{self.learned_frequency_hz:.3f} Hz for a {self.target_frequency_hz:.3f} Hz "
                f"stride; free-running frequency off by at most {100 * fe:.1f} % ({fn}); "
                f"amplitude ratio "
                f"{ar:.2f} at worst ({an}) → {'passed' if self.passed else 'FAILED'} "
                f"(tolerances {100 * REPLAY_FREQUENCY_TOL:g} %, "
                f"{100 * REPLAY_AMPLITUDE_TOL:g} %)")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"target_frequency_hz": self.target_frequency_hz,
                "learned_frequency_hz": self.learned_frequency_hz, "passed": self.passed,
                "worst_frequency": list(self.worst_frequency),
                "worst_amplitude": list(self.worst_amplitude), "signals": self.signals}


def replay_check(result: SelfAdjustResult) -> ReplayCheck:
    """Run ``result``'s network free for :data:`CHECK_STRIDES` strides from the end of
    teaching and compare every signal with the teaching signal (:class:`ReplayCheck`)."""
    from . import measured_frequency

    fT = float(result.teacher.frequency)
    t = np.arange(0.0, CHECK_STRIDES / fT, 1e-3)
    osc = result.bank().simulate(t, None, result.x0, record="y").y
    f_free = measured_frequency(t, osc, start=0.5 / fT)
    grid = t[::10]
    free, taught = result.replay(grid), result.teacher(grid)
    sig = {n: {"frequency_error": float(abs(f_free[j] / fT - 1)),
               "frequency_hz": float(f_free[j]),
               "amplitude_ratio": float(np.ptp(free[:, j]) / np.ptp(taught[:, j]))}
           for j, n in enumerate(result.joint_names)}
    return ReplayCheck(fT, float(result.frequency), sig)


@dataclass(frozen=True)
class CPGReplay:
    """``result``: the tuned network; ``names``: the signals it learned (actuated joint names
    and ``base_*``, see :func:`body_signals`); ``constant``: signals held fixed (no motion to
    learn) [rad, m]; ``replay``: the free-running network's motion of ``robot``; ``report``:
    per signal errors (see :func:`gdimitate.oscillator.self_adjust`)."""

    result: SelfAdjustResult
    names: tuple[str, ...]
    constant: dict[str, float]
    replay: Motion
    check: ReplayCheck | None = None

    @property
    def report(self) -> dict[str, dict[str, Any]]:
        return self.result.report


def _check_motion(robot: Robot, motion: Motion) -> None:
    """The motion must be ``robot``'s: same joint names in the same order, ``q`` of width nq."""
    if not isinstance(motion, Motion):
        raise InvalidInputError(f"motion must be a gdimitate.Motion; got {type(motion).__name__}")
    names, expected = list(motion.joint_names), list(robot.joint_names)
    if names != expected or motion.q.shape[1] != robot.model.nq:
        missing = [n for n in expected if n not in set(names)]
        extra = [n for n in names if n not in set(expected)]
        detail = (f"missing {missing[:8]}, unknown {extra[:8]}" if missing or extra
                  else "same names in another order" if names != expected
                  else f"q has {motion.q.shape[1]} columns, the model nq = {robot.model.nq}")
        raise InvalidInputError(f"the motion does not belong to robot {robot.name!r} ({detail});"
                                f" the robot's joints are {expected}")


@dataclass(frozen=True)
class BodySignals:
    """The periodic signals of a motion that the network learns: ``names`` and ``X`` ``(T, n)``
    [rad, m] — every actuated 1-DoF joint in the robot's order, then the base (free-flyer:
    ``base_x/y/z`` position minus ``base_velocity``·t, ``base_rx/ry/rz`` rotation vector of
    ``R_refᵀ R``; planar: ``base_x`` minus its velocity·t, ``base_z``, ``base_pitch``);
    ``base_velocity`` ``(3,)`` [m/s] the least-squares mean velocity of the base position;
    ``base_rotation`` ``(3, 3)`` the reference orientation ``R_ref`` (the first frame's)."""

    names: tuple[str, ...]
    X: np.ndarray
    base_velocity: np.ndarray
    base_rotation: np.ndarray


def _trend(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Least-squares slope ``(k,)`` of columns ``x`` ``(T, k)`` over ``t``."""
    A = np.column_stack([np.ones_like(t), t - t[0]])
    return np.linalg.lstsq(A, x, rcond=None)[0][1]


def body_signals(robot: Robot, motion: Motion) -> BodySignals:
    """Split ``motion`` into :class:`BodySignals` (see there)."""
    import pinocchio as pin

    m, q, t = robot.model, motion.q, motion.t
    names, cols = [], []
    for j in range(1, m.njoints):
        jm, n = m.joints[j], m.names[j]
        if jm.nq == 1 and n not in PLANAR_BASE:
            names.append(n)
            cols.append(q[:, jm.idx_q])
    vel, R0 = np.zeros(3), np.eye(3)
    if robot.base == "free":
        vel = _trend(t, q[:, :3])
        R0 = pin.Quaternion(q[0, 3:7]).normalized().matrix()
        rot = np.array([pin.log3(R0.T @ pin.Quaternion(qi[3:7]).normalized().matrix())
                        for qi in q])
        names += ["base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz"]
        cols += list((q[:, :3] - np.outer(t - t[0], vel)).T) + list(rot.T)
    elif robot.base == "planar":
        ix = robot.idx_q("base_x")
        vel[0] = _trend(t, q[:, [ix]])[0]
        names += list(PLANAR_BASE)
        cols += [q[:, ix] - vel[0] * (t - t[0]), q[:, robot.idx_q("base_z")],
                 q[:, robot.idx_q("base_pitch")]]
    return BodySignals(tuple(names), np.column_stack(cols), vel, R0)


def _compose(robot: Robot, sig: BodySignals, t: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Configurations ``(T, nq)`` from signals ``Y`` ``(T, n)`` in ``sig.names`` order."""
    import pinocchio as pin

    m = robot.model
    col = {n: Y[:, k] for k, n in enumerate(sig.names)}
    q = np.tile(robot.neutral, (t.size, 1))
    for j in range(1, m.njoints):
        if m.names[j] in col:
            q[:, m.joints[j].idx_q] = col[m.names[j]]
    dt = t - t[0]
    if robot.base == "free":
        q[:, :3] = np.column_stack([col["base_x"], col["base_y"], col["base_z"]])
        q[:, :3] += np.outer(dt, sig.base_velocity)
        for i in range(t.size):
            w = np.array([col["base_rx"][i], col["base_ry"][i], col["base_rz"][i]])
            q[i, 3:7] = pin.Quaternion(sig.base_rotation @ pin.exp3(w)).coeffs()
    elif robot.base == "planar":
        q[:, robot.idx_q("base_x")] += sig.base_velocity[0] * dt
    return q


def _carries_rhythm(sig: BodySignals, robot: Robot) -> np.ndarray:
    """``(n,)`` bool: the signals whose teacher fit is worth a warning — a range of at least
    :data:`HELD_RANGE`, and for a joint at least :data:`HELD_SHARE` of the largest joint's."""
    span = np.ptp(sig.X, axis=0)
    joint = np.array([not n.startswith("base_") for n in sig.names])
    largest = float(span[joint].max()) if joint.any() else 0.0
    return (span >= HELD_RANGE) & (~joint | (span >= HELD_SHARE * largest))


def entrain(robot: Robot, motion: Motion, duration: float | None = None, rate: float | None = None,
            **options) -> CPGReplay:
    """Teach one Matsuoka network the motion's whole body (:func:`body_signals`: every
    actuated joint and the base, one shared frequency) and replay it free-running.

    ``duration`` [s] of the replay (default: the motion's), sampled at ``rate`` [Hz]
    (default: the motion's). ``options`` go to :func:`gdimitate.oscillator.self_adjust`;
    its ``frequency`` defaults to the stride's (:func:`stride_frequency`) when the contact
    schedule has one. The replay is checked (``.check``, :class:`ReplayCheck`); a teacher fit
    worse than :data:`TEACHER_FIT_WARN` warns.

    Raises:
        InvalidInputError: a motion of another robot (joint names differ, or are reordered),
            a constant motion, ``duration``/``rate`` not finite and > 0.
        ResourceLimitError: an implausible time axis (e.g. milliseconds read as seconds), a
            replay longer than :data:`~gdimitate.safety.MAX_MOTION_DURATION_S` or of more than
            :data:`~gdimitate.safety.MAX_OUTPUT_SAMPLES` frames — all before any work.
        OscillatorError: from :func:`~gdimitate.oscillator.self_adjust`.
    """
    _check_motion(robot, motion)
    check_time_axis(motion.t, "motion")
    duration = (float(motion.t[-1] - motion.t[0]) if duration is None
                else check_positive("duration [s]", duration, upper=MAX_MOTION_DURATION_S))
    rate = 1.0 / motion.dt if rate is None else check_positive("rate [Hz]", rate)
    if duration * rate > MAX_OUTPUT_SAMPLES:
        raise ResourceLimitError(f"a replay of {duration:g} s at {rate:g} Hz has "
                                 f"{duration * rate:.3g} frames; the limit is "
                                 f"{MAX_OUTPUT_SAMPLES:,}")
    sig = body_signals(robot, motion)
    names, X = list(sig.names), sig.X
    moving = np.ptp(X, axis=0) > 1e-9
    if not moving.any():
        raise InvalidInputError(f"motion is constant: none of {robot.name}'s joints or base "
                                "coordinates changes; nothing to entrain")
    constant = {n: float(X[0, j]) for j, n in enumerate(names) if not moving[j]}
    learn = [n for j, n in enumerate(names) if moving[j]]
    if options.get("frequency") is None:
        options["frequency"] = stride_frequency(motion)
    result = self_adjust(motion.t, X[:, moving], joint_names=learn, **options)
    # the fit of a signal held nearly still (an unmapped arm joint held near its rest pose)
    # is no news: relative to its small range any wobble is a large nRMSE
    fit = np.where(_carries_rhythm(sig, robot)[moving], result.teacher.fit_nrmse, 0.0)
    if np.max(fit) > TEACHER_FIT_WARN:
        j = int(np.argmax(fit))
        warnings.warn(f"the periodic teaching signal fits {learn[j]} with nRMSE "
                      f"{100 * fit[j]:.1f} % (> {100 * TEACHER_FIT_WARN:g} %; "
                      f"{int(np.sum(fit > TEACHER_FIT_WARN))} signals over): the motion is "
                      f"not periodic at {result.teacher.frequency:.3f} Hz, so the network "
                      "learns a different motion", OscillatorWarning, stacklevel=2)
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    Y = np.empty((t.size, len(names)))
    Y[:, moving] = result.replay(t)
    for j, n in enumerate(names):
        if not moving[j]:
            Y[:, j] = constant[n]
    q = _compose(robot, sig, t, Y)
    return CPGReplay(result, tuple(learn), constant,
                     robot_motion(robot, t, q, kinematic_contact(robot, q)),
                     replay_check(result))
