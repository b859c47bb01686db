"""Self-collision: distances between a robot's own collision geometries (docs/design.md §12).

The robot's collision geometry (the URDF's ``<collision>`` elements, a Pinocchio
``GeometryModel``) is split into the **trunk** and its **limbs** by the kinematic tree alone:
from the root joint the trunk descends while exactly one child subtree is not a leg (the legs
are :attr:`Robot.legs`); where two or more non-leg subtrees branch off (arms, head), each is a
limb, and so is each leg. The pairs checked are every pair of geometries on two different
limbs (limb–limb) or on a limb and the trunk (limb–trunk); geometries of one limb, or of the
trunk, are never paired (neighbouring links overlap by design), nor are neighbouring bodies —
one hanging from the other by a joint, a chain of joints turning about one point (a ball
joint the URDF writes as single-axis joints and small links: iCub's, Talos's, Romeo's hips)
counted as one joint: iCub's thigh hull, 0.5 mm from its root link's at the neutral pose,
went into it at any hip flexion without hip roll (coal's mesh distance: touching too), and
its streamed walk, whose QP kept those hulls apart, fell (0 of 60 frames feasible, 60 with
the rule). Pairs already closer than the
``margin`` at the neutral pose (a thigh against the pelvis, an upper arm against the torso)
are left out and listed (:attr:`SelfCollision.excluded`): no motion could keep them apart.

Distances are computed by coal (GJK/EPA, signed: negative inside each other) between convex
shapes: meshes are replaced by their convex hulls (conservative — a hull is never farther from
anything than its mesh), primitives (spheres, cylinders, boxes, capsules) are kept. A Y-up
Collada mesh is turned back as the URDF placed it (:mod:`gdimitate.model.meshes`, the same rotation
the sole measurement and the viewer apply): as loaded, iCub's meshes lie 90° off their links —
thighs horizontal, the chest in front of the torso, each foot across its leg — so the left
thigh sat 1.5 cm from the chest and the left foot 1 mm from the right ankle at the neutral
pose, and the adaptor's sphere rows, cut from those shapes, held the thighs off the chest.

:class:`Proximity` measures, along a sequence of configurations, only the pairs that may be
near (a lower bound on each pair's distance kept from call to call): the audit's closest pair
per knot and the streaming mode's collision rows, with the answers of measuring every pair.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError
from .kinematics import cross
from .meshes import ASSIMP_Y_UP_UNDO, collada_y_up

__all__ = ["SelfCollision", "Proximity", "self_collision", "limb_groups", "placement", "TRUNK"]

TRUNK = "trunk"
#: Default clearance [m] below which a pair at the neutral pose is left out.
NEUTRAL_MARGIN = 0.0
#: A joint whose origin is within this distance [m] of its parent joint's turns about the
#: same point: the two are one (ball) joint for :func:`_adjacent`.
AT_ONE_POINT = 1e-3


def _children(model: pin.Model) -> dict[int, list[int]]:
    out: dict[int, list[int]] = {j: [] for j in range(model.njoints)}
    for j in range(1, model.njoints):
        out[model.parents[j]].append(j)
    return out


def _subtree(children: dict[int, list[int]], j: int) -> list[int]:
    out, stack = [], [j]
    while stack:
        k = stack.pop()
        out.append(k)
        stack += children[k]
    return out


def limb_groups(robot) -> dict[int, str]:
    """``{joint id: group}``: :data:`TRUNK` or the name of the joint a limb starts at (module
    docstring). Joint 0 (the universe) and the root belong to the trunk."""
    model = robot.model
    children = _children(model)
    leg_joints = set()
    for leg in robot.legs.values():
        if model.existJointName(leg.hip):
            j = model.getJointId(leg.hip)
            leg_joints.add(j)
    groups = {0: TRUNK}
    cur = 1 if model.njoints > 1 and model.parents[1] == 0 else 0
    while True:
        groups[cur] = TRUNK
        kids = children[cur]
        legs = [k for k in kids if leg_joints & set(_subtree(children, k))]
        other = [k for k in kids if k not in legs]
        for k in legs:
            _assign(groups, children, k)
        if len(other) == 1:
            cur = other[0]
            continue
        for k in other:
            _assign(groups, children, k)
        break
    for j in range(model.njoints):  # joints under the universe besides the root chain
        groups.setdefault(j, TRUNK)
    return groups


def _assign(groups: dict[int, str], children, top: int) -> None:
    """One limb: every joint of ``top``'s subtree labelled ``limb:<top>``."""
    for k in _subtree(children, top):
        groups[k] = f"limb:{top}"


@dataclass(frozen=True)
class SelfCollision:
    """A robot's self-collision pairs and how to measure them.

    ``geometry``: the convexified ``pin.GeometryModel`` with the checked pairs as its collision
    pairs; ``pairs`` ``((name_a, name_b), …)``: the checked pairs (geometry object names);
    ``groups`` ``{geometry name: "trunk" | limb}`` (a limb is named after its first joint);
    ``excluded`` ``((name_a, name_b, distance [m]), …)``: pairs closer than ``margin`` at the
    neutral pose (their distance there) and pairs on neighbouring bodies (NaN), left out;
    ``margin`` [m]: that threshold."""

    geometry: pin.GeometryModel
    pairs: tuple[tuple[str, str], ...]
    groups: dict[str, str]
    excluded: tuple[tuple[str, str, float], ...]
    margin: float
    model: pin.Model

    @functools.cached_property
    def spheres(self) -> tuple:
        """What :class:`Proximity` reads, computed once: each geometry's bounding sphere
        centre in its parent joint's frame ``(G, 3)`` [m] and radius ``(G,)`` [m] (its local
        bounding box's centre and half diagonal, coal's ``aabb_center``, ``aabb_radius``),
        the pairs' geometry indices ``(P, 2)`` and parent joints ``(P, 2)``, the parent
        joints used (sorted) and each geometry's index into them ``(G,)``."""
        centre, radius = [], []
        for g in self.geometry.geometryObjects:
            shape = g.geometry
            shape.computeLocalAABB()
            centre.append(g.placement.act(np.asarray(shape.aabb_center, float)))
            radius.append(float(shape.aabb_radius))
        parent = np.array([int(g.parentJoint) for g in self.geometry.geometryObjects], int)
        pairs = np.array([(p.first, p.second) for p in self.geometry.collisionPairs],
                         int).reshape(-1, 2)
        used, of = np.unique(parent, return_inverse=True)
        return (np.array(centre).reshape(-1, 3), np.array(radius), pairs, parent[pairs],
                [int(j) for j in used], of)

    def distances(self, q: np.ndarray) -> np.ndarray:
        """Signed distances ``(T, P)`` [m] of the checked pairs at configurations ``q``
        ``(T, nq)`` (or ``(P,)`` for one ``(nq,)``); negative where two shapes overlap."""
        Q, one = self._configurations(q)
        data, gdata = self.model.createData(), pin.GeometryData(self.geometry)
        out = np.empty((Q.shape[0], len(self.pairs)))
        for k, qk in enumerate(Q):
            pin.computeDistances(self.model, data, self.geometry, gdata, qk)
            out[k] = [r.min_distance for r in gdata.distanceResults]
        return out[0] if one else out

    def closest(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The closest pair at each configuration of ``q`` ``(T, nq)``: its signed distance
        ``(T,)`` [m] and its index into :attr:`pairs` ``(T,)`` — ``distances(q)``'s row minima
        and their indices, measuring only the pairs that could be closest
        (:class:`Proximity`)."""
        Q, _ = self._configurations(q)
        data, near = self.model.createData(), Proximity(self)
        dist, which = np.empty(Q.shape[0]), np.empty(Q.shape[0], int)
        for k, qk in enumerate(Q):
            pin.forwardKinematics(self.model, data, qk)
            dist[k], which[k] = near.closest(data)
        return dist, which

    def _configurations(self, q) -> tuple[np.ndarray, bool]:
        q = np.asarray(q, dtype=float)
        Q = np.atleast_2d(q)
        if Q.shape[1] != self.model.nq:
            raise InvalidInputError(f"q has {Q.shape[1]} columns; the model has nq = "
                                    f"{self.model.nq}")
        return Q, q.ndim == 1


class Proximity:
    """Which pairs of a :class:`SelfCollision` may be near, along a sequence of
    configurations, with as few exact distances as can be: a lower bound on each pair's
    signed distance, kept from call to call, decides which pairs are measured (coal's GJK,
    ~7 µs a pair).

    The bound is the larger of two, both exact bounds (never above the distance):
    - the bounding spheres' gap ``|c_a − c_b| − r_a − r_b`` (each geometry in its local
      bounding box's sphere, coal's ``aabb_center`` and ``aabb_radius``: a shape inside its
      sphere is never closer to another than the spheres, nor deeper inside it);
    - the pair's last measured distance less how far each of its two shapes has moved since
      (a signed distance changes by at most the largest displacement of a point of either
      shape): ``|Δc| + r·|2 sin(θ/2)|`` for a shape whose sphere's centre moved by ``Δc``
      and which turned by the angle ``θ``, ``(2 sin(θ/2))² = 3 − tr(R_new R_oldᵀ)``.

    :meth:`closest` measures pairs in the order of their bounds until the next bound is no
    less than the least distance found: the answer of measuring every pair (Talos walking:
    a few dozen of its 988 pairs a knot)."""

    def __init__(self, collision: SelfCollision):
        self.c = collision
        (self.centre, self.radius, self.pairs, self.joints, self._used,
         self._of) = collision.spheres
        self.gdata = pin.GeometryData(collision.geometry)
        #: tracked()'s view of each pair's result, taken once (live references: indexing
        #: the vector costs 1 µs a pair)
        self._res: list = []
        #: the joints' placements (U, 4, 4) and each pair's lower bound (P,) at the last call
        self._H: np.ndarray | None = None
        self._low = np.full(len(self.pairs), -np.inf)
        self._all = np.arange(len(self.pairs))
        self._kept = self._all  # tracked()'s pairs
    def bounds(self, data) -> np.ndarray:
        """``(P,)`` lower bounds [m] of the pairs' signed distances at ``data``'s joint
        placements (``data.oMi``), and the geometries placed there for :meth:`distance`."""
        pin.updateGeometryPlacements(self.c.model, data, self.c.geometry, self.gdata)
        H, w, low = self._spheres(data)
        if self._H is not None:
            R, a, b = H[self._of, :3, :3], self.pairs[:, 0], self.pairs[:, 1]
            R0, t0 = self._H[self._of, :3, :3], self._H[self._of, :3, 3]
            w0 = (R0 @ self.centre[:, :, None])[:, :, 0] + t0
            turn = np.sqrt(np.maximum(3.0 - np.einsum("gij,gij->g", R, R0), 0.0))
            moved = np.linalg.norm(w - w0, axis=1) + self.radius * turn  # (G,)
            low = np.maximum(low, self._low - moved[a] - moved[b])
        self._H, self._low = H, low
        return low

    def _spheres(self, data) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At ``data``'s joint placements: the joints' placements ``(U, 4, 4)``, the
        bounding spheres' centres ``(G, 3)`` [m] (world) and the pairs' sphere gaps
        ``|c_a − c_b| − r_a − r_b`` ``(P,)`` [m]."""
        H = np.array([data.oMi[j].homogeneous for j in self._used])  # (U, 4, 4)
        R, t = H[self._of, :3, :3], H[self._of, :3, 3]
        w = (R @ self.centre[:, :, None])[:, :, 0] + t  # sphere centres, world (G, 3)
        a, b = self.pairs[:, 0], self.pairs[:, 1]
        return H, w, np.linalg.norm(w[a] - w[b], axis=1) - self.radius[a] - self.radius[b]

    def distance(self, i: int):
        """Pair ``i``'s coal ``DistanceResult`` at the placements of the last :meth:`bounds`
        (its bound becomes that distance)."""
        r = pin.computeDistance(self.c.geometry, self.gdata, int(i))
        self._low[i] = r.min_distance
        return r

    def tracked(self, data, q: np.ndarray, refresh: bool, near: float, watch: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The pairs near at ``q`` (``data``: its joint placements and Jacobians computed
        there), as the streaming mode's frames and first pose measure them: when
        ``refresh``, every pair, keeping those within ``near`` [m] (reading only the pairs
        whose bounding spheres' gap is below it: the others cannot be); otherwise the kept
        ones only (coal's GJK in Pinocchio's loop over the active pairs). Returns the kept
        pairs within ``watch`` [m]: their indices ``(K,)``, signed distances ``(K,)`` [m] and
        :meth:`rates` ``(K, nv)``. Every pair at a refresh, not the bounds every frame, nor
        only those that may be near at a refresh: coal's GJK starts from each pair's last
        answer (``enable_cached_gjk_guess``; the same pair at the same configuration differs
        by up to 2e-3 in its normal with another history), and measuring fewer pairs changed
        the streams' motions (Talos on the SFU-style walk: 248 of 265 frames feasible, not
        253; measuring at a refresh only the pairs whose spheres may be near moved its
        stream by up to 1 rad)."""
        g, gd, m = self.c.geometry, self.gdata, self.c.model
        res = self._res = self._res or list(gd.distanceResults)
        if refresh:
            self._active(self._all)
            pin.computeDistances(m, data, g, gd, q)
            may = np.flatnonzero(self._spheres(data)[2] < near).tolist()
            self._kept = np.array([i for i in may if res[i].min_distance < near], int)
            self._active(self._kept)
        else:
            pin.computeDistances(m, data, g, gd, q)  # the kept pairs: the active ones
        close = [res[i] for i in self._kept.tolist()]
        keep = [k for k, r in enumerate(close) if r.min_distance < watch]
        close = [close[k] for k in keep]
        return (self._kept[keep], np.array([r.min_distance for r in close]),
                self.rates(data, self._kept[keep], close))

    def _active(self, pairs) -> None:
        """Make ``pairs`` (indices) the ones ``pin.computeDistances`` measures."""
        on = np.zeros((self.c.geometry.ngeoms,) * 2, bool)
        ab = self.pairs[np.asarray(pairs, int)]
        on[ab[:, 0], ab[:, 1]] = on[ab[:, 1], ab[:, 0]] = True
        self.gdata.setActiveCollisionPairs(self.c.geometry, on, True)

    def rates(self, data, idx: np.ndarray, res: list) -> np.ndarray:
        """``(K, nv)``: the rate per velocity of the distance of each pair of ``idx`` whose
        coal ``DistanceResult`` is in ``res``, at ``data`` (joint Jacobians computed):
        ``ḋ = nᵀ (ṗ_b − ṗ_a)`` at the nearest points (``n`` the unit normal from a to b).
        All pairs at once, with the arithmetic of one pair at a time — each side's
        ``nᵀ J_v + (r × n)ᵀ J_ω`` summed over its three rows in order, b's less a's — bit for
        bit (the first pose's Gauss–Newton steps turn a difference of 1e-11 into another
        pose)."""
        m = self.c.model
        if not len(res):
            return np.zeros((0, m.nv))
        joints = self.joints[np.asarray(idx, int)][:, ::-1]  # (K, 2): b's, a's
        used = np.unique(joints)
        jac = np.zeros((used.size, 6, m.nv))  # the universe's stays 0: it does not move
        origin = np.zeros((used.size, 3))
        for u, j in enumerate(used.tolist()):
            if j > 0:
                jac[u] = pin.getJointJacobian(m, data, j, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
                origin[u] = data.oMi[j].translation
        at = np.searchsorted(used, joints)  # (K, 2)
        n = np.array([r.normal for r in res], float)  # (K, 3)
        p = np.array([(r.getNearestPoint2(), r.getNearestPoint1()) for r in res], float)
        # nᵀ(v + ω × r) = nᵀ v + (r × n)ᵀ ω at the point; a's moves it away from b
        rn = cross(p - origin[at], n[:, None, :])  # (K, 2, 3)
        J = jac[at]  # (K, 2, 6, nv)
        side = (np.einsum("ki,ksiv->ksv", n, J[:, :, :3])
                + np.einsum("ksi,ksiv->ksv", rn, J[:, :, 3:]))
        return side[:, 0] - side[:, 1]

    def closest(self, data) -> tuple[float, int]:
        """The closest pair at ``data``'s joint placements: its signed distance [m] and index
        (``inf, -1`` without pairs); measured in the order of their bounds, until the next
        bound is no less than the least distance found."""
        low = self.bounds(data)
        best, arg = np.inf, -1
        for i in np.argsort(low):
            if low[i] >= best:
                break
            r = self.distance(int(i)).min_distance
            if r < best:
                best, arg = r, int(i)
        return best, arg


def _convex(geom: pin.GeometryModel) -> pin.GeometryModel:
    """A copy whose meshes are their convex hulls, Y-up Collada meshes placed as their URDF
    means (:func:`placement`)."""
    import coal

    out = pin.GeometryModel()
    for g in geom.geometryObjects:
        g = g.copy()
        g.placement = placement(g)
        shape = g.geometry
        if isinstance(shape, coal.BVHModelBase):
            shape.buildConvexHull(False, "Qt")
            g.geometry = shape.convex
        out.addGeometryObject(g)
    return out


def placement(g: pin.GeometryObject) -> pin.SE3:
    """The placement of a geometry object's vertices (as Pinocchio loaded them) in its parent
    joint's frame: ``g.placement``, times the rotation back to the file's raw coordinates for
    a Y-up Collada mesh (:data:`gdimitate.model.meshes.ASSIMP_Y_UP_UNDO`)."""
    if g.meshPath and collada_y_up(g.meshPath):
        return g.placement * pin.SE3(ASSIMP_Y_UP_UNDO, np.zeros(3))
    return g.placement


def self_collision(robot, margin: float = NEUTRAL_MARGIN) -> SelfCollision | None:
    """The :class:`SelfCollision` of ``robot`` (a :class:`~gdimitate.Robot`), or ``None`` when
    it has no collision geometry. ``margin`` [m]: pairs closer than this at the neutral pose
    are left out. Cached on the robot per margin."""
    if not (np.isfinite(margin) and margin >= 0):
        raise InvalidInputError(f"margin must be a finite distance ≥ 0 [m]; got {margin!r}")
    cache = robot.__dict__.setdefault("_self_collision", {})
    if margin in cache:
        return cache[margin]
    geom = getattr(robot, "collision_model", None)
    if geom is None or geom.ngeoms == 0:
        cache[margin] = None
        return None
    model = robot.model
    convex = _convex(geom)
    jg = limb_groups(robot)
    objs = convex.geometryObjects
    groups = {g.name: jg.get(int(g.parentJoint), TRUNK) for g in objs}
    par, ball = model.parents, _balls(model)
    adjacent = [(i, j) for i in range(len(objs)) for j in range(i + 1, len(objs))
                if groups[objs[i].name] != groups[objs[j].name]
                and _adjacent(par, ball, int(objs[i].parentJoint), int(objs[j].parentJoint))]
    cand = [(i, j) for i in range(len(objs)) for j in range(i + 1, len(objs))
            if groups[objs[i].name] != groups[objs[j].name] and (i, j) not in adjacent]
    for i, j in cand:
        convex.addCollisionPair(pin.CollisionPair(i, j))
    data, gdata = model.createData(), pin.GeometryData(convex)
    pin.computeDistances(model, data, convex, gdata, robot.neutral)
    d0 = np.array([r.min_distance for r in gdata.distanceResults])
    keep = [p for p, d in zip(cand, d0) if d >= margin]
    excluded = tuple((objs[i].name, objs[j].name, float(d)) for (i, j), d in zip(cand, d0)
                     if d < margin)
    excluded += tuple((objs[i].name, objs[j].name, float("nan")) for i, j in adjacent)
    convex.removeAllCollisionPairs()
    for i, j in keep:
        convex.addCollisionPair(pin.CollisionPair(i, j))
    out = SelfCollision(convex, tuple((objs[i].name, objs[j].name) for i, j in keep),
                        {k: _label(model, v) for k, v in groups.items()}, excluded,
                        float(margin), model)
    cache[margin] = out
    return out


def _balls(model: pin.Model) -> list[int]:
    """Per joint, the first joint of the chain of joints at one point it ends (:data:`AT_ONE_POINT`
    from their parents: iCub's, Talos's and Romeo's three-axis hips, iCub's torso pitch at the
    root's origin) — a chain the URDF writes as single-axis joints and small links for one
    ball joint; every other joint is its own."""
    out = list(range(model.njoints))
    for j in range(1, model.njoints):
        p = model.parents[j]
        if p > 0 and np.linalg.norm(model.jointPlacements[j].translation) < AT_ONE_POINT:
            out[j] = out[p]
    return out


def _adjacent(parents, ball: list[int], a: int, b: int) -> bool:
    """Two joints' bodies are neighbours: one hangs from the other by a joint, counting a
    chain of joints at one point (``ball``, :func:`_balls`) as one joint."""
    if ball[a] == ball[b]:
        return True
    return ball[parents[ball[a]]] == ball[b] or ball[parents[ball[b]]] == ball[a]


def _label(model: pin.Model, group: str) -> str:
    return group if group == TRUNK else f"limb from {model.names[int(group.split(':')[1])]}"
