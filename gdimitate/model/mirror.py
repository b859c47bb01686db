"""Walks mirrored left to right (docs/design.md §13): the same walk as if the subject had led
with the other foot, for robots whose two sides are each other's reflection.

The reflection is ``M = diag(1, −1, 1)`` of the world (y → −y, through the plane y = 0).

- **Joints** are paired by name (:func:`partner`: ``left``/``right``, ``Left``/``Right``,
  ``l_``/``r_`` and ``_l``/``_r``, ``L``/``R`` before a capital, as URDFs, OpenSim models and
  BVH skeletons spell them); a joint without a partner is its own (the trunk's). The
  mirrored angle of joint ``j`` is ``s·q[partner(j)]``: at the robot's neutral pose the
  reflection of the partner's twist (Pinocchio's joint Jacobian column in the world frame:
  linear part ``M v``, angular part a pseudovector, ``−M ω``) is ``s`` times the joint's own
  twist direction, ``s = ±1`` (a revolute joint about the lateral axis keeps its angle, one
  about the forward or vertical axis changes sign). A model whose sides are not reflections
  of each other is refused (:class:`~gdimitate.errors.InvalidInputError`, naming the joint).
- **The base** (free flyer): position ``M p``; orientation ``M R Mᵦ`` with ``Mᵦ = Bᵀ M B``
  (``B`` the robot's neutral base rotation), the reflection in the base's own frame, so that
  the neutral pose mirrors to itself.
- **Contacts and forces** swap sides; a force ``f`` becomes ``M f``, a centre of pressure
  ``M p``, a free torque (a pseudovector) ``−M τ``.

Velocities and accelerations are left out of a mirrored motion (the adaptor differentiates
``q``)."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError
from .contact import ContactForces, FootForces
from .motion import Motion
from .robot import Robot

__all__ = ["MIRROR", "partner", "MirrorMap", "mirror_map", "mirror_motion", "mirror_forces"]

MIRROR = np.diag([1.0, -1.0, 1.0])
"""The world's reflection y → −y."""
_TOL = 0.05
"""A joint's twist direction and its partner's reflected may differ by this much (unit
vectors; a scaled subject's two legs are not quite alike)."""
_SWAPS = (("left", "right"), ("right", "left"), ("Left", "Right"), ("Right", "Left"),
          ("LEFT", "RIGHT"), ("RIGHT", "LEFT"),
          (r"(?<![A-Za-z])l_", "r_"), (r"(?<![A-Za-z])r_", "l_"),  # l_hip_pitch (iCub)
          (r"_l(?![a-z])", "_r"), (r"_r(?![a-z])", "_l"),  # hip_flexion_l (OpenSim)
          (r"(?<![A-Za-z])L(?=[A-Z])", "R"), (r"(?<![A-Za-z])R(?=[A-Z])", "L"))  # LHipPitch
"""``(pattern, replacement)``: the spellings of a side in joint names."""


def partner(name: str, names: tuple[str, ...]) -> str:
    """The joint of ``names`` on the other side of ``name`` (module docstring); ``name``
    itself when none is."""
    for pat, rep in _SWAPS:
        other = re.sub(pat, rep, name)
        if other != name and other in names:
            return other
    return name


@dataclass(frozen=True)
class MirrorMap:
    """How a robot's configuration mirrors: ``source`` ``(n,)`` the index in ``q`` each
    mirrored joint column reads, ``sign`` ``(n,)`` ±1, ``columns`` ``(n,)`` the columns they
    fill (every 1-DoF joint's), and ``base`` ``(3, 3)`` the reflection in the base's frame
    (``None`` without a free-flyer base)."""

    columns: np.ndarray
    source: np.ndarray
    sign: np.ndarray
    base: np.ndarray | None


def _twists(robot: Robot) -> dict[str, np.ndarray]:
    """``{joint: (6,) unit twist at the world origin}`` of every 1-DoF joint at neutral."""
    m, d = robot.model, robot.model.createData()
    pin.computeJointJacobians(m, d, robot.neutral)
    out = {}
    for j in range(1, m.njoints):
        if m.joints[j].nv != 1:
            continue
        J = pin.getJointJacobian(m, d, j, pin.ReferenceFrame.WORLD)[:, m.joints[j].idx_v]
        out[m.names[j]] = J / max(np.linalg.norm(J[3:]) or np.linalg.norm(J[:3]), 1e-12)
    return out


def mirror_map(robot: Robot) -> MirrorMap:
    """The :class:`MirrorMap` of ``robot`` (module docstring); refuses a robot with a planar
    or fixed base, or whose sides are not reflections of each other."""
    if robot.base == "planar":
        raise InvalidInputError("a planar model walks in its sagittal plane: it has no "
                                "left-right mirror image to walk")
    m = robot.model
    multi = [m.names[j] for j in range(1, m.njoints)
             if (m.joints[j].nv, m.joints[j].nq) != (1, 1)
             and m.joints[j].shortname() != "JointModelFreeFlyer"]
    if multi:
        raise InvalidInputError(f"{robot.name}: mirroring handles one-angle joints and the "
                                f"free flyer; {multi[:3]} are not (several axes, or an "
                                f"unbounded joint's cos/sin)")
    tw = _twists(robot)
    names = tuple(tw)
    cols, src, sign = [], [], []
    for j in names:
        p = partner(j, names)
        refl = np.r_[MIRROR @ tw[p][:3], -MIRROR @ tw[p][3:]]
        axis = slice(3, 6) if np.linalg.norm(tw[j][3:]) > 0.5 else slice(0, 3)  # revolute?
        s = 1.0 if refl[axis] @ tw[j][axis] >= 0 else -1.0
        if np.linalg.norm(s * refl[axis] - tw[j][axis]) > _TOL:
            raise InvalidInputError(
                f"{robot.name}: joint {j!r} and its mirror partner {p!r} move about axes "
                f"that are not each other's reflection at the neutral pose, so this model "
                f"cannot walk a mirrored motion (name its joints' sides left/right, l_/r_, "
                f"_l/_r or L/R, or use a model whose sides are alike)")
        cols.append(robot.idx_q(j))
        src.append(robot.idx_q(p))
        sign.append(s)
    base = None
    if robot.base == "free":
        B = robot.base_rotation
        base = B.T @ MIRROR @ B
    return MirrorMap(np.array(cols, int), np.array(src, int), np.array(sign), base)


def mirror_motion(robot: Robot, motion: Motion, mmap: MirrorMap | None = None) -> Motion:
    """``motion`` of ``robot`` mirrored left to right (module docstring)."""
    mm = mirror_map(robot) if mmap is None else mmap
    q = np.array(motion.q, float)
    out = q.copy()
    out[:, mm.columns] = q[:, mm.source] * mm.sign
    if mm.base is not None:
        out[:, :3] = q[:, :3] @ MIRROR
        for i, qi in enumerate(q):
            R = MIRROR @ pin.Quaternion(qi[3:7]).normalized().matrix() @ mm.base
            out[i, 3:7] = pin.Quaternion(R).coeffs()
    contact = {_side(s): np.asarray(c) for s, c in motion.contact.items()}
    return motion.replace(q=out, v=None, a=None, contact=contact)


def mirror_forces(forces: ContactForces) -> ContactForces:
    """Measured ``forces`` mirrored like :func:`mirror_motion`: the feet swapped, forces and
    centres of pressure reflected, free torques reflected as pseudovectors."""
    feet = {_side(s): FootForces(f.force @ MIRROR, f.cop @ MIRROR, -(f.torque @ MIRROR),
                                 f.contact) for s, f in forces.feet.items()}
    note = "mirrored left to right"
    return ContactForces(forces.t, feet, forces.source,
                         f"{forces.frame_note}; {note}" if forces.frame_note else note)


def _side(s: str) -> str:
    return {"left": "right", "right": "left"}.get(s, s)
