"""The planar walking generator (paper Fig. 3)."""

import numpy as np
import pytest

from gdimitate import HUMAN_GAIT, ROBOT_GAIT, GaitSpec, InvalidInputError, walking_motion
from gdimitate.assess.metrics import foot_heights, hip_height, sole_paths


@pytest.mark.parametrize("gait", [HUMAN_GAIT, ROBOT_GAIT], ids=["human", "robot"])
@pytest.mark.parametrize("name", ["case1_demonstrator", "hoap2", "talos"])
def test_generated_walk(name, gait, robot):
    r = robot(name)
    m = walking_motion(r, gait)
    L = r.legs["left"].length
    both = m.contact["left"] & m.contact["right"]
    # double-support share of the time = 1 − single_support (per step), ±2 samples per step
    steps = 2 * gait.cycles
    assert both.mean() == pytest.approx(1 - gait.single_support, abs=2 * steps / m.T)
    assert not np.any(~m.contact["left"] & ~m.contact["right"])  # never airborne
    fh = foot_heights(r, m)
    for s in ("left", "right"):
        # Pinocchio FK: stance soles on the ground, swing soles reach the step height
        np.testing.assert_allclose(fh[s][m.contact[s]], 0.0, atol=1e-9 if r.base == "planar"
                                   else 2e-3 * L)
        assert fh[s].max() == pytest.approx(gait.step_height * L, rel=0.02)
    # hip at constant height, constant forward speed
    h = hip_height(r, m)
    assert np.ptp(h) < 1e-9 * L + (0 if r.base == "planar" else 1e-3)
    soles = sole_paths(r, m)
    landings = soles["left"][1:][np.diff(m.contact["left"].astype(int)) == 1, 0]
    assert np.diff(landings) == pytest.approx(2 * gait.step_length * L, rel=1e-6)


def test_bad_gait_parameters(robot):
    with pytest.raises(InvalidInputError, match="single_support"):
        GaitSpec(single_support=1.5)
    with pytest.raises(InvalidInputError, match="too long"):
        walking_motion(robot("hoap2"), GaitSpec(step_length=1.8))
