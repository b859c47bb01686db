"""Which joints and frame are a robot's legs: :func:`resolve_leg_names` (used by
:class:`~gdimitate.Robot`) and :func:`legs_example` (the ``--legs FILE.json`` a user writes
when detection needs help).

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

import numpy as np
import pinocchio as pin

from .errors import LegDetectionError, UnknownNameError

__all__ = ["SIDES", "legs_example", "resolve_leg_names", "side_of"]

SIDES = ("left", "right")
_ROLE_PATTERNS = {
    "hip": r"hip|hfe",
    "knee": r"knee|kfe",
    "ankle": r"ankle",
}
#: Frame names that say "sensor" (an IMU, a force-torque sensor, a camera…): never a sole.
_SENSOR_NAME = re.compile(r"imu|sensor|camera|lidar|(^|[_\W])ft([_\W]|$)|force_?torque", re.I)
_SOLE_PATTERNS = (r"sole", r"foot", r"toe", r"ankle")
_LATERAL_COS = 0.9


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
