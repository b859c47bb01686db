"""Self-collision (issue 20; docs/design.md §12): the pairs a robot's own collision geometry
gives (limb–limb, limb–trunk; neighbours and pairs touching at the neutral pose left out and
listed), their distances against closed forms and coal's own mesh distances, and the audit's
``self_collision`` check: a motion that drives a hand through the pelvis fails it, standing
and a real walk copied onto the robots pass it."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.assess.audit import audit
from gdimitate.assess.wrenches import estimate_wrenches
from gdimitate.errors import InvalidInputError
from gdimitate.model.motion import Motion
from gdimitate.model.selfcollision import TRUNK, limb_groups, self_collision


@pytest.fixture(scope="module")
def g1():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gd.Robot.from_library("g1")


def _world(robot, name, q):
    """Placement of collision geometry ``name`` at ``q`` (Pinocchio)."""
    g = robot.collision_model.geometryObjects[robot.collision_model.getGeometryId(name)]
    d = robot.model.createData()
    pin.forwardKinematics(robot.model, d, q)
    return d.oMi[g.parentJoint] * g.placement, g.geometry


def test_limbs_and_pairs_of_g1(g1):
    """G1's tree gives the trunk (pelvis → waist → torso) and four limbs; no pair lies within
    one group; every left-out pair is a neighbour (NaN) or closer than the margin at the
    neutral pose (recomputed)."""
    groups = limb_groups(g1)
    m = g1.model
    assert groups[m.getJointId("waist_pitch_joint")] == TRUNK
    assert groups[m.getJointId("left_elbow_joint")] == groups[m.getJointId(
        "left_shoulder_pitch_joint")] != groups[m.getJointId("right_elbow_joint")]
    assert groups[m.getJointId("left_knee_joint")] != TRUNK
    assert len({v for v in groups.values()}) == 5
    sc = self_collision(g1, margin=0.01)
    assert sc.pairs and all(sc.groups[a] != sc.groups[b] for a, b in sc.pairs)
    d0 = sc.distances(g1.neutral)
    assert d0.min() >= 0.01
    for *_, d in sc.excluded:
        if np.isfinite(d):
            assert d < 0.01
    assert self_collision(g1, margin=0.01) is sc  # cached
    with pytest.raises(InvalidInputError, match="margin"):
        self_collision(g1, margin=-1.0)


def test_distances_against_closed_forms_and_meshes(g1):
    """Sphere pairs: |c_a − c_b| − r_a − r_b from Pinocchio placements (to 1e-9 m); mesh
    pairs: the hull distance never exceeds coal's distance between the meshes themselves
    (conservative; up to GJK's tolerance, 1e-5 m), at random configurations within the
    limits."""
    import coal

    sc = self_collision(g1)
    rng = np.random.default_rng(3)
    m = g1.model
    spheres = [i for i, (a, b) in enumerate(sc.pairs)
               if all(isinstance(_world(g1, n, g1.neutral)[1], coal.Sphere) for n in (a, b))]
    meshes = [i for i, (a, b) in enumerate(sc.pairs)
              if all(isinstance(_world(g1, n, g1.neutral)[1], coal.BVHModelBase)
                     for n in (a, b))][::25]
    assert len(spheres) >= 4 and len(meshes) >= 10
    for _ in range(5):
        q = g1.neutral.copy()
        q[7:] = rng.uniform(m.lowerPositionLimit[7:], m.upperPositionLimit[7:])
        D = sc.distances(q)
        for i in spheres:
            (Ma, ga), (Mb, gb) = (_world(g1, n, q) for n in sc.pairs[i])
            ref = np.linalg.norm(Ma.translation - Mb.translation) - ga.radius - gb.radius
            assert D[i] == pytest.approx(ref, abs=1e-9)
        for i in meshes:
            (Ma, ga), (Mb, gb) = (_world(g1, n, q) for n in sc.pairs[i])
            req, res = coal.DistanceRequest(), coal.DistanceResult()
            coal.distance(ga, coal.Transform3s(Ma.rotation, Ma.translation), gb,
                          coal.Transform3s(Mb.rotation, Mb.translation), req, res)
            assert D[i] <= res.min_distance + 1e-5  # GJK's convergence tolerance


def _reach(robot, frame: str, geom: str, arm_prefix: str) -> np.ndarray:
    """A configuration that brings ``frame`` as near as the arm reaches to the centre of mesh
    ``geom``'s bounding box (damped least squares on the shoulder and elbow joints, the rest
    at the neutral pose)."""
    m, d = robot.model, robot.model.createData()
    q = robot.neutral.copy()
    Mg, mesh = _world(robot, geom, q)
    V = np.asarray(mesh.vertices())
    centre = Mg.act(0.5 * (V.min(axis=0) + V.max(axis=0)))
    cols = [m.joints[j].idx_v for j in range(1, m.njoints)
            if m.names[j].startswith(arm_prefix) and ("shoulder" in m.names[j]
                                                     or "elbow" in m.names[j])]
    qi = [m.joints[j].idx_q for j in range(1, m.njoints) if m.joints[j].idx_v in cols]
    fid = m.getFrameId(frame)
    for _ in range(100):
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        e = centre - d.oMf[fid].translation
        J = pin.getFrameJacobian(m, d, fid, pin.LOCAL_WORLD_ALIGNED)[:3, cols]
        v = np.zeros(m.nv)
        v[cols] = J.T @ np.linalg.solve(J @ J.T + 1e-4 * np.eye(3), e)
        q = pin.integrate(m, q, 0.5 * v)
        q[qi] = np.clip(q[qi], m.lowerPositionLimit[qi], m.upperPositionLimit[qi])
    return q


def _static(robot, qs: np.ndarray):
    """A motion through configurations ``qs`` at 10 Hz, both feet in stance, its wrenches
    (the cone QP)."""
    from gdimitate.model.kinematics import robot_motion
    from gdimitate.model.motion import differentiate

    t = np.arange(len(qs)) * 0.1
    mo = differentiate(robot.model, robot_motion(robot, t, qs, {s: np.ones(len(qs), bool)
                                                                for s in ("left", "right")}))
    return mo, estimate_wrenches(robot, mo).wrenches


def test_hand_through_the_pelvis_fails_the_audit(g1):
    """The left hand driven into the pelvis (its wrist towards the centre of the pelvis mesh's
    bounding box, shoulder and elbow within their limits): the audit's ``self_collision``
    fails, naming a pair that overlaps, and the wrist–pelvis distance is negative; standing
    still passes."""
    q_in = _reach(g1, "left_wrist_yaw_link", "pelvis_contour_link_0", "left_")
    qs = np.array([g1.neutral + s * (q_in - g1.neutral) for s in np.linspace(0, 1, 6)])
    qs[:, 3:7] = g1.neutral[3:7]
    motion, w = _static(g1, qs)
    rep = audit(g1, motion, w)
    assert not rep.feasible and "self_collision" in rep.binding
    chk = rep.check("self_collision")
    assert chk.value < 0 and chk.knot == 5
    sc = self_collision(g1)
    i = sc.pairs.index(("pelvis_contour_link_0", "left_wrist_yaw_link_0"))
    assert sc.distances(q_in)[i] < 0
    assert rep.check_knots("self_collision")[0]  # the neutral start is clear
    still, w0 = _static(g1, np.tile(g1.neutral, (6, 1)))
    ok = audit(g1, still, w0)
    assert ok.check("self_collision").passed and ok.self_collision.distance > 0
    assert "self-collision" in ok.summary()


@pytest.mark.parametrize("name", ["g1", "talos", "romeo"])
def test_the_real_walk_copied_onto_the_robots_is_clear(name):
    """The shipped 3-D walk, joint angles copied onto the robot (arms at their neutral pose):
    no limb comes within 1 mm of another or of the trunk over the whole clip (measured:
    G1 7.8 mm, Talos 5.1 mm, Romeo 19.7 mm). (iCub's copy is not clear: its right thigh's
    hull goes 8.0 mm into its root link's, 0.5 mm apart at the neutral pose.)"""
    from gdimitate.apps.baselines import joint_copy

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h, motion, _ = gd.gait.human_walk_3d()
        robot = gd.Robot.from_library(name)
        out = joint_copy(motion, h, robot)
    q = getattr(out, "motion", out).q
    assert self_collision(robot).distances(q).min() >= 1e-3


def test_robot_without_collision_geometry_is_not_checked():
    """A robot without collision geometry: no self-collision check, and the report says so."""
    robot = gd.Robot.from_library("hoap2")
    assert self_collision(robot) is None
    t = np.arange(3) * 0.1
    mo = Motion(t=t, joint_names=robot.joint_names, q=np.tile(robot.neutral, (3, 1)),
                contact={s: np.ones(3, bool) for s in ("left", "right")},
                v=np.zeros((3, robot.model.nv)), a=np.zeros((3, robot.model.nv)))
    rep = audit(robot, mo, estimate_wrenches(robot, mo).wrenches)
    assert rep.self_collision is None
    assert "self-collision: not checked" in rep.summary()
    assert all(c.name != "self_collision" for c in rep.checks)


# ------------------------------------------------------------------ the adaptor's parts
def test_sphere_covers_enclose_the_hulls(g1):
    """Every vertex of every collision mesh (hence of its convex hull; a box's corners, a
    cylinder's rims) lies inside one of the spheres that cover it, and a sphere primitive is
    its own cover — so spheres kept apart keep the hulls apart."""
    import coal

    from gdimitate.retarget.parts.self_collision import MAX_SPHERES, _cover, _vertices

    for g in g1.collision_model.geometryObjects:
        cover = _cover(g)
        assert 1 <= len(cover) <= MAX_SPHERES
        if isinstance(g.geometry, coal.Sphere):
            assert cover[0][1] == pytest.approx(g.geometry.radius)
            continue
        V = _vertices(g)  # a mesh's vertices include its hull's
        inside = np.min([np.linalg.norm(V - c, axis=1) - r for c, r in cover], axis=0)
        assert inside.max() <= 1e-9, g.name


def test_self_collision_rows_match_pinocchio():
    """The part's rows at random configurations, one per pair of frames: the soft minimum
    (re-derived here in NumPy) of its sphere pairs' clearances (|c_a − c_b| − r_a − r_b − gap)
    / leg length from Pinocchio's world frame placements (to 1e-10), never above the smallest
    clearance and at most log(n) / β below it; their Jacobian against central differences,
    with no column on the base's q (a distance between two bodies does not see the base);
    bounds 0, no gap above the 1 cm margin; labels per pair of frames."""
    import casadi as ca

    from gdimitate.retarget.parts import Spec
    from gdimitate.retarget.parts.self_collision import (
        MARGIN,
        SHARPNESS,
        SelfCollision,
        sphere_pairs,
    )
    from tests.retarget.parts.test_parts import _fd_check, knot_of, random_point

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = gd.Robot.from_library("romeo")  # the fewest pairs: a quick symbolic model
    pairs = sphere_pairs(robot)
    assert pairs and all(gap <= MARGIN for *_, gap in pairs)
    frames = list(dict.fromkeys((fa, fb) for fa, _, _, fb, *_ in pairs))[:3]
    part = SelfCollision(tuple(pp for pp in pairs if (pp[0], pp[3]) in frames))
    sizes = [len(ix) for *_, ix in part.groups()]
    assert len(sizes) == 3 and max(sizes) > 1  # one soft minimum over several sphere pairs
    k, f = knot_of(robot, part)
    L = robot.legs["left"].length
    for _ in range(3):
        x, p, s = random_point(robot, k)
        d = robot.model.createData()
        pin.framesForwardKinematics(robot.model, d, s["q"])
        row = np.array(f(x, p)).ravel()
        for r, (fa, fb, ix) in zip(row, part.groups()):
            c = np.array([(np.linalg.norm(d.oMf[robot.model.getFrameId(fa)].act(np.array(oa))
                                          - d.oMf[robot.model.getFrameId(fb)].act(np.array(ob)))
                           - ra - rb - gap) / L
                          for _, oa, ra, _, ob, rb, gap in (part.pairs[i] for i in ix)])
            ref = c.min() - np.log(np.sum(np.exp(-SHARPNESS * (c - c.min())))) / SHARPNESS
            assert r == pytest.approx(ref, abs=1e-10)
            assert c.min() - np.log(len(c)) / SHARPNESS - 1e-12 <= r <= c.min() + 1e-12
    _fd_check(f, x, p)
    xs = ca.SX.sym("x", x.size)
    assert f.sx_in(0).shape == xs.shape
    base = np.arange(x.size)[k.var["q"]][:7]
    jac = ca.jacobian(f(xs, f.sx_in(1)), xs).sparsity()
    assert not set(jac.get_col()) & set(base.tolist())
    spec = Spec(T=3, stance={}, swing={}, liftoff={}, goal_active={}, planar=False, free=True,
                cone=False, clearance=0.0, leg_length=L, n_base=6, n_act=0)
    lo, hi = part.bounds(spec)
    np.testing.assert_array_equal(lo, 0.0)
    assert np.all(np.isinf(hi))
    assert part.labels(k) == [f"self-collision: {fa}/{fb}" for fa, fb in frames]


def _rest_rows(robot):
    """``(rest pose, self-collision part with its rest floors, rows(q) -> the part's CasADi
    rows at the pose q, their lower bounds)`` of ``robot``'s adaptor."""
    from gdimitate.retarget.parts import Spec
    from gdimitate.retarget.parts.self_collision import (
        SelfCollision,
        rest_floors,
        rest_pose,
        sphere_pairs,
    )
    from tests.retarget.parts.test_parts import knot_of, random_point

    rest = rest_pose(robot)
    pairs = sphere_pairs(robot, q=rest)
    part = SelfCollision(pairs, (), rest_floors(robot, pairs, rest))
    k, f = knot_of(robot, part)
    x, p, _ = random_point(robot, k)

    def rows(q: np.ndarray) -> np.ndarray:
        x[k.var["q"]] = q
        return np.array(f(x, p)).ravel()

    spec = Spec(T=1, stance={}, swing={}, liftoff={}, goal_active={}, planar=False, free=True,
                cone=False, clearance=0.0, leg_length=robot.legs["left"].length, n_base=6,
                n_act=0)
    return rest, part, rows, part.bounds(spec)[0][0]


def _pair_index(sc, a: str, b: str) -> int:
    """Index of the geometry pair ``{a, b}`` in ``sc.pairs``, in either order."""
    return sc.pairs.index((a, b)) if (a, b) in sc.pairs else sc.pairs.index((b, a))


def test_rest_pose_meets_the_self_collision_rows(g1):
    """G1's adaptor rest pose (where its sphere pairs are taken) meets its self-collision
    part's rows: several sphere pairs of one frame pair keep their gap there (clearance 0), so
    their soft minimum is below 0 at rest — the row's floor is that value, at most log(n) / β
    below 0, and the part's CasADi rows at the rest pose equal the floors there (to 1e-10)."""
    from gdimitate.retarget.parts.self_collision import SHARPNESS

    rest, part, rows_at, lo = _rest_rows(g1)
    floors = part.floors
    n = [len(ix) for *_, ix in part.groups()]
    assert len(floors) == len(n) and min(floors) < -1e-3  # not vacuous: some row needs it
    assert all(-np.log(m) / SHARPNESS - 1e-12 <= f <= 0.0 for f, m in zip(floors, n))
    rows = rows_at(rest)
    assert np.all(rows >= lo - 1e-10)
    neg = np.array(floors) < 0
    np.testing.assert_allclose(rows[neg], lo[neg], atol=1e-10)


def test_unmapped_joints_are_held_by_the_parts(g1):
    """``body_parts``: a posture range over every actuated joint whose ``hold`` parameter is
    1 exactly for the joints the body map leaves out — for subject01 (no arms) on G1 the arms
    and wrists, not the legs — rows ``hold·(q − rest pose)`` within ±HOLD_RANGE (the rest
    pose: the neutral one with G1's shoulders rolled out of its torso's margin); and a
    self-collision part."""
    from types import SimpleNamespace

    from gdimitate.retarget.bodymap import HOLD_RANGE, body_map
    from gdimitate.retarget.parts import Spec
    from gdimitate.retarget.parts.body import body_parts
    from gdimitate.retarget.parts.posture_range import PostureRange
    from gdimitate.retarget.parts.self_collision import SelfCollision, rest_pose

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        human = gd.Robot.from_osim(gd.gait.human_walk_3d_folder() / "subject01.osim")
        bm = body_map(human, g1)
    act = [j for j in g1.joint_names if g1.model.joints[g1.model.getJointId(j)].nq == 1]
    parts = body_parts(g1, act)
    hold = next(p for p in parts if isinstance(p, PostureRange))
    assert any(isinstance(p, SelfCollision) for p in parts)
    mapped = np.array([j in {v[0] for v in bm.joints.values()} for j in act])
    ctx = SimpleNamespace(tg=SimpleNamespace(mapped=mapped, T=3),
                          lim=SimpleNamespace(frozen=np.zeros(len(act), bool)))
    h = hold.values(ctx)["hold"]
    held = {j for j, x in zip(act, h[0]) if x == 1}
    assert {"left_shoulder_pitch_joint", "right_elbow_joint", "left_wrist_yaw_joint"} <= held
    assert not held & {v[0] for v in bm.joints.values()} and h.shape == (3, len(act))
    spec = Spec(T=2, stance={}, swing={}, liftoff={}, goal_active={}, planar=False, free=True,
                cone=False, clearance=0.0, leg_length=0.6, n_base=6, n_act=0)
    lo, hi = hold.bounds(spec)
    np.testing.assert_allclose(hi, HOLD_RANGE)
    np.testing.assert_allclose(lo, -HOLD_RANGE)
    np.testing.assert_allclose(hold.held, rest_pose(g1)[list(hold.q_index)])


def test_sphere_rows_leave_out_pairs_within_the_margin_at_neutral():
    """The adaptor's sphere rows apply the audit's rule: geometry pairs closer than the margin
    at the neutral pose are left out and listed; a sphere pair's least gap is the margin or
    its gap at the neutral pose, whichever is smaller. No sphere pair spans the two legs (their
    covers overlap by centimetres where the hulls pass with millimetres to spare: Talos spent
    its iteration budget); one smooth row keeps the soles apart instead, whose slack at the
    neutral pose is the legs' closest hull distance there less the margin. Distances
    re-derived from Pinocchio placements and coal (:meth:`SelfCollision.distances`)."""
    from gdimitate.retarget.parts.self_collision import (
        MARGIN,
        left_out_sphere_pairs,
        leg_separation,
        sphere_pairs,
    )

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = gd.Robot.from_library("talos")
    model, data = robot.model, robot.model.createData()
    pin.framesForwardKinematics(model, data, robot.neutral)
    pairs, left = sphere_pairs(robot), left_out_sphere_pairs(robot)
    assert pairs and left and all(d < MARGIN for *_, d in left)
    groups = limb_groups(robot)
    legs = {groups[model.getJointId(leg.hip)] for leg in robot.legs.values()}
    for fa, oa, ra, fb, ob, rb, gap in pairs:
        ja, jb = model.getJointId(fa), model.getJointId(fb)
        d = np.linalg.norm(data.oMi[ja].act(np.array(oa)) - data.oMi[jb].act(np.array(ob)))
        assert gap == pytest.approx(min(d - ra - rb, MARGIN), abs=1e-9)
        assert not (groups[ja] in legs and groups[jb] in legs and groups[ja] != groups[jb])
    sc = self_collision(robot)
    d0 = sc.distances(robot.neutral)
    leg_labels = {f"limb from {model.names[int(g.split(':')[1])]}" for g in legs}
    leg_d = min(d for (a, b), d in zip(sc.pairs, d0)
                if {sc.groups[a], sc.groups[b]} <= leg_labels and sc.groups[a] != sc.groups[b])
    (fl, fr, root, least), = leg_separation(robot)
    R = data.oMi[model.getJointId(root)].rotation
    y0 = (R.T @ (data.oMf[model.getFrameId(fl)].translation
                 - data.oMf[model.getFrameId(fr)].translation))[1]
    assert y0 - least == pytest.approx(leg_d - MARGIN, abs=1e-9)


def test_rest_pose_clears_the_limbs_the_neutral_pose_presses_together(g1):
    """The adaptor holds unmapped joints near ``rest_pose``: Talos's neutral pose holds its
    wrists and grippers within the margin of its thighs (8.7–9.6 mm) — at its rest pose every
    such active pair is at least REST_CLEAR apart, no pair the audit checks is closer than
    min(its neutral distance, the margin) (coal's hull distances, recomputed here), only arm
    and head joints moved, inside their limits; those pairs now get sphere rows and none is
    left out. G1's upper arms hang 9.2 mm from its torso at its neutral pose (pairs that get
    rows since :data:`PROXIMAL_ARM`): its rest pose rolls its shoulders out, by less than
    0.1 rad, until they are REST_CLEAR apart, and moves nothing else. (Until its Y-up Collada
    meshes were turned as its URDF means, iCub was this test's robot: its forearms then sat
    2.1 mm from a chest mesh lying in front of its torso.)"""
    from gdimitate.retarget.parts.self_collision import (
        MARGIN,
        REST_CLEAR,
        left_out_sphere_pairs,
        rest_pose,
        sphere_pairs,
    )

    qg = rest_pose(g1)
    moved = np.flatnonzero(qg != g1.neutral)
    assert {g1.model.names[j] for j in range(1, g1.model.njoints)
            if g1.model.joints[j].idx_q in moved} <= {
        f"{s}_shoulder_{r}_joint" for s in ("left", "right") for r in ("pitch", "roll", "yaw")}
    assert 0 < np.max(np.abs(qg - g1.neutral)) < 0.1
    scg = self_collision(g1)
    for a, b in (("torso_link_0", "left_shoulder_yaw_link_0"),
                 ("torso_link_0", "right_shoulder_yaw_link_0")):
        i = _pair_index(scg, a, b)
        assert scg.distances(g1.neutral)[i] < MARGIN <= REST_CLEAR - 1e-9 <= scg.distances(qg)[i]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        talos = gd.Robot.from_library("talos")
    q = rest_pose(talos)
    sc = self_collision(talos)
    d0, d = sc.distances(talos.neutral), sc.distances(q)
    pressed = {(a, b) for a, b, _ in left_out_sphere_pairs(talos)}
    assert {("leg_left_3_link_0", "arm_left_6_link_0"),
            ("leg_right_3_link_0", "gripper_right_motor_double_link_0")} <= pressed
    for (a, b), x0, x in zip(sc.pairs, d0, d):
        if (a, b) in pressed:
            assert x >= REST_CLEAR - 1e-9, (a, b)
        elif x0 >= 0:
            assert x >= min(x0, MARGIN) - 1e-9, (a, b)
    m = talos.model
    groups = limb_groups(talos)
    legs = {groups[m.getJointId(leg.hip)] for leg in talos.legs.values()}
    moved = [j for j in range(1, m.njoints) if m.joints[j].nq == 1
             and abs(q[m.joints[j].idx_q] - talos.neutral[m.joints[j].idx_q]) > 1e-12]
    assert moved and all(groups[j] != TRUNK and groups[j] not in legs for j in moved), moved
    assert np.all(q <= m.upperPositionLimit + 1e-12) and np.all(q >= m.lowerPositionLimit - 1e-12)
    assert not left_out_sphere_pairs(talos, q=q)
    framed = {(fa, fb) for fa, _, _, fb, *_ in sphere_pairs(talos, q=q)}
    assert ("leg_left_3_joint", "arm_left_6_joint") in framed


def test_posture_range_is_a_box_on_the_held_joints(g1):
    """PostureRange bounds the held joints' q (rest pose ± HOLD_RANGE), not rows; the joints
    the body map follows (or frozen ones) are left free of it."""
    from types import SimpleNamespace

    from gdimitate.retarget.bodymap import HOLD_RANGE
    from gdimitate.retarget.knot import Layout
    from gdimitate.retarget.parts import Bound, Spec
    from gdimitate.retarget.parts.posture_range import PostureRange

    idx = (7, 9, 12)
    part = PostureRange(idx, (0.1, -0.2, 0.3), HOLD_RANGE)
    assert isinstance(part, Bound)
    var = Layout()
    var.add("q", g1.model.nq)
    ctx = SimpleNamespace(tg=SimpleNamespace(mapped=np.array([True, False, False]), T=4),
                          lim=SimpleNamespace(frozen=np.array([False, False, True])))
    spec = Spec(T=4, stance={}, swing={}, liftoff={}, goal_active={}, planar=False, free=True,
                cone=False, clearance=0.0, leg_length=0.6, n_base=6, n_act=3)
    ix, lo, hi = part.box(var, ctx, spec)
    np.testing.assert_array_equal(ix, idx)
    assert lo.shape == hi.shape == (4, 3)
    assert np.all(np.isinf(lo[:, [0, 2]])) and np.all(np.isinf(hi[:, [0, 2]]))
    np.testing.assert_allclose(lo[:, 1], -0.2 - HOLD_RANGE)
    np.testing.assert_allclose(hi[:, 1], -0.2 + HOLD_RANGE)


def test_upper_arm_rows_keep_it_off_the_trunk(g1):
    """The upper arm (an arm's third link: :data:`PROXIMAL_ARM` = 2 shoulder links are left to
    the audit) against the trunk gets a self-collision row, and the row stops the arm before
    its hull touches the torso's: G1's right shoulder roll turned from the rest pose towards
    the torso until coal's hull distance of ``torso_link``/``right_shoulder_yaw_link`` is 0
    (bisection, 1e-5 m) puts that pair's row below its floor, while the rest pose meets it
    (CMU → G1 put this arm 2.7 mm into the torso while the pair had no row)."""
    rest, part, rows_at, lo_rows = _rest_rows(g1)
    cm, m = g1.collision_model, g1.model
    joint = {n: m.names[int(cm.geometryObjects[cm.getGeometryId(n)].parentJoint)]
             for n in ("torso_link_0", "right_shoulder_yaw_link_0")}
    row = [i for i, (fa, fb, _) in enumerate(part.groups())
           if {fa, fb} == set(joint.values())]
    assert len(row) == 1, "the upper arm and the torso have no row"
    sc = self_collision(g1)
    pair = _pair_index(sc, "torso_link_0", "right_shoulder_yaw_link_0")
    i = g1.idx_q("right_shoulder_roll_joint")

    def dist(a: float) -> float:
        q = rest.copy()
        q[i] += a
        return float(sc.distances(q)[pair])

    step = min((0.05, -0.05), key=dist)  # towards the torso
    lo, hi = 0.0, step
    while dist(hi) > 0:
        lo, hi = hi, hi + step
        assert abs(hi) < 1.0
    while dist(lo) - dist(hi) > 1e-5:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if dist(mid) > 0 else (lo, mid)
    floor = lo_rows[row[0]]
    for a, met in ((0.0, True), (hi, False)):
        q = rest.copy()
        q[i] += a
        assert (float(rows_at(q)[row[0]]) >= floor - 1e-10) == met
