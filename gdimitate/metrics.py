"""What a walking motion achieves: hip and foot paths, centre of mass, force direction, limits.

All positions are world coordinates [m] (x forward, z up); angles [rad]. Functions take the
robot and one of its :class:`~gdimitate.motion.Motion`\\ s.
"""

from __future__ import annotations

import numpy as np

from .errors import InvalidInputError, UnknownNameError
from .motion import Motion
from .robot import PLANAR_BASE, SIDES, Robot
from .sagittal import frame_paths, joint_paths

__all__ = ["FORCE_MODELS", "angle_down", "hip_path", "hip_height", "ankle_paths", "sole_paths",
           "foot_heights", "foot_distance", "com_path", "force_direction", "joint_limit_margins",
           "hip_height_ratio"]

FORCE_MODELS = ("segment", "com", "grf")
GRAVITY = 9.81


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
    """Horizontal (x) distance between the ankles, left minus right ``(T,)`` (signed)."""
    a = ankle_paths(robot, motion)
    return a["left"][:, 0] - a["right"][:, 0]


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
    the sign convention of every force direction (DESIGN §4–5)."""
    v = np.asarray(v, dtype=float)
    return np.arctan2(v[..., 0], -v[..., 2])


def force_direction(robot: Robot, motion: Motion, model: str = "segment",
                    cutoff: float | None = 4.0) -> dict[str, np.ndarray]:
    """Direction of each stance foot's push on the ground, ``{side: (T,)}`` [rad] from the
    downward vertical, positive when it points forward (+x); NaN where the foot is in swing.

    Models (DESIGN §5): ``segment`` — the shank's absolute angle θ1+θ2 (knee → ankle; knee →
    sole for legs without an ankle); ``com`` — from the whole-body centre of mass to the sole
    (inverted pendulum); ``grf`` — the reverse of the net ground reaction force
    f = m·(c̈ − g), with c̈ from central finite differences of the Pinocchio centre of mass
    low-passed at ``cutoff`` [Hz] (2nd-order Butterworth, zero phase; ``None``: unfiltered —
    the usual gait-analysis practice, as differentiating twice amplifies noise); in double
    support both feet get the net direction, as the split is unknown.
    """
    if model not in FORCE_MODELS:
        raise UnknownNameError("force model", model, FORCE_MODELS)
    _check(robot, motion)
    if not motion.contact or any(s not in motion.contact for s in SIDES):
        raise InvalidInputError("force_direction needs motion.contact for 'left' and 'right'")
    out = {}
    if model == "segment":
        ank = ankle_paths(robot, motion)
        for s in SIDES:
            k = joint_paths(robot, motion.q, [robot.legs[s].knee])[robot.legs[s].knee]
            out[s] = angle_down(ank[s] - k)
    elif model == "com":
        c = com_path(robot, motion)
        sole = sole_paths(robot, motion)
        for s in SIDES:
            out[s] = angle_down(sole[s] - c)
    else:
        c = com_path(robot, motion)
        rate = 1.0 / motion.dt
        if cutoff is not None and cutoff < rate / 2 and motion.T > 15:
            from scipy.signal import butter, filtfilt

            b, a = butter(2, cutoff / (rate / 2))
            c = filtfilt(b, a, c, axis=0)
        acc = np.gradient(np.gradient(c, motion.t, axis=0), motion.t, axis=0)
        f = robot.mass * (acc - np.array([0.0, 0.0, -GRAVITY]))  # GRF on the robot
        for s in SIDES:
            out[s] = angle_down(-f)
    for s in SIDES:
        out[s] = np.where(motion.contact[s], out[s], np.nan)
    return out


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
