"""Body maps: which of the demonstrator's joints and segments correspond to the imitator's.

A :class:`BodyMap` pairs

- joints: ``{demonstrator joint: (imitator joint, scale, offset)}`` — the imitator's angle
  target is ``scale · q_demo + offset`` [rad];
- segments: ``{demonstrator frame: imitator frame}`` — body frames whose world orientation the
  imitator should copy (pelvis, torso).

Presets (:func:`body_map`) cover the demonstrators this package ships or reads — the 3-D
OpenSim human (``hip_flexion_r``, ``knee_angle_r``, ``ankle_angle_r``, ``lumbar_extension``,
``arm_flex_r``, ``arm_add_r``, ``arm_rot_r``, ``elbow_flex_r`` …; bodies ``pelvis``,
``femur_r`` … ``torso``), BVH skeletons (``Hips``, ``LeftUpLeg``, ``LeftLeg``, ``LeftFoot``,
``LeftToeBase``, ``Spine``, ``LeftArm``, ``LeftForeArm`` …) and the planar models
(``left_hip``, ``left_knee``, ``left_ankle``) — and the imitators Talos, G1, iCub, Romeo and
the planar HOAP-2-sized model. Joints are paired by *role* (hip pitch/roll/yaw, knee, ankle
pitch/roll, torso pitch/roll/yaw, shoulder pitch/roll/yaw, elbow); each pair's ``scale`` is
±1, the sign of the dot product of the two joint axes in the world frame (a pair whose axes
are not within 60° of each other is dropped) — legs and torso at the robots' neutral poses
(a BVH skeleton's at :func:`legs_down`: its rest pose may splay the legs, CMU's by 20°),
arms at their arms-down poses (:func:`arms_down`: a BVH T-pose's upper arms rolled down,
Romeo's forward-pointing arms pitched down), the ``offset`` mapping the one onto the other.
A demonstrator without arms (gait2354's subject01) maps none: the imitator's arms are then
unmapped and held (:data:`HOLD_RANGE`). A user's own map is a dict or a JSON file
(:meth:`BodyMap.from_dict`, :meth:`BodyMap.from_json`); names are checked against the robots.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError, UnknownNameError
from ..model.robot import Robot

__all__ = ["BodyMap", "body_map", "ROLES", "UnmappedJointsWarning", "HOLD_RANGE", "arms_down",
           "legs_down", "following", "JointFollowing"]

#: How far [rad] an imitator joint the body map leaves out may move from its rest pose
#: (:func:`~gdimitate.retarget.parts.self_collision.rest_pose`: the neutral pose with the limbs
#: clear of each other; a hard bound of the adaptor,
#: :class:`~gdimitate.retarget.parts.posture_range.PostureRange`).
HOLD_RANGE = 0.1

ROLES = ("hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll",
         "torso_pitch", "torso_roll", "torso_yaw", "shoulder_pitch", "shoulder_roll",
         "shoulder_yaw", "elbow")
"""Joint roles the presets pair (per side for the legs)."""


class UnmappedJointsWarning(UserWarning):
    """Some actuated joints of the imitator have no demonstrator joint: they are held near the
    imitator's rest pose (its neutral pose with the limbs clear of each other)."""


# role -> name pattern per naming family; {s} = side token of that family
_FAMILIES: dict[str, tuple[dict[str, str], dict[str, str]]] = {
    # family: (side tokens, role -> name)
    "opensim": ({"left": "l", "right": "r"}, {
        "hip_pitch": "hip_flexion_{s}", "hip_roll": "hip_adduction_{s}",
        "hip_yaw": "hip_rotation_{s}", "knee": "knee_angle_{s}",
        "ankle_pitch": "ankle_angle_{s}", "ankle_roll": "subtalar_angle_{s}",
        "torso_pitch": "lumbar_extension", "torso_roll": "lumbar_bending",
        "torso_yaw": "lumbar_rotation", "shoulder_pitch": "arm_flex_{s}",
        "shoulder_roll": "arm_add_{s}", "shoulder_yaw": "arm_rot_{s}",
        "elbow": "elbow_flex_{s}"}),
    "talos": ({"left": "left", "right": "right"}, {
        "hip_yaw": "leg_{s}_1_joint", "hip_roll": "leg_{s}_2_joint",
        "hip_pitch": "leg_{s}_3_joint", "knee": "leg_{s}_4_joint",
        "ankle_pitch": "leg_{s}_5_joint", "ankle_roll": "leg_{s}_6_joint",
        "torso_yaw": "torso_1_joint", "torso_pitch": "torso_2_joint",
        "shoulder_pitch": "arm_{s}_1_joint", "shoulder_roll": "arm_{s}_2_joint",
        "shoulder_yaw": "arm_{s}_3_joint", "elbow": "arm_{s}_4_joint"}),
    "g1": ({"left": "left", "right": "right"}, {
        "hip_pitch": "{s}_hip_pitch_joint", "hip_roll": "{s}_hip_roll_joint",
        "hip_yaw": "{s}_hip_yaw_joint", "knee": "{s}_knee_joint",
        "ankle_pitch": "{s}_ankle_pitch_joint", "ankle_roll": "{s}_ankle_roll_joint",
        "torso_yaw": "waist_yaw_joint", "torso_roll": "waist_roll_joint",
        "torso_pitch": "waist_pitch_joint", "shoulder_pitch": "{s}_shoulder_pitch_joint",
        "shoulder_roll": "{s}_shoulder_roll_joint", "shoulder_yaw": "{s}_shoulder_yaw_joint",
        "elbow": "{s}_elbow_joint"}),
    "icub": ({"left": "l", "right": "r"}, {
        "hip_pitch": "{s}_hip_pitch", "hip_roll": "{s}_hip_roll", "hip_yaw": "{s}_hip_yaw",
        "knee": "{s}_knee", "ankle_pitch": "{s}_ankle_pitch", "ankle_roll": "{s}_ankle_roll",
        "torso_pitch": "torso_pitch", "torso_roll": "torso_roll", "torso_yaw": "torso_yaw",
        "shoulder_pitch": "{s}_shoulder_pitch", "shoulder_roll": "{s}_shoulder_roll",
        "shoulder_yaw": "{s}_shoulder_yaw", "elbow": "{s}_elbow"}),
    "romeo": ({"left": "L", "right": "R"}, {
        "hip_pitch": "{s}HipPitch", "hip_roll": "{s}HipRoll", "hip_yaw": "{s}HipYaw",
        "knee": "{s}KneePitch", "ankle_pitch": "{s}AnklePitch", "ankle_roll": "{s}AnkleRoll",
        "torso_yaw": "TrunkYaw", "shoulder_pitch": "{s}ShoulderPitch",
        "shoulder_roll": "{s}ShoulderYaw", "shoulder_yaw": "{s}ElbowYaw",
        "elbow": "{s}ElbowRoll"}),
    "planar": ({"left": "left", "right": "right"}, {
        "hip_pitch": "{s}_hip", "knee": "{s}_knee", "ankle_pitch": "{s}_ankle"}),
    "bvh": ({"left": "Left", "right": "Right"}, {
        "hip_pitch": "{s}UpLeg_Xrotation", "hip_roll": "{s}UpLeg_Zrotation",
        "hip_yaw": "{s}UpLeg_Yrotation", "knee": "{s}Leg_Xrotation",
        "ankle_pitch": "{s}Foot_Xrotation", "ankle_roll": "{s}Foot_Zrotation",
        "torso_pitch": "Spine_Xrotation", "torso_roll": "Spine_Zrotation",
        "torso_yaw": "Spine_Yrotation", "shoulder_pitch": "{s}Arm_Yrotation",
        "shoulder_roll": "{s}Arm_Zrotation", "shoulder_yaw": "{s}Arm_Xrotation",
        "elbow": "{s}ForeArm_Yrotation"}),
}

#: Each family's "arms down" reference pose (joint → value [rad]) where its zero pose holds
#: the arms otherwise: BVH skeletons rest in a T-pose (the upper arm rolled ∓90° about the
#: forward axis hangs it), Romeo's arms point forward at zero (its shoulder pitch at +90°
#: hangs them). Arm roles are paired — axes compared, offsets set — at these poses; the
#: other families' zero poses already hang the arms.
_ARMS_DOWN: dict[str, dict[str, float]] = {
    "bvh": {"LeftArm_Zrotation": -np.pi / 2, "RightArm_Zrotation": np.pi / 2},
    "romeo": {"LShoulderPitch": np.pi / 2, "RShoulderPitch": np.pi / 2},
}
_ARM_ROLES = ("shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow")

# segment presets: family -> (pelvis body, torso body)
_SEGMENTS = {
    "opensim": ("pelvis", "torso"), "bvh": ("Hips", "Spine"), "talos": ("base_link",
                                                                        "torso_2_link"),
    "g1": ("pelvis", "torso_link"), "icub": ("root_link", "chest"), "romeo": ("body", "torso"),
    "planar": ("torso", None),
}


def _family(robot: Robot) -> str | None:
    names = set(robot.joint_names)
    frames = {f.name for f in robot.model.frames}
    for fam, (sides, roles) in _FAMILIES.items():
        probe = roles.get("knee", "").format(s=sides["left"])
        if probe in names or (fam == "bvh" and "LeftUpLeg" in frames):
            return fam
    return None


def _role_names(fam: str) -> dict[str, str]:
    sides, roles = _FAMILIES[fam]
    out = {}
    for role, pat in roles.items():
        if "{s}" in pat:
            for side, tok in sides.items():
                out[f"{side}_{role}"] = pat.format(s=tok)
        else:
            out[role] = pat
    return out


def _axis(robot: Robot, joint: str, q: np.ndarray | None = None) -> np.ndarray | None:
    """World axis of a 1-DoF joint at ``q`` (default: the robot's neutral pose; None for other
    joints)."""
    m = robot.model
    if not m.existJointName(joint):
        return None
    jid = m.getJointId(joint)
    if m.joints[jid].nv != 1:
        return None
    pin.computeJointJacobians(m, robot.data, robot.neutral if q is None else q)
    J = pin.getJointJacobian(m, robot.data, jid, pin.LOCAL_WORLD_ALIGNED)
    col = J[:, m.joints[jid].idx_v]
    return col[3:] if np.linalg.norm(col[3:]) > 1e-9 else col[:3]


def _joint_entry(k: object, v: object) -> tuple[str, float, float]:
    """One ``joints`` entry → ``(imitator joint, scale, offset)``; a wrong shape or a scale or
    offset that is not a finite number is an :class:`InvalidInputError` naming the entry."""
    if isinstance(v, str):
        return (v, 1.0, 0.0)
    form = "give an imitator joint name or [name, scale, offset] (scale, offset: numbers)"
    if not isinstance(v, list | tuple) or len(v) not in (2, 3) or not isinstance(v[0], str):
        raise InvalidInputError(f"body map joint {k!r}: {form}; got {v!r:.200}")
    nums = []
    for what, x in zip(("scale", "offset [rad]"), (*v[1:], 0.0)):
        ok = isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool)
        if not ok or not np.isfinite(x):
            raise InvalidInputError(f"body map joint {k!r}: {what} must be a finite number; "
                                    f"got {x!r:.100} ({form})")
        nums.append(float(x))
    return (v[0], nums[0], nums[1])


@dataclass(frozen=True)
class BodyMap:
    """Correspondence from a demonstrator's joints/segments to an imitator's (module doc)."""

    joints: Mapping[str, tuple[str, float, float]] = field(default_factory=dict)
    segments: Mapping[str, str] = field(default_factory=dict)
    name: str = "custom"

    @classmethod
    def from_dict(cls, d: Mapping, name: str = "custom") -> BodyMap:
        """From ``{"joints": {demo: imitator | [imitator, scale, offset]}, "segments":
        {demo_frame: imitator_frame}}``."""
        if not isinstance(d, Mapping) or set(d) - {"joints", "segments"}:
            raise InvalidInputError("a body map is a dict with keys 'joints' and/or "
                                    f"'segments'; got {d!r:.200}")
        for key in ("joints", "segments"):
            if not isinstance(d.get(key, {}), Mapping):
                raise InvalidInputError(f"body map {key!r} must be a dict; got "
                                        f"{d[key]!r:.200}")
        joints = {}
        for k, v in dict(d.get("joints", {})).items():
            joints[str(k)] = _joint_entry(k, v)
        segs = {}
        for k, v in dict(d.get("segments", {})).items():
            if not isinstance(v, str):
                raise InvalidInputError(f"body map segment {k!r}: give an imitator frame name; "
                                        f"got {v!r:.200}")
            segs[str(k)] = v
        return cls(joints, segs, name)

    @classmethod
    def from_json(cls, path: str | Path) -> BodyMap:
        """Read :meth:`from_dict`'s format from a JSON file."""
        from ..model.inputs import read_json

        p = Path(path)
        d = read_json(p, "body map")  # bounded: size, nesting, digits; no NaN
        if not isinstance(d, dict):
            raise InvalidInputError(f"body map {p}: expected a JSON object "
                                    '{"joints": {...}, "segments": {...}}')
        return cls.from_dict(d, name=p.stem)

    def held(self, imitator: Robot) -> list[str]:
        """The imitator's 1-DoF joints no demonstrator joint drives: held near its rest
        pose."""
        mapped = {b for b, _, _ in self.joints.values()}
        return [j for j in _one_dof(imitator) if j not in mapped]

    def validate(self, demonstrator: Robot, imitator: Robot, preset: bool = False
                 ) -> BodyMap:
        """Check every name against the robots (:class:`UnknownNameError` lists the valid
        ones) and warn (:class:`UnmappedJointsWarning`) about imitator joints left unmapped
        that the user could map: with a user's map every one; with a preset (``preset``)
        those in a limb (left leg, right leg, the rest) where the demonstrator has a joint
        the preset left unmapped — the shipped walk's model has no arms, so G1's 14 arm
        joints have nothing to follow and are held without a warning (:meth:`held` lists
        them)."""
        for a, (b, _, _) in self.joints.items():
            for robot, name in ((demonstrator, a), (imitator, b)):
                if not robot.model.existJointName(name):
                    raise UnknownNameError(f"joint of {robot.name}", name, robot.joint_names)
                jid = robot.model.getJointId(name)
                if robot.model.joints[jid].nq != 1:
                    raise InvalidInputError(f"body map: {robot.name} joint {name!r} is not a "
                                            "1-DoF joint")
        for a, b in self.segments.items():
            for robot, name in ((demonstrator, a), (imitator, b)):
                if not robot.model.existFrame(name):
                    raise UnknownNameError(f"frame of {robot.name}", name,
                                           [f.name for f in robot.model.frames])
        act = _one_dof(imitator)
        missing = self.held(imitator)
        if preset:  # only where the demonstrator has a joint left over in the same limb
            spare = {_limb(demonstrator, j) for j in _one_dof(demonstrator)
                     if j not in self.joints}
            missing = [j for j in missing if _limb(imitator, j) in spare]
        if missing:
            held = len(self.held(imitator))
            why = ("" if not preset else
                   f" although the demonstrator has unmapped joints in the same body region "
                   f"(map them with body_map=; {held} of {len(act)} are held in all, the "
                   "rest where the demonstrator has nothing to follow)")
            warnings.warn(f"body map {self.name!r}: {len(missing)} of {len(act)} actuated "
                          f"joints of {imitator.name} have no demonstrator joint{why} and are "
                          f"held near its rest pose: {', '.join(missing)}",
                          UnmappedJointsWarning, stacklevel=3)
        return self


def body_map(demonstrator: Robot, imitator: Robot, user: BodyMap | Mapping | str | Path |
             None = None) -> BodyMap:
    """The body map for a robot pair: ``user``'s (a :class:`BodyMap`, dict or JSON path) or
    the preset for the two robots' naming families (module doc), validated."""
    if user is not None:
        bm = user if isinstance(user, BodyMap) else (
            BodyMap.from_dict(user) if isinstance(user, Mapping) else BodyMap.from_json(user))
        return bm.validate(demonstrator, imitator)
    fd, fi = _family(demonstrator), _family(imitator)
    joints = _preset_joints(demonstrator, imitator, fd, fi) if fd and fi else {}
    segs = {}
    if fd in _SEGMENTS and fi in _SEGMENTS:
        for a, b in zip(_SEGMENTS[fd], _SEGMENTS[fi]):
            if a and b and demonstrator.model.existFrame(a) and imitator.model.existFrame(b):
                segs[a] = b
    name = f"{fd or '?'}→{fi or '?'}"
    if not joints and not segs:
        raise InvalidInputError(
            f"no body-map preset pairs {demonstrator.name!r} with {imitator.name!r} (naming "
            f"families {fd!r}, {fi!r}; presets: {', '.join(_FAMILIES)}): pass body_map= as a "
            "dict {'joints': {...}, 'segments': {...}} or a JSON file")
    return BodyMap(joints, segs, name).validate(demonstrator, imitator, preset=True)


def _one_dof(robot: Robot) -> list[str]:
    """The robot's 1-DoF joints (not the planar base's)."""
    m = robot.model
    return [j for j in robot.joint_names
            if m.joints[m.getJointId(j)].nq == 1 and not j.startswith("base_")]


def _limb(robot: Robot, joint: str) -> str:
    """The body region of a joint: ``"left"``/``"right"`` for a joint in that leg (its hip
    joint's subtree); else the branch it hangs on (up its parents to the first joint whose
    parent has several children or is the base) by where that branch starts at the neutral
    pose, in the base frame: ``"upper_left"``/``"upper_right"`` more than a tenth of a leg
    length to a side (an arm), ``"middle"`` otherwise (trunk, head)."""
    m = robot.model
    jid = m.getJointId(joint)
    legs = getattr(robot, "legs", {}) or {}
    for side, leg in legs.items():
        if leg.hip and m.existJointName(leg.hip) and jid in m.subtrees[m.getJointId(leg.hip)]:
            return side
    base = {m.getJointId(n) for n in robot.joint_names if n.startswith("base_")} | {0, 1} \
        if robot.base == "free" else {0} | {m.getJointId(n) for n in robot.joint_names
                                             if n.startswith("base_")}
    children = np.bincount([m.parents[k] for k in range(1, m.njoints)], minlength=m.njoints)
    start = jid
    while m.parents[start] not in base and children[m.parents[start]] < 2:
        start = m.parents[start]
    d = robot.data
    pin.forwardKinematics(m, d, robot.neutral)
    root = d.oMi[max(base)] if max(base) > 0 else pin.SE3.Identity()
    y = float(root.actInv(d.oMi[start]).translation[1])
    length = float(np.mean([leg.length for leg in legs.values()])) if legs else 1.0
    return "middle" if abs(y) <= 0.1 * length else ("upper_left" if y > 0 else "upper_right")


def arms_down(robot: Robot, family: str | None = None) -> np.ndarray:
    """The robot's configuration with its arms hanging (:data:`_ARMS_DOWN`; the neutral pose
    for families whose zero pose hangs them) — where arm roles are paired and what the
    imitator's unmapped arm joints are held to."""
    q = robot.neutral.copy()
    for j, v in _ARMS_DOWN.get(family or _family(robot) or "", {}).items():
        if robot.model.existJointName(j):
            q[robot.idx_q(j)] = v
    return q


#: Families whose zero pose is a capture's calibration pose rather than a standing one: their
#: legs may hang splayed (CMU's skeletons: each hip→ankle line 20° out of the vertical), so
#: leg roles are paired at :func:`legs_down` instead of the zero pose.
_SPLAYED_LEGS = ("bvh",)


def _leg_tilt(robot: Robot, q: np.ndarray, side: str) -> float:
    """Frontal-plane angle [rad] of the ``side`` leg's hip→ankle line from the downward
    vertical at ``q`` (the free-flyer turned by ``robot.base_rotation`` to face +x, z up;
    positive: the ankle towards +y)."""
    q = q.copy()
    if robot.base == "free":
        q[3:7] = pin.Quaternion(np.asarray(robot.base_rotation)).coeffs()
    leg = robot.legs[side]
    m, d = robot.model, robot.data
    pin.forwardKinematics(m, d, q)
    hip = d.oMi[m.getJointId(leg.hip)].translation
    ank = d.oMi[m.getJointId(leg.ankle)].translation if leg.ankle else \
        (pin.updateFramePlacements(m, d), d.oMf[m.getFrameId(leg.sole)].translation)[1]
    v = ank - hip
    return float(np.arctan2(v[1], -v[2]))


def legs_down(robot: Robot, family: str | None = None) -> np.ndarray:
    """The robot's neutral pose with, for families whose zero pose may splay the legs
    (:data:`_SPLAYED_LEGS`), each hip-roll joint turned so that the hip→ankle line hangs
    vertically in the frontal plane (a standing subject's legs; found by a secant search on
    :func:`_leg_tilt`, to 1e-9 rad) — where leg roles are paired, the offset mapping this
    pose onto the imitator's neutral (its standing pose). Other families: the neutral pose.
    A hip-roll joint that cannot bring the line within 1e-3 rad of vertical is left at 0."""
    fam = family or _family(robot) or ""
    q = robot.neutral.copy()
    if fam not in _SPLAYED_LEGS:
        return q
    names = _role_names(fam)
    for side in ("left", "right"):
        joint = names.get(f"{side}_hip_roll")
        if joint is None or not robot.model.existJointName(joint) or side not in robot.legs:
            continue
        i = robot.idx_q(joint)
        qa, qb = q.copy(), q.copy()
        qb[i] = 0.1
        ta, tb = _leg_tilt(robot, qa, side), _leg_tilt(robot, qb, side)
        for _ in range(20):
            if abs(tb) < 1e-9 or abs(tb - ta) < 1e-15:
                break
            x = qb[i] - tb * (qb[i] - qa[i]) / (tb - ta)
            qa, ta = qb, tb
            qb = qb.copy()
            qb[i] = x
            tb = _leg_tilt(robot, qb, side)
        if abs(tb) < 1e-3 and abs(qb[i]) < np.pi / 2:
            q[i] = qb[i]
    return q


def _preset_joints(demonstrator: Robot, imitator: Robot, fd: str, fi: str
                   ) -> dict[str, tuple[str, float, float]]:
    """Role-paired joints: ``scale`` = the sign of the two world axes' dot product (pairs
    more than 60° apart dropped); legs and torso compared at the legs-down poses
    (:func:`legs_down`: the neutral pose but for a splayed BVH rest pose), arms at the
    arms-down poses, the offset mapping one onto the other."""
    rd, ri = _role_names(fd), _role_names(fi)
    qd = {False: legs_down(demonstrator, fd), True: arms_down(demonstrator, fd)}
    qi = {False: legs_down(imitator, fi), True: arms_down(imitator, fi)}
    joints = {}
    for role, dn in rd.items():
        iname = ri.get(role)
        if iname is None:
            continue
        arm = role.split("_", 1)[-1] in _ARM_ROLES
        ad, ai = _axis(demonstrator, dn, qd[arm]), _axis(imitator, iname, qi[arm])
        if ad is None or ai is None:
            continue
        c = float(ad @ ai) / (np.linalg.norm(ad) * np.linalg.norm(ai))
        if abs(c) >= 0.5:
            sign = float(np.sign(c))
            offset = (float(qi[arm][imitator.idx_q(iname)])
                      - sign * float(qd[arm][demonstrator.idx_q(dn)]))
            joints[dn] = (iname, sign, offset)
    return joints


@dataclass(frozen=True)
class JointFollowing:
    """How one mapped imitator joint follows its demonstrator joint over a motion: ``r``, the
    correlation of the two angle histories (NaN where either is constant);
    ``demonstrator_range`` [rad]: the range (max − min) of the demonstrator's angle mapped
    and clipped to the imitator's limits (``scale · q + offset``); ``imitator_range`` [rad];
    ``ratio``: imitator range / that (NaN where it is 0)."""

    demonstrator: str
    imitator: str
    r: float
    demonstrator_range: float
    imitator_range: float
    ratio: float


def following(bmap: BodyMap, demo, demonstrator: Robot, imitated, imitator: Robot
              ) -> dict[str, JointFollowing]:
    """``{imitator joint: JointFollowing}`` for every joint ``bmap`` maps: the demonstration
    ``demo`` (a :class:`~gdimitate.Motion` of ``demonstrator``, resampled linearly onto
    ``imitated.t``) against the imitator's motion ``imitated``."""
    t = imitated.t
    out = {}
    for dn, (iname, scale, offset) in bmap.joints.items():
        qd = np.interp(t, demo.t, demo.q[:, demonstrator.idx_q(dn)])
        i = imitator.idx_q(iname)
        lo, hi = imitator.model.lowerPositionLimit[i], imitator.model.upperPositionLimit[i]
        target = np.clip(scale * qd + offset, lo, hi)
        qi = imitated.q[:, i]
        r = (float(np.corrcoef(qd, qi)[0, 1]) if np.ptp(qd) > 1e-12 and np.ptp(qi) > 1e-12
             else float("nan"))
        dr, ir = float(np.ptp(target)), float(np.ptp(qi))
        out[iname] = JointFollowing(dn, iname, r, dr, ir, ir / dr if dr > 0 else float("nan"))
    return out


def _tokens(name: str) -> set[str]:  # pragma: no cover - helper for users' maps
    return set(re.split(r"[_\W]+", name.lower()))
