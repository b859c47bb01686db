"""Self-collision as a constraint of the adaptor: pairs of spheres that enclose the robot's
collision geometries (limb–limb and limb–trunk pairs of :mod:`gdimitate.model.selfcollision`) kept
at least ``margin`` apart at every knot.

Each collision geometry is covered by up to :data:`MAX_SPHERES` spheres, one per cluster of its
vertices (a sphere primitive is itself): every vertex of its convex hull (a box's corners, a
cylinder's rims) lies inside one of them. Only geometry pairs that come within :data:`ACTIVE`
of each other at the neutral pose (arms against the trunk and the thighs) get rows, unless they
meet where the limbs meet the trunk (:data:`PROXIMAL`, :data:`PROXIMAL_ARM`), and of their
spheres those within :data:`ACTIVE_SPHERES`. The audit's rule applies
(:mod:`gdimitate.model.selfcollision`): geometry pairs already closer than the margin at the neutral
pose are left out and listed (:func:`left_out_sphere_pairs`); sphere pairs closer than the
margin at the neutral pose (the spheres' slack over the hulls) keep at least their neutral gap.
The two legs get no sphere pairs: their covers overlap by centimetres where the hulls pass each
other with millimetres to spare (Talos's warm start: rows 62 mm short, hulls 8.6 mm apart); one
smooth row keeps the soles apart along the root's y axis instead (:func:`leg_separation`).
Rows: one per pair of frames, the soft minimum of its sphere pairs' clearances (centre distance
− r_a − r_b − gap) over the leg length, ≥ 0 (:class:`SelfCollision`). Relaxable (the
least-infeasible solve reports an unmet pair of frames)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np
import pinocchio as pin

from ...model.robot import Robot
from ..knot import Knot
from .base import Bounds, Constraint, Spec

if TYPE_CHECKING:
    from ...model.selfcollision import SelfCollision as Hulls

__all__ = ["SelfCollision", "soft_min", "rest_floors", "SHARPNESS", "sphere_pairs",
           "left_out_sphere_pairs", "leg_separation", "MARGIN", "ACTIVE", "MAX_SPHERES",
           "PROXIMAL", "PROXIMAL_ARM",
           "rest_pose", "REST_CLEAR", "SpherePair", "LegSeparation", "LeftOut"]

SpherePair = tuple[str, tuple[float, ...], float, str, tuple[float, ...], float, float]
"""``(frame_a, centre_a (3,) [m], r_a [m], frame_b, centre_b (3,) [m], r_b [m], gap [m])``:
two spheres, their centres in Pinocchio joint frames, and the least gap between their
surfaces."""
LegSeparation = tuple[str, str, str, float]
"""``(left sole frame, right sole frame, root joint, least separation [m])``."""
LeftOut = tuple[str, str, float]
"""``(geometry a, geometry b, hull distance [m])``: a pair left out of the rows."""

#: The adaptor's clearance between sphere covers [m] (the audit's bound is 0 between hulls).
MARGIN = 0.01
#: Geometry pairs closer than this at the neutral pose get rows [m] ...
ACTIVE = 0.15
#: ... for their spheres closer than this [m].
ACTIVE_SPHERES = 0.08
#: At most this many spheres per geometry.
MAX_SPHERES = 4
#: Sharpness β [1/leg length] of the soft minimum over a frame pair's sphere pairs
#: (:func:`soft_min`): two equally close sphere pairs make the row log 2 / β = 0.0035 leg
#: lengths (3 mm on Talos) stricter than either alone; a pair 0.02 leg lengths farther than
#: the closest moves it by 0.1 mm.
SHARPNESS = 200.0
#: Geometries on a leg's first this-many joints (the hip) are "proximal": a proximal geometry
#: and the trunk link its limb hangs from (a thigh and the pelvis), or two proximal geometries
#: of legs hanging from one trunk link (the two hips), get no rows — spheres are too coarse
#: where limbs meet the trunk, and the audit checks those pairs on the hulls themselves.
PROXIMAL = 3
#: ... on an arm's (or head's) first this-many: the shoulder's two links, which sit on the
#: chest. The third carries the upper arm, which hangs beside the trunk and gets rows: without
#: them G1's right upper arm went 2.7 mm into its torso on the CMU walk.
PROXIMAL_ARM = 2
#: :func:`rest_pose` moves the limbs until the pairs within the margin at the neutral pose
#: are this far apart [m].
REST_CLEAR = 1.5 * MARGIN
#: ... by steps of at most this much on any joint [rad] (a linearised distance is good for a
#: few centimetres: uncut, the steps for 3 cm swung Talos's arms by 2.4 rad)
MAX_REST_STEP = 0.1


@dataclass(frozen=True)
class SelfCollision(Constraint):
    """``pairs``: ``((frame_a, (x, y, z), r_a, frame_b, (x, y, z), r_b, gap), …)`` — sphere
    centres in Pinocchio frames (joint frames) [m], radii [m], and the least gap between the
    two spheres' surfaces [m] (:func:`sphere_pairs`); ``legs``: :func:`leg_separation`;
    ``floors``: each row's lower bound (:func:`rest_floors`; default 0 for every row).

    One row per pair of frames (:meth:`groups`): the soft minimum (:func:`soft_min`, sharpness
    :data:`SHARPNESS`) over that frame pair's sphere pairs of their clearance
    ``(|c_a − c_b| − r_a − r_b − gap) / leg length``, bound below by 0 — or by its value at the
    rest pose where that is below 0 (:func:`rest_floors`). The soft minimum never
    exceeds the smallest clearance, so the row admits no sphere overlap a row per sphere pair
    would forbid, and it lies at most ``log(n) / SHARPNESS`` below it (Talos: 315 sphere pairs
    in 42 frame pairs, up to 29 in one). The centres are taken in the root joint's frame
    (:meth:`~gdimitate.model.symbolic.SymbolicModel.root_placement`): a distance between two bodies
    does not depend on the base's pose, and so its row's derivatives carry no base column."""

    pairs: tuple[SpherePair, ...] = ()
    legs: tuple[LegSeparation, ...] = ()
    floors: tuple[float, ...] = ()
    name: str = "self-collision"
    relaxable: bool = True
    screenable = True  # rows that are far from their bounds at most knots

    def groups(self) -> tuple[tuple[str, str, tuple[int, ...]], ...]:
        """``((frame_a, frame_b, indices into pairs), …)``: the sphere pairs of each pair of
        frames, in order of first appearance — one row each."""
        out: dict[tuple[str, str], list[int]] = {}
        for i, (fa, _, _, fb, *_) in enumerate(self.pairs):
            out.setdefault((fa, fb), []).append(i)
        return tuple((fa, fb, tuple(ix)) for (fa, fb), ix in out.items())

    def rows(self, k: Knot) -> ca.SX:
        """``(n_groups + n_legs, 1)``: each frame pair's soft-minimum clearance, then the
        soles' separation along the root's y axis, both over the leg length."""
        L = k.leg["left"].length
        out = []
        for _, _, ix in self.groups():
            clear = []
            for i in ix:
                fa, oa, ra, fb, ob, rb, gap = self.pairs[i]
                Ra, pa = k.sym.root_placement(fa)
                Rb, pb = k.sym.root_placement(fb)
                d = (pa + Ra @ ca.DM(oa)) - (pb + Rb @ ca.DM(ob))
                clear.append((ca.sqrt(ca.sumsqr(d) + 1e-12) - (ra + rb + gap)) / L)
            out.append(soft_min(clear))
        for fl, fr, fo, _ in self.legs:
            Ro = k.sym.placement(fo)[0]
            out.append((Ro.T @ (k.sym.placement(fl)[1] - k.sym.placement(fr)[1]))[1] / L)
        return ca.vertcat(*out) if out else ca.SX(0, 1)

    def bounds(self, spec: Spec) -> Bounds:
        """Below: :attr:`floors` (0 by default) and each legs row's least separation over
        the leg length; above: free. Each ``(T, n)``."""
        lo = np.tile(list(self.floors or [0.0] * len(self.groups()))
                     + [y / spec.leg_length for *_, y in self.legs], (spec.T, 1))
        return Bounds(lo, np.full_like(lo, np.inf))

    def screenable_rows(self, k: Knot) -> np.ndarray:
        """The frame pairs' rows; never the legs-apart row, one per knot, that binds
        wherever the swing foot passes the stance foot: screened out by the warm start's
        parallel feet, it came back violated on the result and cost a second solve (one cycle
        of the shipped walk, 100 knots: iCub 84 → 76 iterations, Romeo 79 → 54; the whole
        clip → G1 76 → 49)."""
        return np.r_[np.ones(len(self.groups()), bool), np.zeros(len(self.legs), bool)]

    def labels(self, k: Knot) -> list[str]:
        return ([f"{self.name}: {fa}/{fb}" for fa, fb, _ in self.groups()]
                + [f"{self.name}: legs apart ({fl}/{fr})" for fl, fr, *_ in self.legs])


def rest_floors(robot: Robot, pairs: tuple[SpherePair, ...], q: np.ndarray
                ) -> tuple[float, ...]:
    """:attr:`SelfCollision.floors` for ``pairs`` taken at the pose ``q`` (``(nq,)``,
    :func:`sphere_pairs`): per pair of frames, ``min(0, soft minimum of its clearances at q)``
    [leg lengths]. A sphere pair closer than the margin at ``q`` keeps its gap there
    (clearance 0); several such pairs in one frame pair would make its soft minimum negative
    at ``q`` itself — up to ``log(n) / SHARPNESS`` — so the row keeps that value instead of 0:
    none of its sphere pairs gets closer than its gap at ``q`` by more than that (Talos:
    ``arm_left_1_joint``/``head_1_joint`` without it, the adaptor's own rest pose was
    infeasible)."""
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, float))
    L = robot.legs["left"].length
    out = []
    for _, _, ix in SelfCollision(pairs).groups():
        c = []
        for fa, oa, ra, fb, ob, rb, gap in (pairs[i] for i in ix):
            pa = data.oMf[model.getFrameId(fa)].act(np.array(oa))
            pb = data.oMf[model.getFrameId(fb)].act(np.array(ob))
            c.append((float(np.linalg.norm(pa - pb)) - ra - rb - gap) / L)
        out.append(min(0.0, float(soft_min(c))))
    return tuple(out)


def soft_min(x: Sequence[ca.SX | float], sharpness: float | None = None) -> ca.SX | float:
    """``−log(Σ exp(−β xᵢ)) / β`` of the SX (or float) values ``x`` (β = ``sharpness``,
    default :data:`SHARPNESS`), written about their minimum ``m`` so that nothing overflows:
    ``m − log(Σ exp(−β (xᵢ − m))) / β`` (its derivatives through ``m`` cancel). Never above
    ``min(x)``, at most ``log(len(x)) / β`` below it; ``x[0]`` itself for one value."""
    if len(x) == 1:
        return x[0]
    b = SHARPNESS if sharpness is None else sharpness
    m = x[0]
    for xi in x[1:]:
        m = ca.fmin(m, xi)
    return m - ca.log(sum(ca.exp(-b * (xi - m)) for xi in x)) / b


def _vertices(g: pin.GeometryObject) -> np.ndarray:
    """Points ``(n, 3)`` in the geometry's own frame whose convex hull contains the shape
    (sphere: its centre only; capsule: its cylinder, the caps covered by the spheres' radius
    only approximately)."""
    import coal

    s = g.geometry
    if isinstance(s, coal.BVHModelBase):
        return np.asarray(s.vertices())
    if isinstance(s, coal.ConvexBase):
        return np.asarray(s.points())
    if isinstance(s, coal.Box):
        h = np.asarray(s.halfSide)
        return np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * h
    if isinstance(s, (coal.Cylinder, coal.Capsule)):
        th = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        rho = s.radius / np.cos(np.pi / 16)  # the 16-gon around the circle, not inside it
        ring = np.c_[rho * np.cos(th), rho * np.sin(th)]
        return np.vstack([np.c_[ring, np.full(16, z)] for z in (-s.halfLength, s.halfLength)])
    return np.zeros((1, 3))


def _cover(g: pin.GeometryObject) -> list[tuple[np.ndarray, float]]:
    """Spheres ``[(centre (3,) in the geometry's frame, radius)]`` enclosing it: its vertices
    split into up to :data:`MAX_SPHERES` clusters (k-means from farthest-point seeds, a few
    Lloyd steps), each cluster's sphere centred on its mean with the radius of its farthest
    vertex."""
    import coal

    if isinstance(g.geometry, coal.Sphere):
        return [(np.zeros(3), float(g.geometry.radius))]
    V = _vertices(g)
    k = min(MAX_SPHERES, len(V))
    seeds = [int(np.argmax(np.linalg.norm(V - V.mean(axis=0), axis=1)))]
    for _ in range(k - 1):
        seeds.append(int(np.argmax(np.min(np.linalg.norm(V[:, None] - V[seeds][None], axis=2),
                                          axis=1))))
    C = V[seeds].copy()
    for _ in range(10):
        near = np.argmin(np.linalg.norm(V[:, None] - C[None], axis=2), axis=1)
        C = np.array([V[near == i].mean(axis=0) if np.any(near == i) else C[i]
                      for i in range(len(C))])
    near = np.argmin(np.linalg.norm(V[:, None] - C[None], axis=2), axis=1)
    return [(C[i], float(np.max(np.linalg.norm(V[near == i] - C[i], axis=1))))
            for i in range(len(C)) if np.any(near == i)]


def _proximal(robot: Robot) -> dict[int, str | None]:
    """``{joint id: where it meets the trunk}``: for a joint on one of a leg's first
    :data:`PROXIMAL` joints or another limb's first :data:`PROXIMAL_ARM`,
    ``"limb:<top>@<trunk joint it hangs from>"``; for a trunk joint, ``"trunk@<joint>"``;
    else ``None``."""
    from ...model.selfcollision import TRUNK, limb_groups

    groups = limb_groups(robot)
    legs = _leg_limbs(robot)
    parents = robot.model.parents
    out: dict[int, str | None] = {}
    for j, g in groups.items():
        if g == TRUNK:
            out[j] = f"trunk@{j}"
            continue
        n, k = 0, j
        while groups.get(parents[k]) == g:
            k, n = parents[k], n + 1
        out[j] = f"{g}@{parents[k]}" if n < (PROXIMAL if g in legs else PROXIMAL_ARM) else None
    return out


def _leg_limbs(robot: Robot) -> set[str]:
    """The limb labels (:func:`~gdimitate.model.selfcollision.limb_groups`) of the robot's legs."""
    from ...model.selfcollision import limb_groups

    groups = limb_groups(robot)
    return {groups[robot.model.getJointId(leg.hip)] for leg in robot.legs.values()
            if robot.model.existJointName(leg.hip)}


def _near_root(a: str | None, b: str | None, legs: set[str]) -> bool:
    """Two geometries where limbs meet the trunk: a proximal limb geometry and the trunk link
    it hangs from (a thigh and the pelvis, an upper arm and the chest), or both proximal on
    two legs hanging from the same trunk joint (the two hips; ``legs``: the legs' limb
    labels)."""
    if a is None or b is None or a.split("@")[1] != b.split("@")[1]:
        return False
    ga, gb = a.split("@")[0], b.split("@")[0]
    return "trunk" in (ga, gb) or (ga in legs and gb in legs)


def _two_legs(ja: int, jb: int, limbs: dict[int, str], legs: set[str]) -> bool:
    """Joints ``ja`` and ``jb`` on the two legs: their sphere covers (a shank's spheres ~17 cm
    on Talos) overlap by centimetres where the hulls pass each other with millimetres to spare
    (Talos's warm start: sphere rows 62 mm short, hulls 8.6 mm apart), so the rows would force
    the legs apart; the audit checks these pairs on the hulls."""
    return limbs[ja] != limbs[jb] and limbs[ja] in legs and limbs[jb] in legs


def leg_separation(robot: Robot, margin: float = MARGIN, active: float = ACTIVE
                   ) -> tuple[LegSeparation, ...]:
    """:attr:`SelfCollision.legs` of ``robot``: ``((left sole frame, right sole frame, root
    joint, least separation [m]),)`` — the soles' separation along the root's y axis at least
    its neutral value less the legs' closest hull distance there less ``margin``, a smooth row
    in place of the two legs' sphere pairs (:func:`_two_legs`); legs already within ``margin``
    at the neutral pose keep their neutral separation; empty when the legs' closest pair there
    is ``active`` or more apart."""
    from ...model.selfcollision import limb_groups, self_collision

    sc = self_collision(robot)
    model, cm = robot.model, robot.collision_model
    if sc is None or cm is None or set(robot.legs) != {"left", "right"}:
        return ()
    limbs, legs = limb_groups(robot), _leg_limbs(robot)
    joint = {n: int(cm.geometryObjects[cm.getGeometryId(n)].parentJoint)
             for pair in sc.pairs for n in pair}
    d = [dn for (a, b), dn in zip(sc.pairs, sc.distances(robot.neutral))
         if _two_legs(joint[a], joint[b], limbs, legs)]
    if not d or min(d) >= active:
        return ()
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.neutral)
    sole = {s: data.oMf[model.getFrameId(robot.legs[s].sole)].translation
            for s in ("left", "right")}
    y0 = float((data.oMi[1].rotation.T @ (sole["left"] - sole["right"]))[1])
    a, b = robot.legs["left"].sole, robot.legs["right"].sole
    if y0 < 0:  # the root's y axis points to the right (iCub's root_link)
        a, b, y0 = b, a, -y0
    return ((a, b, model.names[1], float(y0 - max(min(d) - margin, 0.0))),)


def sphere_pairs(robot: Robot, margin: float = MARGIN, active: float = ACTIVE,
                 q: np.ndarray | None = None) -> tuple[SpherePair, ...]:
    """The :class:`SelfCollision` pairs of ``robot`` (empty without collision geometry): the
    sphere pairs closer than :data:`ACTIVE_SPHERES` of the active geometry pairs at least
    ``margin`` [m] apart at the pose ``q`` (default: the neutral pose; the adaptor's:
    :func:`rest_pose`), each with gap ``min(g, margin)`` (``g`` the spheres' gap at ``q``)."""
    return _sphere_pairs(robot, margin, active, q)[0]


def left_out_sphere_pairs(robot: Robot, margin: float = MARGIN, active: float = ACTIVE,
                          q: np.ndarray | None = None) -> tuple[LeftOut, ...]:
    """The active geometry pairs left out because they are closer than ``margin`` [m] at the
    pose ``q`` (default: neutral): ``((geometry a, geometry b, hull distance at q [m]), …)``."""
    return _sphere_pairs(robot, margin, active, q)[1]


def _active_pairs(robot: Robot, sc: Hulls) -> list[tuple[str, str, int, int]]:
    """``[(geometry a, geometry b, joint a, joint b)]``: the pairs of ``sc`` (a
    :class:`gdimitate.model.selfcollision.SelfCollision`) that may get sphere rows — not where limbs
    meet the trunk (:func:`_near_root`), not across the two legs (:func:`_two_legs`)."""
    from ...model.selfcollision import limb_groups

    cm = robot.collision_model
    if cm is None:  # sc exists only for a robot with collision geometry
        return []
    prox, legs, limbs = _proximal(robot), _leg_limbs(robot), limb_groups(robot)
    out = []
    for a, b in sc.pairs:
        ja, jb = (int(cm.geometryObjects[cm.getGeometryId(n)].parentJoint) for n in (a, b))
        if not (_near_root(prox[ja], prox[jb], legs) or _two_legs(ja, jb, limbs, legs)):
            out.append((a, b, ja, jb))
    return out


def rest_pose(robot: Robot, margin: float = MARGIN, clear: float = REST_CLEAR) -> np.ndarray:
    """``(nq,)``: the pose the adaptor holds the joints a body map leaves out near
    (:class:`.PostureRange`) and takes its sphere pairs at — the neutral pose, with the arms
    (and head) moved the least so that the active pairs closer than ``margin`` there are
    ``clear`` apart (a few least-norm Gauss–Newton steps on coal's hull distances, by finite
    differences; legs and trunk stay). Talos's neutral pose holds its wrists and grippers
    within 1 cm of its thighs (8.7–9.6 mm): those pairs would get no rows; its rest pose moves
    each arm joint by ≤ 0.05 rad. The neutral pose where no pair is that close (G1, Romeo,
    iCub). Cached on the robot."""
    from ...model.selfcollision import TRUNK, limb_groups, self_collision

    cache = robot.__dict__.setdefault("_rest_pose", {})
    if (margin, clear) in cache:
        return cache[margin, clear]
    q = np.array(robot.neutral, float)
    sc = self_collision(robot)
    if sc is not None:
        q = _clear_limbs(robot, sc, q, margin, clear, limb_groups(robot), TRUNK)
    cache[margin, clear] = q
    return q


def _clear_limbs(robot: Robot, sc: Hulls, q: np.ndarray, margin: float, clear: float,
                 groups: dict[int, str], trunk: str) -> np.ndarray:
    """:func:`rest_pose`'s steps from ``q``."""
    model = robot.model
    legs = _leg_limbs(robot)
    idx = {(a, b): i for i, (a, b) in enumerate(sc.pairs)}
    pairs = [idx[a, b] for a, b, *_ in _active_pairs(robot, sc)]
    d0 = sc.distances(q)
    watch = [i for i in pairs if 0.0 <= d0[i] < margin]
    if not watch:
        return q
    free = [j for j in range(1, model.njoints) if model.joints[j].nq == 1
            and groups.get(j) not in (trunk, None) and groups[j] not in legs]
    iq = np.array([model.joints[j].idx_q for j in free])
    lo, hi = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
    # no pair the audit checks (apart at the neutral pose) gets closer than this
    floor = {i: min(d0[i], margin) for i in range(len(sc.pairs)) if d0[i] >= 0.0}
    for _ in range(30):
        d = sc.distances(q)
        bad = [i for i in floor if (i in watch and d[i] < clear) or d[i] < floor[i] - 1e-9]
        if not bad:
            break
        G = np.empty((len(bad), iq.size))
        for c, i in enumerate(iq):
            qe = q.copy()
            qe[i] += 1e-4
            G[:, c] = (sc.distances(qe)[bad] - d[bad]) / 1e-4
        want = np.array([clear if i in watch else floor[i] for i in bad]) + 1e-3 - d[bad]
        dq = np.linalg.lstsq(G, want, rcond=None)[0]
        dq *= min(1.0, MAX_REST_STEP / max(float(np.max(np.abs(dq))), 1e-12))
        q[iq] = np.clip(q[iq] + dq, lo, hi)
    return q


def _sphere_pairs(robot: Robot, margin: float, active: float, q: np.ndarray | None = None
                  ) -> tuple[tuple[SpherePair, ...], tuple[LeftOut, ...]]:
    """``(kept, left out)`` sphere pairs (:func:`sphere_pairs`, :func:`left_out_sphere_pairs`)
    at the pose ``q`` (default neutral), cached on the robot per ``(margin, active, q)``."""
    from ...model.selfcollision import placement, self_collision

    q = np.asarray(robot.neutral if q is None else q, float)
    cache = robot.__dict__.setdefault("_sphere_pairs", {})
    key = (margin, active, q.tobytes())
    if key in cache:
        return cache[key]
    sc, cm = self_collision(robot), robot.collision_model
    if sc is None or cm is None:
        return (), ()
    model = robot.model
    dq = dict(zip(sc.pairs, sc.distances(q)))
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    pairs, left_out = [], []
    for a, b, _, _ in _active_pairs(robot, sc):
        d = dq[a, b]
        if d >= active:
            continue
        if d < margin:  # within the margin at rest: left out and listed, like the audit's
            left_out.append((a, b, float(d)))
            continue
        ends = []
        for n in (a, b):
            g = cm.geometryObjects[cm.getGeometryId(n)]
            j, M = int(g.parentJoint), placement(g)
            ends.append([(model.names[j], M.act(ci), r, data.oMi[j].act(M.act(ci)))
                         for ci, r in _cover(g)])
        for fa, oa, ra, wa in ends[0]:
            for fb, ob, rb, wb in ends[1]:
                gap = float(np.linalg.norm(wa - wb) - ra - rb)
                if gap < ACTIVE_SPHERES:  # closer than the margin at rest: keep that gap
                    pairs.append((fa, tuple(map(float, oa)), ra, fb, tuple(map(float, ob)), rb,
                                  float(min(gap, margin))))
    cache[key] = out = (tuple(pairs), tuple(left_out))
    return out
