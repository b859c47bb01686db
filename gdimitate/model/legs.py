"""A robot's legs: which joints and frame they are (:func:`resolve_leg_names`, the presets
:data:`LEG_PRESETS`, :func:`legs_example` — the ``--legs FILE.json`` a user writes when
detection needs help) and what they measure (:class:`Leg`, :func:`measure_leg`,
:func:`measure_orientation`, :func:`sole_from_geometry`), for any joint axes: nothing here asks
a leg to move in the sagittal plane (the paper's planar measurements — joint signs and offsets
— are :mod:`gdimitate.planar`'s, computed when asked).

Detection, per side:

1. Side from name tokens (``left``/``right`` as words, ``Left``/``Right`` before a capital,
   ``l_``/``r_``, ``L``/``R`` before a capital, ``FL_``/``FR_``).
2. Roles from names (``hip``/``knee``/``ankle``, or ODRI's ``HFE``/``KFE``); among several
   candidates the joint whose axis is nearest the lateral axis (the pitch joint).
3. Where the names do not say the roles (e.g. Talos: ``leg_left_1_joint`` … ``_6_joint``),
   from the chain: the 1-DoF joints on the path from the root to the foot whose axis lies
   along the lateral axis (|cos| > 0.9) at the neutral pose, root to foot: the first is the
   hip, the last the ankle, and the knee is the one between them nearest half-way down
   (two such joints: hip and knee, a point foot).
4. Sole: the lowest body frame (farthest from the root at the neutral pose) of that side
   whose name says sole, foot, toe or ankle (first pattern that matches), never a sensor.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import LegDetectionError, UnknownNameError
from ..types import SIDES

__all__ = ["LEG_PRESETS", "Leg", "SIDES", "hip_height", "legs_example", "measure_leg",
           "measure_orientation", "resolve_leg_names", "side_of", "sole_from_geometry"]

#: Explicit legs for library robots whose joint names don't say hip/knee/ankle.
LEG_PRESETS: dict[str, dict[str, dict[str, str | None]]] = {
    "talos": {
        s: {"hip": f"leg_{s}_3_joint", "knee": f"leg_{s}_4_joint", "ankle": f"leg_{s}_5_joint",
            "sole": f"{s}_sole_link"} for s in SIDES
    },
    "human": {
        s: {"hip": f"{s}_hip_Z", "knee": f"{s}_knee_Z", "ankle": f"{s}_ankle_Z",
            "sole": f"{s}_foot"} for s in SIDES
    },
    "bolt": {
        s: {"hip": f"F{s[0].upper()}_HFE", "knee": f"F{s[0].upper()}_KFE", "ankle": None,
            "sole": f"F{s[0].upper()}_FOOT"} for s in SIDES
    },
}


@dataclass(frozen=True)
class Leg:
    """One leg of a robot, whatever its joint axes.

    ``hip``, ``knee``, ``ankle``: joint names (``ankle`` is ``None`` for point-footed robots
    such as Bolt); ``sole``: frame name of the contact point. Measured at the neutral pose (the
    robot turned to face +x with z up): ``thigh``, ``shank`` [m], the hip→knee and knee→ankle
    extents in the robot's own x–z plane (its reach: the scale walks are normalised by);
    ``segments`` [m], the same two segments' 3-D lengths (rigid: constant over any motion);
    ``foot`` [m], the ankle's height above the sole.

    The paper's planar measurements (the hip's, knee's and ankle's planar angle = sign·q +
    offset) are not a leg's: :func:`gdimitate.planar.sagittal_leg` measures them, and only for
    legs whose joints turn about the lateral axis.
    """

    side: str
    hip: str
    knee: str
    ankle: str | None
    sole: str
    thigh: float
    shank: float
    foot: float
    segments: tuple[float, float] = (0.0, 0.0)

    @property
    def length(self) -> float:
        """Thigh + shank [m] (x–z extents, see the class docstring)."""
        return self.thigh + self.shank


_ROLE_PATTERNS = {
    "hip": r"hip|hfe",
    "knee": r"knee|kfe",
    "ankle": r"ankle",
}
#: Frame names that say "sensor" (an IMU, a force-torque sensor, a camera…): never a sole.
_SENSOR_NAME = re.compile(r"imu|sensor|camera|lidar|(^|[_\W])ft([_\W]|$)|force_?torque", re.I)
_SOLE_PATTERNS = (r"sole", r"foot", r"toe", r"ankle")
_LATERAL_COS = 0.9


def hip_height(robot) -> float:
    """The hip's height [m] over the sole of the longer leg of ``robot`` standing straight
    (leg length plus foot height): the unit of the contact rules' thresholds."""
    return max(robot.legs[s].length + robot.legs[s].foot for s in SIDES)


def side_of(name: str) -> str | None:
    """``"left"``, ``"right"`` or ``None`` from a joint or frame name's tokens."""
    n = name
    if re.search(r"(^|[_\W])left([_\W]|$)", n, re.I) or \
            re.match(r"^(l_|L(?=[A-Z])|FL_|Left(?=[A-Z0-9]))", n):
        return "left"
    if re.search(r"(^|[_\W])right([_\W]|$)", n, re.I) or \
            re.match(r"^(r_|R(?=[A-Z])|FR_|Right(?=[A-Z0-9]))", n):
        return "right"
    return None


# ---------------------------------------------------------------------- geometry at q0
def _axis_world(robot, jid: int, q0: np.ndarray) -> np.ndarray:
    pin.computeJointJacobians(robot.model, robot.data, q0)
    J = pin.getJointJacobian(robot.model, robot.data, jid, pin.LOCAL_WORLD_ALIGNED)
    return J[3:, robot.model.joints[jid].idx_v]


def _lateral(robot) -> np.ndarray:
    """Unit vector from the right-side joints' mean position to the left-side ones'."""
    m = robot.model
    pin.forwardKinematics(m, robot.data, pin.neutral(m))
    pts = {s: [robot.data.oMi[i].translation for i, n in enumerate(m.names)
               if i > 0 and side_of(n) == s] for s in SIDES}
    if not pts["left"] or not pts["right"]:
        return np.array([0.0, 1.0, 0.0])
    v = np.mean(pts["left"], axis=0) - np.mean(pts["right"], axis=0)
    return v / (np.linalg.norm(v) or 1.0)


def _pick_pitch(robot, cands: list[str]) -> str:
    """Among same-side candidates, the joint whose axis is closest to the lateral axis."""
    q0, lat = pin.neutral(robot.model), _lateral(robot)
    score = [abs(float(_axis_world(robot, robot.model.getJointId(c), q0) @ lat)) for c in cands]
    return cands[int(np.argmax(score))]


def _lowest_frame(robot, frames: list[str]) -> str:
    """The frame farthest from the root at the neutral pose ("lowest" along the leg); of
    frames at the same place, the one on the most distal joint (where the foot's geometry
    hangs, e.g. the human's ``left_foot`` rather than ``left_foot_virtual``)."""
    m = robot.model
    pin.framesForwardKinematics(m, robot.data, pin.neutral(m))
    ids = [m.getFrameId(f) for f in frames]
    key = [(round(float(np.linalg.norm(robot.data.oMf[i].translation)), 9),
            m.frames[i].parentJoint) for i in ids]
    return frames[max(range(len(frames)), key=key.__getitem__)]


def _sole_candidates(robot, side: str) -> list[str]:
    bodies = [f.name for f in robot.model.frames if f.type == pin.FrameType.BODY
              and not _SENSOR_NAME.search(f.name)]
    for pat in _SOLE_PATTERNS:  # the first pattern that matches any of the side's frames
        found = [f for f in bodies if side_of(f) == side and re.search(pat, f, re.I)]
        if found:
            return found
    return []


def _chain(robot, frame: str) -> list[int]:
    """Moving 1-DoF joints from the root to ``frame``'s joint, root first."""
    m = robot.model
    j, out = m.frames[m.getFrameId(frame)].parentJoint, []
    while j > 0:
        if m.joints[j].nv == 1 and m.names[j] not in ("base_x", "base_z", "base_pitch"):
            out.append(j)
        j = m.parents[j]
    return out[::-1]


def _roles_from_chain(robot, sole: str) -> dict[str, str | None] | None:
    """Hip, knee and ankle from the lateral-axis joints of the chain to ``sole`` (module
    docstring, rule 3), or ``None`` when fewer than two lie along the lateral axis."""
    m = robot.model
    q0, lat = pin.neutral(m), _lateral(robot)
    pitch = [j for j in _chain(robot, sole)
             if abs(float(_axis_world(robot, j, q0) @ lat)) > _LATERAL_COS]
    if len(pitch) < 2:
        return None
    if len(pitch) == 2:
        return {"hip": m.names[pitch[0]], "knee": m.names[pitch[1]], "ankle": None}
    pin.forwardKinematics(m, robot.data, q0)
    z = {j: robot.data.oMi[j].translation for j in pitch}
    hip, ankle = pitch[0], pitch[-1]
    mid = 0.5 * (z[hip] + z[ankle])
    knee = min(pitch[1:-1], key=lambda j: float(np.linalg.norm(z[j] - mid)))
    return {"hip": m.names[hip], "knee": m.names[knee], "ankle": m.names[ankle]}


# ---------------------------------------------------------------------- the --legs example
def legs_example(robot) -> str:
    """A ``--legs FILE.json`` for ``robot``, filled with its own names: per side the best
    guess this module can make (chain roles, else the first, middle and last joint of the
    side's chain, else of its joints) — a starting point to check, not an answer."""
    m = robot.model
    joints = [n for j, n in enumerate(m.names) if j > 0 and m.joints[j].nv == 1]
    out = {}
    for s in SIDES:
        bodies = [f.name for f in m.frames if f.type == pin.FrameType.BODY
                  and not _SENSOR_NAME.search(f.name)]
        soles = _sole_candidates(robot, s) or [f for f in bodies if side_of(f) == s]
        sole = _lowest_frame(robot, soles) if soles else _lowest_frame(robot, bodies)
        guess = _roles_from_chain(robot, sole) if soles else None
        if guess is None:
            chain = [m.names[j] for j in _chain(robot, sole)] if soles else []
            chain = chain or [n for n in joints if side_of(n) == s] or joints or ["JOINT"]
            guess = {"hip": chain[0], "knee": chain[len(chain) // 2], "ankle": chain[-1]}
        out[s] = {**guess, "sole": sole}
    return json.dumps(out, indent=1)


def _detection_error(robot, what: str) -> LegDetectionError:
    return LegDetectionError(
        f"{what}. Joints: {list(robot.model.names)[1:]}. Pass legs={{'left': {{'hip': …, "
        "'knee': …, 'ankle': …, 'sole': …}, 'right': {…}} (CLI: --legs FILE.json); a "
        f"starting point for FILE.json, filled with {robot.name!r}'s own names — check each "
        f"(hip, knee, ankle: the pitch joints; sole: a frame under the foot):\n"
        f"{legs_example(robot)}")


# ---------------------------------------------------------------------- resolution
def _given(robot, legs) -> dict[str, dict[str, str | None]]:
    joints = list(robot.model.names)[1:]
    frames = [f.name for f in robot.model.frames]
    out = {}
    for s in SIDES:
        if s not in legs:
            raise LegDetectionError(f"legs= must give 'left' and 'right'; got {list(legs)}")
        d = dict(legs[s])
        for role in ("hip", "knee", "ankle"):
            j = d.get(role)
            if j is None and role == "ankle":
                continue
            if j not in joints:
                raise UnknownNameError("joint", j, joints)
        if d.get("sole") not in frames:
            raise UnknownNameError("frame", d.get("sole"), frames)
        out[s] = {k: d.get(k) for k in ("hip", "knee", "ankle", "sole")}
    return out


def _by_name(robot, s: str) -> tuple[dict[str, str | None], str | None]:
    """Roles from names; the first role no name gives (``None`` when all are found)."""
    m = robot.model
    joints = list(m.names)[1:]
    d: dict[str, str | None] = {}
    for role, pat in _ROLE_PATTERNS.items():
        cands = [j for j in joints if side_of(j) == s and re.search(pat, j, re.I)
                 and m.joints[m.getJointId(j)].nv == 1]
        if not cands:
            if role == "ankle":
                d[role] = None
                continue
            return d, role
        d[role] = _pick_pitch(robot, cands) if len(cands) > 1 else cands[0]
    return d, None


def resolve_leg_names(robot, legs=None) -> dict[str, dict[str, str | None]]:
    """``{"left": {"hip", "knee", "ankle", "sole"}, "right": …}`` (joint and frame names) of
    ``robot`` (a :class:`~gdimitate.Robot` under construction: ``model``, ``data``,
    ``name``): ``legs`` checked when given, else detected (module docstring). Raises
    :class:`~gdimitate.errors.LegDetectionError` (with a ``--legs`` example filled with the
    robot's own names) or :class:`~gdimitate.errors.UnknownNameError` (a given name the model
    lacks)."""
    if legs is not None:
        return _given(robot, legs)
    out = {}
    for s in SIDES:
        soles = _sole_candidates(robot, s)
        d, missing = _by_name(robot, s)
        if missing is not None:
            chain = _roles_from_chain(robot, _lowest_frame(robot, soles)) if soles else None
            if chain is None:
                raise _detection_error(
                    robot, f"cannot find the {s} {missing} joint of {robot.name!r}: no 1-DoF "
                    f"joint name has a {s}-side token (left/l_/L…/FL_) and matches "
                    f"/{_ROLE_PATTERNS[missing]}/i, and no {s} foot frame ends a chain of "
                    "lateral-axis joints")
            d = chain
        if not soles:
            raise _detection_error(
                robot, f"cannot find the {s} sole frame of {robot.name!r}: no body frame name "
                f"with a {s}-side token matches /sole/, /foot/, /toe/ or /ankle/")
        d["sole"] = _lowest_frame(robot, soles)
        out[s] = d
    return out


# ---------------------------------------------------------------------- measurements
def _turned_neutral(robot) -> np.ndarray:
    """Pinocchio's neutral pose with a free-flyer turned by ``robot.base_rotation``."""
    q0 = pin.neutral(robot.model)
    if robot.base == "free":
        q0[3:7] = pin.Quaternion(robot.base_rotation).coeffs()
    return q0


def _position(robot, joint: str | None = None, frame: str | None = None) -> np.ndarray:
    """World position of a joint's origin or a frame after forward kinematics (``robot.data``)."""
    if joint is not None:
        return robot.data.oMi[robot.model.getJointId(joint)].translation.copy()
    return robot.data.oMf[robot.model.getFrameId(frame)].translation.copy()


def measure_orientation(robot, spec: dict[str, dict[str, str | None]]) -> np.ndarray:
    """The constant base rotation ``(3, 3)`` that turns ``robot`` to face +x with z up: rows
    are the world x, y, z axes in model coordinates, with up from the soles to the hips and
    left from the right hip to the left one (at Pinocchio's neutral pose). Identity for a
    non-floating model, which must already face +x with z up (:class:`LegDetectionError`)."""
    pin.framesForwardKinematics(robot.model, robot.data, pin.neutral(robot.model))
    up = np.mean([_position(robot, spec[s]["hip"]) - _position(robot, frame=spec[s]["sole"])
                  for s in SIDES], axis=0)
    up /= np.linalg.norm(up)
    left = _position(robot, spec["left"]["hip"]) - _position(robot, spec["right"]["hip"])
    left -= (left @ up) * up
    if np.linalg.norm(left) < 1e-6:
        raise LegDetectionError(f"{robot.name}: the left and right hips coincide; "
                                "cannot tell left from right")
    left /= np.linalg.norm(left)
    fwd = np.cross(left, up)
    R0 = np.vstack([fwd, left, up])
    if robot.base != "free" and not np.allclose(R0, np.eye(3), atol=1e-6):
        raise LegDetectionError(
            f"{robot.name}: a non-floating model must face +x with z up (found forward "
            f"{np.round(fwd, 3)}, up {np.round(up, 3)})")
    return R0 if robot.base == "free" else np.eye(3)


def sole_from_geometry(robot, side: str, names: dict[str, str | None],
                       min_gap: float = 0.01) -> str:
    """The sole frame to use: where the foot's visual geometry reaches more than ``min_gap``
    [m] below the named sole frame (e.g. example-robot-data's ``human``, whose "foot" frame
    sits at the ankle), a frame ``<side>_sole_auto`` is added directly below the sole frame at
    the geometry's lowest point (neutral pose) and its name returned (``robot.data`` is made
    anew). Legs without an ankle (point feet) keep their frame."""
    sole_name = str(names["sole"])
    if robot.visual_model is None or names["ankle"] is None:
        return sole_name
    m = robot.model
    fid = m.getFrameId(sole_name)
    parent = m.frames[fid].parentJoint
    pin.framesForwardKinematics(m, robot.data, _turned_neutral(robot))
    sole = robot.data.oMf[fid].translation
    low = sole[2]
    for g in robot.visual_model.geometryObjects:
        if g.parentJoint != parent or not hasattr(g.geometry, "vertices"):
            continue
        v = np.asarray(g.geometry.vertices())
        if v.size == 0:
            continue
        M = robot.data.oMi[parent] * g.placement
        low = min(low, float((v @ M.rotation.T + M.translation)[:, 2].min()))
    if sole[2] - low <= min_gap:
        return sole_name
    target = sole - np.array([0.0, 0.0, sole[2] - low])
    placement = pin.SE3(np.eye(3), robot.data.oMi[parent].actInv(target))
    name = f"{side}_sole_auto"
    m.addFrame(pin.Frame(name, parent, fid, placement, pin.FrameType.OP_FRAME))
    robot.data = m.createData()
    return name


def measure_leg(robot, side: str, names: dict[str, str | None]) -> Leg:
    """A :class:`Leg` of ``robot`` (``model``, ``data``, ``base``, ``base_rotation``) from its
    joint and sole names, measured at the turned neutral pose. Any joint axes."""
    pin.framesForwardKinematics(robot.model, robot.data, _turned_neutral(robot))
    hip, knee = _position(robot, names["hip"]), _position(robot, names["knee"])
    sole = _position(robot, frame=names["sole"])
    ankle = _position(robot, names["ankle"]) if names["ankle"] else sole
    return Leg(
        side=side, hip=str(names["hip"]), knee=str(names["knee"]), ankle=names["ankle"],
        sole=str(names["sole"]),
        thigh=float(np.hypot(*(knee - hip)[[0, 2]])),
        shank=float(np.hypot(*(ankle - knee)[[0, 2]])),
        foot=float(ankle[2] - sole[2]),
        segments=(float(np.linalg.norm(knee - hip)), float(np.linalg.norm(ankle - knee))),
    )
