"""The optimal adaptor (issue 4): Eq. (1) recovery, Case II feasibility, torque limits,
infeasible-problem report, per-frame mode and bad input.

References are independent of the optimiser: the closed-form Eq. (1) (``planar.eq1`` through
``adapt(method="analytic")``), Pinocchio's ``rnea``/frame Jacobians for torques, and NumPy finite
differences. Knots are subsampled to keep the file under a minute on two cores.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.adapt import adapt
from gdimitate.cases import paper_case
from gdimitate.errors import InvalidInputError, LegMatchError, UnknownNameError
from gdimitate.optimal import (
    Limits,
    StreamingAdaptor,
    Weights,
    difference_matrices,
    resolve_limits,
    sagittal_model,
    slice_motion,
)
from gdimitate.robot import SIDES

NO_RATE_LIMITS = Limits(velocity=np.inf, effort=np.inf)


@pytest.fixture(scope="module")
def case1():
    return paper_case("I")


@pytest.fixture(scope="module")
def case2():
    return paper_case("II")


def test_difference_matrices_match_numpy():
    t = np.cumsum(np.r_[0.0, np.random.default_rng(0).uniform(0.01, 0.02, 20)])
    f = np.sin(3 * t)
    D1, D2 = difference_matrices(t)
    np.testing.assert_allclose(D1 @ f, np.gradient(f, t), atol=1e-12)
    quad = 1.5 * t**2 - t  # the three-point second difference is exact on quadratics
    np.testing.assert_allclose(D2 @ quad, 3.0, atol=1e-8)


def test_case1_recovers_eq1(case1):
    """No active limit, Eq. (1)'s own contact model: the optimum is Eq. (1) to ≤ 1e-6 rad."""
    d, i, m = case1
    demo = slice_motion(m, slice(None, None, 4))
    ref = adapt(demo, d, i, method="analytic")
    assert ref.report.infeasible_frames == {"left": 0, "right": 0}
    r = adapt(demo, d, i, method="optimal", limits=NO_RATE_LIMITS, contact="anchor")
    assert r.report.solver["success"]
    assert r.report.infeasible_constraint is None
    cols = [i.idx_q(j) for j in i.joint_names if not j.startswith("base_")] + [i.idx_q(
        "base_pitch")]
    assert np.abs(r.motion.q[:, cols] - ref.motion.q[:, cols]).max() <= 1e-6
    assert r.report.force_direction_error_max <= 1e-9


def test_case1_all_feet_fixed_changes_only_double_support(case1):
    """With every stance foot fixed, Eq. (1) (whose landing foot slides) is still matched in
    single support away from the double-support transitions' smoothing."""
    d, i, m = case1
    demo = slice_motion(m, slice(None, None, 4))
    ref = adapt(demo, d, i, method="analytic")
    r = adapt(demo, d, i, method="optimal", limits=NO_RATE_LIMITS, contact="all")
    assert r.report.all_feasible
    assert r.report.force_direction_error_max <= 1e-6
    soles = {s: [] for s in SIDES}
    from gdimitate.metrics import sole_paths

    p = sole_paths(i, r.motion)
    for s in SIDES:  # no slip at all
        c = demo.contact[s]
        both = c[1:] & c[:-1]
        assert np.abs(np.diff(p[s][:, 0])[both]).max() <= 1e-8
        soles[s] = p[s]
    diff = np.abs(r.motion.q[:, 3:] - ref.motion.q[:, 3:]).max(axis=1)
    assert diff.max() > 1e-3  # Eq. (1) slides the landing foot; the optimum does not


def test_case2_feasible_where_eq1_is_not(case2):
    d, i, m = case2
    demo = slice_motion(m, slice(None, None, 4))
    ana = adapt(demo, d, i, method="analytic")
    assert sum(ana.report.infeasible_frames.values()) > 0
    r = adapt(demo, d, i, method="optimal")
    rep = r.report
    assert rep.infeasible_constraint is None, rep.infeasible_constraint
    assert rep.all_feasible
    assert rep.force_direction_error_max <= 1e-6
    assert rep.joint_limit_violation_max == 0.0
    assert max(rep.torque_ratio_max.values()) <= 1 + 1e-6


def _pinocchio_torques(robot, q, t, wrenches):
    """τ = rnea(q, q̇, q̈) − Σ Jᵀ w with finite-difference q̇, q̈ (planar model: v = q̇)."""
    D1, D2 = difference_matrices(t)
    v, a = D1 @ q, D2 @ q
    out = np.empty_like(q)
    m, data = robot.model, robot.data
    for k in range(len(q)):
        tau = pin.rnea(m, data, q[k], v[k], a[k]).copy()
        pin.computeJointJacobians(m, data, q[k])
        pin.updateFramePlacements(m, data)
        for c, s in enumerate(SIDES):
            fx, fz, my = wrenches[k, 3 * c: 3 * c + 3]
            J = pin.getFrameJacobian(m, data, robot.frame_id(robot.legs[s].sole),
                                     pin.LOCAL_WORLD_ALIGNED)
            tau -= J.T @ np.array([fx, 0, fz, 0, my, 0])
        out[k] = tau
    return out


def test_torque_limits_enforced_and_checked_against_pinocchio():
    d, i, m = paper_case("humanoid")
    demo = slice_motion(m, slice(0, 120, 3))
    free = adapt(demo, d, i, method="optimal", limits=Limits(effort=1e6))
    peak = {j: np.abs(free.report.extra["torques"][:, k]).max()
            for k, j in enumerate(free.report.extra["driven"])}
    knee = "left_knee"
    lowered = {j: 0.8 * peak[j] if j == knee else 1e6 for j in peak}
    r = adapt(demo, d, i, method="optimal", limits=Limits(effort=lowered))
    rep = r.report
    assert rep.infeasible_constraint is None, rep.infeasible_constraint
    assert rep.torque_ratio_max[knee] <= 1 + 1e-6
    assert rep.extra["analytic"]["torque_ratio_max"][knee] > 1.0  # Eq. (1) exceeds it
    tau_pin = _pinocchio_torques(i, r.motion.q, r.motion.t, rep.extra["wrenches"])
    cols = [i.idx_v(j) for j in rep.extra["driven"]]
    np.testing.assert_allclose(tau_pin[:, cols], rep.extra["torques"], atol=1e-6)
    assert np.abs(tau_pin[:, :3]).max() <= 1e-6  # the unactuated base needs no force


def test_infeasible_problem_is_reported_not_raised(case2):
    d, i, m = case2
    demo = slice_motion(m, slice(0, 120, 6))
    r = adapt(demo, d, i, method="optimal", limits=Limits(effort=0.05),
              ipopt={"max_iter": 40})
    rep = r.report
    assert not rep.all_feasible
    assert rep.solver["success"] is False and rep.solver["elastic"] is True
    assert "torque limit" in rep.infeasible_constraint
    assert r.motion.q.shape == (demo.T, i.model.nq)
    assert sum(rep.infeasible_frames.values()) > 0
    assert rep.to_dict()["infeasible_constraint"] == rep.infeasible_constraint


def test_per_frame_mode(case2):
    d, i, m = case2
    demo = slice_motion(m, slice(0, 120))
    r = adapt(demo, d, i, method="optimal", mode="per_frame")
    rep = r.report
    assert rep.solver["mode"] == "per_frame"
    assert rep.force_direction_error_max <= 1e-6
    assert rep.joint_limit_violation_max == 0.0
    assert rep.all_feasible
    # streaming API: one frame at a time gives the same motion
    ad = StreamingAdaptor(d, i, dt=demo.dt)
    q = np.array([ad.step(demo.q[k], {s: demo.contact[s][k] for s in SIDES})
                  for k in range(10)])
    np.testing.assert_allclose(q, r.motion.q[:10], atol=1e-7)


def test_free_flyer_velocity_conversion_matches_pinocchio():
    """Base velocity/acceleration of the sagittal free-flyer vs ``pin.difference``."""
    import casadi as ca

    from gdimitate.robot import Robot

    r = Robot.from_library("bolt")
    M = sagittal_model(r)
    x0 = M.x_of_q(r.neutral[None])[0]

    def f(t):
        return x0 + np.array([0.3 * t, 0.05 * np.sin(3 * t), 0.2 * np.sin(2 * t)]
                             + [0.3 * np.sin(t + k) for k in range(M.nx - 3)])

    t0, h = 0.4, 1e-4
    x, xd = f(t0), (f(t0 + h) - f(t0 - h)) / (2 * h)
    xdd = (f(t0 + h) - 2 * f(t0) + f(t0 - h)) / h**2
    X, Xd, Xdd = (ca.SX.sym(n, M.nx) for n in "abc")
    F = ca.Function("f", [X, Xd, Xdd], list(M.pin_va(X, Xd, Xdd)))
    v, a = (np.array(z).ravel() for z in F(x, xd, xdd))

    def q(t):
        return M.q_numeric(f(t))[0]

    vn = pin.difference(r.model, q(t0 - h), q(t0 + h)) / (2 * h)
    an = (pin.difference(r.model, q(t0), q(t0 + 2 * h))
          - pin.difference(r.model, q(t0 - 2 * h), q(t0))) / (4 * h * h)
    np.testing.assert_allclose(v, vn, atol=1e-6)
    np.testing.assert_allclose(a, an, atol=1e-4)


# ---------------------------------------------------------------------- bad input
def test_bad_input(case1):
    d, i, m = case1
    with pytest.raises(UnknownNameError, match="valid force models"):
        adapt(m, d, i, method="optimal", force="magnetic")
    with pytest.raises(UnknownNameError, match="left_knee"):
        adapt(m, d, i, method="optimal", limits=Limits(effort={"left_kne": 1.0}))
    with pytest.raises(InvalidInputError, match="shape"):
        resolve_limits(i, sagittal_model(i).driven, Limits(velocity=np.ones(4)))
    with pytest.raises(InvalidInputError, match="positive"):
        resolve_limits(i, sagittal_model(i).driven, Limits(effort=-1.0))
    from gdimitate.robot import Robot

    with pytest.raises(InvalidInputError, match="do not match"):  # planar motion, 3-D robot
        adapt(m, Robot.from_library("bolt"), i, method="optimal")
    with pytest.raises(UnknownNameError, match="contact mode"):
        adapt(m, d, i, method="optimal", contact="glued")
    with pytest.raises(UnknownNameError, match="per-frame force model"):
        StreamingAdaptor(d, i, force="grf")
    with pytest.raises(InvalidInputError):
        Weights(height=-1.0)
    with pytest.raises(InvalidInputError, match="subsample"):
        adapt(m, d, i, method="optimal", subsample=0)
    ad = StreamingAdaptor(d, i)
    with pytest.raises(InvalidInputError, match="shape"):
        ad.step(np.zeros(3), {"left": True, "right": True})


def test_leg_mismatch_raises(case1):
    from gdimitate.robot import Robot

    d, i, m = case1
    fixed = Robot.from_library("hoap2")
    fixed.base = "fixed"
    with pytest.raises(LegMatchError):
        adapt(m, d, fixed, method="optimal")


def test_resolved_limits_forms(case1):
    _, i, _ = case1
    drv = sagittal_model(i).driven
    nv = i.model.nv
    r = resolve_limits(i, drv, Limits(effort=2.0, velocity={"left_knee": 1.5},
                                      upper=np.full(nv, 0.5)))
    assert np.all(r.effort == 2.0)
    assert r.velocity[drv.index("left_knee")] == 1.5
    assert np.all(r.upper == 0.5)


def test_nlp_is_cached_per_shape(case2):
    """A second call with the same robot pair and knot count reuses the built NLP (the build
    counter does not move) and gives the same motion; an equal robot loaded again shares it."""
    from gdimitate.optimal import problem
    from gdimitate.robot import Robot

    d, i, m = case2
    problem.clear_cache()
    demo = slice_motion(m, slice(0, 60, 3))
    first = adapt(demo, d, i, method="optimal")
    built = problem.BUILD_COUNT
    again = adapt(demo, d, i, method="optimal")
    assert problem.BUILD_COUNT == built
    np.testing.assert_allclose(again.motion.q, first.motion.q, atol=1e-9)
    assert again.report.infeasible_constraint == first.report.infeasible_constraint
    # other targets on the same knots (another demonstration) reuse it too
    other = slice_motion(m, slice(60, 120, 3))
    adapt(other, d, i, method="optimal")
    assert problem.BUILD_COUNT == built
    # a different shape (knot count) builds a new one
    adapt(slice_motion(m, slice(0, 60, 4)), d, i, method="optimal")
    assert problem.BUILD_COUNT == built + 1
    # an equal robot built again shares the sagittal model
    assert sagittal_model(Robot.from_library("bolt")) is sagittal_model(
        Robot.from_library("bolt"))
