"""The exact-consistency step before a result is reported (gdimitate.retarget.trajectory.polish):
the
wrench correction zeroes the base rows of Pinocchio's inverse dynamics and, given the soles,
keeps every wrench inside its cone (checked with the audit's own margins)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.model.contact import cone_margin
from gdimitate.model.kinematics import base_v_indices
from gdimitate.model.robot import SIDES, Robot
from gdimitate.retarget.trajectory.polish import make_consistent


@pytest.fixture(scope="module")
def g1():
    return Robot.load("g1")


def _base_residual(robot, q, v, a, W, frames, base_idx):
    m, d = robot.model, robot.data
    tau = pin.rnea(m, d, q, v, a).copy()
    pin.computeJointJacobians(m, d, q)
    pin.updateFramePlacements(m, d)
    for s in SIDES:
        tau -= pin.getFrameJacobian(m, d, m.getFrameId(frames[s]), pin.LOCAL).T @ W[s]
    return tau[base_idx]


def _case(robot):
    """Double support at the neutral pose: the wrenches that hold it still (each centre of
    pressure 3 cm inside the sole's side edges), then a lateral base acceleration of 1 m/s²
    (as a closed seam gives a knot a new acceleration). The plain least-norm correction
    answers with ankle roll moments and puts both centres of pressure 4 cm past the soles'
    edges; shifting load from one foot to the other meets the same base rows inside them."""
    nv = robot.model.nv
    q, v = robot.neutral.copy(), np.zeros(nv)
    frames = {s: robot.contacts[s].frame for s in SIDES}
    stance = {s: np.ones(1, bool) for s in SIDES}
    guess = {s: np.array([[0.0, 0.0, 0.5 * robot.mass * 9.81, 0.0, 0.0, 0.0]]) for s in SIDES}
    still = make_consistent(robot, np.zeros(1), q[None], v[None], v[None], guess, stance,
                            frames, base_v_indices(robot))[3]
    a = np.zeros(nv)
    a[1] = 1.0  # the free-flyer's lateral acceleration [m/s²]
    return q, v, a, still, frames


def test_the_correction_keeps_the_cones_where_the_base_rows_leave_room(g1):
    q, v, a, W, frames = _case(g1)
    base_idx = base_v_indices(g1)
    stance = {s: np.ones(1, bool) for s in SIDES}
    for s in SIDES:  # the starting wrenches are inside the cones
        assert cone_margin(g1.contacts[s], W[s][0])["cop"] > 0.02
    args = (g1, np.zeros(1), q[None], v[None], a[None], W, stance, frames, base_idx)
    plain = make_consistent(*args)[3]
    kept = make_consistent(*args, contacts=dict(g1.contacts))[3]
    for out in (plain, kept):  # both meet Pinocchio's base rows to round-off
        r = _base_residual(g1, q, v, a, {s: out[s][0] for s in SIDES}, frames, base_idx)
        assert np.max(np.abs(r)) < 1e-8 * g1.mass * 9.81
    # the plain correction leaves a cone (the test's premise); the kept one stays inside all
    assert min(float(cone_margin(g1.contacts[s], plain[s][0])["cop"]) for s in SIDES) < -0.03
    for s in SIDES:
        mg = cone_margin(g1.contacts[s], kept[s][0])
        assert mg["cop"] >= -1e-9 and mg["friction"] >= -1e-9 and mg["yaw"] >= -1e-9
        assert mg["normal"] > 0


def test_one_foot_has_no_room_and_keeps_the_plain_correction(g1):
    q, v, a, W, frames = _case(g1)
    base_idx = base_v_indices(g1)
    stance = {"left": np.ones(1, bool), "right": np.zeros(1, bool)}
    W = {s: w.copy() for s, w in W.items()}
    W["left"] *= 2.0
    args = (g1, np.zeros(1), q[None], v[None], a[None], W, stance, frames, base_idx)
    plain = make_consistent(*args)[3]
    kept = make_consistent(*args, contacts=dict(g1.contacts))[3]
    np.testing.assert_allclose(kept["left"], plain["left"], atol=1e-9)


def test_the_correction_keeps_the_push_directions_it_is_given(g1):
    """The wrenches that hold the neutral pose still, with 5 N·m of yaw moment added to the
    left sole (the base rows then miss it): the plain least-norm correction takes some of it
    back through opposite horizontal forces and turns both pushes 1.8 mrad off their
    directions (the audit allows 1 mrad); given the directions, the correction stays within
    half of that (the yaw moments alone can take it back)."""
    from gdimitate.assess.audit.report import AuditTolerances

    q, v, _, W, frames = _case(g1)
    a = np.zeros_like(v)
    base_idx = base_v_indices(g1)
    stance = {s: np.ones(1, bool) for s in SIDES}
    m, d = g1.model, g1.data
    pin.framesForwardKinematics(m, d, q)
    R = {s: d.oMf[m.getFrameId(frames[s])].rotation.copy() for s in SIDES}

    def push(s, w):  # the foot's push on the ground, world, unit
        p = -(R[s] @ w[:3])
        return p / np.linalg.norm(p)

    targets = {s: push(s, W[s][0])[None] for s in SIDES}
    W = {s: w.copy() for s, w in W.items()}
    W["left"][0, 5] += 5.0
    args = (g1, np.zeros(1), q[None], v[None], a[None], W, stance, frames, base_idx)
    tol = AuditTolerances().force_direction
    for out, within in ((make_consistent(*args)[3], False),
                        (make_consistent(*args, contacts=dict(g1.contacts))[3], False),
                        (make_consistent(*args, contacts=dict(g1.contacts), targets=targets)[3],
                         True)):
        r = _base_residual(g1, q, v, a, {s: out[s][0] for s in SIDES}, frames, base_idx)
        assert np.max(np.abs(r)) < 1e-8 * g1.mass * 9.81
        off = [float(np.arccos(np.clip(push(s, out[s][0]) @ targets[s][0], -1, 1)))
               for s in SIDES]
        assert (max(off) <= 0.5 * tol) == within, off
