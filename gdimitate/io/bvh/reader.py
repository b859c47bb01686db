"""``read_bvh``: a BVH motion-capture file → a free-flyer :class:`~gdimitate.model.robot.Robot` and
its
:class:`~gdimitate.model.motion.Motion`."""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.spatial.transform import Rotation

from ...errors import BVHError, InvalidInputError
from ...model.contact import SoleContact, sole_frame_name
from ...model.kinematics import robot_motion
from ...model.motion import Motion
from ...model.robot import Robot
from .contacts import ContactRule, detect_contacts, estimate_floor, sole_corners
from .inertia import segment_inertias
from .parse import BVHFile, parse_bvh
from .skeleton import (
    LegChain,
    detect_scale,
    find_legs,
    hip_height_units,
    leg_splay,
    measure_sole,
    pitch_channel,
    world_turn,
    zero_pose,
)
from .urdf import ChannelJoint, skeleton_urdf

__all__ = ["BVHInfo", "read_bvh", "bvh_to_q", "channel_rotation", "is_reference_frame"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class BVHInfo:
    """What :func:`read_bvh` found and decided (also at ``robot.bvh_info``).

    ``path``; ``scale`` [m per file unit]; ``unit`` (its name, or ``"given"``);
    ``hip_height`` [m] (root to the lowest point at the zero pose); ``up``; ``turn`` (3, 3):
    x_ours = turn · x_bvh; ``skipped_first_frame``; ``frame_time`` [s]; ``floor`` [m]: the
    floor's height in the file's world (our axes), as estimated from the feet; ``grounded``:
    whether it was subtracted from the base height (``read_bvh(ground=True)``);
    ``unmatched``: links massed by length (not in the segment table); ``urdf``: the URDF text;
    ``channels``: where each frame column went."""

    path: str
    scale: float
    unit: str
    hip_height: float
    up: str
    turn: np.ndarray
    skipped_first_frame: bool
    frame_time: float
    floor: float
    grounded: bool
    unmatched: tuple[str, ...]
    urdf: str
    channels: tuple[ChannelJoint, ...]


def channel_rotation(channel: str, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(T, 3, 3)`` of one rotation channel (``"Xrotation"`` …) for angles
    ``(T,)`` [rad] (right-handed about the channel's axis)."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(angle), np.zeros_like(angle)
    axis = channel[0]
    if axis == "X":
        m = [[o, z, z], [z, c, -s], [z, s, c]]
    elif axis == "Y":
        m = [[c, z, s], [z, o, z], [-s, z, c]]
    else:
        m = [[c, -s, z], [s, c, z], [z, z, o]]
    return np.moveaxis(np.array(m), (0, 1), (-2, -1))


def is_reference_frame(bvh: BVHFile, factor: float = 10.0, min_deg: float = 2.0) -> bool:
    """Whether frame 0 is a reference pose (e.g. CMU's T-pose) rather than part of the motion:
    the RMS change of the rotation channels from frame 0 to frame 1 exceeds ``factor`` times the
    median RMS change between consecutive later frames and ``min_deg`` [deg]. Needs 4 frames."""
    F = bvh.frames
    cols = [j.column + k for j in bvh.joints for k, c in enumerate(j.channels)
            if c.endswith("rotation")]
    if F.shape[0] < 4 or not cols:
        return False
    d = np.diff(F[:, cols], axis=0)
    d = (d + 180.0) % 360.0 - 180.0
    rms = np.sqrt(np.mean(d**2, axis=1))
    typical = float(np.median(rms[1:]))
    return bool(rms[0] > max(factor * typical, min_deg))


def bvh_to_q(bvh: BVHFile, model: pin.Model, channels: tuple[ChannelJoint, ...],
             C: np.ndarray, scale: float, frames: np.ndarray | None = None) -> np.ndarray:
    """Pinocchio configurations ``(T, nq)`` of the frames ``(T, n_channels)`` (default: all
    of the file's): the free-flyer from the root's channels (position in metres in our axes,
    quaternion x, y, z, w, sign kept continuous), one angle per rotation channel [rad]
    (unwrapped in time), one length per non-root position channel [m]."""
    F = bvh.frames if frames is None else frames
    T = F.shape[0]
    root = bvh.joints[0]
    q = np.zeros((T, model.nq))
    p = np.tile(root.offset, (T, 1)).astype(float)
    R = np.tile(np.eye(3), (T, 1, 1))
    for k, c in enumerate(root.channels):
        x = F[:, root.column + k]
        if c.endswith("position"):
            p[:, "XYZ".index(c[0])] += x
        else:
            R = R @ channel_rotation(c, np.deg2rad(x))
    q[:, :3] = (p * scale) @ C.T
    quat = Rotation.from_matrix(C @ R @ C.T).as_quat()  # x, y, z, w
    flip = np.cumprod(np.where(np.sum(quat[1:] * quat[:-1], axis=1) < 0, -1.0, 1.0))
    quat[1:] *= flip[:, None]
    q[:, 3:7] = quat
    for cj in channels:
        if cj.joint is None:
            continue
        iq = model.joints[model.getJointId(cj.joint)].idx_q
        x = F[:, cj.column]
        q[:, iq] = np.unwrap(np.deg2rad(x)) if cj.channel.endswith("rotation") else x * scale
    return q


def _robot_legs(bvh: BVHFile, legs, C):
    chains = find_legs(bvh, legs)
    spec = {}
    for s, ch in chains.items():
        spec[s] = {role: f"{bvh.joints[i].name}_{pitch_channel(bvh, i, C)}"
                   for role, i in (("hip", ch.hip), ("knee", ch.knee), ("ankle", ch.ankle))}
        spec[s]["sole"] = f"{s}_sole"
    return chains, spec


def read_bvh(path: str | Path, *, scale: float | None = None,
             skip_first_frame: bool | None = None, up: str = "y", name: str | None = None,
             mass: float = 75.0,
             contacts: ContactRule | Mapping[str, np.ndarray] | None = None,
             legs: Mapping[str, Mapping[str, str]] | None = None,
             ground: bool = True, urdf_path: str | Path | None = None
             ) -> tuple[Robot, Motion]:
    """Read a BVH file → ``(robot, motion)``.

    The skeleton becomes a URDF (see :mod:`gdimitate.io.bvh.urdf`: a link per BVH joint, one
    joint per channel in the file's order, the root's channels as the free-flyer), loaded as a
    :class:`~gdimitate.model.robot.Robot` with ``legs=`` (hip/knee/ankle: the thigh's, shank's and
    foot's rotation channel whose axis is lateral at the zero pose) and ``contacts=`` (sole
    rectangles, :func:`gdimitate.io.bvh.skeleton.measure_sole`) given explicitly. The motion's
    ``q`` ``(T, nq)`` is Pinocchio's: free-flyer position [m] in our world (x forward, y left,
    z up) and quaternion (x, y, z, w), then one angle per rotation channel [rad].

    - ``scale`` [m per file unit]: ``None`` detects the unit from the hip height at the zero
      pose (:func:`gdimitate.io.bvh.skeleton.detect_scale`: m, cm, mm, inches, CMU units); the
      choice is logged and kept in ``robot.bvh_info``.
    - ``skip_first_frame``: drop frame 0 (CMU's T-pose). ``None`` detects it
      (:func:`is_reference_frame`). Times start at 0 on the first kept frame.
    - ``up``: the file's up axis, ``"y"`` (facing +Z) or ``"z"`` (facing −Y); see
      :data:`gdimitate.io.bvh.skeleton.UP_TURNS`. The subject keeps its walking direction; the
      Robot's :attr:`~gdimitate.model.robot.Robot.base_rotation` measures its facing at the zero
      pose.
    - ``name``: the robot's name (default: the file's stem). ``mass`` [kg]: total body mass,
      spread by de Leva's (1996) segment table (:mod:`gdimitate.io.bvh.inertia`).
    - ``contacts``: the stance masks ``{"left": (T,) bool, "right": (T,) bool}`` (after any
      skipped frame), or a :class:`~gdimitate.io.bvh.contacts.ContactRule` for the detection from
      foot height and speed (default thresholds when ``None``).
    - ``legs``: BVH joint names ``{"left": {"hip", "knee", "ankle", "toe"?}, "right": …}``
      where the names do not follow a known convention.
    - ``ground``: lower (or raise) the base on every frame by the floor height estimated from
      the clip (:func:`gdimitate.io.bvh.contacts.estimate_floor`), so that the floor is z = 0;
      ``robot.bvh_info.floor`` keeps that height. ``False`` keeps the file's heights.
    - ``urdf_path``: also write the URDF there (``robot.urdf_path``).

    Raises :class:`~gdimitate.errors.BVHError` for malformed files and skeletons it cannot
    convert, :class:`~gdimitate.errors.LegDetectionError` when the legs cannot be found.
    """
    bvh = parse_bvh(path)
    C = world_turn(up)
    if not (isinstance(mass, (int, float, np.floating)) and np.isfinite(mass) and mass > 0):
        raise InvalidInputError(f"mass must be a positive number of kg; got {mass!r}")
    scale, unit, hip_height = _scale(bvh, C, scale)
    robot, xml, cmap, unmatched = _skeleton_robot(bvh, name or Path(path).stem, C, scale,
                                                  mass, hip_height, legs, urdf_path)
    skip = is_reference_frame(bvh) if skip_first_frame is None else bool(skip_first_frame)
    frames = bvh.frames[1:] if skip else bvh.frames
    if frames.shape[0] < 2:
        raise BVHError(f"{bvh.path}: a motion needs at least 2 frames; the file has "
                       f"{bvh.frames.shape[0]}" + (" and the first (a reference pose) is skipped"
                                                   if skip else ""))
    q = bvh_to_q(bvh, robot.model, cmap, C, scale, frames)
    t = np.arange(frames.shape[0]) * bvh.frame_time
    corners = sole_corners(robot, q)
    floor = estimate_floor(corners)
    if ground:
        q[:, 2] -= floor
        corners = {s: c - np.array([0.0, 0.0, floor]) for s, c in corners.items()}
    contact = _stance(contacts, corners, t, hip_height, 0.0 if ground else floor)
    motion = robot_motion(robot, t, q, contact)
    robot.bvh_info = BVHInfo(str(path), float(scale), unit, float(hip_height), up, C, skip,
                             bvh.frame_time, floor, bool(ground), unmatched, xml, cmap)
    return robot, motion


def _scale(bvh: BVHFile, C: np.ndarray, scale: float | None) -> tuple[float, str, float]:
    """``(metres per file unit, how it was found, hip height [m])``."""
    if scale is None:
        scale, unit, h_units = detect_scale(bvh, C)
        log.info("%s: units detected as %s (hip height %.3g m)", bvh.path, unit, h_units * scale)
    else:
        if not (isinstance(scale, (int, float, np.floating)) and np.isfinite(scale)
                and scale > 0):
            raise BVHError(f"scale={scale!r} must be a positive number of metres per file unit")
        unit = "given"
        h_units = hip_height_units(bvh, C)
    return float(scale), unit, h_units * scale


def _skeleton_robot(bvh: BVHFile, name: str, C: np.ndarray, scale: float, mass: float,
                    hip_height: float, legs, urdf_path
                    ) -> tuple[Robot, str, tuple[ChannelJoint, ...], tuple[str, ...]]:
    """The skeleton as a :class:`Robot` (legs and sole rectangles given), with its URDF text,
    channel map and the segments de Leva's table does not name."""
    chains, leg_spec = _robot_legs(bvh, legs, C)
    soles = {s: (ch.ankle, measure_sole(bvh, ch, C, scale)) for s, ch in chains.items()}
    n_extra = sum(max(len(j.channels) - 1, 0) for j in bvh.joints[1:])
    inertias, unmatched = segment_inertias(bvh, C, scale, mass, n_extra)
    xml, cmap = skeleton_urdf(bvh, name, C, scale, inertias, soles, hip_height)
    model = pin.buildModelFromXML(xml, pin.JointModelFreeFlyer())
    visual = pin.buildGeomFromUrdfString(model, xml, pin.GeometryType.VISUAL)
    collision = pin.buildGeomFromUrdfString(model, xml, pin.GeometryType.COLLISION)
    sole_contacts = {s: SoleContact(s, sole_frame_name(s), sole.length / 2, sole.width / 2)
                     for s, (_, sole) in soles.items()}
    if urdf_path is not None:
        Path(urdf_path).write_text(xml)
    robot = Robot(name, model, visual, leg_spec, urdf_path=Path(urdf_path) if urdf_path
                  else None, contacts=sole_contacts, collision_model=collision)
    for s, ch in chains.items():
        thigh, shank = hanging_extents(bvh, ch, C, C.T @ np.array([1.0, 0.0, 0.0]))
        robot.legs[s] = replace(robot.legs[s], thigh=thigh * scale, shank=shank * scale)
    return robot, xml, cmap, unmatched


def hanging_extents(bvh: BVHFile, leg: LegChain, C: np.ndarray, fwd: np.ndarray
                    ) -> tuple[float, float]:
    """The thigh's and shank's extents in the sagittal plane [file units] with the leg
    hanging — turned about the subject's forward unit ``fwd`` ``(3,)`` (file axes) by
    −:func:`~.skeleton.leg_splay` — which is what :class:`~gdimitate.model.legs.Leg`'s ``thigh`` and
    ``shank`` mean (the reach walks are normalised by). Measured at a rest pose that splays the
    legs they would be short by the splay's cosine (CMU: 0.79 m instead of 0.84 m, so that
    the subject's hip height in stance read 1.02 legs, more than a leg's reach)."""
    pos, _ = zero_pose(bvh)
    up = C.T @ np.array([0.0, 0.0, 1.0])
    theta = leg_splay(bvh, leg, up, fwd)
    k = np.array([[0.0, -fwd[2], fwd[1]], [fwd[2], 0.0, -fwd[0]], [-fwd[1], fwd[0], 0.0]])
    down = np.eye(3) - np.sin(theta) * k + (1.0 - np.cos(theta)) * (k @ k)  # turn by -theta
    out = []
    for a, b in ((leg.hip, leg.knee), (leg.knee, leg.ankle)):
        v = down @ (pos[b] - pos[a])
        out.append(float(np.hypot(v @ fwd, v @ up)))
    return out[0], out[1]


def _stance(contacts, corners: dict[str, np.ndarray], t: np.ndarray, hip_height: float,
            floor: float) -> dict[str, np.ndarray]:
    """The stance masks: detected from the sole corners by a rule, or the ones given."""
    if contacts is None or isinstance(contacts, ContactRule):
        return detect_contacts(corners, t, hip_height, contacts or ContactRule(), floor)
    contact = {s: np.asarray(contacts[s], dtype=bool) for s in contacts}
    if set(contact) != {"left", "right"} or any(c.shape != t.shape for c in contact.values()):
        raise InvalidInputError(
            f"contacts= must map 'left' and 'right' to ({t.size},) bool arrays (one per "
            f"kept frame); got {({k: np.shape(v) for k, v in contacts.items()})}")
    return contact
