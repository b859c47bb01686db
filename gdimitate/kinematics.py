"""A robot's configurations as a :class:`~gdimitate.Motion` (general, any leg axes).

This module sits between :mod:`gdimitate.motion` and everything that reads or writes a robot's
trajectory (loaders such as :mod:`gdimitate.opensim`, the adaptors, :mod:`gdimitate.sagittal`).
It takes the robot as an argument and imports nothing from :mod:`gdimitate.robot`, so a loader
that :class:`~gdimitate.Robot` calls (``Robot.from_osim``) can use it without an import cycle.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .errors import InvalidInputError
from .motion import Motion

if TYPE_CHECKING:
    from .robot import Robot

__all__ = ["check_q", "robot_motion"]


def check_q(robot: Robot, q: np.ndarray) -> np.ndarray:
    """``q`` as a float array ``(T, nq)`` of ``robot``; InvalidInputError on another shape."""
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != robot.model.nq:
        raise InvalidInputError(
            f"q must have shape (T, {robot.model.nq}) for {robot.name}; got {q.shape}")
    return q


def robot_motion(robot: Robot, t: np.ndarray, q: np.ndarray,
                 contact: dict[str, np.ndarray]) -> Motion:
    """A :class:`Motion` of ``robot`` (joint names, per-joint widths and base width filled in).

    ``t`` ``(T,)`` [s], ``q`` ``(T, nq)`` in Pinocchio order, ``contact`` ``{side: (T,) bool}``.
    """
    m = robot.model
    nqs = tuple(int(m.joints[i].nq) for i in range(1, m.njoints))
    base_nq = 7 if robot.base == "free" else 3 if robot.base == "planar" else 0
    return Motion(t=t, joint_names=robot.joint_names, q=check_q(robot, q), contact=contact,
                  base_nq=base_nq, joint_nq=nqs)
