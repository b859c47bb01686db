"""What a walking motion achieves: hip and foot paths, centre of mass, force direction, limits.

All positions are world coordinates [m] (x forward, z up); angles [rad]. Functions take the
robot and one of its :class:`~gdimitate.model.motion.Motion`\\ s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError, UnknownNameError
from ..model.contact import ContactForces
from ..model.heading import walk_heading
from ..model.kinematics import frame_paths, frame_rotations, joint_paths
from ..model.motion import Motion
from ..model.robot import PLANAR_BASE, SIDES, Robot

__all__ = ["FORCE_MODELS", "angle_down", "hip_path", "hip_height", "ankle_paths", "sole_paths",
           "foot_heights", "foot_distance", "com_path", "force_direction", "joint_limit_margins",
           "hip_height_ratio", "ForceDirection", "angle_between", "frame_rotations"]

#: Force-direction models of :func:`force_direction`.
FORCE_MODELS = ("measured", "dynamics", "com", "segment")


def _check(robot: Robot, motion: Motion) -> None:
    if motion.q.shape[1] != robot.model.nq or tuple(motion.joint_names) != robot.joint_names:
        raise InvalidInputError(
            f"motion does not belong to {robot.name}: its joints {list(motion.joint_names)[:6]}… "
            f"(nq={motion.q.shape[1]}) vs the robot's {list(robot.joint_names)[:6]}… "
            f"(nq={robot.model.nq})")


def hip_path(robot: Robot, motion: Motion) -> np.ndarray:
    """Midpoint of the two hip joints ``(T, 3)``."""
    _check(robot, motion)
    p = joint_paths(robot, motion.q, [robot.legs[s].hip for s in SIDES])
    return (p[robot.legs["left"].hip] + p[robot.legs["right"].hip]) / 2


def hip_height(robot: Robot, motion: Motion) -> np.ndarray:
    """Height of the hip midpoint above the ground ``(T,)``."""
    return hip_path(robot, motion)[:, 2]


def ankle_paths(robot: Robot, motion: Motion) -> dict[str, np.ndarray]:
    """Ankle joint positions ``{side: (T, 3)}`` (the sole for legs without an ankle)."""
    _check(robot, motion)
    out = {}
    for s in SIDES:
        leg = robot.legs[s]
        out[s] = (joint_paths(robot, motion.q, [leg.ankle])[leg.ankle] if leg.ankle
                  else frame_paths(robot, motion.q, [leg.sole])[leg.sole])
    return out


def sole_paths(robot: Robot, motion: Motion) -> dict[str, np.ndarray]:
    """Sole frame positions ``{side: (T, 3)}``."""
    _check(robot, motion)
    p = frame_paths(robot, motion.q, [robot.legs[s].sole for s in SIDES])
    return {s: p[robot.legs[s].sole] for s in SIDES}


def foot_heights(robot: Robot, motion: Motion) -> dict[str, np.ndarray]:
    """Sole heights above the ground ``{side: (T,)}``."""
    return {s: p[:, 2] for s, p in sole_paths(robot, motion).items()}


def foot_distance(robot: Robot, motion: Motion) -> np.ndarray:
    """Horizontal distance between the ankles along the walk, left minus right ``(T,)`` [m]
    (signed): along the motion's heading (:func:`gdimitate.model.heading.walk_heading`, the
    direction of its base's travel; +x for planar models), so that a walk along any
    direction of the lab gives the same curve."""
    a = ankle_paths(robot, motion)
    psi = walk_heading(robot, motion)
    return (a["left"][:, :2] - a["right"][:, :2]) @ np.array([np.cos(psi), np.sin(psi)])


def com_path(robot: Robot, motion: Motion) -> np.ndarray:
    """Whole-body centre of mass ``(T, 3)`` (Pinocchio)."""
    _check(robot, motion)
    return robot.com(motion.q)


def hip_height_ratio(robot: Robot, motion: Motion) -> dict[str, np.ndarray]:
    """Per leg, the hip joint's height over its ankle divided by the leg length ``{side: (T,)}``
    — the quantity Eq. (1) keeps."""
    _check(robot, motion)
    a = ankle_paths(robot, motion)
    out = {}
    for s in SIDES:
        leg = robot.legs[s]
        h = joint_paths(robot, motion.q, [leg.hip])[leg.hip]
        out[s] = (h[:, 2] - a[s][:, 2]) / leg.length
    return out


def angle_down(v: np.ndarray) -> np.ndarray:
    """Angle [rad] of vectors ``(..., 3)`` from the downward vertical, positive forward (+x):
    the sign convention of every force direction (docs/design.md §4–5)."""
    v = np.asarray(v, dtype=float)
    return np.arctan2(v[..., 0], -v[..., 2])


@dataclass(frozen=True)
class ForceDirection:
    """One foot's push on the ground over a motion (docs/design.md §5 of docs/design.md).

    ``vector`` ``(T, 3)``: unit push ON THE GROUND in the world frame (the ground's reaction on
    the foot is its reverse); ``sagittal`` ``(T,)`` [rad]: its angle from the downward vertical
    in the x–z plane, positive when it points forward (+x); ``frontal`` ``(T,)`` [rad]: in the
    y–z plane, positive when it points left (+y); ``model``: how it was obtained. NaN where
    the foot is in swing (or, for ``measured``, carries no force).
    """

    vector: np.ndarray
    sagittal: np.ndarray
    frontal: np.ndarray
    model: str

    @classmethod
    def from_vectors(cls, v: np.ndarray, stance: np.ndarray, model: str) -> ForceDirection:
        """Normalise push vectors ``(T, 3)`` and blank them (NaN) outside ``stance`` ``(T,)``
        and where they vanish."""
        v = np.asarray(v, dtype=float)
        n = np.linalg.norm(v, axis=1)
        ok = np.asarray(stance, bool) & (n > 1e-12)
        u = np.full_like(v, np.nan)
        u[ok] = v[ok] / n[ok, None]
        return cls(u, angle_down(u), np.arctan2(u[:, 1], -u[:, 2]), model)


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle [rad] between vectors ``(..., 3)`` (NaN where either is NaN or zero)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.sum(a * b, axis=-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
        s = np.linalg.norm(np.cross(a, b), axis=-1) / (np.linalg.norm(a, axis=-1)
                                                        * np.linalg.norm(b, axis=-1))
    return np.arctan2(s, c)


def _measured_on(forces: ContactForces, t: np.ndarray, side: str):
    """Measured force (T, 3), cop (T, 3) and contact (T,) of one foot on the times ``t``."""
    f = forces[side]
    if f.force.shape[0] == t.size and np.allclose(forces.t, t, atol=1e-9):
        return f.force, f.cop, f.contact
    if t[0] < forces.t[0] - 1e-9 or t[-1] > forces.t[-1] + 1e-9:
        raise InvalidInputError(
            f"the forces cover {forces.t[0]:.3f}–{forces.t[-1]:.3f} s but the motion "
            f"{t[0]:.3f}–{t[-1]:.3f} s: give forces that span the motion")
    force = np.column_stack([np.interp(t, forces.t, f.force[:, k]) for k in range(3)])
    cop = np.column_stack([np.interp(t, forces.t, np.nan_to_num(f.cop[:, k])) for k in range(3)])
    contact = np.interp(t, forces.t, f.contact.astype(float)) > 0.5
    cop[~contact] = np.nan
    return force, cop, contact


def force_direction(robot: Robot, motion: Motion, model: str = "segment",
                    forces: ContactForces | None = None, cutoff: float | None = 6.0
                    ) -> dict[str, ForceDirection]:
    """Direction of each stance foot's push on the ground, ``{"left": ForceDirection,
    "right": ForceDirection}`` (NaN where ``motion.contact`` says the foot is in swing).

    Models (docs/design.md §5 of docs/design.md):

    - ``measured`` — the reverse of the measured ground reaction force on each foot
      (``forces``: :class:`~gdimitate.contact.ContactForces`, resampled onto the motion's
      times by linear interpolation);
    - ``dynamics`` — from the demonstrator's own whole-body dynamics: the contact wrenches that
      explain the base rows of its inverse dynamics inside each foot's contact wrench cone,
      split between the feet in double support (a QP per knot,
      :func:`gdimitate.assess.wrenches.estimate_wrenches`); velocities and accelerations from
      ``motion.v``/``motion.a`` or, when absent, :func:`gdimitate.model.motion.differentiate` with a
      ``cutoff`` [Hz] low-pass (zero phase; OpenSim's inverse dynamics uses 6 Hz);
    - ``com`` — from the whole-body centre of mass to the contact point (the measured centre
      of pressure where ``forces`` are given, else the sole frame): an inverted pendulum;
    - ``segment`` — the paper's: along the shank, knee → ankle (knee → sole for legs without
      an ankle). In the planar case its sagittal angle is the absolute shank angle θ1+θ2.
    """
    if model not in FORCE_MODELS:
        raise UnknownNameError("force model", model, FORCE_MODELS)
    _check(robot, motion)
    if not motion.contact or any(s not in motion.contact for s in SIDES):
        raise InvalidInputError("force_direction needs motion.contact for 'left' and 'right'")
    if model == "measured" and forces is None:
        raise InvalidInputError("force model 'measured' needs forces= (the demonstrator's "
                                "measured ContactForces, e.g. from gdimitate.io.opensim.read_grf)")
    stance = {s: np.asarray(motion.contact[s], bool) for s in SIDES}
    push: dict[str, np.ndarray] = {}
    if model == "segment":
        ank = ankle_paths(robot, motion)
        for s in SIDES:
            k = joint_paths(robot, motion.q, [robot.legs[s].knee])[robot.legs[s].knee]
            push[s] = ank[s] - k
    elif model == "com":
        c = com_path(robot, motion)
        sole = sole_paths(robot, motion)
        for s in SIDES:
            point = sole[s]
            if forces is not None:
                _, cop, _ = _measured_on(forces, motion.t, s)
                point = np.where(np.isfinite(cop), cop, point)
            push[s] = point - c
    elif model == "measured":
        assert forces is not None  # checked above
        for s in SIDES:
            f, _, contact = _measured_on(forces, motion.t, s)
            push[s] = -f
            stance[s] = stance[s] & contact
    else:
        from ..model.motion import differentiate
        from .wrenches import estimate_wrenches

        m = motion if motion.v is not None and motion.a is not None else differentiate(
            robot.model, motion, cutoff_hz=cutoff)
        est = estimate_wrenches(robot, m, method="cone")
        contacts = robot.require_contacts()
        for s in SIDES:
            R = frame_rotations(robot, m.q, contacts[s].frame)
            push[s] = -np.einsum("tij,tj->ti", R, est.wrenches[s][:, :3])
    return {s: ForceDirection.from_vectors(push[s], stance[s], model) for s in SIDES}


def joint_limit_margins(robot: Robot, motion: Motion) -> dict[str, np.ndarray]:
    """Per 1-DoF joint with finite limits, the distance to the nearer position limit ``(T,)``
    [rad or m]; negative where the limit is violated."""
    _check(robot, motion)
    m = robot.model
    out = {}
    for j in robot.joint_names:
        jm = m.joints[m.getJointId(j)]
        if jm.nq != 1:
            continue
        lo, hi = m.lowerPositionLimit[jm.idx_q], m.upperPositionLimit[jm.idx_q]
        if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
            continue
        if j in PLANAR_BASE:
            continue
        qj = motion.q[:, jm.idx_q]
        out[j] = np.minimum(qj - lo, hi - qj)
    return out
