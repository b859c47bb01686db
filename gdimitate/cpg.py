"""From an adapted motion to a central pattern generator and back: entrain and replay.

:func:`entrain` teaches one Matsuoka network (:func:`gdimitate.oscillator.self_adjust`, one
shared frequency) the whole body of a robot's motion — every actuated 1-DoF joint, and the
floating base as periodic signals (its position with the mean walking velocity removed, its
orientation as a rotation vector about the first frame's) — and lets it run free after the
teaching input stops. The replay is a new :class:`~gdimitate.motion.Motion` of the same robot
in the same joint order: the base advances at the taught mean velocity plus the network's
periodic part; stance is read from the replayed feet (the lower sole is in stance).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import InvalidInputError, ResourceLimitError
from .motion import Motion
from .oscillator import SelfAdjustResult, self_adjust
from .robot import PLANAR_BASE, Robot
from .safety import (
    MAX_MOTION_DURATION_S,
    MAX_OUTPUT_SAMPLES,
    check_positive,
    check_time_axis,
)
from .sagittal import kinematic_contact, robot_motion

__all__ = ["CPGReplay", "entrain", "BodySignals", "body_signals"]


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


def entrain(robot: Robot, motion: Motion, duration: float | None = None, rate: float | None = None,
            **options) -> CPGReplay:
    """Teach one Matsuoka network the motion's whole body (:func:`body_signals`: every
    actuated joint and the base, one shared frequency) and replay it free-running.

    ``duration`` [s] of the replay (default: the motion's), sampled at ``rate`` [Hz]
    (default: the motion's). ``options`` go to :func:`gdimitate.oscillator.self_adjust`.

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
    result = self_adjust(motion.t, X[:, moving], joint_names=learn, **options)
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    Y = np.empty((t.size, len(names)))
    Y[:, moving] = result.replay(t)
    for j, n in enumerate(names):
        if not moving[j]:
            Y[:, j] = constant[n]
    q = _compose(robot, sig, t, Y)
    return CPGReplay(result, tuple(learn), constant,
                     robot_motion(robot, t, q, kinematic_contact(robot, q)))
