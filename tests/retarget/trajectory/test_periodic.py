"""The periodic gait cycle (``adapt(..., periodic=True)``, docs/design.md §14): the seam rows
against a NumPy re-derivation, the cycle's seam to 1e-9 recomputed from the output (and the
audit holding on the cycle and across the seam), against the non-periodic adaptation of the
same stride as the negative control (its seam is open by centimetres). HOAP-2 (planar) and
the shipped 3-D walk keep it to a few seconds."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.assess.audit.periodic import SEAM_TOL, seam_errors
from gdimitate.errors import InvalidInputError
from gdimitate.model.footsteps import walking_direction
from gdimitate.retarget.knot import Flags, Knot
from gdimitate.retarget.parts.periodic import PeriodicSeam
from gdimitate.retarget.parts.seam import seam_functions
from gdimitate.retarget.trajectory.periodic import periodic_rate, periodic_stride
from gdimitate.retarget.trajectory.problem import symbolic_model

RNG = np.random.default_rng(18)


@pytest.fixture(scope="module")
def story():
    from gdimitate.apps.demo import default_demonstration

    return default_demonstration()


@pytest.fixture(scope="module")
def cycles(story):
    robot, demo, forces = story
    hoap = gd.Robot.load("hoap2")
    opts = dict(force="measured", forces=forces, rate=30, verbose=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        per = gd.adapt(demo, robot, hoap, "optimal", periodic=True, **opts)
        plain = gd.adapt(demo, robot, hoap, "optimal", **opts)
    return hoap, per, plain


@pytest.mark.parametrize("name", ["hoap2", "alexander"])
def test_seam_rows_match_numpy(name):
    robot = gd.Robot.load(name)
    part = PeriodicSeam()
    sym = symbolic_model(robot)
    k0 = Knot(robot, sym, Flags())
    k = Knot(robot, sym, Flags(), extra=part.params(k0))
    k.add_slacks(0)
    fun, labels, sizes = seam_functions(k, [part])
    m = robot.model
    for _ in range(3):
        xs, qs, vs = [], [], []
        for _ in range(2):
            x = RNG.normal(size=k.var.size)
            q = pin.randomConfiguration(m, -np.ones(m.nq), np.ones(m.nq))
            x[k.var["q"]] = q
            xs.append(x)
            qs.append(q)
            vs.append(x[k.var["v"]])
        p = RNG.normal(size=k.par.size)
        d = RNG.normal(size=2)
        d /= np.linalg.norm(d)
        p[k.par["seam_dir"]] = d
        got = np.asarray(fun["sg"](xs[0], xs[1], p)).ravel()
        dq, dv = qs[1] - qs[0], vs[1] - vs[0]
        if robot.base == "planar":
            ix = robot.idx_q("base_x")
            want = np.r_[np.delete(dq, ix), dv]
        else:
            want = np.r_[d[0] * dq[1] - d[1] * dq[0], dq[2:], dv]
        np.testing.assert_allclose(got, want, atol=1e-12)
        assert sizes == [want.size] and labels == ["periodic seam"] * want.size


def test_periodic_cycle_seam_and_audit(cycles, story):
    hoap, per, plain = cycles
    m = per.motion
    _, demo, _ = story
    # one stride, heel strike to heel strike of the right foot, a knot on each end
    assert m.t[-1] - m.t[0] == pytest.approx(demo.t[-1] - demo.t[0], abs=1e-9)
    assert m.contact["right"][0] and m.contact["right"][-1] and not m.contact["right"].all()
    assert per.feasible, per.audit.summary(only_failed=True)
    d = walking_direction(story[0], story[1].q)
    err = seam_errors(hoap, m, per.wrenches, d)
    assert max(err.values()) <= SEAM_TOL, err
    # the base advanced by one stride (HOAP-2 walks forward)
    assert m.q[-1, hoap.idx_q("base_x")] - m.q[0, hoap.idx_q("base_x")] > 0.02
    # the seam checks are in the audit report
    names = [c.name for c in per.audit.checks]
    assert {"seam_position", "seam_velocity", "seam_contact"} <= set(names)
    # integration across the seam: the last step's forward difference is the first knot's v
    h = m.t[-1] - m.t[-2]
    v_fd = pin.difference(hoap.model, m.q[-2], m.q[-1]) / h
    np.testing.assert_allclose(v_fd, m.v[0], atol=1e-9)


def test_non_periodic_stride_has_an_open_seam(cycles, story):
    """Negative control: the same stride adapted without the seam does not close."""
    hoap, _, plain = cycles
    err = seam_errors(hoap, plain.motion, plain.wrenches, walking_direction(story[0],
                                                                           story[1].q))
    assert err["seam_position"] > 1e-3 or err["seam_velocity"] > 1e-2, err


def test_periodic_stride_needs_two_strikes(story):
    _, demo, forces = story
    half = demo.replace(t=demo.t[:20], q=demo.q[:20],
                        contact={s: np.zeros(20, bool) for s in demo.contact}, v=None, a=None)
    with pytest.raises(InvalidInputError, match="heel strike"):
        periodic_stride(half, None)
    m, f = periodic_stride(demo, forces)
    assert m.T == demo.T and np.all(f["left"].force[-1] == f["left"].force[0])
    assert periodic_rate(m, 30.0) * (m.t[-1] - m.t[0]) == pytest.approx(round(
        30.0 * (m.t[-1] - m.t[0])))


def test_periodic_needs_trajectory_mode(story):
    robot, demo, forces = story
    with pytest.raises(InvalidInputError, match="trajectory"):
        gd.adapt(demo, robot, gd.Robot.load("hoap2"), "optimal", periodic=True,
                 mode="per_frame", verbose=False)


def test_froude_cycle_ends_on_a_knot(story):
    """On the Froude clock (durations × √r) the cycle is one stride of that clock long, with a
    knot on its end: the seam joins the two heel strikes (before the knot rate was taken on
    the demonstrator's clock, so the last knot fell short of the stride's end and the
    ``seam_contact`` check failed)."""
    robot, demo, forces = story
    hoap = gd.Robot.load("hoap2")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        per = gd.adapt(demo, robot, hoap, "optimal", periodic=True, force="measured",
                       forces=forces, rate=30, verbose=False, gait_scaling="froude")
    stride, _ = periodic_stride(demo, forces)
    span = (stride.t[-1] - stride.t[0]) * np.sqrt(np.mean(
        [hoap.legs[s].length for s in ("left", "right")])
        / np.mean([robot.legs[s].length for s in ("left", "right")]))
    m = per.motion
    assert m.t[-1] - m.t[0] == pytest.approx(span, abs=1e-9)
    assert m.contact["right"][0] and m.contact["right"][-1] and not m.contact["right"].all()
    assert per.audit.check("seam_contact").passed, per.audit.summary(only_failed=True)
