"""The paper's planar adaptors (docs/design.md §4): Eq. (1) per leg and joint copying.

``"analytic"`` maps each leg's planar thigh and shank angles with Eq. (1)
(:func:`gdimitate.planar.eq1`, on the legs measured by :func:`gdimitate.planar.sagittal_leg`);
``"copy"`` keeps the demonstrator's planar joint angles (the paper's "without adaptor"
baseline). Both keep the torso and ankle angles and place the base so that the stance foot
stands on the ground without slipping. :func:`gdimitate.adapt` dispatches here; the optimal
adaptor's warm start (:mod:`gdimitate.retarget.trajectory.initial`) calls :func:`adapt_planar`
directly,
so that the adaptors never import their dispatcher. Both need legs whose joints turn about the
lateral axis (:class:`~gdimitate.errors.LegDetectionError` otherwise).
"""

from __future__ import annotations

import numpy as np

from ..assess.result import AdaptedMotion, compare
from ..errors import InvalidInputError, LegMatchError
from ..model.kinematics import robot_motion
from ..model.motion import Motion
from ..model.robot import Robot
from ..model.sagittal import compose_q, ground_base, leg_angles, sagittal_leg
from ..types import SIDES, ForceModel, PlanarMethod
from .twolink import eq1

__all__ = ["adapt_planar", "check_pair"]


def check_pair(motion: Motion, demonstrator: Robot, imitator: Robot) -> None:
    """Refuse a motion that is not ``demonstrator``'s, robots without a left and a right leg,
    a fixed base and a motion without a contact schedule (InvalidInputError,
    LegMatchError)."""
    if not isinstance(motion, Motion):
        raise InvalidInputError(f"motion must be a gdimitate.Motion; got {type(motion).__name__}")
    if tuple(motion.joint_names) != demonstrator.joint_names or \
            motion.q.shape[1] != demonstrator.model.nq:
        raise InvalidInputError(
            f"the motion's joints do not match the demonstrator {demonstrator.name!r}: "
            f"motion has {list(motion.joint_names)}, robot has {list(demonstrator.joint_names)}")
    for r in (demonstrator, imitator):
        if set(r.legs) != set(SIDES):
            raise LegMatchError(f"{r.name} legs {sorted(r.legs)} cannot be matched to {SIDES}")
        if not r.floating:
            raise LegMatchError(f"{r.name} has a fixed base; a walking imitator needs a floating "
                                "base to follow its feet")
    missing = [s for s in SIDES if s not in motion.contact]
    if missing:
        raise InvalidInputError(
            f"the motion has no contact schedule for {missing} (a motion from "
            "gd.opensim.read_coordinates has none yet): read the file with "
            "gd.load_demonstration(path, grf=...) — contacts from the measured forces, or "
            "from the feet when there are none —, or give the schedule yourself: "
            "motion.replace(contact={'left': (T,) bool, 'right': (T,) bool}) (e.g. "
            "contact=forces.contact of gd.opensim.read_grf(..., t=motion.t))")


def adapt_planar(demo: Motion, demonstrator: Robot, imitator: Robot,
                 method: PlanarMethod = "analytic",
                 force: ForceModel = "segment") -> AdaptedMotion:
    """``demo`` (a motion of ``demonstrator``, ``q`` ``(T, nq)``) regenerated for ``imitator``
    by Eq. (1) (``method="analytic"``) or by copying the planar joint angles (``"copy"``);
    ``force`` names the force-direction model of the report's comparison."""
    check_pair(demo, demonstrator, imitator)
    motion = demo
    torso, angles = leg_angles(demonstrator, motion.q)
    new, feasible = {}, {}
    for s in SIDES:
        a = angles[s]
        if method == "copy":
            new[s] = a.copy()
            feasible[s] = np.ones(len(a), dtype=bool)
        else:
            dl, il = sagittal_leg(demonstrator, s), sagittal_leg(imitator, s)
            r = eq1(a[:, 0], a[:, 1], (dl.thigh, dl.shank), (il.thigh, il.shank))
            new[s] = np.column_stack([r.theta1, r.theta2, a[:, 2]])
            feasible[s] = r.feasible
    q = ground_base(imitator, compose_q(imitator, torso, new), motion.contact)
    out = robot_motion(imitator, motion.t, q, motion.contact)
    report = compare(demonstrator, motion, imitator, out, method, feasible, force)
    return AdaptedMotion(motion=out, report=report, robot=imitator)
