"""gdimitate.sim.simulate: the QP tracking controller in MuJoCo — positive runs, negative controls.

Independent references: the weight m·g and momentum balance (closed forms) for MuJoCo's
contact forces; Pinocchio's centre of mass of the simulated and planned configurations; the
capture-point bound of the linear inverted pendulum (Pratt et al. 2006) for a push no ankle
strategy can hold; the plan's own wrenches against the sole's contact wrench cone.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.apps.scenarios import kinematic_walk_plan, standing_plan, sway_plan
from gdimitate.model.contact import ContactForces, FootForces, cone_margin
from gdimitate.model.robot import SIDES
from gdimitate.sim import Push, Reference, TrackingController, build_model, check_plan, simulate

G = 9.81
PUSH = 20.0  # [N], the push


@pytest.fixture(scope="module")
def robots(robot):
    return {n: robot(n) for n in ("talos", "g1", "hoap2", "romeo")}


def _tipping_force(robot) -> float:
    """Static horizontal force [N] at the CoM that puts the CoP on the front sole edge."""
    c = robot.com(robot.neutral)
    m, d = robot.model, robot.model.createData()
    pin.framesForwardKinematics(m, d, robot.neutral)
    front = min(d.oMf[robot.frame_id(robot.contacts[s].frame)].translation[0]
                + robot.contacts[s].half_length for s in SIDES)
    return robot.mass * G * (front - c[0]) / c[2]


def _push_for(robots, name):
    """20 N for Talos and G1; HOAP-2 (7 kg, 9.5 cm soles) tips statically at ~11 N, so it
    gets the same fraction of its tipping force as G1 gets from 20 N."""
    if name != "hoap2":
        return PUSH
    return PUSH / _tipping_force(robots["g1"]) * _tipping_force(robots["hoap2"])


@pytest.mark.parametrize("name", ["g1", "hoap2"])
def test_controller_output_satisfies_pinocchio_dynamics_and_cones(robots, name):
    """At perturbed states, the QP's (a, w, τ) satisfy Pinocchio's rnea(q, v, a) =
    Sᵀτ + Σ J_cᵀ w_c on every row (the QP used crba + nle), its wrenches lie in the sole
    cones and its torques within the effort limits."""
    robot = robots[name]
    plan = standing_plan(robot, 1.0)
    sim = build_model(robot)
    ctl = TrackingController(sim)
    ref = Reference(robot, check_plan(robot, plan))
    m, d = robot.model, robot.model.createData()
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = pin.integrate(m, robot.neutral, 0.05 * rng.normal(size=m.nv))
        v = 0.2 * rng.normal(size=m.nv)
        out = ctl.step(q, v, ref.at(0.5))
        assert out.status >= 1
        tau = np.zeros(m.nv)
        tau[sim.idx_v_act] = out.tau
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        for s in SIDES:
            J = pin.getFrameJacobian(m, d, robot.frame_id(sim.contacts[s].frame),
                                     pin.ReferenceFrame.LOCAL)
            tau += J.T @ out.wrench[s]
            assert np.all(sim.contacts[s].cone() @ out.wrench[s] <= 1e-6 * robot.mass * G)
            assert out.wrench[s][2] >= -1e-9
        ref_tau = pin.rnea(m, d, q, v, out.a)
        assert np.allclose(tau, ref_tau, atol=1e-6 * robot.mass * G)
        assert np.all(np.abs(out.tau) <= sim.effort + 1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["talos", "g1", "hoap2", "romeo"])
def test_standing_robot_stays_up_and_holds_a_push(robots, name):
    robot = robots[name]
    F = _push_for(robots, name)
    plan = standing_plan(robot, 5.0)
    res = simulate(robot, plan, push=Push(2.0, 0.2, (F, 0.0, 0.0)))
    mt = res.metrics
    assert not mt.fell and res.t[-1] == pytest.approx(5.0)
    assert mt.qp_failures == 0
    assert mt.slip_max < 0.005
    assert mt.joint_rmse < 0.02
    assert mt.torque_saturation < 0.01
    mg = robot.mass * G
    fz = sum(res.contact_forces[s][:, 2] for s in SIDES)
    fx = sum(res.contact_forces[s][:, 0] for s in SIDES)
    quiet = ((res.t > 1.0) & (res.t < 2.0)) | (res.t > 4.5)
    assert fz[quiet].mean() == pytest.approx(mg, rel=2e-3)
    # momentum balance: the floor takes back the push's impulse (robot at rest before/after)
    after = res.t >= 1.9
    impulse = fx[after].sum() * res.control_period
    assert impulse == pytest.approx(-F * 0.2, rel=0.05)
    for s in SIDES:
        fd = mt.force_vs_plan[s]
        assert fd.n_stance > 4900
        assert fd.stance_rmse_sagittal_deg < 3.0 and fd.stance_rmse_frontal_deg < 3.0
        assert mt.cop_margin_min[s] > -0.003  # on the sole, within MuJoCo's contact softness


def test_push_beyond_the_capture_bound_falls(robots):
    """Negative control: 30 N for 0.2 s on HOAP-2. In the linear inverted pendulum with an
    external force F, the capture point ξ = x + ẋ/ω obeys ξ̇ = ω (ξ − p_eff) with
    p_eff = p − F h/(m g); even with the centre of pressure p on the front sole edge the whole
    time, ξ ends well beyond that edge — without a step the robot must fall."""
    robot = robots["hoap2"]
    F = 1.5 * PUSH
    c = robot.com(robot.neutral)
    h, mg = c[2], robot.mass * G
    front = c[0] + _tipping_force(robot) * h / mg
    omega = np.sqrt(G / h)
    p_eff = front - F * h / mg
    xi = p_eff + (c[0] - p_eff) * np.exp(omega * 0.2)
    assert xi - front > robot.contacts["left"].half_length  # far beyond the support
    res = simulate(robot, standing_plan(robot, 3.0), push=Push(1.0, 0.2, (F, 0.0, 0.0)))
    assert res.metrics.fell
    assert 1.0 < res.metrics.fall_time < 3.0


@pytest.mark.slow
def test_weight_shift_follows_the_plan(robots):
    """G1 shifts its centre of mass 6 cm to the left and back (feet fixed): the simulated
    vertical forces follow the plan's split and the centre of mass the plan's path."""
    robot = robots["g1"]
    plan = sway_plan(robot, 4.0, 0.06, 4.0)
    mo = plan.motion
    # the plan's own forces as a "demonstration" on its 100 Hz grid: resampled by time
    m, d = robot.model, robot.model.createData()
    feet = {}
    for s in SIDES:
        f = np.zeros((mo.T, 3))
        for k in range(mo.T):
            pin.framesForwardKinematics(m, d, mo.q[k])
            f[k] = d.oMf[robot.frame_id(plan.contacts[s].frame)].rotation @ \
                plan.wrenches[s][k, :3]
        nan = np.full((mo.T, 3), np.nan)
        feet[s] = FootForces(f, nan, np.zeros((mo.T, 3)), np.ones(mo.T, bool))
    demo = ContactForces(mo.t, feet, source="plan")
    res = simulate(robot, plan, demo_forces=demo)
    mt = res.metrics
    assert not mt.fell and mt.qp_failures == 0
    assert mt.slip_max < 0.005
    mg = robot.mass * G
    settled = res.t > 0.2  # the first ~0.1 s: the feet settle into MuJoCo's soft contact
    fl = res.contact_forces["left"][settled, 2]
    pl = res.plan_forces["left"][settled, 2]
    assert pl.max() - pl.min() > 0.3 * mg  # a real weight shift
    assert np.corrcoef(fl, pl)[0, 1] > 0.98
    assert np.sqrt(np.mean((fl - pl) ** 2)) < 0.05 * mg
    assert max(mt.plan_stance_foot_speed_max.values()) < 1e-3  # IK kept the feet still
    com_err = np.linalg.norm(robot.com(res.q) - robot.com(res.plan_q), axis=1)
    assert com_err.max() < 0.01
    for s in SIDES:
        assert mt.force_vs_plan[s].stance_rmse_frontal_deg < 3.0
        assert mt.force_vs_demo[s].n_stance == mt.force_vs_plan[s].n_stance
        assert mt.force_vs_demo[s].stance_rmse_frontal_deg == pytest.approx(
            mt.force_vs_plan[s].stance_rmse_frontal_deg, abs=0.3)


def test_centre_of_mass_outside_the_support_falls(robots):
    """Negative control: a sway whose centre of mass goes 20 cm left, beyond the left sole's
    outer edge (at 15 cm). Its wrenches leave the cone and the robot falls."""
    robot = robots["g1"]
    plan = sway_plan(robot, 4.0, 0.2, 4.0)
    # the plan says so: its right foot has to pull on the floor
    normal = cone_margin(plan.contacts["right"], plan.wrenches["right"])["normal"]
    assert normal.min() < -0.2 * robot.mass * G
    res = simulate(robot, plan)
    mt = res.metrics
    assert mt.fell and mt.fall_reason in ("height", "tilt")
    assert res.t[-1] < plan.motion.t[-1]  # stopped at the fall


@pytest.fixture(scope="module")
def walk(robots):
    robot = robots["hoap2"]
    plan = kinematic_walk_plan(robot)
    return robot, plan, simulate(robot, plan)


def test_joint_angle_walk_falls_or_slips(walk):
    """Negative control: a kinematic walk (hip at constant height and speed, no balance) on
    HOAP-2 — its centre of mass leaves the stance sole in single support."""
    robot, plan, res = walk
    mt = res.metrics
    assert mt.fell or mt.slip_max > 0.05
    summary = json.loads(json.dumps(mt.to_dict()))  # JSON-safe
    assert summary["fell"] is True and summary["fall_time_s"] == pytest.approx(mt.fall_time)
    # the metrics cover single support: forces compared while one foot carries the robot
    assert any(mt.force_vs_plan[s].n > 0 for s in SIDES)


def test_plots_and_side_by_side_animation(walk, tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from gdimitate.sim import plots
    from gdimitate.sim.animation import show_simulation

    robot, plan, res = walk
    for name in ("plot_forces", "plot_force_directions", "plot_cop", "plot_tracking",
                 "plot_summary"):
        path = tmp_path / f"{name}.png"
        getattr(plots, name)(res, path=path)
        assert path.stat().st_size > 10_000
    html = tmp_path / "sim.html"
    v = show_simulation(robot, res, html=html)
    try:
        assert set(v.tracks) == {"plan", "simulation"}
        # the simulated track replays the simulated configurations, the plan track the plan's
        assert np.array_equal(v.tracks["simulation"].q, res.q)
        assert np.array_equal(v.tracks["plan"].q, res.plan_q)
    finally:
        v.close()
    text = html.read_text()
    assert text.lstrip().startswith("<!DOCTYPE html>") and len(text) > 100_000


def test_cop_margin_keeps_the_centre_of_pressure_inside_the_sole(robots):
    """``ControllerGains.cop_margin``: the QP's wrenches keep their centre of pressure
    (closed form −τ_y/f_z, τ_x/f_z) within (1 − margin) of the sole's half-sizes; without
    it the same states put it further out (the check can fail). A margin of 1 or more is
    refused."""
    from gdimitate.errors import SimulationError
    from gdimitate.model.contact import centre_of_pressure
    from gdimitate.sim import ControllerGains

    robot = robots["hoap2"]
    sim = build_model(robot)
    ref = Reference(robot, check_plan(robot, standing_plan(robot, 1.0)))
    m = robot.model
    rng = np.random.default_rng(3)
    states = [(pin.integrate(m, robot.neutral, 0.05 * rng.normal(size=m.nv)),
               1.5 * rng.normal(size=m.nv)) for _ in range(8)]

    def reach(margin: float) -> float:
        ctl = TrackingController(sim, ControllerGains(cop_margin=margin))
        worst = 0.0
        for q, v in states:
            out = ctl.step(q, v, ref.at(0.5))
            assert out.status >= 1
            for s in SIDES:
                c, w = sim.contacts[s], out.wrench[s]
                if w[2] > 1e-6 * robot.mass * G:
                    cop = centre_of_pressure(w)
                    worst = max(worst, abs(cop[0]) / c.half_length, abs(cop[1]) / c.half_width)
        return worst

    assert reach(0.0) > 0.8
    assert reach(0.2) <= 0.8 + 1e-6
    with pytest.raises(SimulationError, match="cop_margin"):
        ControllerGains(cop_margin=1.0)
