"""The whole-body optimal adaptor on the paper's planar cases (issue 9): Eq. (1) recovery,
Case II feasibility, limits, the infeasible report, the streaming mode, caching, bad input and
Ctrl-C.

References are independent of the optimiser: the closed-form Eq. (1)
(``adapt(method="analytic")``), Pinocchio (``rnea``, frame Jacobians, ``difference``) directly
and through :func:`gdimitate.assess.audit.audit`.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.adaptation.adaptor import adapt
from gdimitate.apps.cases import paper_case
from gdimitate.errors import ContactError, GdimitateError, InvalidInputError, UnknownNameError
from gdimitate.model.contact import SoleContact
from gdimitate.model.robot import SIDES
from gdimitate.retarget import Contact, Limits, Weights, resample, schedule
from gdimitate.retarget.trajectory import problem


def _slice(m, a, b):
    return m.replace(t=m.t[a:b], q=m.q[a:b], contact={s: c[a:b] for s, c in m.contact.items()})


@pytest.fixture(scope="module")
def case1():
    return paper_case("I")


@pytest.fixture(scope="module")
def case2():
    return paper_case("II")


@pytest.fixture(scope="module")
def case2_optimal(case2):
    d, i, m = case2
    return adapt(m, d, i, method="optimal", rate=25, verbose=False)


def test_case1_recovers_eq1(case1):
    """`segment`, Eq. (1)'s contact rule (the anchor foot), no active limit (efforts and
    velocities lifted, a sole long enough for the centre of pressure, μ = 5): the optimum is
    Eq. (1) to ≤ 1e-6 rad. IPOPT's objective is scaled up so that its stopping test resolves
    1e-8-sized residuals."""
    d, i, m = case1
    demo = resample(d, m, 25)
    ref = adapt(demo.replace(contact=schedule(demo, None, "anchor")), d, i, method="analytic")
    assert ref.report.infeasible_frames == {"left": 0, "right": 0}
    r = adapt(m, d, i, method="optimal", force="segment", rate=25, verbose=False,
              limits=Limits(effort=math.inf, velocity=math.inf),
              contact=Contact(rule="anchor", mu=5.0, f_min=0.0),
              contacts={s: {"half_length": 1.0, "half_width": 0.05} for s in SIDES},
              weights=Weights(placement=0, joints=0, posture=0, smoothness=0, wrench=1e-12),
              ipopt={"obj_scaling_factor": 1e8, "tol": 1e-12, "constr_viol_tol": 1e-12})
    assert r.solver.unmet == () and not r.solver.elastic
    cols = [i.idx_q(j) for j in i.joint_names if not j.startswith("base_")]
    cols.append(i.idx_q("base_pitch"))
    assert np.abs(r.motion.q[:, cols] - ref.motion.q[:, cols]).max() <= 1e-6
    assert r.report.force_direction_error_max <= 1e-6


def _pinocchio_check(robot, motion, wrenches, contacts):
    """Independent recomputation: base residual [N, N·m], torques, forward differences."""
    m, data = robot.model, robot.data
    base = [robot.idx_v(j) for j in ("base_x", "base_z", "base_pitch")]
    worst, tau_ratio = 0.0, 0.0
    act = [k for k in range(m.nv) if k not in base]
    for k in range(motion.T):
        q, v, a = motion.q[k], motion.v[k], motion.a[k]
        tau = pin.rnea(m, data, q, v, a).copy()
        pin.computeJointJacobians(m, data, q)
        pin.framesForwardKinematics(m, data, q)
        for s in SIDES:
            fid = m.getFrameId(contacts[s].frame)
            J = pin.getFrameJacobian(m, data, fid, pin.LOCAL)
            tau -= J.T @ wrenches[s][k]
        worst = max(worst, np.abs(tau[base]).max())
        tau_ratio = max(tau_ratio, np.max(np.abs(tau[act]) / m.effortLimit[act]))
    h = np.diff(motion.t)
    fd = np.array([pin.difference(m, motion.q[k], motion.q[k + 1]) / h[k]
                   for k in range(motion.T - 1)])
    return worst, tau_ratio, np.abs(fd - motion.v[1:]).max()


def test_case2_feasible_where_eq1_is_not(case2, case2_optimal):
    d, i, m = case2
    ref = adapt(resample(d, m, 25), d, i, method="analytic")
    assert sum(ref.report.infeasible_frames.values()) > 0  # Eq. (1) cannot reach them
    r = case2_optimal
    assert r.audit.feasible, r.audit.binding
    res, tau_ratio, fd_err = _pinocchio_check(i, r.motion, r.wrenches, r.contacts)
    assert res <= 1e-6  # N, N·m: the base rows of the inverse dynamics vanish
    assert tau_ratio <= 1.001  # every actuated joint within its effort limit
    assert fd_err <= 1e-9  # forward differences of q are the velocities
    for s in SIDES:
        st = r.motion.contact[s]
        w = r.wrenches[s]
        assert np.all(w[~st] == 0.0)
        assert np.all(w[st, 2] >= 0.0)
        assert np.all(np.abs(w[st, 0]) <= r.contacts[s].mu * w[st, 2] + 1e-9)
        assert np.all(np.abs(w[st, 4]) <= r.contacts[s].half_length * w[st, 2] + 1e-9)
        assert np.all(w[:, [1, 3, 5]] == 0.0)  # planar: f_y = τ_x = τ_z = 0
    # velocity limits, recomputed
    vl = i.model.velocityLimit
    act = [i.idx_v(j) for j in i.joint_names if not j.startswith("base_")]
    assert np.max(np.abs(r.motion.v[:, act]) / vl[act]) <= 1.01


def test_second_call_skips_the_build(case2, case2_optimal):
    d, i, m = case2
    n = problem.BUILD_COUNT
    r = adapt(m, d, i, method="optimal", rate=25, verbose=False)
    assert problem.BUILD_COUNT == n and r.solver.cached and r.solver.build_s == 0.0
    np.testing.assert_allclose(r.motion.q, case2_optimal.motion.q, atol=1e-9)


def test_infeasible_problem_is_reported_not_raised(case2):
    d, i, m = case2
    # the adaptor's own iteration budget: a cap on IPOPT's iterations (``max_iter``) can stop
    # the least-infeasible solve short of the hard solve's result, which then stands
    # (``elastic`` False; 60 iterations here: 37 hard, stalled, then 60 elastic, cut short)
    r = adapt(_slice(m, 0, 40), d, i, method="optimal", rate=25, verbose=False,
              limits=Limits(effort=1e-6))
    assert r.solver.elastic and not r.solver.success
    assert not r.audit.feasible
    assert any(b.startswith("torque:") for b in r.audit.binding)
    assert any(u.name.startswith("torque limit") for u in r.solver.unmet)


def test_per_frame_flags_agree_with_the_audit(case2):
    d, i, m = case2
    demo = resample(d, _slice(m, 0, 30), 25)
    r = adapt(demo, d, i, method="optimal", mode="per_frame", verbose=False)
    assert r.frame_feasible.shape == (demo.T,)
    np.testing.assert_array_equal(r.frame_feasible, r.audit.knot_feasible)
    r2 = adapt(demo, d, i, method="optimal", mode="per_frame", verbose=False,
               limits=Limits(effort=1e-6), ipopt={"max_iter": 40})
    np.testing.assert_array_equal(r2.frame_feasible, r2.audit.knot_feasible)
    # every frame after the first two is infeasible; the first ones may be met by a limp robot
    # (no joint torque) in a momentarily consistent state — a free fall, or, once its stance
    # feet start still (their velocity rows at knot 0), contact forces through its joint axes
    # while it decelerates — which only later frames' slip and penetration expose
    assert not r2.frame_feasible[2:].any()
    act = [k for k in range(i.model.nv)
           if k not in [i.idx_v(j) for j in ("base_x", "base_z", "base_pitch")]]
    for k in np.flatnonzero(r2.frame_feasible):
        assert np.abs(r2.audit.tau[k, act]).max() <= 1e-6 * (1 + 1e-3), k


def test_bad_input(case1, robot):
    d, i, m = case1
    with pytest.raises(UnknownNameError, match="valid optimal-adaptor options"):
        adapt(m, d, i, method="optimal", nonsense=1)
    with pytest.raises(InvalidInputError, match="mu"):
        Contact(mu=0.0)
    with pytest.raises(InvalidInputError, match="zero size"):
        SoleContact("left", "left_sole_contact", 0.0, 0.02)
    with pytest.raises(InvalidInputError, match="contact"):
        adapt(m.replace(contact={}), d, i, method="optimal", verbose=False)
    with pytest.raises(InvalidInputError, match="forces"):
        adapt(m, d, i, method="optimal", force="measured", verbose=False)
    with pytest.raises(UnknownNameError, match="valid joint of"):
        adapt(m, d, i, method="optimal", verbose=False,
              body_map={"joints": {"left_hip": "no_such_joint"}})
    with pytest.raises(UnknownNameError, match="force model"):
        adapt(m, d, i, method="optimal", force="magic", verbose=False)
    bolt = robot("bolt")
    assert isinstance(bolt.contacts, dict)
    if not bolt.contacts:
        with pytest.raises(ContactError):
            adapt(m, d, bolt, method="optimal", verbose=False)
    assert issubclass(UnknownNameError, GdimitateError)


#: 961 knots: the solve runs ~10 s after its first progress line (at 100 knots/s it ended
#: 1.3 s after it, before a loaded parallel run's test had sent its signal); Python's own
#: SIGINT handler first, as a terminal's process has (a shell's background job ignores it)
_SCRIPT = textwrap.dedent("""
    import signal
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import gdimitate as gd
    from gdimitate.apps.cases import paper_case
    d, i, m = paper_case("II")
    print("ready", flush=True)
    gd.adapt(m, d, i, method="optimal", rate=400, ipopt={"max_iter": 100000, "tol": 1e-14},
             verbose=True)
    print("finished", flush=True)
""")


def test_ctrl_c_stops_the_solve(tmp_path):
    """A real SIGINT during IPOPT stops the solve and raises KeyboardInterrupt."""
    script = tmp_path / "solve.py"
    script.write_text(_SCRIPT)
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env={**os.environ})
    try:
        t0 = time.time()
        line = ""
        while "iter" not in line and time.time() - t0 < 120:  # the solve has started
            line = p.stderr.readline()
        assert "iter" in line
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=60)
    finally:
        p.kill()
    assert p.returncode != 0
    assert "KeyboardInterrupt" in err
    assert "finished" not in out


def test_frozen_joint_is_held_and_its_torque_still_counts(case2):
    d, i, m = case2
    r = adapt(_slice(m, 0, 40), d, i, method="optimal", rate=25, verbose=False,
              limits=Limits(freeze=("left_ankle",), freeze_at={"left_ankle": 0.05}))
    col = r.motion.q[:, i.idx_q("left_ankle")]
    np.testing.assert_allclose(col, 0.05, atol=1e-12)
    j = next(j for j in r.audit.joints if j.name == "left_ankle")
    assert j.torque_max > 0.0 and np.isfinite(j.torque_ratio)  # counted against its limit
    with pytest.raises(InvalidInputError, match="mu"):
        adapt(m, d, i, method="optimal", verbose=False, contacts={"left": {"mu": 0.0}})
    with pytest.raises(UnknownNameError, match="actuated joint"):
        adapt(m, d, i, method="optimal", verbose=False, limits=Limits(freeze=("nope",)))
