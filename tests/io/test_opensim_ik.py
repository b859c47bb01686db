"""Marker-based inverse kinematics (``gd.opensim.inverse_kinematics``).

References: (1) closed form — markers made by Pinocchio's forward kinematics of a known
trajectory are fitted back to that trajectory; (2) OpenSim's own ``InverseKinematicsTool`` on
subject01 (``subject01_walk1.trc`` + ``subject01.osim``, the same marker weights), run in a
subprocess (``tests/opensim_ref/osim_ik.py``: ``opensim`` and ``casadi`` cannot share a
process): hips, knees and ankles within 2° RMS, marker residuals no worse than 1.1×
OpenSim's own (its model's markers at its angles vs the measured ones).
"""

from __future__ import annotations

import functools
import importlib.util
import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gdimitate import Robot
from gdimitate.errors import InvalidInputError, MarkerGapWarning, OpenSimDataError
from gdimitate.io.demonstration import load_demonstration
from gdimitate.io.opensim import WORLD_FROM_OPENSIM as C
from gdimitate.io.opensim import Markers, inverse_kinematics, read_trc
from tests.helpers import ROOT, TESTS

D3 = ROOT / "gdimitate/data/gait/opensim_subject01_walk1_3d"
SCRIPT = TESTS / "opensim_ref/osim_ik.py"
LEG_JOINTS = [f"{j}_{s}" for s in "rl" for j in ("hip_flexion", "hip_adduction",
                                                  "hip_rotation", "knee_angle", "ankle_angle")]


@functools.cache
def _robot():
    return Robot.from_osim(D3 / "subject01.osim")


@functools.cache
def _trc():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MarkerGapWarning)
        return read_trc(D3 / "subject01_walk1.trc")


def _fk_markers(robot, Q, names):
    m, d = robot.model, robot.model.createData()
    out = np.empty((len(Q), len(names), 3))
    for k, q in enumerate(Q):
        pin.framesForwardKinematics(m, d, q)
        out[k] = [d.oMf[m.getFrameId(n)].translation for n in names]
    return out


def test_recovers_known_motion_and_respects_limits():
    """Markers from Pinocchio FK of a smooth trajectory (joints swinging inside their
    ranges, the base walking and turning) → the same trajectory, residuals ~0; a marker
    pulled beyond the knee's range leaves the knee at its limit, never past it."""
    robot = _robot()
    m = robot.model
    names = list(robot.osim.markers)
    T = 20
    t = np.arange(T) / 60
    Q = np.tile(robot.neutral, (T, 1))
    for k, j in enumerate(LEG_JOINTS + ["lumbar_extension"]):
        i = robot.idx_q(j)
        lo, hi = m.lowerPositionLimit[i], m.upperPositionLimit[i]
        mid, amp = 0.5 * (lo + hi), min(0.25 * (hi - lo), 0.5)
        Q[:, i] = mid + amp * np.sin(2 * np.pi * 1.1 * t + k)
    Q[:, 0] += 1.2 * t
    for k in range(T):
        R = pin.exp3(np.array([0, 0, 0.3 * np.sin(2 * t[k])])) @ \
            pin.Quaternion(*Q[k, [6, 3, 4, 5]]).matrix()
        Q[k, 3:7] = pin.Quaternion(R).coeffs()
    X = _fk_markers(robot, Q, names)
    X[5, 3] = np.nan  # a gap: that marker drops out of frame 5 only
    motion, res = inverse_kinematics(robot, Markers(t, tuple(names), X), return_result=True,
                                     iterations=30)
    assert np.nanmax(res.residuals) < 1e-6 and np.isnan(res.residuals[5, 3])
    for j in LEG_JOINTS:
        i = robot.idx_q(j)
        np.testing.assert_allclose(motion.q[:, i], Q[:, i], atol=1e-5, err_msg=j)
    # beyond the range: a knee flexed 30° past its limit
    i = robot.idx_q("knee_angle_r")
    lo, hi = m.lowerPositionLimit[i], m.upperPositionLimit[i]
    Qx = Q[:3].copy()
    Qx[:, i] = lo - np.radians(30)
    Xx = _fk_markers(robot, Qx, names)  # FK does not clamp
    mx = inverse_kinematics(robot, Markers(t[:3], tuple(names), Xx))
    assert np.all(mx.q[:, 7:] >= m.lowerPositionLimit[7:] - 1e-9)
    assert np.all(mx.q[:, 7:] <= m.upperPositionLimit[7:] + 1e-9)
    assert np.allclose(mx.q[:, i], lo, atol=1e-3)


def test_bad_inputs():
    robot = _robot()
    t = np.arange(3) / 60
    with pytest.raises(OpenSimDataError, match="marker names must match"):
        inverse_kinematics(robot, Markers(t, ("a", "b", "c"), np.zeros((3, 3, 3))))
    mk = _trc()
    with pytest.raises(InvalidInputError, match="weights name markers"):
        inverse_kinematics(robot, mk, {"No.Such.Marker": 2.0})


def _opensim_ik(tmp: Path, weights: dict[str, float]) -> dict:
    (tmp / "w.json").write_text(json.dumps(weights))
    out = tmp / "osim_ik.npz"
    subprocess.run([sys.executable, str(SCRIPT), str(D3 / "subject01.osim"),
                    str(D3 / "subject01_walk1.trc"), str(out), "0.5", "2.5",
                    str(tmp / "w.json")], check=True, capture_output=True, timeout=300)
    d = np.load(out)
    return {k: d[k] for k in d.files}


#: Weights for the second comparison: the pelvis, heels and toe tips held closely, the
#: head and shoulders (the least rigid markers) loosely — OpenSim's own example setups weight
#: markers this way; any weights serve, both solvers are given the same.
WEIGHTED = {"Top.Head": 0.1, "R.Acromium": 0.5, "L.Acromium": 0.5, "R.ASIS": 10, "L.ASIS": 10,
            "V.Sacral": 10, "R.Heel": 10, "L.Heel": 10, "R.Toe.Tip": 10, "L.Toe.Tip": 10}


@pytest.mark.skipif(importlib.util.find_spec("opensim") is None,
                    reason="the OpenSim reference needs the `opensim` wheel")
@pytest.mark.parametrize("weights", [{}, WEIGHTED], ids=["uniform", "weighted"])
def test_matches_opensims_own_ik(tmp_path, weights):
    robot, mk = _robot(), _trc()
    ref = _opensim_ik(tmp_path, weights)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MarkerGapWarning)  # arm markers: not on the model
        motion, res = inverse_kinematics(robot, mk, weights or None, return_result=True)
    sel = np.flatnonzero(mk.t >= 0.5 - 1e-9)
    np.testing.assert_allclose(mk.t[sel], ref["t"], atol=1e-3)
    names = [str(n) for n in ref["names"]]
    rms = {}
    for j in LEG_JOINTS:
        e = motion.q[sel, robot.idx_q(j)] - ref["q"][:, names.index(j)]
        rms[j] = float(np.degrees(np.sqrt(np.mean(e ** 2))))
    print("RMS vs OpenSim [deg]:", {k: round(v, 3) for k, v in rms.items()})
    assert max(rms.values()) <= 2.0, rms
    # residuals: OpenSim's model markers at OpenSim's angles vs the measured markers
    mn = [str(n) for n in ref["markers"]]
    P = ref["marker_p"][:, [mn.index(n) for n in res.names]] @ C.T
    X = mk.xyz[sel][:, [mk.names.index(n) for n in res.names]]
    theirs = np.sqrt(np.nanmean(np.linalg.norm(P - X, axis=2) ** 2))
    ours = np.sqrt(np.nanmean(res.residuals[sel] ** 2))
    print(f"marker residual RMS: ours {1000 * ours:.2f} mm, OpenSim {1000 * theirs:.2f} mm")
    assert ours <= 1.1 * theirs
    assert np.all(motion.q[:, 7:] >= robot.model.lowerPositionLimit[7:] - 1e-9)
    assert np.all(motion.q[:, 7:] <= robot.model.upperPositionLimit[7:] + 1e-9)
    assert set(res.per_marker()) == set(res.names) and len(res.names) == 31


def test_load_demonstration_with_markers():
    demo = load_demonstration(D3 / "subject01.osim", markers=D3 / "subject01_walk1.trc",
                              grf=D3 / "subject01_walk1_grf.mot")
    assert demo.motion.T == 151 and demo.forces is not None and demo.ik is not None
    assert "marker-based IK" in demo.note and "subject01_walk1_grf.mot" in demo.note
    from gdimitate.errors import DemonstrationFormatError

    with pytest.raises(DemonstrationFormatError, match="--osim"):
        load_demonstration(D3 / "subject01_walk1.trc")
    with pytest.raises(DemonstrationFormatError, match="either coordinates= .* or markers="):
        load_demonstration(D3 / "subject01.osim")


def test_walker_knee_followers_follow_their_coordinate():
    """A converted walker knee (spline-driven joints ``knee_angle_r__*``) is fitted with its
    followers set from the knee angle after every step (gdimitate.opensim.follow_coordinates):
    markers made by Pinocchio of a knee sweep are fitted (residual < 0.1 mm) and every
    follower equals its spline of the fitted knee angle."""
    from gdimitate.io.opensim import follow_coordinates

    robot = Robot.from_osim(TESTS / "data/osim/rajagopal_like.osim")
    names = list(robot.osim.markers)
    T = 12
    t = np.arange(T) / 60
    Q = np.tile(robot.neutral, (T, 1))
    i = robot.idx_q("knee_angle_r")
    m = robot.model
    Q[:, i] = np.linspace(m.lowerPositionLimit[i] + 0.1, m.upperPositionLimit[i] - 0.1, T)
    Q = follow_coordinates(robot.osim.plans, Q, robot.idx_q)
    X = _fk_markers(robot, Q, names)
    motion, res = inverse_kinematics(robot, Markers(t, tuple(names), X), return_result=True,
                                     iterations=40)
    assert np.nanmax(res.residuals) < 1e-4
    again = follow_coordinates(robot.osim.plans, motion.q.copy(), robot.idx_q)
    np.testing.assert_allclose(motion.q, again, atol=1e-12)
    followers = [j for j in robot.joint_names if j.startswith("knee_angle_r__")]
    assert followers and np.ptp(motion.q[:, robot.idx_q(followers[0])]) > 1e-3
