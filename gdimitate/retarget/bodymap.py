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
unmapped and held (:data:`HOLD_RANGE`).

The naming families are data: one JSON file per family in :data:`FAMILY_DIR`
(``gdimitate/data/bodymaps/``; :func:`family_from_dict` gives the schema and
docs/guide/your-robot.md shows one), validated when first used (:func:`families`; a malformed
file is a :class:`~gdimitate.errors.BodyMapError` that says what to fix). A user's own map is
a dict or a JSON file (:meth:`BodyMap.from_dict`, :meth:`BodyMap.from_json`), or a naming
family of the user's robot in a file of the same schema, passed as ``body_map=``; names are
checked against the robots.
"""

from __future__ import annotations

import functools
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from importlib.abc import Traversable
from os import PathLike
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import BodyMapError, InvalidInputError, UnknownNameError
from ..model.robot import Robot

__all__ = ["BodyMap", "body_map", "ROLES", "UnmappedJointsWarning", "HOLD_RANGE", "arms_down",
           "legs_down", "following", "JointFollowing", "Family", "families", "family_from_dict",
           "family_from_json", "FAMILY_DIR"]

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


#: Where the shipped naming families live: one JSON file per family (the schema:
#: :func:`family_from_dict`; docs/guide/your-robot.md).
FAMILY_DIR = resources.files("gdimitate") / "data" / "bodymaps"

_FAMILY_KEYS = {"family": "a name", "description": "free text",
                "priority": "an integer: families are tried in ascending order",
                "match": '{"joints": [...], "frames": [...]}', "sides": '{"left": …, "right": …}',
                "roles": "{role: joint name}", "segments": '{"pelvis": …, "torso": …}',
                "arms_down": "{joint: angle [rad]}", "splayed_legs": "true or false"}
_REQUIRED = ("family", "match", "sides", "roles")
_ARM_ROLES = ("shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow")


@dataclass(frozen=True)
class Family:
    """A naming family (one file of :data:`FAMILY_DIR`): how its robots name the joints that
    play each role of :data:`ROLES`, and the poses where roles are paired.

    ``roles``: role → joint name, where ``{s}`` stands for ``sides[side]`` (a per-side role:
    ``left_`` and ``right_`` roles) and a name without it is one joint (the torso's);
    ``match_joints``/``match_frames``: a robot is of this family when it has one of these
    joints or frames; ``segments``: the ``(pelvis, torso)`` frames whose rotations a preset
    pairs (``None``: none); ``arms_down``: joint → angle [rad] hanging the arms where the
    zero pose does not (a BVH T-pose, Romeo's forward arms); ``splayed_legs``: the zero pose
    may splay the legs (a capture's calibration pose: legs paired at :func:`legs_down`);
    ``priority``: families are tried in ascending ``(priority, name)``."""

    name: str
    sides: Mapping[str, str]
    roles: Mapping[str, str]
    match_joints: tuple[str, ...] = ()
    match_frames: tuple[str, ...] = ()
    segments: tuple[str | None, str | None] = (None, None)
    arms_down: Mapping[str, float] = field(default_factory=dict)
    splayed_legs: bool = False
    priority: int = 100
    description: str = ""

    def names(self) -> dict[str, str]:
        """``{role: joint}``, per-side roles as ``left_<role>``/``right_<role>``, in the
        file's order (the order a preset's joints take)."""
        out = {}
        for role, pat in self.roles.items():
            if "{s}" in pat:
                for side, tok in self.sides.items():
                    out[f"{side}_{role}"] = pat.format(s=tok)
            else:
                out[role] = pat
        return out

    def matches(self, robot: Robot) -> bool:
        """Whether ``robot`` has one of :attr:`match_joints` or :attr:`match_frames`."""
        if set(self.match_joints) & set(robot.joint_names):
            return True
        return bool(self.match_frames) and bool(
            set(self.match_frames) & {f.name for f in robot.model.frames})


def _fail(where: str, what: str) -> BodyMapError:
    return BodyMapError(f"body-map family {where}: {what} (docs/guide/your-robot.md)")


def _names(value: object, where: str, key: str) -> tuple[str, ...]:
    """A JSON list of distinct non-empty strings, or :class:`BodyMapError`."""
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise _fail(where, f"{key} must be a list of names; got {value!r:.120}")
    dup = sorted({v for v in value if value.count(v) > 1})
    if dup:
        raise _fail(where, f"{key} lists {dup[0]!r} twice")
    return tuple(value)


def _roles(d: Mapping, where: str) -> tuple[dict[str, str], dict[str, str]]:
    """``(sides, roles)`` of a family dict, checked: sides ``left``/``right`` → distinct
    tokens; roles among :data:`ROLES`, each a name whose only placeholder is ``{s}``, no two
    naming one joint."""
    sides, roles = d["sides"], d["roles"]
    if (not isinstance(sides, Mapping) or set(sides) != {"left", "right"}
            or not all(isinstance(v, str) and v for v in sides.values())
            or sides["left"] == sides["right"]):
        raise _fail(where, 'sides must be {"left": token, "right": token}, two different '
                    f"non-empty strings that replace {{s}} in the roles; got {sides!r:.120}")
    if not isinstance(roles, Mapping) or not roles:
        raise _fail(where, f"roles must be a non-empty object {{role: joint name}}; got "
                    f"{roles!r:.120}")
    for role, pat in roles.items():
        if role not in ROLES:
            raise UnknownNameError(f"body-map role (in {where})", role, ROLES)
        if not isinstance(pat, str) or not pat or pat.replace("{s}", "").count("{") \
                or pat.replace("{s}", "").count("}"):
            raise _fail(where, f"role {role!r}: give a joint name, {{s}} standing for the "
                        f"side token; got {pat!r:.120}")
    fam = Family("", dict(sides), dict(roles))
    seen: dict[str, str] = {}
    for role, joint in fam.names().items():
        if joint in seen:
            raise _fail(where, f"roles {seen[joint]!r} and {role!r} both name joint {joint!r}")
        seen[joint] = role
    return dict(sides), dict(roles)


def family_from_dict(d: object, where: str = "<dict>") -> Family:
    """A :class:`Family` from its JSON object (``where`` names it in messages)::

        {"family": "g1", "description": "…", "priority": 30,
         "match": {"joints": ["left_knee_joint"], "frames": []},
         "sides": {"left": "left", "right": "right"},
         "roles": {"hip_pitch": "{s}_hip_pitch_joint", …, "torso_yaw": "waist_yaw_joint"},
         "segments": {"pelvis": "pelvis", "torso": "torso_link"},
         "arms_down": {}, "splayed_legs": false}

    ``family``, ``match``, ``sides`` and ``roles`` are required (:class:`Family` says what
    each means); a missing or unknown key, a role outside :data:`ROLES`, an ``arms_down``
    joint the roles do not name, a name given twice or a value of the wrong type is a
    :class:`~gdimitate.errors.BodyMapError` (an unknown role an
    :class:`~gdimitate.errors.UnknownNameError`) that says what to fix."""
    if not isinstance(d, Mapping):
        raise _fail(where, f"expected a JSON object; got {type(d).__name__}")
    unknown = sorted(set(d) - set(_FAMILY_KEYS))
    if unknown:
        raise _fail(where, f"unknown key {unknown[0]!r}; valid keys: " + ", ".join(
            f"{k!r} ({v})" for k, v in _FAMILY_KEYS.items()))
    missing = [k for k in _REQUIRED if k not in d]
    if missing:
        raise _fail(where, f"missing key(s) {', '.join(map(repr, missing))}; required: "
                    + ", ".join(f"{k!r} ({_FAMILY_KEYS[k]})" for k in _REQUIRED))
    name = d["family"]
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise _fail(where, f"family must be a name of letters, digits, '_', '.', '-'; got "
                    f"{name!r:.80}")
    where = f"{name!r} ({where})"
    sides, roles = _roles(d, where)
    match = d["match"]
    if not isinstance(match, Mapping) or set(match) - {"joints", "frames"}:
        raise _fail(where, 'match must be {"joints": [names], "frames": [names]}; got '
                    f"{match!r:.120}")
    mj = _names(match.get("joints", []), where, "match.joints")
    mf = _names(match.get("frames", []), where, "match.frames")
    if not mj and not mf:
        raise _fail(where, "match names no joint and no frame: give the joint (or frame) "
                    "that tells this family's robots apart, e.g. its left knee")
    segs = d.get("segments", {})
    if not isinstance(segs, Mapping) or set(segs) - {"pelvis", "torso"} or not all(
            v is None or (isinstance(v, str) and v) for v in segs.values()):
        raise _fail(where, 'segments must be {"pelvis": frame or null, "torso": frame or '
                    f"null}}; got {segs!r:.120}")
    joints = Family(name, sides, roles).names().values()
    arms = d.get("arms_down", {})
    if not isinstance(arms, Mapping):
        raise _fail(where, f"arms_down must be an object {{joint: angle [rad]}}; got "
                    f"{arms!r:.120}")
    for j, v in arms.items():
        if j not in joints:
            raise UnknownNameError(f"arms_down joint (in {where}; the roles' joints)", j,
                                   list(joints))
        if isinstance(v, bool) or not isinstance(v, int | float) or not np.isfinite(v):
            raise _fail(where, f"arms_down {j!r}: an angle [rad] must be a finite number; "
                        f"got {v!r:.80}")
    splayed, prio = d.get("splayed_legs", False), d.get("priority", 100)
    if not isinstance(splayed, bool):
        raise _fail(where, f"splayed_legs must be true or false; got {splayed!r:.80}")
    if isinstance(prio, bool) or not isinstance(prio, int):
        raise _fail(where, f"priority must be an integer; got {prio!r:.80}")
    desc = d.get("description", "")
    if not isinstance(desc, str):
        raise _fail(where, f"description must be a string; got {desc!r:.80}")
    return Family(name, sides, roles, mj, mf, (segs.get("pelvis"), segs.get("torso")),
                  {j: float(v) for j, v in arms.items()}, splayed, prio, desc)


def family_from_json(path: str | Path | Traversable) -> Family:
    """:func:`family_from_dict` of a JSON file (read within the bounds of
    :mod:`gdimitate.model.inputs`; a key repeated in one object is an error)."""
    from ..model.inputs import read_json

    p = path if isinstance(path, Path | str) else Path(str(path))
    return family_from_dict(read_json(p, "body-map family", BodyMapError, unique_keys=True),
                            str(p))


@functools.cache
def families() -> tuple[Family, ...]:
    """The shipped naming families (every ``*.json`` of :data:`FAMILY_DIR`, validated), in the
    order they are tried: ascending ``(priority, name)``."""
    found = [family_from_json(f) for f in FAMILY_DIR.iterdir() if f.name.endswith(".json")]
    return _ordered(found)


def _ordered(found: list[Family]) -> tuple[Family, ...]:
    names = [f.name for f in found]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise BodyMapError(f"two body-map family files name the family {dup[0]!r}: rename one")
    return tuple(sorted(found, key=lambda f: (f.priority, f.name)))


def _lookup(family: Family | str | None, robot: Robot) -> Family | None:
    """``family`` (a name is looked up among :func:`families`), else ``robot``'s."""
    if isinstance(family, Family):
        return family
    if family:
        return next((f for f in families() if f.name == family), None)
    return _family(robot)


def _family(robot: Robot, among: tuple[Family, ...] | None = None) -> Family | None:
    """The first family (of ``among``, default :func:`families`) that matches ``robot``."""
    return next((f for f in (families() if among is None else among) if f.matches(robot)),
                None)


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
    offset that is not a finite number is a :class:`BodyMapError` naming the entry."""
    if isinstance(v, str):
        return (v, 1.0, 0.0)
    form = "give an imitator joint name or [name, scale, offset] (scale, offset: numbers)"
    if not isinstance(v, list | tuple) or len(v) not in (2, 3) or not isinstance(v[0], str):
        raise BodyMapError(f"body map joint {k!r}: {form}; got {v!r:.200}")
    nums = []
    for what, x in zip(("scale", "offset [rad]"), (*v[1:], 0.0)):
        ok = isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool)
        if not ok or not np.isfinite(x):
            raise BodyMapError(f"body map joint {k!r}: {what} must be a finite number; "
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
            raise BodyMapError("a body map is a dict with keys 'joints' and/or 'segments' (a "
                               "naming family, with 'roles', is body_map='family.json'); got "
                               f"{d!r:.200}")
        for key in ("joints", "segments"):
            if not isinstance(d.get(key, {}), Mapping):
                raise BodyMapError(f"body map {key!r} must be a dict; got {d[key]!r:.200}")
        joints = {}
        for k, v in dict(d.get("joints", {})).items():
            joints[str(k)] = _joint_entry(k, v)
        segs = {}
        for k, v in dict(d.get("segments", {})).items():
            if not isinstance(v, str):
                raise BodyMapError(f"body map segment {k!r}: give an imitator frame name; "
                                   f"got {v!r:.200}")
            segs[str(k)] = v
        for what, targets in (("joint", [b for b, _, _ in joints.values()]),
                              ("frame", list(segs.values()))):
            dup = next((t for t in targets if targets.count(t) > 1), None)
            if dup is not None:  # two targets for one imitator joint or frame
                raise BodyMapError(f"body map: imitator {what} {dup!r} is mapped from "
                                   f"{targets.count(dup)} demonstrator {what}s; map it once")
        return cls(joints, segs, name)

    @classmethod
    def from_json(cls, path: str | Path) -> BodyMap:
        """Read :meth:`from_dict`'s format from a JSON file (a key given twice in one object
        is a :class:`~gdimitate.errors.BodyMapError`)."""
        from ..model.inputs import read_json

        p = Path(path)
        d = read_json(p, "body map", BodyMapError, unique_keys=True)  # bounded; no NaN
        if not isinstance(d, dict):
            raise BodyMapError(f"body map {p}: expected a JSON object "
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
    """The body map for a robot pair, validated: ``user``'s — a :class:`BodyMap`, a dict or a
    JSON file of :meth:`BodyMap.from_dict`'s format, or a naming family (a dict or JSON file
    with ``roles``, :func:`family_from_dict`; tried before the shipped ones, replacing one of
    its name) — else the preset for the two robots' naming families (module doc)."""
    among = families()
    if user is not None:
        given = _given(user)
        if isinstance(given, BodyMap):
            return given.validate(demonstrator, imitator)
        among = (given, *(f for f in among if f.name != given.name))
    fd, fi = _family(demonstrator, among), _family(imitator, among)
    joints = _preset_joints(demonstrator, imitator, fd, fi) if fd and fi else {}
    segs = {}
    if fd and fi:
        for a, b in zip(fd.segments, fi.segments):
            if a and b and demonstrator.model.existFrame(a) and imitator.model.existFrame(b):
                segs[a] = b
    nd, ni = (fd.name if fd else None), (fi.name if fi else None)
    name = f"{nd or '?'}→{ni or '?'}"
    if not joints and not segs:
        raise InvalidInputError(
            f"no body-map preset pairs {demonstrator.name!r} with {imitator.name!r} (naming "
            f"families {nd!r}, {ni!r}; presets: {', '.join(f.name for f in among)}): pass "
            "body_map= as a dict {'joints': {...}, 'segments': {...}} or a JSON file")
    return BodyMap(joints, segs, name).validate(demonstrator, imitator, preset=True)


def _given(user: BodyMap | Mapping | str | Path) -> BodyMap | Family:
    """A user's ``body_map=``: a map as it is, or read from a dict or a JSON file — a naming
    family where it has ``roles``."""
    if isinstance(user, BodyMap):
        return user
    if isinstance(user, Mapping):
        return family_from_dict(user) if "roles" in user else BodyMap.from_dict(user)
    if not isinstance(user, str | PathLike):
        raise BodyMapError("body_map= must be a BodyMap, a dict or a JSON file's path; got "
                           f"{type(user).__name__}")
    from ..model.inputs import read_json

    p = Path(user)
    d = read_json(p, "body map", BodyMapError, unique_keys=True)
    if isinstance(d, dict) and "roles" in d:
        return family_from_dict(d, str(p))
    if not isinstance(d, dict):
        raise BodyMapError(f"body map {p}: expected a JSON object "
                           '{"joints": {...}, "segments": {...}} or a naming family')
    return BodyMap.from_dict(d, name=p.stem)


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


def arms_down(robot: Robot, family: Family | str | None = None) -> np.ndarray:
    """The robot's configuration with its arms hanging (its family's ``arms_down``, by default
    the family of :func:`families` that matches it; the neutral pose for families whose zero
    pose hangs them) — where arm roles are paired and what the imitator's unmapped arm joints
    are held to."""
    q = robot.neutral.copy()
    fam = _lookup(family, robot)
    for j, v in (fam.arms_down if fam else {}).items():
        if robot.model.existJointName(j):
            q[robot.idx_q(j)] = v
    return q


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


def legs_down(robot: Robot, family: Family | str | None = None) -> np.ndarray:
    """The robot's neutral pose with, for families whose zero pose may splay the legs
    (``splayed_legs``: a capture's calibration pose, not a standing one — CMU's skeletons'
    hip→ankle lines hang 20° out of the vertical), each hip-roll joint turned so that the
    hip→ankle line hangs vertically in the frontal plane (a standing subject's legs; found
    by a secant search on :func:`_leg_tilt`, to 1e-9 rad) — where leg roles are paired, the
    offset mapping this pose onto the imitator's neutral (its standing pose). Other
    families: the neutral pose.
    A hip-roll joint that cannot bring the line within 1e-3 rad of vertical is left at 0."""
    fam = _lookup(family, robot)
    q = robot.neutral.copy()
    if fam is None or not fam.splayed_legs:
        return q
    names = fam.names()
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


def _preset_joints(demonstrator: Robot, imitator: Robot, fd: Family, fi: Family
                   ) -> dict[str, tuple[str, float, float]]:
    """Role-paired joints: ``scale`` = the sign of the two world axes' dot product (pairs
    more than 60° apart dropped); legs and torso compared at the legs-down poses
    (:func:`legs_down`: the neutral pose but for a splayed BVH rest pose), arms at the
    arms-down poses, the offset mapping one onto the other."""
    rd, ri = fd.names(), fi.names()
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
