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

from .motion import Motion
from .oscillator import SelfAdjustResult, self_adjust
from .robot import SIDES, Robot
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
    """
    names, X = sagittal_targets(robot, motion)
    moving = np.ptp(X, axis=0) > 1e-9
    constant = {n: float(X[0, j]) for j, n in enumerate(names) if not moving[j]}
    learn = [n for j, n in enumerate(names) if moving[j]]
    result = self_adjust(motion.t, X[:, moving], joint_names=learn, **options)
    duration = float(motion.t[-1] - motion.t[0]) if duration is None else float(duration)
    rate = 1.0 / motion.dt if rate is None else float(rate)
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
