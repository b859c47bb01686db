"""A treadmill trial turned overground: the belt speed added back to the body and the forces.

On a treadmill the pelvis stays in place and each stance foot rides the belt backwards. The
belt speed is estimated as the median backward speed of the stance feet (each sole frame's
world x velocity, central differences, over the frames the measured forces mark as stance);
``speed·(t − t₀)`` is then added to the floating base's x and to the centres of pressure' x,
so kinematics and forces stay consistent (the forces and free torques themselves are
unchanged: a belt at constant speed is an inertial frame).
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidInputError
from ...model.contact import ContactForces, FootForces
from ...model.kinematics import frame_paths
from ...model.motion import Motion

__all__ = ["belt_speed", "treadmill_to_overground"]


def _base_x_index(robot) -> int:
    if robot.base == "free":
        return 0
    if robot.base == "planar":
        return robot.idx_q("base_x")
    raise InvalidInputError(f"robot {robot.name!r} has a fixed base; a treadmill trial can be "
                            "turned overground only for a floating base")


def _sole(robot, side: str) -> str:
    c = robot.contacts.get(side)
    return c.frame if c is not None else robot.legs[side].sole


def belt_speed(robot, motion: Motion, contact: dict[str, np.ndarray]) -> float:
    """Belt speed [m/s] (positive when the belt carries the feet backwards, −x): the median of
    −ẋ of each foot's sole frame over its stance frames ``contact[side]`` ``(T,)``."""
    speeds = []
    for side in ("left", "right"):
        c = np.asarray(contact[side], dtype=bool)
        if c.shape != motion.t.shape:
            raise InvalidInputError(f"contact[{side!r}] must have shape {motion.t.shape}")
        sole = _sole(robot, side)
        x = frame_paths(robot, motion.q, [sole])[sole][:, 0]
        speeds.append(-np.gradient(x, motion.t)[c])
    v = np.concatenate(speeds)
    if v.size == 0:
        raise InvalidInputError("no stance frame: cannot estimate the belt speed")
    return float(np.median(v))


def treadmill_to_overground(robot, motion: Motion, forces: ContactForces,
                            speed: float | None = None) -> tuple[Motion, ContactForces]:
    """``(motion, forces)`` of a treadmill trial as if walked overground.

    ``forces`` must be on the motion's times (``read_grf(..., t=motion.t)``); ``speed`` [m/s]
    the belt speed (estimated by :func:`belt_speed` from the forces' stance masks when
    ``None``). The returned motion has ``speed·(t − t₀)`` added to its base x and no ``v``/``a``
    (differentiate it again); the forces' centres of pressure move with it, and their
    ``frame_note`` says what was done and the speed used.
    """
    if forces.t.shape != motion.t.shape or not np.allclose(forces.t, motion.t):
        raise InvalidInputError("forces must be sampled on the motion's times: read them with "
                                "read_grf(..., t=motion.t)")
    estimated = speed is None
    if estimated:
        speed = belt_speed(robot, motion, forces.contact)
    shift = float(speed or 0.0) * (motion.t - motion.t[0])
    q = motion.q.copy()
    q[:, _base_x_index(robot)] += shift
    feet = {}
    for side, f in forces.feet.items():
        cop = f.cop.copy()
        cop[:, 0] += shift
        feet[side] = FootForces(f.force, cop, f.torque, f.contact)
    how = "estimated from the stance feet" if estimated else "given"
    note = forces.frame_note.replace("positions as measured (not turned overground)",
                                     "").rstrip("; ")
    note += (f"; treadmill trial turned overground: belt speed {speed:.3f} m/s ({how}), "
             "speed·(t − t₀) added to the base x and to the centre-of-pressure x")
    return (motion.replace(q=q, v=None, a=None),
            ContactForces(forces.t, feet, source=forces.source, frame_note=note))
