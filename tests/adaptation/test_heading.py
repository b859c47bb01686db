"""Nothing assumes a heading (docs/design.md §13): turning a walk about the vertical turns the
frames Pinocchio computes from it, and the whole-body adaptor gives the same motion up to that
turn, with the same audit verdict, whichever way the subject walked in the lab."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.errors import InvalidInputError
from gdimitate.model.heading import (
    facing_yaw,
    forces_on_clock,
    on_clock,
    turn_forces,
    turn_motion,
    turn_points,
    walk_heading,
    yaw_matrix,
)
from gdimitate.model.kinematics import frame_placements
from gdimitate.model.robot import SIDES


@pytest.fixture(scope="module")
def walk(walk_3d):
    h, m, f = walk_3d
    return h, m, f


def _wrap(a: float) -> float:
    return float((a + np.pi) % (2 * np.pi) - np.pi)


@pytest.mark.parametrize("yaw", [np.pi / 2, np.pi, -2.4, 0.3])
def test_a_turned_walk_turns_every_frame(walk, yaw):
    """Pinocchio on the turned configurations puts every sole and the pelvis where the turn
    puts the original ones (1e-12 m, 1e-12 in rotation entries); the measured forces and
    centres of pressure turn with them, and the heading turns by the yaw."""
    h, m, f = walk
    about = np.array([0.4, -1.3])
    m2, f2 = turn_motion(m, yaw, about), turn_forces(f, yaw, about)
    frames = [h.contacts[s].frame for s in SIDES] + ["pelvis"]
    a, b = frame_placements(h, m.q, frames), frame_placements(h, m2.q, frames)
    R = yaw_matrix(yaw)
    for fr in frames:
        np.testing.assert_allclose(b[fr].translation,
                                   turn_points(a[fr].translation, yaw, about), atol=1e-12)
        np.testing.assert_allclose(b[fr].rotation, R @ a[fr].rotation, atol=1e-12)
    for s in SIDES:
        np.testing.assert_allclose(f2[s].force, f[s].force @ R.T, atol=1e-9)
        np.testing.assert_allclose(f2[s].torque, f[s].torque @ R.T, atol=1e-9)
        ok = f[s].contact
        np.testing.assert_allclose(f2[s].cop[ok], turn_points(f[s].cop[ok], yaw, about),
                                   atol=1e-12)
    assert _wrap(walk_heading(h, m2) - walk_heading(h, m) - yaw) == pytest.approx(0, abs=1e-9)
    # the base's facing turns by the yaw as well (at every frame)
    d = facing_yaw(m2.q, h.base_rotation) - facing_yaw(m.q, h.base_rotation)
    assert np.allclose([_wrap(x - yaw) for x in d], 0, atol=1e-9)


def test_heading_of_a_walk_and_of_a_turn_on_the_spot(walk):
    """The shipped walk heads along +x (its pelvis travels 4 m in 3.5 s); a clip whose base
    stays put takes its heading from the base's facing (turned by 1 rad: 1 rad)."""
    h, m, _ = walk
    assert abs(walk_heading(h, m)) < np.radians(3)
    still = m.replace(q=np.tile(m.q[:1], (m.T, 1)))
    assert walk_heading(h, turn_motion(still, 1.0)) == pytest.approx(
        walk_heading(h, still) + 1.0, abs=1e-9)


def test_foot_distance_is_measured_along_the_walk(walk):
    """The feet's distance of the paper's Fig. 4 is along the walk's heading: the shipped walk
    turned by −137° gives the same curve (1e-9 m), which is the ankles' horizontal
    difference projected on the direction of the pelvis's travel (Pinocchio's ankle frames)."""
    from gdimitate.assess.metrics import foot_distance

    h, m, _ = walk
    turned = turn_motion(m, np.radians(-137), m.q[0, :2])
    d = foot_distance(h, m)
    np.testing.assert_allclose(foot_distance(h, turned), d, atol=1e-9)
    legs = [h.legs[s].ankle for s in SIDES]
    p = frame_placements(h, turned.q, legs)
    travel = turned.q[-1, :2] - turned.q[0, :2]
    e = travel / np.linalg.norm(travel)
    diff = p[legs[0]].translation[:, :2] - p[legs[1]].translation[:, :2]
    np.testing.assert_allclose(diff @ e, d, atol=1e-9)
    assert np.ptp(d) > 0.8  # the feet pass each other: ±0.4–0.7 m on this walk


def test_clock_scaling_keeps_the_path_and_scales_durations(walk):
    """Froude's clock: the same configurations at times t0 + s·(t − t0), velocities ÷ s."""
    h, m, f = walk
    m = m.replace(v=np.ones((m.T, h.model.nv)))
    m2, f2 = on_clock(m, 0.8), forces_on_clock(f, 0.8)
    np.testing.assert_allclose(m2.t - m2.t[0], 0.8 * (m.t - m.t[0]), atol=1e-12)
    np.testing.assert_array_equal(m2.q, m.q)
    np.testing.assert_allclose(m2.v, m.v / 0.8)
    np.testing.assert_allclose(f2.t - f2.t[0], 0.8 * (f.t - f.t[0]), atol=1e-12)


def test_only_a_free_flyer_turns(robot):
    """A base that cannot turn is refused (unless the turn is none); so is a NaN yaw."""
    r = robot("g1")
    m = gd.Motion(np.arange(3) * 0.1, r.joint_names, np.tile(r.neutral, (3, 1)),
                  base_nq=7, joint_nq=tuple(int(r.model.joints[j].nq)
                                            for j in range(1, r.model.njoints)))
    with pytest.raises(InvalidInputError, match="finite"):
        turn_motion(m, float("nan"))
    fixed = m.replace(base_nq=0)
    assert turn_motion(fixed, 0.0) is fixed
    with pytest.raises(InvalidInputError, match="free-flyer"):
        turn_motion(fixed, 0.5)


def _turned_back(q: np.ndarray, yaw: float) -> np.ndarray:
    out = q.copy()
    out[:, :3] = turn_points(q[:, :3], -yaw)
    Q = pin.Quaternion(yaw_matrix(-yaw))
    for i in range(len(q)):
        out[i, 3:7] = (Q * pin.Quaternion(q[i, 3:7])).coeffs()
    return out


@pytest.mark.slow
def test_the_adaptor_does_not_care_which_way_the_subject_walked(g1_stride, robot):
    """One stride of the shipped walk → G1 (measured push) as recorded and turned by 90°,
    180° and −137° about the vertical: the same iterations, joint angles within 1e-4 rad, the
    base equal to the turned one within 1e-4 m (orientation within 1e-4 in quaternion
    entries), the same audit verdict. Before the problem was written in the heading frame the
    turns ran out of their 150 iterations, audit-infeasible (torques, cones, slip)."""
    h, stride, fs, ref = g1_stride
    g1 = robot("g1")
    assert ref.audit.feasible
    for yaw in (np.pi / 2, np.pi, np.radians(-137)):
        r = gd.adapt(turn_motion(stride, yaw, stride.q[0, :2]), h, g1, force="measured",
                     forces=turn_forces(fs, yaw, stride.q[0, :2]), verbose=False)
        assert abs(r.solver.iterations - ref.solver.iterations) <= 2
        assert r.audit.feasible == ref.audit.feasible
        back = _turned_back(r.motion.q, yaw)
        np.testing.assert_allclose(back[:, 7:], ref.motion.q[:, 7:], atol=1e-4)
        np.testing.assert_allclose(back[:, :3], ref.motion.q[:, :3], atol=1e-4)
        sign = np.sign(back[:, 3:7] @ ref.motion.q[:, 3:7].T).diagonal()[:, None]
        np.testing.assert_allclose(sign * back[:, 3:7], ref.motion.q[:, 3:7], atol=1e-4)
        # the motion heads where the demonstrator heads
        d = r.motion.q[-1, :2] - r.motion.q[0, :2]
        assert _wrap(np.arctan2(d[1], d[0]) - walk_heading(h, stride) - yaw) == \
            pytest.approx(0, abs=np.radians(5))


@pytest.mark.slow
def test_a_stream_does_not_care_which_way_the_subject_walked(walk, robot):
    """The streaming adaptor (per frame, measured push) on one stride → G1, as recorded and
    turned by 90° and −137°: the same frames up to that turn (joints within 1e-9 rad, the
    base within 1e-9 m) and the same per-frame verdicts. Before the stream was adapted in
    its first frame's heading, the 90° turn changed the joints by up to 0.82 rad and a 180°
    turn moved the base by 0.41 m."""
    h, m, f = walk
    stride, fs = gd.gait.one_stride(m, f)
    g1 = robot("g1")
    ref = gd.adapt(stride, h, g1, force="measured", forces=fs, mode="per_frame",
                   verbose=False)
    about = stride.q[0, :2]
    for yaw in (np.pi / 2, np.radians(-137)):
        r = gd.adapt(turn_motion(stride, yaw, about), h, g1, force="measured",
                     forces=turn_forces(fs, yaw, about), mode="per_frame", verbose=False)
        back = r.motion.q.copy()
        back[:, :3] = turn_points(back[:, :3], -yaw, about)
        back[:, 3:7] = _turned_back(r.motion.q, yaw)[:, 3:7]
        np.testing.assert_allclose(back[:, 7:], ref.motion.q[:, 7:], atol=1e-9)
        np.testing.assert_allclose(back[:, :3], ref.motion.q[:, :3], atol=1e-9)
        sign = np.sign(np.einsum("ij,ij->i", back[:, 3:7], ref.motion.q[:, 3:7]))[:, None]
        np.testing.assert_allclose(sign * back[:, 3:7], ref.motion.q[:, 3:7], atol=1e-9)
        np.testing.assert_array_equal(r.frame_feasible, ref.frame_feasible)
