"""The whole-body CPG stage: the signals a network learns reconstruct the motion exactly, and
the free-running replay keeps the robot's joints, order and rhythm."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.oscillator.replay import _compose, body_signals
from tests.helpers import shared


@pytest.mark.parametrize("which", ["3d", "planar"])
def test_body_signals_reconstruct_the_motion(which):
    """Splitting a motion into joint and periodic base signals and composing it back is exact
    (Pinocchio's configuration difference ≤ 1e-12), for the free-flyer 3-D walk and a planar
    robot."""
    if which == "3d":
        robot, motion, _ = shared.walk_3d()
    else:
        human, walk = shared.walk_sagittal()
        robot = shared.library_robot("hoap2")
        motion = gd.adapt(walk, human, robot, "analytic").motion
    sig = body_signals(robot, motion)
    q = _compose(robot, sig, motion.t, sig.X)
    err = max(np.linalg.norm(pin.difference(robot.model, a, b)) for a, b in zip(q, motion.q))
    assert err < 1e-12
    actuated = [n for n in sig.names if not n.startswith("base_")]
    assert len(actuated) == len([j for j in range(1, robot.model.njoints)
                                 if robot.model.joints[j].nq == 1]) - (3 * (robot.base == "planar"))
    # the base signals are periodic-ish: the mean velocity is taken out of the position
    ix = sig.names.index("base_x")
    assert abs(np.polyfit(motion.t, sig.X[:, ix], 1)[0]) < 1e-9


def test_replay_keeps_joint_order_and_rhythm():
    human, walk = shared.walk_sagittal()
    robot = shared.library_robot("hoap2")
    taught = gd.adapt(walk, human, robot, "analytic").motion
    cpg = gd.entrain(robot, taught, duration=4.0)
    assert cpg.replay.joint_names == robot.joint_names
    # one shared frequency, near the demonstration's stride frequency (heel strikes)
    c = taught.contact["left"].astype(int)
    strikes = taught.t[1:][np.diff(c) == 1]
    stride = np.mean(np.diff(strikes))
    assert cpg.result.frequency == pytest.approx(1 / stride, rel=0.05)
    # the base walks on at the taught mean speed (±5 %)
    v_taught = np.polyfit(taught.t, taught.column("base_x"), 1)[0]
    v_replay = np.polyfit(cpg.replay.t, cpg.replay.column("base_x"), 1)[0]
    assert v_replay == pytest.approx(v_taught, rel=0.05)
    for j in ("left_hip", "left_knee", "right_knee"):
        assert np.ptp(cpg.replay.column(j)) > 0.8 * np.ptp(taught.column(j))
