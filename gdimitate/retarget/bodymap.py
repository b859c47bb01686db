"""Body maps: which of the demonstrator's joints and segments correspond to the imitator's.

A :class:`BodyMap` pairs

- joints: ``{demonstrator joint: (imitator joint, scale, offset)}`` — the imitator's angle
  target is ``scale · q_demo + offset`` [rad];
- segments: ``{demonstrator frame: imitator frame}`` — body frames whose world orientation the
  imitator should copy (pelvis, torso).

Presets (:func:`body_map`) cover the demonstrators this package ships or reads — the 3-D
OpenSim human (``hip_flexion_r``, ``knee_angle_r``, ``ankle_angle_r``, ``lumbar_extension`` …;
bodies ``pelvis``, ``femur_r`` … ``torso``), BVH skeletons (``Hips``, ``LeftUpLeg``, ``LeftLeg``,
``LeftFoot``, ``LeftToeBase``, ``Spine`` …) and the planar models (``left_hip``,
``left_knee``, ``left_ankle``) — and the imitators Talos, G1, iCub, Romeo and the planar
HOAP-2-sized model. Joints are paired by *role* (hip pitch/roll/yaw, knee, ankle pitch/roll,
torso pitch/roll/yaw); each pair's ``scale`` is ±1, the sign of the dot product of the two
joint axes in the world frame at the robots' neutral poses (a pair whose axes are not within
60° of each other is dropped). A user's own map is a dict or a JSON file
(:meth:`BodyMap.from_dict`, :meth:`BodyMap.from_json`); names are checked against the robots.
"""

from __future__ import annotations

import json
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError, UnknownNameError
from ..robot import Robot

__all__ = ["BodyMap", "body_map", "ROLES", "UnmappedJointsWarning"]

ROLES = ("hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll",
         "torso_pitch", "torso_roll", "torso_yaw")
"""Joint roles the presets pair (per side for the legs)."""


class UnmappedJointsWarning(UserWarning):
    """Some actuated joints of the imitator have no demonstrator joint: they are held near the
    imitator's neutral pose by the posture cost."""


# role -> name pattern per naming family; {s} = side token of that family
_FAMILIES: dict[str, tuple[dict[str, str], dict[str, str]]] = {
    # family: (side tokens, role -> name)
    "opensim": ({"left": "l", "right": "r"}, {
        "hip_pitch": "hip_flexion_{s}", "hip_roll": "hip_adduction_{s}",
        "hip_yaw": "hip_rotation_{s}", "knee": "knee_angle_{s}",
        "ankle_pitch": "ankle_angle_{s}", "ankle_roll": "subtalar_angle_{s}",
        "torso_pitch": "lumbar_extension", "torso_roll": "lumbar_bending",
        "torso_yaw": "lumbar_rotation"}),
    "talos": ({"left": "left", "right": "right"}, {
        "hip_yaw": "leg_{s}_1_joint", "hip_roll": "leg_{s}_2_joint",
        "hip_pitch": "leg_{s}_3_joint", "knee": "leg_{s}_4_joint",
        "ankle_pitch": "leg_{s}_5_joint", "ankle_roll": "leg_{s}_6_joint",
        "torso_yaw": "torso_1_joint", "torso_pitch": "torso_2_joint"}),
    "g1": ({"left": "left", "right": "right"}, {
        "hip_pitch": "{s}_hip_pitch_joint", "hip_roll": "{s}_hip_roll_joint",
        "hip_yaw": "{s}_hip_yaw_joint", "knee": "{s}_knee_joint",
        "ankle_pitch": "{s}_ankle_pitch_joint", "ankle_roll": "{s}_ankle_roll_joint",
        "torso_yaw": "waist_yaw_joint", "torso_roll": "waist_roll_joint",
        "torso_pitch": "waist_pitch_joint"}),
    "icub": ({"left": "l", "right": "r"}, {
        "hip_pitch": "{s}_hip_pitch", "hip_roll": "{s}_hip_roll", "hip_yaw": "{s}_hip_yaw",
        "knee": "{s}_knee", "ankle_pitch": "{s}_ankle_pitch", "ankle_roll": "{s}_ankle_roll",
        "torso_pitch": "torso_pitch", "torso_roll": "torso_roll", "torso_yaw": "torso_yaw"}),
    "romeo": ({"left": "L", "right": "R"}, {
        "hip_pitch": "{s}HipPitch", "hip_roll": "{s}HipRoll", "hip_yaw": "{s}HipYaw",
        "knee": "{s}KneePitch", "ankle_pitch": "{s}AnklePitch", "ankle_roll": "{s}AnkleRoll",
        "torso_yaw": "TrunkYaw"}),
    "planar": ({"left": "left", "right": "right"}, {
        "hip_pitch": "{s}_hip", "knee": "{s}_knee", "ankle_pitch": "{s}_ankle"}),
    "bvh": ({"left": "Left", "right": "Right"}, {
        "hip_pitch": "{s}UpLeg_Xrotation", "hip_roll": "{s}UpLeg_Zrotation",
        "hip_yaw": "{s}UpLeg_Yrotation", "knee": "{s}Leg_Xrotation",
        "ankle_pitch": "{s}Foot_Xrotation", "ankle_roll": "{s}Foot_Zrotation",
        "torso_pitch": "Spine_Xrotation", "torso_roll": "Spine_Zrotation",
        "torso_yaw": "Spine_Yrotation"}),
}

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


def _axis(robot: Robot, joint: str) -> np.ndarray | None:
    """World axis of a 1-DoF joint at the robot's neutral pose (None for other joints)."""
    m = robot.model
    if not m.existJointName(joint):
        return None
    jid = m.getJointId(joint)
    if m.joints[jid].nv != 1:
        return None
    pin.computeJointJacobians(m, robot.data, robot.neutral)
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
        p = Path(path)
        try:
            d = json.loads(p.read_text())
        except (OSError, json.JSONDecodeError) as e:
            raise InvalidInputError(f"cannot read the body map {p}: {e}") from None
        return cls.from_dict(d, name=p.stem)

    def validate(self, demonstrator: Robot, imitator: Robot) -> BodyMap:
        """Check every name against the robots (:class:`UnknownNameError` lists the valid
        ones) and warn (:class:`UnmappedJointsWarning`) about imitator joints left unmapped."""
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
        mapped = {b for b, _, _ in self.joints.values()}
        act = [j for j in imitator.joint_names
               if imitator.model.joints[imitator.model.getJointId(j)].nq == 1
               and not j.startswith("base_")]
        missing = [j for j in act if j not in mapped]
        if missing:
            warnings.warn(f"body map {self.name!r}: {len(missing)} of {len(act)} actuated "
                          f"joints of {imitator.name} have no demonstrator joint and are held "
                          f"near its neutral pose: {', '.join(missing)}", UnmappedJointsWarning,
                          stacklevel=3)
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
    joints: dict[str, tuple[str, float, float]] = {}
    if fd and fi:
        rd, ri = _role_names(fd), _role_names(fi)
        for role, dn in rd.items():
            iname = ri.get(role)
            if iname is None:
                continue
            ad, ai = _axis(demonstrator, dn), _axis(imitator, iname)
            if ad is None or ai is None:
                continue
            c = float(ad @ ai) / (np.linalg.norm(ad) * np.linalg.norm(ai))
            if abs(c) >= 0.5:
                joints[dn] = (iname, float(np.sign(c)), 0.0)
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
    return BodyMap(joints, segs, name).validate(demonstrator, imitator)


def _tokens(name: str) -> set[str]:  # pragma: no cover - helper for users' maps
    return set(re.split(r"[_\W]+", name.lower()))
