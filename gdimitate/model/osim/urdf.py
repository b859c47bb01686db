"""Write an OpenSim model as a URDF that Pinocchio loads (:func:`opensim_to_urdf`).

* Every body becomes a link of the same name (mass, centre of mass, inertia about it).
* The ground→pelvis joint becomes the free-flyer: the URDF starts at the root body, and
  :func:`~gdimitate.model.osim.joints.pelvis_to_freeflyer` maps the six root coordinates to
  Pinocchio's ``q[:7]``.
* Every other joint becomes a chain of revolute/prismatic URDF joints named after the
  coordinates, through massless links ``<joint>__<coordinate>``, then a fixed joint
  ``<joint>__child`` where the chain does not end in the child body's frame (see
  :mod:`.joints` for the rules and the approximation of coupled motions, e.g. spline knees);
  a joint that moves nothing (a ``WeldJoint``, constants only) is one fixed joint of its name.
  Coordinate ranges become joint limits; OpenSim has no torque or speed limits (muscles drive
  the model), so the URDF carries nominal ones, :data:`EFFORT_LIMIT` and :data:`VELOCITY_LIMIT`.
* OpenSim's Y-up axes are turned to ours (x forward, y left, z up) by conjugating every
  constant transform with :data:`~gdimitate.model.osim.joints.WORLD_FROM_OPENSIM`; each link
  frame is the OpenSim body frame with its axes renamed, so the model stands upright facing +x
  at q = 0.
* Markers become frames (links on fixed joints) named after the markers.
* Visual shapes (OpenSim's ``.vtp`` meshes are not shipped): a cylinder from each body's origin
  to each child joint and, where no child joint lies along the centre of mass, to twice the
  centre of mass (radius from the mass at the density of water), a sphere for bodies without
  either, and per foot one box covering the foot body and its descendants (their
  origins, mirrored centres of mass and markers), its bottom at the bones or, given a marker
  trial of the subject, on the lab floor below the foot marker that came closest to it
  (``OsimConversion.sole_height`` says which). On each foot box's lowest face two frames:
  ``<foot>_sole`` directly below the ankle (the leg's sole frame) and ``<foot>_contact`` at
  the face's centre (the centre of the foot's contact rectangle, the box's length × width).
"""

from __future__ import annotations

import math
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yourdfpy

from ...errors import OsimError
from .joints import (
    WORLD_FROM_OPENSIM,
    Approximation,
    JointPlan,
    _compose,
    chain_transform,
    plan_joint,
    root_joint,
)
from .model import OsimModel, read_osim

__all__ = ["OsimConversion", "convert_osim", "opensim_to_urdf", "marker_floor_heights",
           "EFFORT_LIMIT", "VELOCITY_LIMIT"]

#: Nominal joint limits written into the URDF [N·m or N], [rad/s or m/s] (OpenSim models have
#: none: muscles drive them). 300 N·m is above the peak hip, knee and ankle moments of adult
#: walking and running (Winter 2009).
EFFORT_LIMIT = 300.0
VELOCITY_LIMIT = 20.0
_DENSITY = 1000.0  # [kg/m³] for the visual shapes' size
C = WORLD_FROM_OPENSIM


@dataclass(frozen=True)
class OsimConversion:
    """What :func:`convert_osim` wrote and found.

    ``urdf``: the file; ``model``: the parsed OpenSim model; ``plans``: one
    :class:`~gdimitate.model.osim.joints.JointPlan` per non-root joint; ``approximations``: the
    joints whose coupled motions were approximated (with their measured errors); ``root``:
    the root body; ``root_joint``: the OpenSim joint replaced by the free-flyer; ``legs``:
    ``{"left": {"hip", "knee", "ankle", "sole", "contact", "foot"}, "right": …}`` (URDF joint
    / frame / body names: ``sole`` under the ankle, ``contact`` at the sole rectangle's
    centre, both on the foot box's lowest face); ``soles``: ``{"left": (half_length,
    half_width), …}`` [m] of the sole rectangles; ``markers``: marker frame names;
    ``sole_height``: ``{"left": how the sole plane's height was chosen, …}``.
    """

    urdf: Path
    model: OsimModel
    plans: tuple[JointPlan, ...]
    approximations: tuple[Approximation, ...]
    root: str
    root_joint: str
    legs: dict[str, dict[str, str]]
    soles: dict[str, tuple[float, float]]
    markers: tuple[str, ...]
    sole_height: dict[str, str] = field(default_factory=dict)


def _conj(X):
    """An OpenSim-axes transform (R, p) expressed in our axes."""
    R, p = X
    return C @ R @ C.T, C @ p


def _T(X) -> np.ndarray:
    R, p = _conj(X)
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = R, p
    return M


def _neutral_poses(model: OsimModel, plans: dict[str, JointPlan], root: str):
    """Pose (R, p) of every body in the root body's frame at default coordinates (OpenSim
    axes), through the approximating chains (what the URDF will do)."""
    defaults = {c.name: np.array([c.default]) for c in model.coordinates}
    poses = {root: (np.eye(3), np.zeros(3))}
    for j in model.joints:
        if j.child == root:
            continue
        pl = plans[j.name]
        R, p = chain_transform(pl.steps, pl.tail, defaults, 1)
        poses[j.child] = _compose(poses[j.parent], (R[0], p[0]))
    return poses


def _side(name: str) -> str | None:
    if re.search(r"(_r$|^r_|_r_|right)", name, re.I):
        return "right"
    if re.search(r"(_l$|^l_|_l_|left)", name, re.I):
        return "left"
    return None


def _subtree(model: OsimModel, body: str) -> list[str]:
    out = [body]
    for j in model.children(body):
        out += _subtree(model, j.child)
    return out


def _find_legs(model, plans, poses, root):
    """Per side: the chain root → lowest leaf of the two lowest first-level subtrees."""
    up = np.array([0.0, 1.0, 0.0])
    cands = []
    for j in model.children(root):
        sub = _subtree(model, j.child)
        low = min(sub, key=lambda b: poses[b][1] @ up)
        cands.append((float(poses[low][1] @ up), j.child, low))
    cands.sort()
    if len(cands) < 2 or cands[1][0] > poses[root][1] @ up - 0.2:
        raise OsimError(f"{model.name}: cannot find two legs (two chains from {root!r} reaching "
                        "more than 20 cm below it)")
    legs = {}
    for _, first, leaf in cands[:2]:
        chain = [leaf]
        while chain[-1] != first:
            chain.append(model.joint_of(chain[-1]).parent)
        chain = chain[::-1]  # thigh, shank, ..., leaf
        side = _side(first) or _side(leaf)
        if side is None:  # OpenSim Z points right
            side = "right" if poses[leaf][1][2] > 0 else "left"
        if len(chain) < 3:
            raise OsimError(f"{model.name}: leg {chain} needs a thigh, a shank and a foot")
        legs[side] = chain
    if set(legs) != {"left", "right"}:
        raise OsimError(f"{model.name}: both legs look like the same side ({list(legs)}); "
                        "name the bodies with _r/_l suffixes or r_/l_ prefixes")
    return legs


def _lateral_revolute(plan: JointPlan, R_parent: np.ndarray, where: str) -> str:
    """Name of the plan's revolute whose axis (at the neutral pose) is closest to lateral."""
    best, score = None, -1.0
    R = R_parent
    for s in plan.steps:
        R = R @ s.origin[0]
        if s.kind == "revolute" and s.follows is None:
            a = C @ (R @ s.axis)
            if abs(a[1]) > score:
                best, score = s.coordinate, abs(a[1])
    if best is None:
        raise OsimError(f"{where}: joint {plan.joint!r} has no rotational coordinate; the leg "
                        "needs hip, knee and ankle rotations")
    return best


def _foot_box(model, poses, foot: str, floor: dict[str, float] | None = None):
    """Axis-aligned (world at neutral) box of the foot subtree, in world-oriented coordinates
    relative to the foot origin (ours): (lo (3,), hi (3,)), and how its bottom was placed.
    Forward, backward and sideways it spans the subtree's body origins, their centres of mass
    mirrored through them (a segment reaches about twice as far as its centre of mass) and the
    markers on the subtree. Its bottom (the sole plane): with ``floor`` (marker → its lowest
    recorded height over the lab floor [m], :func:`marker_floor_heights`), that height below
    the foot's marker that came closest to the floor (markers sit on the shoe; the bones stand
    a shoe's sole and a heel pad above the floor: 4.6–5.4 cm for subject01); else the lowest
    body origin or centre of mass."""
    Rf, pf = poses[foot]
    pts, low = [], []  # horizontal extent; bottom
    for b in _subtree(model, foot):
        R, p = poses[b]
        c = R @ model.body(b).com
        pts += [p, p + 2 * c]  # origin and mirrored centre of mass span the segment
        low += [p, p + c]
    P = (np.array(pts) - pf) @ C.T
    lo, hi = P.min(axis=0), P.max(axis=0)
    lo[2] = float(((np.array(low) - pf) @ C.T)[:, 2].min())
    note = "bones (lowest body origin or centre of mass)"
    sub = _subtree(model, foot)
    marks = {m.name: (poses[m.body][1] + poses[m.body][0] @ m.location - pf) @ C.T
             for m in model.markers if m.body in sub}
    if marks:  # skin markers widen and lengthen the box
        Mk = np.array(list(marks.values()))
        lo[:2], hi[:2] = np.minimum(lo[:2], Mk.min(axis=0)[:2]), np.maximum(hi[:2],
                                                                            Mk.max(axis=0)[:2])
    seen = {n: float(marks[n][2] - h) for n, h in (floor or {}).items() if n in marks}
    # each marker's lowest height is at most its flat-foot one: an upper bound
    if seen and floor is not None:
        low_mark = min(seen, key=lambda n: seen[n])
        lo[2] = seen[low_mark]
        note = (f"marker {low_mark}: {floor[low_mark] * 1e3:.1f} mm over the floor at its "
                "lowest (the tightest of the foot markers' bounds)")
    length = hi[0] - lo[0]
    if hi[1] - lo[1] < 0.35 * length:  # no markers across the foot: a typical width
        mid = 0.5 * (hi[1] + lo[1])
        lo[1], hi[1] = mid - 0.175 * length, mid + 0.175 * length
    hi[2] = max(hi[2], lo[2] + 0.03)
    return lo, hi, note


def marker_floor_heights(markers) -> dict[str, float]:
    """``{marker: its lowest recorded height [m]}`` over a marker trial (a ``.trc`` path or
    :class:`~gdimitate.model.osim.trc.Markers`; our world frame, the lab floor at z = 0 as
    OpenSim's ground has it) — the 1st percentile of its heights, robust to a stray frame.
    Markers never seen are left out."""
    from .trc import Markers, read_trc

    mk = markers if isinstance(markers, Markers) else read_trc(markers)
    out = {}
    for i, n in enumerate(mk.names):
        z = mk.xyz[:, i, 2]
        if np.isfinite(z).any():
            out[n] = float(np.nanpercentile(z, 1))
    return out


def _cylinder(v: np.ndarray, radius: float, name: str) -> yourdfpy.Visual:
    L = float(np.linalg.norm(v))
    z = v / L
    x = np.cross([0.0, 0.0, 1.0], z) if abs(z[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    M = np.eye(4)
    M[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    M[:3, 3] = v / 2
    return yourdfpy.Visual(name=name, origin=M, geometry=yourdfpy.Geometry(
        cylinder=yourdfpy.Cylinder(radius=radius, length=L)), material=_MATERIAL)


_MATERIAL = yourdfpy.Material(name="osim_segment", color=yourdfpy.Color(
    rgba=np.array([0.8, 0.7, 0.55, 1.0])))


def _visuals(model, plans, poses, body: str, feet: dict[str, tuple]) -> list[yourdfpy.Visual]:
    if body in feet:
        lo, hi = feet[body]
        M = np.eye(4)
        Rf = C @ poses[body][0] @ C.T  # foot link axes in world (ours) at neutral
        M[:3, :3] = Rf.T
        M[:3, 3] = Rf.T @ ((lo + hi) / 2)
        return [yourdfpy.Visual(name=f"{body}_box", origin=M, geometry=yourdfpy.Geometry(
            box=yourdfpy.Box(size=hi - lo)), material=_MATERIAL)]
    if any(body in _subtree(model, f)[1:] for f in feet):
        return []  # toes: inside the foot box
    b = model.body(body)
    R, p = poses[body]
    vecs = [C @ (R.T @ (poses[j.child][1] - p)) for j in model.children(body)]
    vecs = [v for v in vecs if np.linalg.norm(v) > 0.02]
    com = C @ b.com
    L = float(np.linalg.norm(com))
    along = any(v @ com > max(float(np.linalg.norm(v)), L) * L * math.cos(math.radians(20))
                for v in vecs)
    if L > 0.02 and not along:  # no child joint along the mass: e.g. a torso carrying arms
        vecs.append(2 * com)
    if not vecs:
        r = (3 * max(b.mass, 1e-3) / (4 * math.pi * _DENSITY)) ** (1 / 3)
        return [yourdfpy.Visual(name=f"{body}_sphere", origin=np.eye(4),
                                geometry=yourdfpy.Geometry(sphere=yourdfpy.Sphere(radius=r)),
                                material=_MATERIAL)]
    total = sum(float(np.linalg.norm(v)) for v in vecs)
    r = float(np.clip(math.sqrt(max(b.mass, 1e-3) / (_DENSITY * math.pi * total)), 0.01, 0.12))
    return [_cylinder(v, r, f"{body}_seg{i}") for i, v in enumerate(vecs)]


def _link(name, body=None, visuals=()) -> yourdfpy.Link:
    inertial = None
    if body is not None and body.mass > 0:
        M = np.eye(4)
        M[:3, 3] = C @ body.com
        inertial = yourdfpy.Inertial(origin=M, mass=body.mass, inertia=C @ body.inertia @ C.T)
    return yourdfpy.Link(name=name, inertial=inertial, visuals=list(visuals))


def convert_osim(osim_path: str | Path, out: str | Path | None = None, *,
                 markers=None) -> OsimConversion:
    """Convert an ``.osim`` file to a URDF; see the module docstring. ``out``: the URDF path
    (default: ``<stem>.urdf`` in a new temporary folder). ``markers``: a marker trial of the
    model's subject (``.trc`` path or :class:`~gdimitate.model.osim.trc.Markers`, lab floor at
    z = 0) that places each sole on the floor below the foot's markers
    (:func:`marker_floor_heights`); without one the soles lie at the bones. Returns an
    :class:`OsimConversion`."""
    model = read_osim(osim_path)
    floor = marker_floor_heights(markers) if markers is not None else None
    rj = root_joint(model)
    root = rj.child
    claimed: set[str] = set(c.name for c in rj.coordinates)
    plans = {j.name: plan_joint(j, claimed) for j in model.joints if j is not rj}
    poses = _neutral_poses(model, plans, root)
    chains = _find_legs(model, plans, poses, root)
    legs, soles, feet, notes = {}, {}, {}, {}
    for side, chain in chains.items():
        roles = []
        for k in range(3):
            pl = plans[model.joint_of(chain[k]).name]
            roles.append(_lateral_revolute(pl, poses[pl.parent][0], model.name))
        after = chain[2:] if len(chain) > 2 else chain[-1:]
        foot = max(after, key=lambda b: model.body(b).mass)
        lo, hi, notes[side] = _foot_box(model, poses, foot, floor)
        feet[foot] = (lo, hi)
        legs[side] = {"hip": roles[0], "knee": roles[1], "ankle": roles[2],
                      "sole": f"{foot}_sole", "contact": f"{foot}_contact", "foot": foot}
        soles[side] = (float(hi[0] - lo[0]) / 2, float(hi[1] - lo[1]) / 2)
    links, joints = [], []
    for b in model.bodies:
        links.append(_link(b.name, b, _visuals(model, plans, poses, b.name, feet)))
    for pl in plans.values():
        parent = pl.parent
        for i, s in enumerate(pl.steps):
            last = i == len(pl.steps) - 1
            ident = np.allclose(pl.tail[0], np.eye(3)) and np.allclose(pl.tail[1], 0.0)
            child = pl.child if last and ident else f"{pl.joint}__{s.coordinate}"
            if child != pl.child:
                links.append(_link(child))
            lim = _limits(model, s)
            joints.append(yourdfpy.Joint(
                name=s.coordinate, type=s.kind, parent=parent, child=child, origin=_T(s.origin),
                axis=C @ s.axis, limit=yourdfpy.Limit(effort=EFFORT_LIMIT,
                                                      velocity=VELOCITY_LIMIT,
                                                      lower=lim[0], upper=lim[1])))
            parent = child
        if parent != pl.child:
            name = pl.joint if not pl.steps else f"{pl.joint}__child"
            joints.append(yourdfpy.Joint(name=name, type="fixed", parent=parent,
                                         child=pl.child, origin=_T(pl.tail)))
    for side, d in legs.items():
        lo, hi = feet[d["foot"]]
        Rf = C @ poses[d["foot"]][0] @ C.T
        aj = model.joint_of(chains[side][2])  # the ankle's centre: its parent offset frame
        Rp, pp = poses[aj.parent]
        ankle = C @ (pp + Rp @ aj.parent_offset[1] - poses[d["foot"]][1])  # ankle − foot
        for frame, xy in ((d["sole"], ankle[:2]), (d["contact"], (lo[:2] + hi[:2]) / 2)):
            M = np.eye(4)
            M[:3, :3] = Rf.T
            M[:3, 3] = Rf.T @ np.array([xy[0], xy[1], lo[2]])
            links.append(_link(frame))
            joints.append(yourdfpy.Joint(name=f"{frame}_joint", type="fixed",
                                         parent=d["foot"], child=frame, origin=M))
    for m in model.markers:
        M = np.eye(4)
        M[:3, 3] = C @ m.location
        links.append(_link(m.name))
        joints.append(yourdfpy.Joint(name=f"{m.name}_marker", type="fixed", parent=m.body,
                                     child=m.name, origin=M))
    _check_names(model, links, joints)
    robot = yourdfpy.Robot(name=model.name, links=links, joints=joints, materials=[_MATERIAL])
    path = Path(out) if out is not None else \
        Path(tempfile.mkdtemp(prefix="gdimitate_osim_")) / f"{Path(osim_path).stem}.urdf"
    path.parent.mkdir(parents=True, exist_ok=True)
    yourdfpy.URDF(robot=robot, build_scene_graph=False, load_meshes=False).write_xml_file(
        str(path))
    approx = tuple(p.approximation for p in plans.values() if p.approximation is not None)
    return OsimConversion(path, model, tuple(plans.values()), approx, root, rj.name, legs,
                          soles, tuple(m.name for m in model.markers), notes)


def _limits(model: OsimModel, s) -> tuple[float, float]:
    """A URDF joint's limits: its coordinate's range, or for a spline-driven joint the range
    its function sweeps over its coordinate's (widened by 1e-6 where it barely moves)."""
    name = s.follows[0] if s.follows is not None else s.coordinate
    lo, hi = next(c for c in model.coordinates if c.name == name).range
    if s.follows is None:
        return lo, hi
    v = s.follows[1](np.linspace(lo, hi, 401)) - s.follows[2]
    return float(v.min()) - 1e-6, float(v.max()) + 1e-6


def _check_names(model, links, joints):
    names = [x.name for x in links] + [x.name for x in joints]
    seen, dup = set(), set()
    for n in names:
        (dup if n in seen else seen).add(n)
    if dup:
        raise OsimError(f"{model.name}: names used twice once converted (bodies, coordinates, "
                        f"markers, '<joint>__<coordinate>' links share one namespace): "
                        f"{sorted(dup)}; rename them in the .osim file")


def opensim_to_urdf(osim_path: str | Path, out: str | Path | None = None) -> Path:
    """Convert an OpenSim model (``.osim``, 3.x or 4.x) to a URDF → the URDF's path.

    ``out``: where to write (default ``<stem>.urdf`` in a new temporary folder). Load the
    result with ``Robot.from_osim`` (free-flyer, legs and soles set) or Pinocchio with a
    ``JointModelFreeFlyer`` root. Joint names are the OpenSim coordinate names; see the module
    docstring of :mod:`gdimitate.model.osim.urdf` for frames and shapes and
    :mod:`gdimitate.model.osim.joints` for approximated couplings (gait2354 knees: a fixed hinge
    within 3.2 mm of the spline knee over its range, 1.6 mm over subject01's walk). Raises
    :class:`~gdimitate.errors.OsimError` on malformed models.
    """
    return convert_osim(osim_path, out).urdf
