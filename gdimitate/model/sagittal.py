"""Between a robot's configuration q and docs/design.md §4's planar (sagittal) leg angles.

Per leg the planar angles are ``(θ1, θ2, θ3)``: θ1 the absolute thigh angle from the downward
vertical (torso pitch included), θ2 the knee angle relative to the thigh (negative in flexion),
θ3 the ankle angle relative to the shank (positive in dorsiflexion), all positive when the distal
end moves forward (+x). The torso angle has the same sign convention (for our planar models it is
``base_pitch``; for free-flyers, minus the base's rotation about +y).

A joint angle maps onto its planar angle as ``sign · q + offset`` (:class:`SagittalLeg`,
measured by :func:`sagittal_leg` when first asked, from the joint axes and segment directions
at the neutral pose). Only legs whose hip, knee and ankle turn about the lateral axis have
such a map: :func:`sagittal_leg` raises :class:`~gdimitate.errors.LegDetectionError` for any
other, and the 3-D core (:mod:`gdimitate.retarget`, the audit) never asks for it.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError, LegDetectionError
from ..types import SIDES
from .kinematics import (
    anchored_base_offsets,
    frame_paths,
    joint_paths,
    kinematic_contact,
    robot_motion,
)
from .kinematics import check_q as _check_q

if TYPE_CHECKING:
    from .robot import Robot

__all__ = ["SagittalLeg", "compose_q", "frame_paths", "ground_base", "joint_paths",
           "kinematic_contact", "leg_angles", "robot_motion", "sagittal_leg", "torso_angle"]


class SagittalLeg(NamedTuple):
    """A leg as the paper's planar two-link leg (docs/design.md §4).

    ``thigh``, ``shank`` [m]: hip→knee and knee→ankle in the robot's x–z plane at the neutral
    pose (= :attr:`gdimitate.Leg.thigh`/``shank``); ``foot`` [m]: the ankle's height above the
    sole; ``signs``, ``offsets`` (hip, knee, ankle): planar angle = sign·q + offset, the hip
    angle relative to the torso, the knee and ankle angles relative to their parent segment
    (an ankle-less leg: sign 1, offset 0)."""

    side: str
    thigh: float
    shank: float
    foot: float
    signs: tuple[float, float, float]
    offsets: tuple[float, float, float]


#: measured legs per robot (a robot's joints never change after loading)
_MEASURED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _axis_world(robot: Robot, joint: str, q: np.ndarray) -> np.ndarray:
    jid = robot.model.getJointId(joint)
    data = robot.model.createData()
    pin.computeJointJacobians(robot.model, data, q)
    J = pin.getJointJacobian(robot.model, data, jid, pin.LOCAL_WORLD_ALIGNED)
    return J[3:, robot.model.joints[jid].idx_v]


def _measure(robot: Robot, side: str) -> SagittalLeg:
    leg = robot.legs[side]
    q0 = pin.neutral(robot.model)
    if robot.base == "free":
        q0[3:7] = pin.Quaternion(robot.base_rotation).coeffs()
    ends = [leg.hip, leg.knee] + ([leg.ankle] if leg.ankle else [])
    p = joint_paths(robot, q0[None], ends)
    hip, knee = p[leg.hip][0], p[leg.knee][0]
    ankle = p[leg.ankle][0] if leg.ankle else frame_paths(robot, q0[None], [leg.sole])[leg.sole][0]

    def ang(v: np.ndarray) -> float:  # planar angle of v from the downward vertical, + forward
        return math.atan2(v[0], -v[2])

    signs = []
    for role, j in (("hip", leg.hip), ("knee", leg.knee), ("ankle", leg.ankle)):
        if j is None:
            signs.append(1.0)
            continue
        a = _axis_world(robot, j, q0)
        if abs(a[1]) < 0.9:
            raise LegDetectionError(
                f"{robot.name}: {side} {role} joint {j!r} turns about {np.round(a, 3)}, not "
                "about the lateral axis, so the leg has no planar (sagittal) angles: Eq. (1) "
                "and the 'analytic'/'copy' adaptors need pitch joints (pass them in legs=); "
                "the optimal adaptor (method='optimal') takes any axes")
        signs.append(-float(np.sign(a[1])))
    th_off, sh_off = ang(knee - hip), ang(ankle - knee)
    return SagittalLeg(side, leg.thigh, leg.shank, leg.foot, (signs[0], signs[1], signs[2]),
                       (th_off, sh_off - th_off, 0.0))


def sagittal_leg(robot: Robot, side: str) -> SagittalLeg:
    """``robot``'s ``side`` leg as the paper's planar leg (measured once per robot).
    :class:`~gdimitate.errors.LegDetectionError` where a hip, knee or ankle joint does not turn
    about the lateral axis (|cos| < 0.9 at the neutral pose)."""
    per_robot = _MEASURED.setdefault(robot, {})
    if side not in per_robot:
        per_robot[side] = _measure(robot, side)
    return per_robot[side]


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
        leg, sag = robot.legs[s], sagittal_leg(robot, s)
        a = np.zeros((len(q), 3))
        for k, j in enumerate((leg.hip, leg.knee, leg.ankle)):
            if j is not None:
                a[:, k] = sag.signs[k] * q[:, robot.idx_q(j)] + sag.offsets[k]
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
        leg, sag = robot.legs[side], sagittal_leg(robot, side)
        a = np.asarray(angles[side], dtype=float)
        if a.shape != (T, 3):
            raise InvalidInputError(f"angles[{side!r}] must have shape ({T}, 3); got {a.shape}")
        rel = a.copy()
        rel[:, 0] -= torso
        for k, j in enumerate((leg.hip, leg.knee, leg.ankle)):
            if j is not None:
                q[:, robot.idx_q(j)] = (rel[:, k] - sag.offsets[k]) / sag.signs[k]
    return q


def _set_base_xz(robot: Robot, q: np.ndarray, x: np.ndarray, z: np.ndarray) -> None:
    if robot.base == "planar":
        q[:, robot.idx_q("base_x")] = x
        q[:, robot.idx_q("base_z")] = z
    elif robot.base == "free":
        q[:, 0] = x
        q[:, 2] = z
    else:
        raise InvalidInputError(f"{robot.name} has a fixed base; it cannot be placed on the ground")


def ground_base(robot: Robot, q: np.ndarray, contact: Mapping[str, np.ndarray],
                x0: float = 0.0) -> np.ndarray:
    """Place the floating base so that the motion walks on the ground z = 0 without slipping.

    Base height: the lowest stance sole touches z = 0 (interpolated through flight phases).
    Base x: the *anchor* foot — the stance foot that has been down longest — stays where it
    landed; when it lifts off, the other stance foot becomes the anchor where it stands
    (:func:`gdimitate.model.kinematics.anchored_base_offsets`). In double support the second foot
    may slide if the legs disagree: that is what the metrics report. ``x0``: initial x of the
    base [m]. Returns a new ``(T, nq)`` array.
    """
    q = _check_q(robot, q).copy()
    T = len(q)
    _set_base_xz(robot, q, np.zeros(T), np.zeros(T))
    soles = frame_paths(robot, q, [robot.legs[s].sole for s in SIDES])
    rel = {s: soles[robot.legs[s].sole] for s in SIDES}  # relative to the base at x = z = 0
    off = anchored_base_offsets(rel, contact)
    z = off[:, 2]
    if np.all(np.isnan(z)):  # no stance knot: the lower sole on the ground
        z = -np.minimum(rel["left"][:, 2], rel["right"][:, 2])
    _set_base_xz(robot, q, x0 + off[:, 0], z)
    return q
