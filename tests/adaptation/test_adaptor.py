"""adapt(): the paper's cases through Eq. (1) and the joint-copy baseline."""

import numpy as np
import pytest

from gdimitate import (
    InvalidInputError,
    UnknownNameError,
    adapt,
    paper_case,
)
from gdimitate.assess.metrics import force_direction, hip_height_ratio
from gdimitate.model.sagittal import leg_angles
from gdimitate.planar import eq1


@pytest.fixture(scope="module", params=["I", "II", "humanoid"])
def case(request):
    return (request.param, *paper_case(request.param))


def test_analytic_keeps_force_direction_and_hip_ratio(case):
    name, demo, imit, motion = case
    a = adapt(motion, demo, imit, "analytic")
    rep = a.report
    assert rep.force_direction_error_max < 1e-12
    fd_m = force_direction(demo, motion, "segment")
    fd_r = force_direction(imit, a.motion, "segment")
    for s in ("left", "right"):
        np.testing.assert_array_equal(np.isnan(fd_m[s].sagittal), ~motion.contact[s])
        np.testing.assert_allclose(fd_r[s].sagittal, fd_m[s].sagittal, atol=1e-12,
                                   equal_nan=True)
        np.testing.assert_allclose(fd_r[s].vector, fd_m[s].vector, atol=1e-12, equal_nan=True)
    hm, hr = hip_height_ratio(demo, motion), hip_height_ratio(imit, a.motion)
    for s in ("left", "right"):
        ok = rep.feasible[s]
        np.testing.assert_allclose(hr[s][ok], hm[s][ok], atol=1e-12)
        # independent of the adaptor's code path: the report's mask is Eq. (1)'s |arg| ≤ 1
        _, ang = leg_angles(demo, motion.q)
        dl, il = demo.legs[s], imit.legs[s]
        r = eq1(ang[s][:, 0], ang[s][:, 1], (dl.thigh, dl.shank), (il.thigh, il.shank))
        np.testing.assert_array_equal(ok, r.feasible)
    if name in ("I", "humanoid"):
        assert rep.infeasible_frames == {"left": 0, "right": 0}
    else:  # Case II: infeasible on part of the cycle (paper Fig. 9), reported, never hidden
        frac = sum(rep.infeasible_frames.values()) / (2 * motion.T)
        assert 0.05 < frac < 0.9
        assert rep.hip_height_ratio_error_max > 1e-3


def test_copy_baseline_changes_hip_ratio(case):
    name, demo, imit, motion = case
    c = adapt(motion, demo, imit, "copy")
    _, a_m = leg_angles(demo, motion.q)
    _, a_r = leg_angles(imit, c.motion.q)
    for s in a_m:
        np.testing.assert_allclose(a_r[s], a_m[s], atol=1e-12)  # same joint angles
    assert c.report.hip_height_ratio_error_max > 0.01
    assert c.report.to_dict()["method"] == "copy"


def test_imitator_stance_foot_does_not_slip():
    demo, imit, motion = paper_case("I")
    a = adapt(motion, demo, imit, "analytic")
    from gdimitate.assess.metrics import sole_paths

    soles = sole_paths(imit, a.motion)
    for s in ("left", "right"):
        c = a.motion.contact[s]
        single = c & ~a.motion.contact["left" if s == "right" else "right"]
        # from the frame before the other foot lifts off to the end of single support
        # (the hand-over of the anchor included), the foot stays put
        pairs = single[1:] & c[:-1]
        dx = np.diff(soles[s][:, 0])[pairs]
        assert pairs.sum() > 20 and np.max(np.abs(dx)) < 1e-12
        np.testing.assert_allclose(np.minimum.reduce([soles[k][:, 2] for k in soles])[c], 0.0,
                                   atol=1e-9)


def test_bad_input():
    demo, imit, motion = paper_case("I")
    with pytest.raises(UnknownNameError, match="analytic"):
        adapt(motion, demo, imit, method="magic")
    with pytest.raises(InvalidInputError, match="do not match"):
        adapt(motion, imit.__class__.from_library("talos"), imit)
    with pytest.raises(InvalidInputError, match="no options"):
        adapt(motion, demo, imit, method="analytic", weights=1)
