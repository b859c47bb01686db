"""From an adapted motion to a central pattern generator and back: entrain and replay.

:func:`entrain` teaches a Matsuoka network (:func:`gdimitate.oscillator.self_adjust`) the
sagittal angles of a robot's motion — the torso angle and each leg's planar (θ1, θ2, θ3),
DESIGN §4 — and lets it run free after the teaching input stops; the replayed angles become a
new :class:`~gdimitate.motion.Motion` of the same robot, grounded with stance read from the
replayed feet (the lower sole is in stance).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import InvalidInputError, ResourceLimitError
from .motion import Motion
from .oscillator import SelfAdjustResult, self_adjust
from .robot import SIDES, Robot
from .safety import (
    MAX_MOTION_DURATION_S,
    MAX_OUTPUT_SAMPLES,
    check_positive,
    check_time_axis,
)
from .sagittal import compose_q, ground_base, kinematic_contact, leg_angles, robot_motion

__all__ = ["CPGReplay", "entrain", "sagittal_targets"]

ROLES = ("hip", "knee", "ankle")


@dataclass(frozen=True)
class CPGReplay:
    """``result``: the tuned network; ``names``: its joints (``torso``, ``left_hip``, …);
    ``constant``: sagittal angles held fixed (no motion to learn) [rad]; ``replay``: the
    free-running network's motion of ``robot``; ``report``: per joint errors (see
    :func:`gdimitate.oscillator.self_adjust`)."""

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


def sagittal_targets(robot: Robot, motion: Motion) -> tuple[list[str], np.ndarray]:
    """``(names, X (T, 7))``: torso angle and per-leg planar hip (absolute), knee, ankle [rad]."""
    torso, ang = leg_angles(robot, motion.q)
    names = ["torso"] + [f"{s}_{r}" for s in SIDES for r in ROLES]
    return names, np.column_stack([torso] + [ang[s] for s in SIDES])


def entrain(robot: Robot, motion: Motion, duration: float | None = None, rate: float | None = None,
            **options) -> CPGReplay:
    """Teach a Matsuoka network the motion's sagittal angles and replay it free-running.

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
    names, X = sagittal_targets(robot, motion)
    moving = np.ptp(X, axis=0) > 1e-9
    if not moving.any():
        raise InvalidInputError(f"motion is constant: none of {robot.name}'s sagittal angles "
                                "(torso, hips, knees, ankles) changes; nothing to entrain")
    constant = {n: float(X[0, j]) for j, n in enumerate(names) if not moving[j]}
    learn = [n for j, n in enumerate(names) if moving[j]]
    result = self_adjust(motion.t, X[:, moving], joint_names=learn, **options)
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    Y = np.empty((t.size, len(names)))
    Y[:, moving] = result.replay(t)
    for j, n in enumerate(names):
        if not moving[j]:
            Y[:, j] = constant[n]
    angles = {s: Y[:, 1 + 3 * k: 4 + 3 * k] for k, s in enumerate(SIDES)}
    q = compose_q(robot, Y[:, 0], angles)
    contact = kinematic_contact(robot, q)
    q = ground_base(robot, q, contact)
    return CPGReplay(result, tuple(learn), constant, robot_motion(robot, t, q, contact))
