"""A BVH skeleton as a URDF, written through ``yourdfpy``'s object model.

- one link per BVH joint, of the same name; the root link is the free-flyer's body (its six
  channels are the free-flyer: Pinocchio adds it, ``root_joint``);
- a BVH joint with k channels gives k URDF joints ``<joint>_<channel>`` (e.g.
  ``LeftUpLeg_Zrotation``) in the file's channel order, position channels first (prismatic,
  [m]), then the rotation channels (revolute about the channel's axis, [rad]), with k − 1
  intermediate links ``<joint>_<channel>_link`` (:data:`~gdimitate.io.bvh.inertia.TINY_MASS`);
  a joint without channels is a fixed joint ``<joint>_fixed``;
- the first joint of the chain sits at the BVH OFFSET (scaled to metres); below the root every
  link frame has the file's axes, and the root's children are turned by the constant world
  rotation ``C`` (x_ours = C x_bvh), so the root link's frame is in our axes (x forward, y
  left, z up) when its channels are zero;
- End Sites are links ``<joint>_end`` (``_end2``, … for more than one) on fixed joints
  ``<joint>_end_joint``; each foot gets two links on fixed joints (``<link>_joint``), x along
  the foot and z up at the zero pose: ``<side>_sole`` on the sole plane under the ankle (the
  legs' sole frame) and ``<side>_sole_contact`` at the sole rectangle's centre (the contact
  frame);
- limits: revolute ±2π rad (angles are unwrapped in time, so they may pass ±π), prismatic
  ±10 m; effort and velocity ``0`` — URDF requires the attributes and a human has no
  meaningful value; gdimitate reads a zero effort or velocity limit as "no limit";
- visuals: a cylinder per segment (radius :data:`BONE_RADIUS` × hip height) from the joint to
  each child; each foot a box (also its collision shape) covering the sole rectangle from the
  sole plane up to the ankle; no shape on the toes (the foot box covers them).
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np
import yourdfpy as yd

from ...errors import BVHError
from ...model.contact import sole_frame_name
from .inertia import LinkInertia, tiny
from .parse import BVHFile
from .skeleton import Sole

__all__ = ["ChannelJoint", "skeleton_urdf", "BONE_RADIUS", "REVOLUTE_LIMIT"]

#: Bone cylinder radius as a fraction of the hip height [-].
BONE_RADIUS = 0.035
#: Revolute joint limits ±[rad].
REVOLUTE_LIMIT = 2 * math.pi
PRISMATIC_LIMIT = 10.0
#: Names Pinocchio gives its own joints (the world, the free-flyer).
RESERVED = frozenset({"universe", "root_joint"})


@dataclass(frozen=True)
class ChannelJoint:
    """Where a frame column goes: BVH ``column``, its ``channel`` name, the URDF ``joint``
    (``None`` for the root's channels, which make the free-flyer)."""

    column: int
    channel: str
    joint: str | None


def _T(R: np.ndarray | None = None, p: np.ndarray | None = None) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def _inertial(li: LinkInertia) -> yd.Inertial:
    return yd.Inertial(origin=_T(p=li.com), mass=float(li.mass), inertia=li.inertia)


def _cylinder(a: np.ndarray, b: np.ndarray, r: float) -> yd.Visual | None:
    d = b - a
    L = float(np.linalg.norm(d))
    if L < 1e-6:
        return None
    z = d / L
    x = np.cross(z, [1.0, 0.0, 0.0])
    if np.linalg.norm(x) < 1e-6:
        x = np.cross(z, [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    return yd.Visual(origin=_T(R, (a + b) / 2),
                     geometry=yd.Geometry(cylinder=yd.Cylinder(radius=r, length=L)))


def _foot_box(sole: Sole) -> tuple[yd.Visual, yd.Collision]:
    h = max(sole.height, 0.02)
    T = _T(sole.rotation, sole.centre + sole.rotation[:, 2] * h / 2)
    g = yd.Geometry(box=yd.Box(size=np.array([sole.length, sole.width, h])))
    return yd.Visual(origin=T, geometry=g), yd.Collision(name=None, origin=T, geometry=g)


def skeleton_urdf(bvh: BVHFile, name: str, C: np.ndarray, scale: float,
                  inertias: list[LinkInertia], soles: dict[str, tuple[int, Sole]],
                  hip_height: float) -> tuple[str, tuple[ChannelJoint, ...]]:
    """The URDF text of ``bvh`` and where each frame column goes. ``inertias``: one per BVH
    joint; ``soles``: ``{side: (ankle joint index, Sole)}``; ``hip_height`` [m] sizes the
    bones."""
    links: list[yd.Link] = []
    joints: list[yd.Joint] = []
    cmap: list[ChannelJoint] = []
    r = BONE_RADIUS * hip_height
    feet = {a: s for s, (a, _) in soles.items()}
    for i, j in enumerate(bvh.joints):
        visuals, collisions = [], []
        # the root link's frame has our axes: turn what is written in the file's axes
        turn = C if j.parent < 0 else np.eye(3)
        kids = [bvh.joints[k].offset * scale for k in bvh.children(i)]
        if i not in feet and j.parent not in feet:
            for v in kids + [e * scale for e in j.end_sites]:
                cyl = _cylinder(np.zeros(3), turn @ v, r)
                if cyl is not None:
                    visuals.append(cyl)
        if i in feet:
            vis, col = _foot_box(soles[feet[i]][1])
            visuals.append(vis)
            collisions.append(col)
        li = inertias[i]
        li = LinkInertia(li.mass, turn @ li.com, turn @ li.inertia @ turn.T, li.segment)
        links.append(yd.Link(name=j.name, inertial=_inertial(li), visuals=visuals,
                             collisions=collisions))
        if j.parent < 0:
            cmap.extend(ChannelJoint(j.column + k, c, None) for k, c in enumerate(j.channels))
            continue
        parent = bvh.joints[j.parent].name
        pturn = C if bvh.joints[j.parent].parent < 0 else np.eye(3)
        origin = _T(pturn, pturn @ j.offset * scale)
        order = ([c for c in j.channels if c.endswith("position")]
                 + [c for c in j.channels if c.endswith("rotation")])
        if not order:
            joints.append(yd.Joint(name=f"{j.name}_fixed", type="fixed", parent=parent,
                                   child=j.name, origin=origin))
        for k, c in enumerate(order):
            child = j.name if k == len(order) - 1 else f"{j.name}_{c}_link"
            if child != j.name:
                links.append(yd.Link(name=child, inertial=_inertial(tiny())))
            axis = np.eye(3)["XYZ".index(c[0])]
            rot = c.endswith("rotation")
            lim = REVOLUTE_LIMIT if rot else PRISMATIC_LIMIT
            joints.append(yd.Joint(
                name=f"{j.name}_{c}", type="revolute" if rot else "prismatic", parent=parent,
                child=child, origin=origin if k == 0 else _T(), axis=axis,
                limit=yd.Limit(effort=0.0, velocity=0.0, lower=-lim, upper=lim)))
            cmap.append(ChannelJoint(j.column + j.channels.index(c), c, f"{j.name}_{c}"))
            parent = child
    for j in bvh.joints:
        turn = C if j.parent < 0 else np.eye(3)
        for k, e in enumerate(j.end_sites):
            end = f"{j.name}_end" + (str(k + 1) if k else "")
            links.append(yd.Link(name=end))
            joints.append(yd.Joint(name=f"{end}_joint", type="fixed", parent=j.name, child=end,
                                   origin=_T(turn, turn @ e * scale)))
    for side, (a, sole) in soles.items():
        for link, p in ((f"{side}_sole", sole.below_ankle),
                        (sole_frame_name(side), sole.centre)):
            links.append(yd.Link(name=link))
            joints.append(yd.Joint(name=f"{link}_joint", type="fixed",
                                   parent=bvh.joints[a].name, child=link,
                                   origin=_T(sole.rotation, p)))
    names = [lk.name for lk in links]
    dup = sorted({n for n in names if names.count(n) > 1})
    jn = [jt.name for jt in joints]
    dup += sorted({n for n in jn if jn.count(n) > 1})
    dup += sorted(RESERVED & {j.name for j in bvh.joints})
    if dup:
        raise BVHError(f"{bvh.path}: BVH joint names collide with generated URDF names or "
                       f"Pinocchio's own: {dup}; rename those BVH joints")
    robot = yd.Robot(name=name, links=links, joints=joints)
    tree = yd.URDF(robot=robot, build_scene_graph=False, load_meshes=False).write_xml()
    buf = io.BytesIO()
    tree.write(buf, pretty_print=True, xml_declaration=True, encoding="UTF-8")  # lxml's tree
    return buf.getvalue().decode(), tuple(cmap)
