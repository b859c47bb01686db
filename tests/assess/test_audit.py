"""The audit (gdimitate.audit) against independent references.

References: Newton–Euler statics of a standing robot solved by hand (vertical forces under the
centre of mass, split by the lateral lever rule), Pinocchio's generalised gravity with the
contact forces mapped through point Jacobians at the centres of pressure (not the LOCAL frame
Jacobians the audit uses), and closed forms (centre of pressure of a point force, the friction
ratio of a 3-4-5 force, a 5 mm drop, the angle of a rotated target). Each known-bad plan is
dynamically consistent by construction (the base acceleration is solved from the base rows),
so exactly one check — the one planted — must fail.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.assess.audit import AuditReport, AuditTolerances, audit
from gdimitate.errors import InvalidInputError
from gdimitate.model.motion import Motion, differentiate
from gdimitate.model.robot import Robot

SIDES = ("left", "right")
G = 9.81


@pytest.fixture(scope="module")
def talos(robot) -> Robot:
    return robot("talos")


@pytest.fixture(scope="module")
def hoap2(robot) -> Robot:
    return robot("hoap2")


# ---------------------------------------------------------------------- independent helpers
def point_on_sole(robot, data, side, xy):
    """The point of the sole plane whose world (x, y) is ``xy``; returns (world point, local
    (d, e))."""
    c = robot.contacts[side]
    M = data.oMf[robot.frame_id(c.frame)]
    R, o = M.rotation, M.translation
    d = np.linalg.solve(R[:2, :2], np.asarray(xy) - o[:2])  # o + R (d, e, 0) has world xy
    return o + R @ np.r_[d, 0.0], d


def static_split(robot, q):
    """Vertical contact forces that hold ``robot`` still at ``q`` (Newton–Euler statics by
    hand): each foot's force acts at the point of its sole under the centre of mass's x (and
    its own origin's y); free bases split the weight by the lateral lever rule, planar ones in
    half. Returns ``{side: (F [N], world point (3,), wrench (6,) in the contact frame)}``."""
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    c = pin.centerOfMass(model, data, q)
    mg = robot.mass * G
    pts = {}
    for s in SIDES:
        o = data.oMf[robot.frame_id(robot.contacts[s].frame)].translation
        pts[s] = point_on_sole(robot, data, s, (c[0], o[1]))[0]
    if robot.base == "free":
        yl, yr = pts["left"][1], pts["right"][1]
        F = {"left": mg * (c[1] - yr) / (yl - yr)}
        F["right"] = mg - F["left"]
    else:
        F = {"left": mg / 2, "right": mg / 2}
    out = {}
    for s in SIDES:
        M = data.oMf[robot.frame_id(robot.contacts[s].frame)]
        f = np.array([0.0, 0.0, F[s]])
        tau = np.cross(pts[s] - M.translation, f)
        out[s] = (F[s], pts[s], np.r_[M.rotation.T @ f, M.rotation.T @ tau])
    return out


def point_force_wrench(p, f):
    """Wrench at the sole origin (contact frame) of a force ``f`` applied at point ``p``."""
    return np.r_[f, np.cross(p, f)]


def base_acceleration(robot, q, v, a, W):
    """``a`` with its base part solved from the base rows M a + h = Σ Jᵀw (so that the plan is
    dynamically consistent whatever the wrenches)."""
    model = robot.model
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    g = sum(pin.getFrameJacobian(model, data, robot.frame_id(robot.contacts[s].frame),
                                 pin.LOCAL).T @ W[s] for s in SIDES)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    h = pin.rnea(model, data, q, v, np.zeros(model.nv))
    nb = 6 if robot.base == "free" else 3
    a = a.copy()
    a[:nb] = np.linalg.solve(M[:nb, :nb], g[:nb] - h[:nb] - M[:nb, nb:] @ a[nb:])
    return a


def plan(robot, q, v=None, a=None, W=None, contact=None, t=None):
    """A Motion (with v, a) and its wrenches; wrenches default to the static split per knot;
    base accelerations solved for consistency."""
    q = np.atleast_2d(q)
    T = q.shape[0]
    nv = robot.model.nv
    v = np.zeros((T, nv)) if v is None else v
    a = np.zeros((T, nv)) if a is None else a.copy()
    if W is None:
        W = {s: np.zeros((T, 6)) for s in SIDES}
        for k in range(T):
            split = static_split(robot, q[k])
            for s in SIDES:
                W[s][k] = split[s][2]
    for k in range(T):
        a[k] = base_acceleration(robot, q[k], v[k], a[k], {s: W[s][k] for s in SIDES})
    contact = contact or {s: np.ones(T, bool) for s in SIDES}
    m = robot.model
    motion = Motion(np.arange(T) * 0.01 if t is None else t, robot.joint_names, q, contact,
                    {"free": 7, "planar": 3, "fixed": 0}[robot.base],
                    tuple(m.joints[j].nq for j in range(1, m.njoints)), v, a)
    return motion, W


def standing(robot, T=3):
    return np.tile(robot.neutral, (T, 1))


# ---------------------------------------------------------------------- static standing
def test_static_standing_matches_generalised_gravity(talos):
    """Talos standing still on the static split: base residual ~0 (the split balances the
    weight by hand), joint torques = computeGeneralizedGravity − Σ J_pᵀ f (point Jacobians at
    the centres of pressure, world-aligned), every check holds."""
    q = talos.neutral
    motion, W = plan(talos, standing(talos))
    np.testing.assert_allclose(motion.a, 0.0, atol=1e-9)  # the hand split is in balance
    rep = audit(talos, motion, W)
    assert isinstance(rep, AuditReport)
    assert rep.feasible, rep.summary(only_failed=True)
    assert rep.binding == ()
    assert rep.base_residual.value < 1e-9
    model, data = talos.model, talos.model.createData()
    tau = pin.computeGeneralizedGravity(model, data, q).copy()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    for s, (F, p, _) in static_split(talos, q).items():
        fid = talos.frame_id(talos.contacts[s].frame)
        J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
        r = p - data.oMf[fid].translation
        Jp = J[:3] - pin.skew(r) @ J[3:]  # Jacobian of the contact point
        tau -= Jp.T @ np.array([0.0, 0.0, F])
    np.testing.assert_allclose(tau[:6], 0.0, atol=1e-9)
    np.testing.assert_allclose(rep.tau[:, 6:], np.tile(tau[6:], (3, 1)), atol=1e-9)
    for j in rep.joints:
        i = talos.idx_v(j.name)
        assert j.torque_max == pytest.approx(abs(tau[i]), abs=1e-9)
    assert rep.knot_feasible.all()
    assert rep.penetration.depth == pytest.approx(0.0, abs=1e-9)
    json.dumps(rep.to_dict(), allow_nan=False)
    assert "feasible: yes" in rep.summary()


def test_static_standing_planar(hoap2):
    """The planar base (x, z, pitch): 3 base rows, wrenches f_x, f_z, τ_y."""
    q = hoap2.neutral
    motion, W = plan(hoap2, standing(hoap2))
    rep = audit(hoap2, motion, W)
    assert rep.feasible, rep.summary(only_failed=True)
    model, data = hoap2.model, hoap2.model.createData()
    tau = pin.computeGeneralizedGravity(model, data, q).copy()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    for s, (F, p, _) in static_split(hoap2, q).items():
        fid = hoap2.frame_id(hoap2.contacts[s].frame)
        J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
        Jp = J[:3] - pin.skew(p - data.oMf[fid].translation) @ J[3:]
        tau -= Jp.T @ np.array([0.0, 0.0, F])
    np.testing.assert_allclose(tau[:3], 0.0, atol=1e-9)
    np.testing.assert_allclose(rep.tau[0], tau, atol=1e-9)


# ---------------------------------------------------------------------- known-bad plans
def test_pulling_foot(talos):
    """The left foot pulls (f_z = −50 N) at one knot: only that knot and only normal:left."""
    motion, W = plan(talos, standing(talos))
    W["left"][1] = [0, 0, -50.0, 0, 0, 0]
    motion, W = plan(talos, standing(talos), W=W)
    rep = audit(talos, motion, W)
    assert not rep.feasible
    assert rep.binding == ("normal:left",)
    assert rep.feet["left"].normal == (-50.0, 1)
    np.testing.assert_array_equal(rep.knot_feasible, [True, False, True])


def test_cop_outside_the_sole(talos):
    """A point force 1 cm in front of the sole's front edge: CoP margin −0.01 m by hand."""
    c = talos.contacts["left"]
    motion, W = plan(talos, standing(talos))
    F = W["left"][0, 2]
    W["left"][:] = point_force_wrench([c.half_length + 0.01, 0, 0], [0, 0, F])
    motion, W = plan(talos, standing(talos), W=W)
    rep = audit(talos, motion, W)
    assert rep.binding == ("cop:left",)
    assert rep.feet["left"].cop.value == pytest.approx(-0.01, abs=1e-12)


def test_closed_forms_friction_and_cop(talos):
    """A 3-4-5 point force (f_t/f_z = 0.5) at p = (3, −2) cm: friction ratio 0.5, CoP margin
    min(X − 0.03, Y − 0.02) — and feasible, as a point force in its friction cone at a point
    of the sole is in the contact wrench cone."""
    c = talos.contacts["left"]
    motion, W = plan(talos, standing(talos))
    F = W["left"][0, 2]
    W["left"][:] = point_force_wrench([0.03, -0.02, 0], [0.3 * F, 0.4 * F, F])
    motion, W = plan(talos, standing(talos), W=W)
    rep = audit(talos, motion, W)
    foot = rep.feet["left"]
    assert foot.friction.value == pytest.approx(0.5, abs=1e-12)
    assert foot.cop.value == pytest.approx(min(c.half_length - 0.03, c.half_width - 0.02),
                                           abs=1e-12)
    assert foot.yaw.value >= 0
    assert rep.feasible, rep.summary(only_failed=True)


def test_torque_over_its_limit(talos):
    """The joint with the largest static torque given half that torque as its limit."""
    motion, W = plan(talos, standing(talos))
    rep = audit(talos, motion, W)
    worst = max(rep.joints, key=lambda j: j.torque_max)
    weak = copy.copy(talos)
    weak.model = pin.Model(talos.model)
    weak.data = weak.model.createData()
    eff = weak.model.effortLimit.copy()
    eff[talos.idx_v(worst.name)] = worst.torque_max / 2
    weak.model.effortLimit = eff
    rep = audit(weak, motion, W)
    assert rep.binding == (f"torque:{worst.name}",)
    assert rep.joint(worst.name).torque_ratio == pytest.approx(2.0, rel=1e-12)


def test_corners_under_the_floor(talos):
    """(a) The whole robot 5 mm down: every corner 5 mm under. (b) The robot pitched about
    the line through both sole centres so the toes dip 5 mm (X·sin θ = 5 mm) while the sole
    origins stay on the floor: the audit measures corners, not frame origins (and the heels,
    5 mm up, break the flat contact)."""
    q = standing(talos)
    q[:, 2] -= 0.005
    motion, W = plan(talos, q)
    rep = audit(talos, motion, W)
    assert rep.binding == ("penetration",)
    assert rep.penetration.depth == pytest.approx(0.005, abs=1e-12)

    X = talos.contacts["left"].half_length
    theta = np.arcsin(0.005 / X)
    data = talos.model.createData()
    pin.framesForwardKinematics(talos.model, data, talos.neutral)
    o = data.oMf[talos.frame_id(talos.contacts["left"].frame)].translation
    pivot = pin.SE3(np.eye(3), np.array([o[0], 0.0, o[2]]))
    turn = pivot * pin.SE3(pin.rpy.rpyToMatrix(0, theta, 0), np.zeros(3)) * pivot.inverse()
    base = turn * pin.XYZQUATToSE3(talos.neutral[:7])
    q = standing(talos)
    q[:, :7] = pin.SE3ToXYZQUAT(base)
    motion, W = plan(talos, q)
    rep = audit(talos, motion, W)
    pin.framesForwardKinematics(talos.model, data, q[0])
    for s in SIDES:
        assert data.oMf[talos.frame_id(talos.contacts[s].frame)].translation[2] == \
            pytest.approx(0.0, abs=1e-12)
    assert set(rep.binding) == {"penetration", "contact_gap:left", "contact_gap:right"}
    assert rep.penetration.depth == pytest.approx(0.005, abs=1e-9)
    assert rep.penetration.corner in (0, 1)  # a front corner
    assert rep.feet["right"].contact_gap.value == pytest.approx(0.005, abs=1e-9)  # heels up


def test_stance_foot_above_the_floor(talos):
    """The whole robot 5 mm up while its feet are in stance and loaded: contact_gap."""
    q = standing(talos)
    q[:, 2] += 0.005
    motion, W = plan(talos, q)
    rep = audit(talos, motion, W)
    assert set(rep.binding) == {"contact_gap:left", "contact_gap:right"}
    assert rep.feet["left"].contact_gap.value == pytest.approx(0.005, abs=1e-12)
    assert rep.penetration.depth == pytest.approx(-0.005, abs=1e-12)


def test_zigzag_beats_central_differences(talos):
    """A knot-to-knot zig-zag of ±0.03 rad at 100 Hz: central differences see no motion,
    forward differences see 6 rad/s > the 4.58 rad/s limit of arm_left_3_joint."""
    name = "arm_left_3_joint"
    T = 7
    q = standing(talos, T)
    i = talos.idx_q(name)
    q[:, i] += 0.03 * (-1.0) ** np.arange(T)
    motion, W = plan(talos, q)
    central = differentiate(talos.model, motion).v[1:-1, talos.idx_v(name)]
    np.testing.assert_allclose(central, 0.0, atol=1e-12)
    rep = audit(talos, motion, W)
    assert set(rep.binding) == {f"velocity:{name}", "velocity_consistency"}
    j = rep.joint(name)
    assert j.velocity_max == pytest.approx(0.06 / 0.01, rel=1e-12)
    assert j.velocity_ratio == pytest.approx(6.0 / talos.model.velocityLimit[talos.idx_v(name)])
    assert rep.velocity_consistency.value == pytest.approx(6.0, rel=1e-12)


def test_stance_slip(talos):
    """The whole robot glides 2 mm per knot (v consistent): both stance feet slip."""
    T = 5
    q = standing(talos, T)
    q[:, 0] += 0.002 * np.arange(T)
    v = np.zeros((T, talos.model.nv))
    v[:, 0] = 0.2
    motion, W = plan(talos, q, v=v)
    rep = audit(talos, motion, W)
    # the gliding feet also move at every stance knot (0.2 m/s, the base's velocity)
    assert set(rep.binding) == {"slip:left", "slip:right", "stance_velocity:left",
                                "stance_velocity:right"}
    assert rep.feet["left"].slip == (pytest.approx(0.008, abs=1e-12), T - 1)
    assert rep.feet["left"].stance_velocity.value == pytest.approx(0.2, abs=1e-12)


def test_stance_foot_moving(talos):
    """A stance knot whose velocity moves a foot while its pose is still on the floor (the last
    knot: its forward differences are those of a motion coming to rest there, so velocity
    consistency holds): flagged by stance_velocity alone. References: a base translating at
    0.1 m/s with an identity orientation moves every sole frame at 0.1 m/s; the left knee at
    0.5 rad/s turns the left sole at 0.5 rad/s and moves its origin at |ω × (p_sole − p_knee)|."""
    T = 3
    knee = "leg_left_4_joint"
    for case in ("base", "knee"):
        v = np.zeros((T, talos.model.nv))
        if case == "base":
            v[T - 1, 0] = 0.1
        else:
            v[T - 1, talos.idx_v(knee)] = 0.5
        motion, W = plan(talos, standing(talos, T), v=v)
        rep = audit(talos, motion, W)
        feet = ("left", "right") if case == "base" else ("left",)
        assert set(rep.binding) == {f"stance_velocity:{s}" for s in feet}, case
        sv = rep.feet["left"].stance_velocity
        assert sv.knot == T - 1
        assert sv.value == pytest.approx(0.1 if case == "base" else 0.5, abs=1e-12)
        if case == "knee":
            assert rep.feet["right"].stance_velocity.value == pytest.approx(0.0, abs=1e-15)
            assert rep.check_knots("stance_velocity:left").tolist() == [True, True, False]
    # the knee case by central finite differences of the sole frame's pose along q ⊕ ε v
    model, eps = talos.model, 1e-6
    data = model.createData()
    fid = talos.frame_id(talos.contacts["left"].frame)
    poses = []
    for e in (-eps, eps):
        pin.framesForwardKinematics(model, data, pin.integrate(model, talos.neutral, e * v[-1]))
        poses.append(data.oMf[fid].copy())
    lin = np.linalg.norm(poses[1].translation - poses[0].translation) / (2 * eps)
    ang = np.linalg.norm(pin.log3(poses[0].rotation.T @ poses[1].rotation)) / (2 * eps)
    assert ang == pytest.approx(0.5, rel=1e-6) and 0.05 < lin < ang
    assert sv.value == pytest.approx(max(lin, ang), rel=1e-6)
    # a tolerance above the speed passes it
    assert audit(talos, motion, W,
                 tolerances=AuditTolerances(stance_velocity=0.51)).feasible


def test_force_direction_error(talos):
    """A target rotated 0.1 rad forward of the actual (vertical) push: error 0.1 rad, all of it
    sagittal; binding beyond a 0.05 rad cone, feasible within 0.2 rad."""
    motion, W = plan(talos, standing(talos))
    target = {"left": np.tile([np.sin(0.1), 0.0, -np.cos(0.1)], (3, 1)),
              "right": np.tile([0.0, 0.0, -1.0], (3, 1))}
    rep = audit(talos, motion, W, target=target, cone_half_angle=0.05)
    assert rep.binding == ("force_direction:left",)
    fd = rep.force_direction_error["left"]
    assert fd.error_max == pytest.approx(0.1, abs=1e-9)
    assert fd.sagittal_max == pytest.approx(0.1, abs=1e-9)
    assert fd.frontal_max == pytest.approx(0.0, abs=1e-9)
    assert rep.force_direction_error["right"].error_max == pytest.approx(0.0, abs=1e-6)
    assert audit(talos, motion, W, target=target, cone_half_angle=0.2).feasible
    target["left"][1] = np.nan  # no target at knot 1: not checked there
    assert audit(talos, motion, W, target=target).feet["left"].force_direction.knots == 2


def test_wrench_on_a_swing_foot(talos):
    motion, W = plan(talos, standing(talos))
    swing = motion.replace(contact={"left": np.array([True, False, True]),
                                    "right": np.ones(3, bool)})
    rep = audit(talos, swing, W)
    assert rep.binding == ("swing_wrench:left",)


def test_tolerances_decide(talos):
    """Loosening the one failing tolerance past the violation makes the plan feasible."""
    q = standing(talos)
    q[:, 2] -= 0.005
    motion, W = plan(talos, q)
    assert audit(talos, motion, W, tolerances=AuditTolerances(penetration=0.006)).feasible


def test_unlimited_joints_are_listed(hoap2):
    """hoap2's planar base has no effort limits (not actuated) and is not listed; its leg
    joints are limited."""
    motion, W = plan(hoap2, standing(hoap2))
    rep = audit(hoap2, motion, W)
    names = {j.name for j in rep.joints}
    assert "base_x" not in names and "left_knee" in names
    weak = copy.copy(hoap2)
    weak.model = pin.Model(hoap2.model)
    eff = weak.model.effortLimit.copy()
    eff[hoap2.idx_v("left_knee")] = 0.0
    weak.model.effortLimit = eff
    rep = audit(weak, motion, W)
    assert ("left_knee", "effort") in rep.unlimited
    assert np.isnan(rep.joint("left_knee").torque_ratio)


# ---------------------------------------------------------------------- bad input
def test_bad_input(talos):
    motion, W = plan(talos, standing(talos))
    with pytest.raises(InvalidInputError, match="differentiate"):
        audit(talos, motion.replace(v=None), W)
    with pytest.raises(InvalidInputError, match=r"\(T, 6\)"):
        audit(talos, motion, {"left": W["left"][:, :3], "right": W["right"]})
    with pytest.raises(InvalidInputError, match="missing"):
        audit(talos, motion, {"left": W["left"]})
    with pytest.raises(InvalidInputError, match="unit vectors"):
        audit(talos, motion, W, target={"left": np.tile([0, 0, -2.0], (3, 1))})
    with pytest.raises(InvalidInputError, match="cone_half_angle"):
        audit(talos, motion, W, cone_half_angle=-0.1)
    with pytest.raises(InvalidInputError, match="AuditTolerances.slip"):
        AuditTolerances(slip=-1.0)


def test_random_state_torques_match_crba_and_world_wrenches(talos):
    """Random (q, v, a) and wrenches: the audit's τ equals M(q)·a + nle(q, v) (crba and
    nonLinearEffects, not rnea) minus the wrenches turned into the world frame and mapped by
    world-aligned Jacobians."""
    rng = np.random.default_rng(3)
    model, data = talos.model, talos.model.createData()
    T = 4
    q = standing(talos, T)
    q[:, 7:] += rng.normal(0, 0.1, (T, model.nv - 6))
    q[:, 3:7] = [pin.SE3ToXYZQUAT(pin.SE3(pin.rpy.rpyToMatrix(*rng.normal(0, 0.2, 3)),
                                          np.zeros(3)))[3:] for _ in range(T)]
    v, a = rng.normal(0, 0.5, (T, model.nv)), rng.normal(0, 2.0, (T, model.nv))
    W = {s: rng.normal(0, 100, (T, 6)) for s in SIDES}
    motion = Motion(np.arange(T) * 0.01, talos.joint_names, q, {s: np.ones(T, bool)
                    for s in SIDES}, 7, tuple(model.joints[j].nq for j in range(1, model.njoints)),
                    v, a)
    rep = audit(talos, motion, W)
    for k in range(T):
        M = pin.crba(model, data, q[k])
        M = np.triu(M) + np.triu(M, 1).T
        tau = M @ a[k] + pin.nonLinearEffects(model, data, q[k], v[k])
        pin.computeJointJacobians(model, data, q[k])
        pin.updateFramePlacements(model, data)
        for s in SIDES:
            fid = talos.frame_id(talos.contacts[s].frame)
            R = data.oMf[fid].rotation
            J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            tau -= J.T @ np.r_[R @ W[s][k, :3], R @ W[s][k, 3:]]
        np.testing.assert_allclose(rep.tau[k], tau, atol=1e-8)
    assert rep.base_residual.value == pytest.approx(np.abs(rep.tau[:, :6]).max())
    assert "base_residual" in rep.binding


def test_velocity_consistency_of_honest_schemes(talos):
    """No false alarm: a smooth arm swing integrated by semi-implicit Euler (v_k+1 = v_k + h a_k,
    q_k+1 = q_k ⊕ h v_k+1: the forward difference is v_k+1 exactly) and the same swing
    differentiated by central differences both pass the consistency check."""
    name = "arm_left_3_joint"
    T, h = 60, 0.01
    i = talos.idx_v(name)
    t = np.arange(T) * h
    a = np.zeros((T, talos.model.nv))
    a[:, i] = -0.5 * (2 * np.pi) ** 2 * np.sin(2 * np.pi * t)
    v = np.zeros_like(a)
    q = standing(talos, T)
    v[0, i] = 0.5 * 2 * np.pi
    for k in range(T - 1):
        v[k + 1] = v[k] + h * a[k]
        q[k + 1] = pin.integrate(talos.model, q[k], h * v[k + 1])
    motion, W = plan(talos, q, v=v, a=a)
    rep = audit(talos, motion, W)
    assert rep.velocity_consistency.value < 1e-12
    assert rep.check("velocity_consistency").passed
    central = differentiate(talos.model, motion.replace(v=None, a=None))
    motion, W = plan(talos, q, v=central.v, a=central.a)
    assert audit(talos, motion, W).check("velocity_consistency").passed


def test_cone_checks_agree_with_the_cone_matrix(talos):
    """200 random wrenches on the left foot (dynamically consistent plans): the audit's
    normal, friction, CoP and yaw checks pass a knot exactly when Caron et al.'s 16 rows, the
    Coulomb circle ‖f_t‖ ≤ μ f_z and f_z ≥ 0 hold (wrenches within 1e-4·m·g of the boundary
    left out, where the tolerances decide)."""
    rng = np.random.default_rng(7)
    T = 200
    c = talos.contacts["left"]
    motion, W = plan(talos, standing(talos, T))
    F = W["left"][0, 2]
    scale = np.array([F, F, F, F * c.half_length, F * c.half_width, F * c.half_length])
    W["left"] = W["left"] + rng.normal(0, 0.5, (T, 6)) * scale
    A = c.cone()
    w = W["left"]
    rows = np.c_[w @ A.T, -w[:, 2], np.hypot(w[:, 0], w[:, 1]) - c.mu * w[:, 2]]
    keep = np.min(np.abs(rows), axis=1) > 1e-4 * talos.mass * G
    inside = np.all(rows <= 0, axis=1)
    assert 20 < inside[keep].sum() < keep.sum() - 20  # both kinds present
    motion, W = plan(talos, standing(talos, T), W=W)
    rep = audit(talos, motion, W)
    ok = np.logical_and.reduce([rep.check_knots(f"{n}:left")
                                for n in ("normal", "friction", "cop", "yaw")])
    np.testing.assert_array_equal(ok[keep], inside[keep])
    assert rep.check("friction:left").failures == np.sum(~rep.check_knots("friction:left"))
