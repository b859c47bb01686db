"""The symbolic configuration update (``SymbolicModel.integrate``) against Pinocchio's
``integrate``: free-flyer (SE(3) exponential map), planar base, continuous and 1-DoF joints,
and finite derivatives at a zero step (the small-angle branch)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from gdimitate.model.symbolic import SymbolicModel


@pytest.mark.parametrize("name", ["talos", "hoap2"])
def test_integrate_matches_pinocchio(robot, name):
    m = robot(name).model
    S = SymbolicModel(m)
    rng = np.random.default_rng(1)
    for scale in (1e-7, 1e-3, 0.3, 1.5):  # rotation angles below π: same quaternion sign
        q = pin.randomConfiguration(m, -np.ones(m.nq), np.ones(m.nq))
        dv = rng.normal(size=m.nv) * scale / np.sqrt(3)
        got = np.array(S.integrate(q, dv)).ravel()
        np.testing.assert_allclose(got, pin.integrate(m, q, dv), atol=1e-12)


def test_planar_and_continuous_joints():
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "p")
    m.appendBodyToJoint(j, pin.Inertia.Random(), pin.SE3.Identity())
    j2 = m.addJoint(j, pin.JointModelRUBZ(), pin.SE3.Random(), "c")
    m.appendBodyToJoint(j2, pin.Inertia.Random(), pin.SE3.Identity())
    S = SymbolicModel(m)
    rng = np.random.default_rng(2)
    for scale in (1e-6, 0.5, 3.0):
        q = pin.randomConfiguration(m, -np.ones(m.nq), np.ones(m.nq))
        dv = rng.normal(size=m.nv) * scale
        np.testing.assert_allclose(np.array(S.integrate(q, dv)).ravel(),
                                   pin.integrate(m, q, dv), atol=1e-12)


def test_derivative_at_zero_step_is_finite_and_matches_finite_differences(robot):
    m = robot("talos").model
    S = SymbolicModel(m)
    J = ca.Function("J", [S.q, S.v], [ca.jacobian(S.integrate(S.q, S.v), S.v)])
    q = pin.randomConfiguration(m, -np.ones(m.nq), np.ones(m.nq))
    Jz = np.array(J(q, np.zeros(m.nv)))
    assert np.all(np.isfinite(Jz))
    eps = 1e-7
    num = np.column_stack([(pin.integrate(m, q, eps * e) - q) / eps for e in np.eye(m.nv)])
    np.testing.assert_allclose(Jz, num, atol=1e-6)
