"""Force-direction models (DESIGN §5 of docs/design.md) against closed forms, Pinocchio and the
measured ground reaction forces of the shipped walks."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.contact import ContactForces, FootForces
from gdimitate.errors import InvalidInputError, UnknownNameError
from gdimitate.gait import human_walk_path, read_opensim
from gdimitate.metrics import ForceDirection, angle_between, force_direction
from gdimitate.sagittal import joint_paths, leg_angles

GRF = human_walk_path().parent / "walk_gait1018_subject01_grf.mot"


@pytest.fixture(scope="module")
def sagittal_walk():
    """The shipped sagittal walk with the pelvis as measured (treadmill frame, as the forces)."""
    return read_opensim(human_walk_path(), grf=GRF, base="measured")


def _rmse_deg(a, b):
    return float(np.degrees(np.sqrt(np.nanmean((a - b) ** 2))))


def test_segment_is_the_shank_and_planar_angle_is_theta1_plus_theta2(sagittal_walk):
    robot, motion = sagittal_walk
    fd = force_direction(robot, motion, "segment")
    _, ang = leg_angles(robot, motion.q)
    for s in ("left", "right"):
        leg = robot.legs[s]
        p = joint_paths(robot, motion.q, [leg.knee, leg.ankle])
        shank = p[leg.ankle] - p[leg.knee]
        st = motion.contact[s]
        np.testing.assert_allclose(fd[s].vector[st],
                                   shank[st] / np.linalg.norm(shank[st], axis=1)[:, None],
                                   atol=1e-12)
        np.testing.assert_allclose(fd[s].sagittal[st], ang[s][st, 0] + ang[s][st, 1], atol=1e-12)
        assert np.all(np.isnan(fd[s].vector[~st]))
        np.testing.assert_allclose(fd[s].frontal[st], 0.0, atol=1e-12)  # planar model


def test_measured_is_the_reverse_grf_resampled():
    t = np.linspace(0, 1, 11)
    tf = np.linspace(0, 1, 101)
    f = np.c_[np.sin(tf), 0.2 * np.cos(tf), 600 + 10 * tf]
    feet = {s: FootForces(f * (1 if s == "left" else 0.5), np.zeros((101, 3)),
                          np.zeros((101, 3)), np.ones(101, bool)) for s in ("left", "right")}
    forces = ContactForces(tf, feet, "synthetic")
    robot = gd.Robot.from_library("hoap2")
    motion = gd.Motion(t=t, joint_names=robot.joint_names, q=np.tile(robot.neutral, (11, 1)),
                       contact={"left": np.ones(11, bool), "right": t < 0.5})
    fd = force_direction(robot, motion, "measured", forces=forces)
    expect = -np.c_[np.sin(t), 0.2 * np.cos(t), 600 + 10 * t]
    expect /= np.linalg.norm(expect, axis=1)[:, None]
    np.testing.assert_allclose(fd["left"].vector, expect, atol=1e-6)  # linear interp of sin
    assert np.all(np.isnan(fd["right"].vector[t >= 0.5]))
    np.testing.assert_allclose(fd["left"].sagittal, np.arctan2(expect[:, 0], -expect[:, 2]))
    np.testing.assert_allclose(fd["left"].frontal, np.arctan2(expect[:, 1], -expect[:, 2]))
    with pytest.raises(InvalidInputError, match="forces="):
        force_direction(robot, motion, "measured")
    short = ContactForces(tf[:50], {s: FootForces(f[:50], f[:50] * 0, f[:50] * 0,
                                                  np.ones(50, bool)) for s in feet})
    with pytest.raises(InvalidInputError, match="span"):
        force_direction(robot, motion, "measured", forces=short)
    with pytest.raises(UnknownNameError, match="grf"):
        force_direction(robot, motion, "grf")


def test_com_points_from_the_centre_of_mass_to_the_sole(sagittal_walk):
    robot, motion = sagittal_walk
    fd = force_direction(robot, motion, "com")
    k = int(np.flatnonzero(motion.contact["left"])[3])
    q = motion.q[k]
    c = pin.centerOfMass(robot.model, robot.data, q)
    pin.framesForwardKinematics(robot.model, robot.data, q)
    sole = robot.data.oMf[robot.frame_id(robot.legs["left"].sole)].translation
    np.testing.assert_allclose(fd["left"].vector[k], (sole - c) / np.linalg.norm(sole - c),
                               atol=1e-12)


def test_from_vectors_and_angle_between():
    v = np.array([[1.0, 0, -1], [0, 0, 0], [0, 1, -1]])
    d = ForceDirection.from_vectors(v, np.array([True, True, False]), "x")
    np.testing.assert_allclose(d.sagittal[0], np.pi / 4)
    assert np.isnan(d.sagittal[1]) and np.isnan(d.sagittal[2])  # zero vector, swing
    np.testing.assert_allclose(angle_between(np.array([1.0, 0, 0]), np.array([1.0, 1, 0])),
                               np.pi / 4)
