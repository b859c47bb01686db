"""The demonstrator's heading, and walks turned about the vertical (docs/design.md §13).

A lab's x axis is arbitrary: a subject may walk along any direction of it. Whatever depends
on "forward" is written in the demonstration's *heading frame*: the world turned about the
vertical by the heading yaw ψ (:func:`walk_heading`), x along the walk, y to its left, z up.

- :func:`walk_heading` ``ψ`` [rad]: the direction of the base's horizontal travel over the
  clip where it travels at least :data:`MIN_TRAVEL` [m]; else (a turn or a step on the
  spot) the circular mean of the base's facing yaw relative to its neutral orientation
  (every :class:`~gdimitate.Robot` faces +x at its neutral pose).
- :func:`turn_motion`, :func:`turn_forces`: a motion (free-flyer base) and measured forces
  turned by a yaw about a vertical axis — what the tests and the corpus benchmark use to make
  a walk along another direction, and what the adaptor uses to write its warm start in the
  heading frame. Pinocchio's free-flyer velocities are in the base's local frame, the sole
  wrenches in the sole's: a turn leaves them as they are.
- :func:`on_clock`, :func:`forces_on_clock`: a demonstration on a clock running ``scale``
  times as long (Froude's time scaling of a gait, :mod:`gdimitate.model.footsteps`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError
from .contact import ContactForces, FootForces
from .motion import Motion

__all__ = ["MIN_TRAVEL", "walk_heading", "facing_yaw", "yaw_matrix", "turn_motion",
           "turn_configurations",
           "turn_forces", "turn_points", "on_clock", "forces_on_clock"]

MIN_TRAVEL = 0.1
"""[m] Base travel over a clip below which its heading is the base's facing, not its path."""


def yaw_matrix(yaw: float) -> np.ndarray:
    """``(3, 3)`` rotation by ``yaw`` [rad] about +z."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def facing_yaw(q: np.ndarray, base_rotation: np.ndarray) -> np.ndarray:
    """``(T,)`` [rad]: yaw of the forward axis of free-flyer bases ``q`` ``(T, ≥7)`` turned
    by ``base_rotation`` ``(3, 3)`` (the robot's neutral base rotation, which faces +x): the
    horizontal direction of ``R(t) R₀ᵀ e_x``, unwrapped."""
    out = np.empty(len(q))
    for i, qi in enumerate(np.asarray(q, float)):
        R = pin.Quaternion(qi[3:7]).normalized().matrix() @ base_rotation.T
        out[i] = np.arctan2(R[1, 0], R[0, 0])
    return np.unwrap(out)


def walk_heading(robot, motion: Motion) -> float:
    """Heading yaw ψ [rad] of a demonstration of ``robot`` (module docstring); 0 for robots
    without a free-flyer base (planar models walk along +x by construction)."""
    if robot.base != "free":
        return 0.0
    q = np.asarray(motion.q, float)
    d = q[-1, :2] - q[0, :2]
    if float(np.hypot(*d)) >= MIN_TRAVEL:
        return float(np.arctan2(d[1], d[0]))
    yaw = facing_yaw(q, robot.base_rotation)
    return float(np.arctan2(np.mean(np.sin(yaw)), np.mean(np.cos(yaw))))


def turn_points(p: np.ndarray, yaw: float, about: np.ndarray | None = None) -> np.ndarray:
    """Points ``p`` ``(..., 3)`` [m] turned by ``yaw`` [rad] about the vertical through
    ``about`` ``(2,)`` (default: the origin); NaN rows stay NaN."""
    return _turned(np.asarray(p, float), yaw_matrix(yaw), about)


def _turned(p: np.ndarray, R: np.ndarray, about: np.ndarray | None) -> np.ndarray:
    """:func:`turn_points` by the rotation ``R`` ``(3, 3)`` (numpy's per-call overhead kept
    off a streamed frame's path)."""
    if about is None:
        return p @ R.T
    c = np.array([float(about[0]), float(about[1]), 0.0])
    return (p - c) @ R.T + c


def turn_motion(motion: Motion, yaw: float, about: np.ndarray | None = None) -> Motion:
    """``motion`` (a free-flyer robot's) turned by ``yaw`` [rad] about the vertical through
    ``about`` ``(2,)`` [m] (default: the origin): base positions turned, base orientations
    premultiplied by the turn, joints, local velocities and contacts as they are. A fixed or
    planar base cannot turn (:class:`~gdimitate.errors.InvalidInputError`) unless ``yaw`` is
    0."""
    if not np.isfinite(yaw):
        raise InvalidInputError(f"yaw must be a finite angle in rad; got {yaw!r}")
    if motion.base_nq != 7:
        if yaw == 0.0:
            return motion
        raise InvalidInputError(
            f"only a free-flyer base turns about the vertical; this motion's base has "
            f"{motion.base_nq} columns (planar models walk along +x)")
    return motion.replace(q=turn_configurations(motion.q, yaw, about))


def turn_configurations(q: np.ndarray, yaw: float, about: np.ndarray | None = None
                        ) -> np.ndarray:
    """Free-flyer configurations ``q`` ``(..., nq)`` turned like :func:`turn_motion`."""
    return Turn(yaw, about).configurations(q)


class Turn:
    """A turn by ``yaw`` [rad] about the vertical through ``about`` ``(2,)`` [m] (default:
    the origin), its rotation made once: :meth:`configurations` is
    :func:`turn_configurations` (a stream turns two configurations a frame)."""

    def __init__(self, yaw: float, about: np.ndarray | None = None):
        self.R = yaw_matrix(yaw)
        self.Q = pin.Quaternion(self.R)
        self.about = about

    def configurations(self, q: np.ndarray) -> np.ndarray:
        """Free-flyer configurations ``q`` ``(..., nq)`` turned: base positions turned, base
        orientations premultiplied by the turn, the rest as it is (a copy)."""
        q = np.array(q, float)
        flat = q.reshape(-1, q.shape[-1])
        flat[:, :3] = _turned(flat[:, :3], self.R, self.about)
        for row in flat:
            row[3:7] = (self.Q * pin.Quaternion(row[3:7])).coeffs()
        return q


def turn_forces(forces: ContactForces, yaw: float, about: np.ndarray | None = None
                ) -> ContactForces:
    """Measured ``forces`` turned like :func:`turn_motion`: force and free torque vectors
    rotated, centres of pressure turned about ``about``."""
    R = yaw_matrix(yaw)
    feet = {s: FootForces(f.force @ R.T, turn_points(f.cop, yaw, about), f.torque @ R.T,
                          f.contact) for s, f in forces.feet.items()}
    note = f"turned {np.degrees(yaw):.1f} deg about the vertical"
    return ContactForces(forces.t, feet, forces.source,
                         f"{forces.frame_note}; {note}" if forces.frame_note else note)


def on_clock(motion: Motion, scale: float) -> Motion:
    """``motion`` with its durations × ``scale`` (times ``t₀ + scale·(t − t₀)``; velocities
    ÷ ``scale``, accelerations ÷ ``scale²``): the clock of a Froude-scaled gait."""
    if scale == 1.0:
        return motion
    t = motion.t[0] + scale * (motion.t - motion.t[0])
    return motion.replace(t=t, v=None if motion.v is None else motion.v / scale,
                          a=None if motion.a is None else motion.a / scale ** 2)


def forces_on_clock(forces: ContactForces, scale: float) -> ContactForces:
    """Measured ``forces`` on the clock of :func:`on_clock` (their directions, centres of
    pressure and contacts as they are)."""
    if scale == 1.0:
        return forces
    t = forces.t[0] + scale * (forces.t - forces.t[0])
    return ContactForces(t, forces.feet, forces.source,
                         f"{forces.frame_note}; clock × {scale:.4g}".lstrip("; "))
