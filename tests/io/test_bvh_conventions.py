"""A BVH clip rewritten in other conventions reads back as the same walk (issue 32).

``tests.helpers.bvh.rewrite_bvh`` writes a clip with every joint's rotation channels in
another order, in another unit, turned about the vertical and cut to a window; the corpus
benchmark's SFU-style clip (XYZ channels, inches, walking along −y, 2.2 s at 120 Hz) is the
shipped CMU walk rewritten so. The reference is independent of the writer and of the reader:
``tests/io/test_bvh.py``'s few-line BVH reader and forward kinematics on the original file's
numbers, turned here by the yaw with numpy. What the reader makes of the new file (Pinocchio's
frames, the contact schedule, the heading) must be that walk turned.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.io.bvh import parse_bvh, read_bvh
from gdimitate.io.demonstration import load_demonstration
from gdimitate.model.heading import walk_heading, yaw_matrix
from tests.helpers.bvh import CMU_BVH, SFU_STYLE, rewrite_bvh, root_heading, write_sfu_style
from tests.io.test_bvh import C_Y, C_Z, make_case, reference_fk, tiny_reader

CMU_SCALE = 0.056444  # m per CMU unit (the clip's README)
INCH = 0.0254
EXACT_TOL = 1e-9  # m, rad: every digit written
SFU_TOL = 1e-6  # m, rad: 6 decimals of inches and degrees (≤ 1.3e-8 m, 8.7e-9 rad a number)


def frame_poses(robot, motion, names):
    """{name: (p (T, 3), R (T, 3, 3))} of the Pinocchio frames ``names`` on every frame."""
    m, d = robot.model, robot.data
    ids = {n: m.getFrameId(n) for n in names}
    assert all(m.frames[f].name == n for n, f in ids.items())
    out = {n: (np.empty((motion.T, 3)), np.empty((motion.T, 3, 3))) for n in names}
    for k, q in enumerate(motion.q):
        pin.framesForwardKinematics(m, d, q)
        for n, f in ids.items():
            out[n][0][k] = d.oMf[f].translation
            out[n][1][k] = d.oMf[f].rotation
    return out


def turned_reference(joints, values, C, scale, yaw):
    """reference_fk of the original numbers in our world [m] (x_ours = scale · C · x_file),
    turned by ``yaw`` about the vertical through the root's first position: {name: (p, R)}
    with R as the reader's frames carry it (C · R_file, the root's C · R_file · Cᵀ)."""
    ref = reference_fk(joints, values)
    root = joints[0][0]
    Y = yaw_matrix(yaw)
    about = scale * C @ ref[root][0][0]
    about[2] = 0.0
    out = {}
    for n, (p, R) in ref.items():
        pw = (scale * p @ C.T - about) @ Y.T + about
        Rw = Y @ C @ R @ (C.T if n == root else np.eye(3))
        out[n] = (pw, Rw)
    return out


def assert_same_poses(got, want, tol):
    worst_p = max(np.abs(got[n][0] - want[n][0]).max() for n in want)
    worst_R = max(np.abs(got[n][1] - want[n][1]).max() for n in want)
    assert worst_p < tol and worst_R < tol, (worst_p, worst_R)
    return worst_p, worst_R


def window(values, dt, first):
    """The frame indices of the SFU-style window: 2.2 s around the motion's middle."""
    mid = (first + values.shape[0] - 1) / 2
    k0 = int(round(mid - SFU_STYLE["duration"] / 2 / dt))
    return k0, k0 + int(round(SFU_STYLE["duration"] / dt)) + 1


def test_sfu_style_clip_is_the_cmu_walk_turned(tmp_path):
    """The benchmark's SFU-style file: its conventions as declared, and every joint and End
    Site where the CMU walk's is, turned to walk along −y, within 1e-6 m (the file's 6
    decimals; the same file with every digit: 1e-9 m)."""
    path = write_sfu_style(tmp_path / "sfu_style.bvh")
    bvh = parse_bvh(path)
    assert bvh.joints[0].channels == ("Xposition", "Yposition", "Zposition", "Xrotation",
                                      "Yrotation", "Zrotation")
    assert all(j.channels == ("Xrotation", "Yrotation", "Zrotation") for j in bvh.joints[1:])
    assert {"LeftUpLeg", "LeftLeg", "LeftFoot", "RightUpLeg"} <= {j.name for j in bvh.joints}
    joints, values, dt = tiny_reader(CMU_BVH)
    assert bvh.frame_time == dt == pytest.approx(1 / 120, rel=1e-4)
    k0, k1 = window(values, dt, first=1)  # frame 0 of the CMU file is a T-pose
    assert bvh.frames.shape[0] == k1 - k0 == 265  # 2.2 s at 120 Hz
    # the CMU clip's own heading over the window, and the turn that makes it −y
    yaw = -np.pi / 2 - root_heading(parse_bvh(CMU_BVH), values[k0:k1])
    assert abs(np.degrees(yaw) + 90) < 2  # the CMU subject walks along +x (BVH +Z)

    robot, motion = read_bvh(path, ground=False)
    info = robot.bvh_info
    assert info.unit == "inches" and info.scale == INCH and not info.skipped_first_frame
    assert motion.T == 265 and motion.t[-1] == pytest.approx(264 * dt, abs=1e-12)
    want = turned_reference(joints, values[k0:k1], C_Y, CMU_SCALE, yaw)
    assert_same_poses(frame_poses(robot, motion, want), want, SFU_TOL)
    assert abs(walk_heading(robot, motion) + np.pi / 2) < SFU_TOL

    exact = rewrite_bvh(parse_bvh(CMU_BVH), tmp_path / "exact.bvh",
                        start=k0 * dt, **{**SFU_STYLE, "decimals": None})
    robot, motion = read_bvh(exact, ground=False)
    assert_same_poses(frame_poses(robot, motion, want), want, EXACT_TOL)
    assert abs(walk_heading(robot, motion) + np.pi / 2) < EXACT_TOL


def test_sfu_style_contacts_and_heading_through_load_demonstration(tmp_path):
    """What the adaptor is given (``load_demonstration``, the command line's reader): the
    SFU-style file and the CMU file merely cut to the same window (its own channels, units
    and heading; the numbers copied) have the same floor, the same contact schedule frame
    for frame, and the same grounded joint positions up to the turn; the heading found is −y,
    the cut file's is the CMU walk's."""
    sfu = load_demonstration(write_sfu_style(tmp_path / "sfu_style.bvh"))
    joints, values, dt = tiny_reader(CMU_BVH)
    k0, k1 = window(values, dt, first=1)
    cut = rewrite_bvh(parse_bvh(CMU_BVH), tmp_path / "cut.bvh", order=None, unit=CMU_SCALE,
                      start=k0 * dt, duration=SFU_STYLE["duration"])
    assert np.array_equal(parse_bvh(cut).frames, values[k0:k1])  # the numbers as written
    ref = load_demonstration(cut)
    assert ref.robot.bvh_info.unit.startswith("CMU") and sfu.robot.bvh_info.unit == "inches"
    assert sfu.motion.T == ref.motion.T == 265
    assert sfu.robot.bvh_info.floor == pytest.approx(ref.robot.bvh_info.floor, abs=SFU_TOL)
    for side in ("left", "right"):
        a, b = sfu.motion.contact[side], ref.motion.contact[side]
        assert np.array_equal(a, b), f"{side}: frames {np.flatnonzero(a != b)} differ"
        assert a.any() and not a.all()  # a walk: each foot lands and swings
    psi = walk_heading(ref.robot, ref.motion)
    assert abs(walk_heading(sfu.robot, sfu.motion) + np.pi / 2) < SFU_TOL
    assert abs(psi) < np.radians(2)
    names = [j[0] for j in joints] + ["LeftToeBase_end", "RightToeBase_end"]
    got = frame_poses(sfu.robot, sfu.motion, names)
    base = frame_poses(ref.robot, ref.motion, names)
    Y = yaw_matrix(-np.pi / 2 - psi)
    about = np.r_[ref.motion.q[0, :2], 0.0]
    want = {n: ((p - about) @ Y.T + about, Y @ R) for n, (p, R) in base.items()}
    assert_same_poses(got, want, SFU_TOL)


@pytest.mark.parametrize("key,order,unit,yaw_deg", [
    ("cmu_units_mixed_orders_100Hz_knee1", "XYZ", "inches", -90.0),
    ("mm_mixamo_prefix_positions_on_a_joint", "YZX", "m", 137.0),
    ("m_z_up", "ZXY", "cm", 30.0),
])
def test_rewrite_any_skeleton(tmp_path, key, order, unit, yaw_deg):
    """The writer on the reader tests' synthetic skeletons (mixed rotation orders, a
    one-channel knee, position channels on a joint, a Z-up file, a yaw written wrapped
    across ±180°): the rewritten file, cut to frames 5–35, is the original's forward
    kinematics turned, to 1e-9 m."""
    path, joints, values, _, scale, dt, up = make_case(tmp_path, key)
    new = rewrite_bvh(parse_bvh(path), tmp_path / "new.bvh", order=order, unit=unit,
                      scale=scale, yaw=np.radians(yaw_deg), start=5 * dt, duration=30 * dt,
                      up=up)
    robot, motion = read_bvh(new, up=up, ground=False)
    assert motion.T == 31
    C = C_Z if up == "z" else C_Y
    want = turned_reference(joints, values[5:36], C, scale, np.radians(yaw_deg))
    assert_same_poses(frame_poses(robot, motion, want), want, EXACT_TOL)
    assert {"".join(c[0] for c in j.channels if c.endswith("rotation"))
            for j in parse_bvh(new).joints} == {order}
