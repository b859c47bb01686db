"""gdimitate.model.mjcf: the MuJoCo model built from a Robot agrees with Pinocchio.

References: Pinocchio's ``rnea``/``crba``/forward kinematics on the same states (MuJoCo's
``mj_inverse``/``mj_fullM``/``mj_kinematics`` are an independent implementation), finite
differences of MuJoCo's own ``mj_differentiatePos`` for the velocity conventions, and the
robot's URDF limits and sole rectangles.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.apps.scenarios import standing_plan
from gdimitate.errors import ContactError, PlanError, SimModelError
from gdimitate.model.contact import SoleContact
from gdimitate.model.robot import SIDES
from gdimitate.sim import ModelOptions, build_model
from gdimitate.sim.reference import Plan, check_plan
from tests.helpers import shared

ROBOTS = ["hoap2", "talos", "g1", "icub", "romeo"]


@pytest.fixture(scope="module")
def robots():
    return {}


def _robot(cache, name):
    if name not in cache:
        cache[name] = shared.library_robot(name)
    return cache[name]


def _random_state(model, rng):
    lo = np.maximum(model.lowerPositionLimit, -3.0)
    hi = np.minimum(model.upperPositionLimit, 3.0)
    q = pin.randomConfiguration(model, lo, hi)
    return q, rng.normal(size=model.nv), rng.normal(size=model.nv)


@pytest.mark.parametrize("name", ROBOTS)
def test_inverse_dynamics_and_mass_matrix_match_pinocchio(robots, name):
    robot = _robot(robots, name)
    sim = build_model(robot)
    mj = sim.mj
    mj.opt.disableflags |= (mujoco.mjtDisableBit.mjDSBL_CONTACT
                            | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    data = mujoco.MjData(mj)
    m, d = robot.model, robot.model.createData()
    rng = np.random.default_rng(7)
    for _ in range(10):
        q, v, a = _random_state(m, rng)
        data.qpos[:] = sim.qpos_from_q(q)
        data.qvel[:] = sim.qvel_from_v(q, v)
        data.qacc[:] = sim.qacc_from_a(q, v, a)
        mujoco.mj_inverse(mj, data)
        tau = sim.tau_from_qfrc(q, data.qfrc_inverse)
        ref = pin.rnea(m, d, q, v, a)
        assert np.linalg.norm(tau - ref) <= 1e-8 * np.linalg.norm(ref)
        Mmj = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, data, Mmj)
        T = sim.velocity_map(q)
        Mpin = pin.crba(m, d, q)
        Mpin = np.triu(Mpin) + np.triu(Mpin, 1).T
        assert np.linalg.norm(T.T @ Mmj @ T - Mpin) <= 1e-8 * np.linalg.norm(Mpin)
    # the same masses, no hidden passive terms; left out: exactly the joints that move no
    # mass (Pinocchio's subtree masses; Romeo's 24 hand joints, no other robot's)
    assert mj.body_mass.sum() == pytest.approx(robot.mass, rel=1e-12)
    pin.computeSubtreeMasses(m, d)
    assert set(sim.frozen) == {j for j in range(1, m.njoints) if d.mass[j] == 0}
    assert len(sim.frozen) == (24 if name == "romeo" else 0)
    assert np.all(mj.dof_damping == 0) and np.all(mj.dof_frictionloss == 0)
    T = sim.velocity_map(robot.neutral)
    assert np.allclose(T.T @ np.diag(mj.dof_armature) @ T, np.diag(m.armature))
    assert np.all(mj.jnt_stiffness == 0)


@pytest.mark.parametrize("name", ["hoap2", "talos", "icub", "romeo"])
def test_kinematics_and_sole_boxes_match_pinocchio(robots, name):
    robot = _robot(robots, name)
    sim = build_model(robot)
    data = sim.new_data()
    m, d = robot.model, robot.model.createData()
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, v, _ = _random_state(m, rng)
        sim.set_state(data, q, v)
        pin.framesForwardKinematics(m, d, q)
        for j in range(1, m.njoints):
            b = mujoco.mj_name2id(sim.mj, mujoco.mjtObj.mjOBJ_BODY, m.names[j])
            if b < 0:  # merged massless link (the planar base's x and z) or frozen subtree
                assert j in sim.frozen or m.inertias[j].mass == 0
                continue
            assert np.allclose(data.xpos[b], d.oMi[j].translation, atol=1e-12)
            assert np.allclose(data.xmat[b].reshape(3, 3), d.oMi[j].rotation, atol=1e-12)
        for s in SIDES:
            c = robot.contacts[s]
            oMf = d.oMf[robot.frame_id(c.frame)]
            g = sim.foot_geom[s]
            size = sim.mj.geom_size[g]
            assert np.allclose(size[:2], [c.half_length, c.half_width])
            R, p = data.geom_xmat[g].reshape(3, 3), data.geom_xpos[g]
            bottom = np.array([[sx * size[0], sy * size[1], -size[2]]
                               for sx, sy in ((1, 1), (1, -1), (-1, -1), (-1, 1))])
            corners_mj = bottom @ R.T + p
            corners_pin = c.corners() @ oMf.rotation.T + oMf.translation
            assert np.allclose(corners_mj, corners_pin, atol=1e-12)


@pytest.mark.parametrize("name", ["hoap2", "talos"])
def test_coordinate_conversions_against_finite_differences(robots, name):
    robot = _robot(robots, name)
    sim = build_model(robot)
    m = robot.model
    rng = np.random.default_rng(11)
    eps = 1e-7
    for _ in range(5):
        q, v, a = _random_state(m, rng)
        assert np.allclose(sim.q_from_qpos(sim.qpos_from_q(q)), q, atol=1e-14)
        assert np.allclose(sim.v_from_qvel(sim.qpos_from_q(q), sim.qvel_from_v(q, v)), v,
                           atol=1e-14)
        # MuJoCo's own finite difference of positions gives its qvel
        q2 = pin.integrate(m, q, eps * v)
        fd = np.zeros(sim.mj.nv)
        mujoco.mj_differentiatePos(sim.mj, fd, eps, sim.qpos_from_q(q), sim.qpos_from_q(q2))
        assert np.allclose(fd, sim.qvel_from_v(q, v), atol=1e-6)
        # d/dt qvel along (q, v, a)
        qv2 = sim.qvel_from_v(q2, v + eps * a)
        assert np.allclose((qv2 - sim.qvel_from_v(q, v)) / eps, sim.qacc_from_a(q, v, a),
                           atol=1e-5)


@pytest.mark.parametrize("name", ["hoap2", "g1"])
def test_limits_friction_and_actuators(robots, name):
    robot = _robot(robots, name)
    sim = build_model(robot)
    mj, m = sim.mj, robot.model
    mu = robot.contacts["left"].mu
    assert mj.geom_friction[sim.floor_geom][0] == mu
    for s in SIDES:
        assert mj.geom_friction[sim.foot_geom[s]][0] == mu
    assert mj.nu == len(sim.actuated) == m.nv - (6 if robot.base == "free" else 3)
    for i, j in enumerate(sim.actuated):
        jm = m.joints[j]
        e = m.effortLimit[jm.idx_v]
        assert np.allclose(mj.actuator_ctrlrange[i], [-e, e])
        assert np.allclose(mj.actuator_forcerange[i], [-e, e])
        jid = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, m.names[j])
        assert mj.jnt_limited[jid]
        assert np.allclose(mj.jnt_range[jid], [m.lowerPositionLimit[jm.idx_q],
                                               m.upperPositionLimit[jm.idx_q]])
    # only the soles collide, only with the floor
    assert mj.ngeom == 3


def test_zero_inertia_links_are_reported(robots):
    robot = _robot(robots, "icub")
    sim = build_model(robot)
    # example-robot-data's iCub has point masses on its right leg and wrists
    assert "r_knee" in sim.inertia_changes
    assert all(0 < x <= ModelOptions().min_inertia * (1 + 1e-6)
               for x in sim.inertia_changes.values())
    assert build_model(_robot(robots, "talos")).inertia_changes == {}


def test_bad_inputs_raise_specific_errors(robots):
    robot = _robot(robots, "hoap2")
    with pytest.raises(SimModelError, match="timestep"):
        ModelOptions(timestep=0.0)
    with pytest.raises(SimModelError, match="contact_timeconst"):
        ModelOptions(timestep=0.01, contact_timeconst=0.01)
    with pytest.raises(SimModelError, match="cone"):
        ModelOptions(cone="round")
    other = {s: robot.contacts[s] for s in SIDES}
    other["right"] = other["right"].replace(mu=0.3)
    with pytest.raises(SimModelError, match="friction"):
        build_model(robot, contacts=other)
    with pytest.raises(ContactError):
        build_model(gd.Robot.from_library("bolt"))  # point feet: no sole rectangle


def test_plan_contract_is_checked(robots):
    robot = _robot(robots, "hoap2")
    plan = standing_plan(robot, 0.2)
    assert check_plan(robot, plan).motion is plan.motion
    with pytest.raises(PlanError, match="differentiate"):
        check_plan(robot, Plan(plan.motion.replace(v=None, a=None), plan.wrenches,
                               plan.contacts))
    bad = dict(plan.wrenches, left=plan.wrenches["left"][:, :3])
    with pytest.raises(PlanError, match="shape"):
        check_plan(robot, Plan(plan.motion, bad, plan.contacts))
    swing = plan.motion.replace(contact={"left": np.zeros(plan.motion.T, bool),
                                         "right": plan.motion.contact["right"]})
    with pytest.raises(PlanError, match="swing"):
        check_plan(robot, Plan(swing, plan.wrenches, plan.contacts))
    wrong = dict(plan.contacts, left=SoleContact("left", "no_such_frame", 0.05, 0.02))
    with pytest.raises(PlanError, match="frame"):
        check_plan(robot, Plan(plan.motion, plan.wrenches, wrong))
    with pytest.raises(PlanError, match="fit"):
        check_plan(_robot(robots, "talos"), plan)
    with pytest.raises(PlanError, match="motion"):
        check_plan(robot, object())
