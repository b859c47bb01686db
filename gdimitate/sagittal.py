"""Between a robot's configuration q and docs/design.md §4's planar (sagittal) leg angles.

Per leg the planar angles are ``(θ1, θ2, θ3)``: θ1 the absolute thigh angle from the downward
vertical (torso pitch included), θ2 the knee angle relative to the thigh (negative in flexion),
θ3 the ankle angle relative to the shank (positive in dorsiflexion), all positive when the distal
end moves forward (+x). The torso angle has the same sign convention (for our planar models it is
``base_pitch``; for free-flyers, minus the base's rotation about +y).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .errors import InvalidInputError
from .kinematics import check_q as _check_q
from .kinematics import robot_motion
from .robot import SIDES, Robot

__all__ = ["leg_angles", "compose_q", "frame_paths", "joint_paths", "ground_base",
           "kinematic_contact", "robot_motion", "torso_angle"]


def torso_angle(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Torso planar angle ``(T,)`` [rad] (0 = upright as at the neutral pose)."""
    q = _check_q(robot, q)
    if robot.base == "planar":
        return q[:, robot.idx_q("base_pitch")].copy()
    if robot.base == "free":
        out = np.empty(len(q))
        for i, qi in enumerate(q):
            R = pin.Quaternion(qi[3:7]).normalized().matrix() @ robot.base_rotation.T
            out[i] = -np.arctan2(R[0, 2], R[0, 0])  # rotation about +y is φ; planar = −φ
        return out
    return np.zeros(len(q))


def leg_angles(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """``(torso (T,), {side: (T, 3)})``: torso angle and per-leg planar ``(θ1, θ2, θ3)`` [rad]."""
    q = _check_q(robot, q)
    torso = torso_angle(robot, q)
    out = {}
    for s in SIDES:
        leg = robot.legs[s]
        a = np.zeros((len(q), 3))
        for k, j in enumerate((leg.hip, leg.knee, leg.ankle)):
            if j is not None:
                a[:, k] = leg.signs[k] * q[:, robot.idx_q(j)] + leg.offsets[k]
        a[:, 0] += torso
        out[s] = a
    return torso, out


def compose_q(robot: Robot, torso: np.ndarray, angles: dict[str, np.ndarray],
              template: np.ndarray | None = None) -> np.ndarray:
    """Configurations ``(T, nq)`` with the given torso angle ``(T,)`` and planar leg angles
    ``{side: (T, 3)}``; every other joint as in ``template`` ``(nq,)`` (default: the grounded
    neutral pose). Base position is left at the template's; see :func:`ground_base`."""
    torso = np.asarray(torso, dtype=float)
    T = torso.shape[0]
    base = robot.neutral if template is None else np.asarray(template, dtype=float)
    q = np.tile(base, (T, 1))
    if robot.base == "planar":
        q[:, robot.idx_q("base_pitch")] = torso
    elif robot.base == "free":
        for i, th in enumerate(torso):
            c, s = np.cos(-th), np.sin(-th)
            Ry = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
            q[i, 3:7] = pin.Quaternion(Ry @ robot.base_rotation).coeffs()
    for side in SIDES:
        leg = robot.legs[side]
        a = np.asarray(angles[side], dtype=float)
        if a.shape != (T, 3):
            raise InvalidInputError(f"angles[{side!r}] must have shape ({T}, 3); got {a.shape}")
        rel = a.copy()
        rel[:, 0] -= torso
        for k, j in enumerate((leg.hip, leg.knee, leg.ankle)):
            if j is not None:
                q[:, robot.idx_q(j)] = (rel[:, k] - leg.offsets[k]) / leg.signs[k]
    return q


def frame_paths(robot: Robot, q: np.ndarray, frames: list[str]) -> dict[str, np.ndarray]:
    """World positions ``{frame: (T, 3)}`` [m] of the named frames (Pinocchio FK)."""
    q = _check_q(robot, q)
    ids = [robot.frame_id(f) for f in frames]
    out = {f: np.empty((len(q), 3)) for f in frames}
    m, d = robot.model, robot.data
    for i, qi in enumerate(q):
        pin.forwardKinematics(m, d, qi)
        for f, fid in zip(frames, ids):
            out[f][i] = pin.updateFramePlacement(m, d, fid).translation
    return out


def joint_paths(robot: Robot, q: np.ndarray, joints: list[str]) -> dict[str, np.ndarray]:
    """World positions ``{joint: (T, 3)}`` [m] of the named joints' origins."""
    q = _check_q(robot, q)
    ids = [robot.model.getJointId(robot.joint_names[robot.joint_names.index(j)]) for j in joints]
    out = {j: np.empty((len(q), 3)) for j in joints}
    for i, qi in enumerate(q):
        pin.forwardKinematics(robot.model, robot.data, qi)
        for j, jid in zip(joints, ids):
            out[j][i] = robot.data.oMi[jid].translation
    return out


def _set_base_xz(robot: Robot, q: np.ndarray, x: np.ndarray, z: np.ndarray) -> None:
    if robot.base == "planar":
        q[:, robot.idx_q("base_x")] = x
        q[:, robot.idx_q("base_z")] = z
    elif robot.base == "free":
        q[:, 0] = x
        q[:, 2] = z
    else:
        raise InvalidInputError(f"{robot.name} has a fixed base; it cannot be placed on the ground")


def ground_base(robot: Robot, q: np.ndarray, contact: dict[str, np.ndarray],
                x0: float = 0.0) -> np.ndarray:
    """Place the floating base so that the motion walks on the ground z = 0 without slipping.

    Base height: the lowest stance sole touches z = 0 (interpolated through flight phases).
    Base x: the *anchor* foot — the stance foot that has been down longest — stays where it
    landed; when it lifts off, the other stance foot becomes the anchor where it stands. In
    double support the second foot may slide if the legs disagree: that is what the metrics
    report. ``x0``: initial x of the base [m]. Returns a new ``(T, nq)`` array.
    """
    q = _check_q(robot, q).copy()
    T = len(q)
    _set_base_xz(robot, q, np.zeros(T), np.zeros(T))
    soles = frame_paths(robot, q, [robot.legs[s].sole for s in SIDES])
    rel = {s: soles[robot.legs[s].sole] for s in SIDES}  # relative to the base at x = z = 0
    c = {s: np.asarray(contact[s], dtype=bool) for s in SIDES}
    z = np.full(T, np.nan)
    for i in range(T):
        down = [rel[s][i, 2] for s in SIDES if c[s][i]]
        if down:
            z[i] = -min(down)
    if np.all(np.isnan(z)):
        z[:] = -np.minimum(rel["left"][:, 2], rel["right"][:, 2])
    ok = ~np.isnan(z)
    z = np.interp(np.arange(T), np.flatnonzero(ok), z[ok])
    x = np.empty(T)
    anchor, foot_x = None, 0.0
    since = {s: -1 for s in SIDES}
    for i in range(T):
        for s in SIDES:
            if not c[s][i]:
                since[s] = -1
            elif since[s] < 0:
                since[s] = i
        if anchor is None or not c[anchor][i]:
            cands = [s for s in SIDES if c[s][i]]
            if cands:
                new = min(cands, key=lambda s: since[s])
                if i == 0:
                    foot_x = x0 + rel[new][0, 0]
                elif c[new][i - 1]:  # already down: it stays where it stood at i − 1
                    foot_x = x[i - 1] + rel[new][i - 1, 0]
                else:  # just landed: where it touches down, base continuing from i − 1
                    foot_x = x[i - 1] + rel[new][i, 0]
                anchor = new
        if anchor is not None and c[anchor][i]:
            x[i] = foot_x - rel[anchor][i, 0]
        else:
            x[i] = x[i - 1] if i > 0 else x0  # flight: keep (a ballistic model is out of scope)
    x += x0 - x[0]
    _set_base_xz(robot, q, x, z)
    return q


def kinematic_contact(robot: Robot, q: np.ndarray, tol: float | None = None
                      ) -> dict[str, np.ndarray]:
    """Stance flags ``{side: (T,)}``: a sole is in stance while it is within ``tol`` [m]
    (default 2 % of the leg length) of the lower sole."""
    soles = frame_paths(robot, q, [robot.legs[s].sole for s in SIDES])
    z = {s: soles[robot.legs[s].sole][:, 2] for s in SIDES}
    low = np.minimum(z["left"], z["right"])
    tol = 0.02 * robot.legs["left"].length if tol is None else tol
    return {s: z[s] - low < tol for s in SIDES}
