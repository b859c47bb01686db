"""A robot's kinematics over a trajectory, for any leg axes (3-D; docs/design.md §3).

The one place for what many modules need of a robot's configurations ``q`` ``(T, nq)``:

- frame and joint placements along a trajectory (:func:`frame_placements`,
  :func:`frame_paths`, :func:`joint_paths`, :func:`frame_rotations`) — Pinocchio forward
  kinematics, one call per knot, on a ``pin.Data`` of their own (``robot.data`` is left alone);
- the base: its kind's configuration width (:func:`base_nq`), which velocity indices are the
  unactuated base and which the actuated joints (:func:`base_v_indices`,
  :func:`actuated_v_indices`), the joint whose body is the base (:func:`base_joint_id`);
- the anchor-foot rule that puts a walk on the floor without slipping
  (:func:`anchor_schedule`, :func:`anchored_base_offsets`) and stance from the soles' heights
  (:func:`kinematic_contact`);
- a robot's configurations as a :class:`~gdimitate.Motion` (:func:`robot_motion`).

It takes the robot as an argument and imports :mod:`gdimitate.model.robot` for type annotations
only,
so loaders below :class:`~gdimitate.Robot` (``gdimitate.io.opensim``) can use it without a cycle.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ..errors import InvalidInputError, UnknownNameError
from ..types import SIDES
from .motion import Motion
from .urdfgen import PLANAR_BASE

if TYPE_CHECKING:
    from .robot import Robot

__all__ = ["Placements", "cross", "actuated_v_indices", "anchor_schedule", "anchored_base_offsets",
           "base_joint_id", "base_nq", "base_v_indices", "check_q", "frame_paths",
           "frame_placements", "frame_rotations", "joint_paths", "kinematic_contact",
           "robot_motion", "PLANAR_BASE"]


def check_q(robot: Robot, q: np.ndarray) -> np.ndarray:
    """``q`` as a float array ``(T, nq)`` of ``robot``; InvalidInputError on another shape."""
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != robot.model.nq:
        raise InvalidInputError(
            f"q must have shape (T, {robot.model.nq}) for {robot.name}; got {q.shape}")
    return q


# ---------------------------------------------------------------------- the base
def base_nq(robot: Robot) -> int:
    """Width of the base in ``q``: 7 (free-flyer ``[x, y, z, qx, qy, qz, qw]``), 3 (our planar
    ``base_x, base_z, base_pitch``) or 0 (fixed)."""
    return {"free": 7, "planar": 3}.get(robot.base, 0)


def base_v_indices(robot: Robot) -> np.ndarray:
    """Indices ``(nb,)`` in ``v`` of the unactuated base: the free-flyer's 0–5 (local twist,
    linear first), the planar base's ``base_x``, ``base_z``, ``base_pitch``; empty when fixed."""
    if robot.base == "free":
        return np.arange(6)
    if robot.base == "planar":
        return np.array([robot.idx_v(j) for j in PLANAR_BASE], dtype=int)
    return np.zeros(0, dtype=int)


def actuated_v_indices(robot: Robot) -> np.ndarray:
    """Indices ``(nv − nb,)`` in ``v`` of every joint that is not the base, in order."""
    return np.setdiff1d(np.arange(robot.model.nv), base_v_indices(robot))


def base_joint_id(robot: Robot) -> int | None:
    """Pinocchio id of the joint whose body is the floating base: the free-flyer (1) or the
    last planar base joint (``base_pitch``); ``None`` for a fixed base."""
    if robot.base == "free":
        return 1
    if robot.base == "planar":
        return int(robot.model.getJointId(PLANAR_BASE[-1]))
    return None


# ---------------------------------------------------------------------- placements
class Placements(NamedTuple):
    """World placements of one frame along a trajectory: ``translation`` ``(T, 3)`` [m] and
    ``rotation`` ``(T, 3, 3)`` (columns: the frame's axes in the world)."""

    translation: np.ndarray
    rotation: np.ndarray


def _ids(robot: Robot, names: Sequence[str], kind: str) -> list[int]:
    m = robot.model
    if kind == "frame":
        return [robot.frame_id(f) for f in names]
    for j in names:
        if not m.existJointName(j):
            raise UnknownNameError("joint", j, robot.joint_names)
    return [int(m.getJointId(j)) for j in names]


def _placements(robot: Robot, q: np.ndarray, names: Sequence[str], kind: str
                ) -> dict[str, Placements]:
    import pinocchio as pin

    q = check_q(robot, q)
    m = robot.model
    d = m.createData()
    ids = _ids(robot, names, kind)
    T = len(q)
    out = {n: Placements(np.empty((T, 3)), np.empty((T, 3, 3))) for n in names}
    for i, qi in enumerate(q):
        pin.forwardKinematics(m, d, qi)
        for n, k in zip(names, ids):
            M = pin.updateFramePlacement(m, d, k) if kind == "frame" else d.oMi[k]
            out[n].translation[i] = M.translation
            out[n].rotation[i] = M.rotation
    return out


def frame_placements(robot: Robot, q: np.ndarray, frames: Sequence[str]
                     ) -> dict[str, Placements]:
    """World placements ``{frame: Placements}`` of the named frames along ``q`` ``(T, nq)``
    (Pinocchio forward kinematics). :class:`UnknownNameError` lists the valid frames."""
    return _placements(robot, q, list(frames), "frame")


def frame_paths(robot: Robot, q: np.ndarray, frames: Sequence[str]) -> dict[str, np.ndarray]:
    """World positions ``{frame: (T, 3)}`` [m] of the named frames along ``q`` ``(T, nq)``."""
    return {f: p.translation for f, p in frame_placements(robot, q, frames).items()}


def frame_rotations(robot: Robot, q: np.ndarray, frame: str) -> np.ndarray:
    """World rotation ``(T, 3, 3)`` of one frame along ``q`` ``(T, nq)``."""
    return frame_placements(robot, q, [frame])[frame].rotation


def joint_paths(robot: Robot, q: np.ndarray, joints: Sequence[str]) -> dict[str, np.ndarray]:
    """World positions ``{joint: (T, 3)}`` [m] of the named joints' origins along ``q``."""
    return {j: p.translation for j, p in _placements(robot, q, list(joints), "joint").items()}


# ---------------------------------------------------------------------- stance and anchor
def kinematic_contact(robot: Robot, q: np.ndarray, tol: float | None = None
                      ) -> dict[str, np.ndarray]:
    """Stance flags ``{side: (T,)}``: a sole is in stance while it is within ``tol`` [m]
    (default 2 % of the leg length) of the lower sole."""
    soles = frame_paths(robot, q, [robot.legs[s].sole for s in SIDES])
    z = {s: soles[robot.legs[s].sole][:, 2] for s in SIDES}
    low = np.minimum(z["left"], z["right"])
    tol = 0.02 * robot.legs["left"].length if tol is None else tol
    return {s: z[s] - low < tol for s in SIDES}


def anchor_schedule(contact: Mapping[str, np.ndarray]) -> list[str | None]:
    """The anchor foot per knot (``(T,)`` list of ``"left"``/``"right"``/``None``): the stance
    foot that has been down longest; it stays the anchor until it lifts off, then the other
    stance foot (if any) takes over. ``contact``: ``{side: (T,) bool}``."""
    c = {s: np.asarray(contact[s], dtype=bool) for s in SIDES}
    out: list[str | None] = []
    anchor: str | None = None
    since = {s: -1 for s in SIDES}
    for k in range(len(c["left"])):
        for s in SIDES:
            since[s] = (since[s] if since[s] >= 0 else k) if c[s][k] else -1
        if anchor is None or not c[anchor][k]:
            down = [s for s in SIDES if c[s][k]]
            anchor = min(down, key=lambda s: since[s]) if down else None
        out.append(anchor)
    return out


def anchored_base_offsets(rel: Mapping[str, np.ndarray], contact: Mapping[str, np.ndarray]
                          ) -> np.ndarray:
    """Base translations ``(T, 3)`` [m] that put a walk on the floor z = 0 without the anchor
    foot slipping (the paper's kinematic rule, docs/design.md §6 "anchor").

    ``rel``: ``{side: (T, 3)}`` sole positions with the base translation at zero;
    ``contact``: ``{side: (T,) bool}``. Height: the lowest stance sole on z = 0, interpolated
    through flight (NaN everywhere when no knot has a stance foot). Horizontal: the anchor foot
    (:func:`anchor_schedule`) stays where it landed — a foot that was already down when it
    becomes the anchor stays where it stood the knot before, one that just landed where it
    touches down; a second stance foot may slide (the metrics and the audit measure it). In
    flight the base keeps its last horizontal position. Starts at x = y = 0."""
    T = len(rel["left"])
    c = {s: np.asarray(contact[s], dtype=bool) for s in SIDES}
    z = np.full(T, np.nan)
    for i in range(T):
        down = [rel[s][i, 2] for s in SIDES if c[s][i]]
        if down:
            z[i] = -min(down)
    ok = ~np.isnan(z)
    if ok.any():
        z = np.interp(np.arange(T), np.flatnonzero(ok), z[ok])
    xy = np.zeros((T, 2))
    foot, prev = np.zeros(2), None
    for i, anchor in enumerate(anchor_schedule(c)):
        if anchor is not None and anchor != prev:
            if i == 0:
                foot = rel[anchor][0, :2].copy()
            elif c[anchor][i - 1]:  # already down: it stays where it stood at i − 1
                foot = xy[i - 1] + rel[anchor][i - 1, :2]
            else:  # just landed: where it touches down, the base continuing from i − 1
                foot = xy[i - 1] + rel[anchor][i, :2]
        if anchor is not None:
            xy[i] = foot - rel[anchor][i, :2]
        else:
            xy[i] = xy[i - 1] if i > 0 else 0.0  # flight: keep (no ballistic model)
        prev = anchor
    xy -= xy[0]
    return np.column_stack([xy, z])


# ---------------------------------------------------------------------- a robot's motion
def robot_motion(robot: Robot, t: np.ndarray, q: np.ndarray,
                 contact: Mapping[str, np.ndarray]) -> Motion:
    """A :class:`Motion` of ``robot`` (joint names, per-joint widths and base width filled in).

    ``t`` ``(T,)`` [s], ``q`` ``(T, nq)`` in Pinocchio order, ``contact`` ``{side: (T,) bool}``.
    """
    m = robot.model
    nqs = tuple(int(m.joints[i].nq) for i in range(1, m.njoints))
    return Motion(t=t, joint_names=robot.joint_names, q=check_q(robot, q), contact=contact,
                  base_nq=base_nq(robot), joint_nq=nqs)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` along the last axis (``(..., 3)`` each, broadcast): ``np.cross`` without its
    axis handling (~25 µs a call for two 3-vectors with numpy 2; 2 µs here)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.ndim == 1 and b.ndim == 1:
        a0, a1, a2 = a.tolist()
        b0, b1, b2 = b.tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    return a[..., _NEXT] * b[..., _AFTER] - a[..., _AFTER] * b[..., _NEXT]


_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])
