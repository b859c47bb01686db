"""Exports, each read back and checked against an independent reference: CSV columns against
the motion's own q by name, NPZ (q, v, a, wrenches, robot), MuJoCo qpos loaded into MuJoCo
(body positions vs Pinocchio to 1e-9), and the LAFAN1 retargeted CSV read the way BeyondMimic's
``csv_to_npz.py`` reads it (G1's published joint order, xyzw quaternion)."""

from __future__ import annotations

import csv
import dataclasses
import functools

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

from gdimitate import Robot, adapt
from gdimitate.demonstration import load_demonstration
from gdimitate.errors import ExportError, FileFormatError
from gdimitate.export import (
    BASE_COLUMNS,
    FORMATS,
    export_motion,
    read_csv,
    read_lafan1_csv,
    read_mujoco,
    read_wrenches,
)
from gdimitate.gait import human_walk
from gdimitate.motion import Motion, differentiate
from gdimitate.sim import build_model

#: The 29 joint columns of a Unitree G1 row in unitreerobotics/LAFAN1_Retargeting_Dataset (its
#: README; the order BeyondMimic's whole_body_tracking and mjlab read), after x y z qx qy qz qw.
G1_CSV_JOINTS = [f"{s}_{j}_joint" for s in ("left", "right") for j in
                 ("hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll")]
G1_CSV_JOINTS += ["waist_yaw_joint", "waist_roll_joint", "waist_pitch_joint"]
G1_CSV_JOINTS += [f"{s}_{j}_joint" for s in ("left", "right") for j in
                  ("shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow", "wrist_roll",
                   "wrist_pitch", "wrist_yaw")]


@functools.cache
def _hoap_walk():
    human, walk = human_walk()
    hoap = Robot.load("hoap2")
    return hoap, adapt(walk, human, hoap, "analytic")


@functools.cache
def _g1_motion(T: int = 61, rate: float = 60.0):
    """G1 free-flyer motion: every joint swinging within its limits, the base translating and
    turning about a tilted axis (so every quaternion component moves)."""
    g1 = Robot.load("g1")
    m = g1.model
    t = np.arange(T) / rate
    q = np.tile(g1.neutral, (T, 1))
    for k, j in enumerate(g1.joint_names[1:]):
        i = g1.idx_q(j)
        lo, hi = m.lowerPositionLimit[i], m.upperPositionLimit[i]
        q[:, i] = 0.5 * (lo + hi) + 0.3 * (hi - lo) * np.sin(2 * np.pi * 0.8 * t + k)
    q[:, 0] = 0.9 * t
    q[:, 1] = 0.05 * np.sin(2 * np.pi * t)
    axis = np.array([0.2, 0.3, 1.0]) / np.linalg.norm([0.2, 0.3, 1.0])
    for k, tk in enumerate(t):
        R = pin.exp3(axis * 0.8 * np.sin(2 * np.pi * 0.5 * tk)) @ g1.base_rotation
        q[k, 3:7] = pin.Quaternion(R).coeffs()
    nq = tuple(m.joints[j].nq for j in range(1, m.njoints))
    motion = Motion(t, g1.joint_names, q, {"left": t < 0.5, "right": t >= 0.3}, 7, nq)
    return g1, differentiate(m, motion)


def test_unknown_format_and_wrong_robot(tmp_path):
    hoap, res = _hoap_walk()
    with pytest.raises(ExportError) as e:
        export_motion(hoap, res.motion, tmp_path / "x", "bvh")
    assert all(k in str(e.value) for k in FORMATS)
    with pytest.raises(ExportError, match="free-floating base"):
        export_motion(hoap, res.motion, tmp_path / "x.csv", "lafan1_csv")  # planar base


def test_csv_round_trip_and_columns(tmp_path):
    hoap, res = _hoap_walk()
    p = res.save(tmp_path / "walk.csv", "csv")
    with open(p) as f:
        rows = list(csv.reader(f))
    head = rows[0]
    assert head[:8] == ["time", *BASE_COLUMNS]
    data = np.array(rows[1:], dtype=float)
    for j in ("left_hip", "right_knee", "left_ankle"):  # every joint, by name
        assert np.array_equal(data[:, head.index(j)], res.motion.column(j))
    # the planar base as a 3-D pose: (x, 0, z) and a rotation about y by the pitch
    m = res.motion
    assert np.allclose(data[:, head.index("base_x")], m.column("base_x"), atol=1e-12)
    assert np.allclose(data[:, head.index("base_y")], 0.0, atol=1e-12)
    assert np.allclose(data[:, head.index("base_z")], m.column("base_z"), atol=1e-12)
    quat = data[:, [head.index(c) for c in BASE_COLUMNS[3:]]]
    R = Rotation.from_quat(quat).as_matrix()  # scipy: scalar-last (x, y, z, w)
    pitch = -m.column("base_pitch")  # our planar pitch turns about −y (URDF axis 0 −1 0)
    Ry = Rotation.from_euler("y", pitch[:, None]).as_matrix()
    assert np.allclose(R, Ry, atol=1e-12)
    back = read_csv(p, hoap)
    assert np.max(np.abs(back.q - m.q)) < 1e-12 and np.array_equal(back.t, m.t)
    # a free-flyer: base columns are q[:, :7] (same sign), then every joint
    g1, gm = _g1_motion()
    p = export_motion(g1, gm, tmp_path / "g1.csv", "csv")
    back = read_csv(p, g1)
    assert np.max(np.abs(back.q - gm.q)) < 1e-12
    with pytest.raises(FileFormatError, match="columns do not match"):
        read_csv(p, hoap)


def test_npz_holds_q_v_a_wrenches_and_robot(tmp_path):
    hoap, res = _hoap_walk()
    motion = differentiate(hoap.model, res.motion)
    rng = np.random.default_rng(0)
    wrenches = {s: rng.normal(size=(motion.T, 6)) for s in ("left", "right")}
    full = dataclasses.replace(res, motion=motion, wrenches=wrenches)
    p = full.save(tmp_path / "walk_out", "npz")  # no suffix: written exactly there
    assert p == tmp_path / "walk_out" and p.is_file()
    d = load_demonstration(p.rename(tmp_path / "walk_out.npz"))  # robot from the file
    assert d.robot.name == "hoap2" and d.robot.fingerprint == hoap.fingerprint
    for k in ("q", "v", "a"):
        assert np.array_equal(getattr(d.motion, k), getattr(motion, k))
    w = read_wrenches(tmp_path / "walk_out.npz")
    assert all(np.array_equal(w[s], wrenches[s]) for s in wrenches)
    with np.load(tmp_path / "walk_out.npz") as z:
        assert str(z["wrench_frame_left"]) == hoap.contacts["left"].frame
    with pytest.raises(ExportError, match="shape"):
        export_motion(hoap, motion, tmp_path / "bad.npz", "npz",
                      wrenches={"left": np.zeros((3, 6)), "right": np.zeros((3, 6))})


@pytest.mark.parametrize("which", ["hoap2", "g1"])
def test_mujoco_qpos_reproduces_pinocchio_body_positions(tmp_path, which):
    if which == "g1":
        robot, motion = _g1_motion()
    else:
        robot, res = _hoap_walk()
        motion = differentiate(robot.model, res.motion)
    p = export_motion(robot, motion, tmp_path / "m.npz", "mujoco")
    exp = read_mujoco(p)
    assert exp.qpos.shape[0] == motion.T and exp.qvel is not None
    # the model gdimitate.sim builds: body poses equal Pinocchio's to 1e-9
    assert _worst_body_error(build_model(robot).mj, exp.qpos, robot, motion) < 1e-9
    # the MJCF text in the file (no gdimitate needed to play it): MuJoCo's XML writer rounds
    # orientations to 6 significant digits, so 1e-5 here
    mj = mujoco.MjModel.from_xml_string(exp.mjcf)
    assert tuple(mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_JOINT, i)
                 for i in range(mj.njnt)) == exp.joint_names
    assert _worst_body_error(mj, exp.qpos, robot, motion) < 1e-5
    # MuJoCo's quaternion convention: w first, unit norm
    if which == "g1":
        assert np.allclose(exp.qpos[:, 3:7], motion.q[:, [6, 3, 4, 5]], atol=1e-12) or \
            np.allclose(exp.qpos[:, 3:7], -motion.q[:, [6, 3, 4, 5]], atol=1e-12)


def _worst_body_error(mj, qpos, robot, motion) -> float:
    """Largest |MuJoCo − Pinocchio| of body positions [m] and rotation-matrix entries over
    every 7th frame (bodies named after the Pinocchio joints; the planar base's massless links
    are merged into one MuJoCo body)."""
    data = mujoco.MjData(mj)
    m, pd = robot.model, robot.model.createData()
    bodies = [(j, mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, m.names[j]))
              for j in range(1, m.njoints)]
    bodies = [(j, b) for j, b in bodies if b >= 0]
    assert len(bodies) >= m.njoints - 3
    worst = 0.0
    for k in range(0, motion.T, 7):
        data.qpos[:] = qpos[k]
        mujoco.mj_kinematics(mj, data)
        pin.forwardKinematics(m, pd, motion.q[k])
        for j, b in bodies:
            worst = max(worst, float(np.abs(data.xpos[b] - pd.oMi[j].translation).max()))
            R = np.asarray(data.xmat[b]).reshape(3, 3)
            worst = max(worst, float(np.abs(R - pd.oMi[j].rotation).max()))
    return worst


def test_lafan1_csv_as_beyondmimic_reads_it(tmp_path):
    g1, motion = _g1_motion()  # 60 Hz
    p = export_motion(g1, motion, tmp_path / "walk.csv", "lafan1_csv")  # 30 Hz by default
    raw = np.loadtxt(p, delimiter=",")  # their loader: no header, comma-separated
    assert raw.shape == (31, 7 + 29)
    assert list(g1.joint_names[1:]) == G1_CSV_JOINTS  # our columns are the dataset's order
    src = motion.q[::2]  # 30 Hz rows = every other 60 Hz frame
    assert np.max(np.abs(raw[:, :3] - src[:, :3])) < 1e-12
    assert np.max(np.abs(raw[:, 7:] - src[:, 7:])) < 1e-12
    # the quaternion is (x, y, z, w): reordered [3, 0, 1, 2] it is w-first, and it is the base
    # link's orientation
    wxyz = raw[:, 3:7][:, [3, 0, 1, 2]]
    for k in range(0, 31, 5):
        R = Rotation.from_quat(wxyz[k], scalar_first=True).as_matrix()
        pd = g1.model.createData()
        pin.forwardKinematics(g1.model, pd, src[k])
        assert np.allclose(R, pd.oMi[1].rotation, atol=1e-12)
    back = read_lafan1_csv(p, g1)
    assert np.allclose(back.t, motion.t[::2]) and np.max(np.abs(back.q - src)) < 1e-12
    # resampling between frames: halfway in time = halfway in angle (slerp), joints linear
    p = export_motion(g1, motion, tmp_path / "w40.csv", "lafan1_csv", fps=120.0)
    r = np.loadtxt(p, delimiter=",")
    qa, qb = (pin.Quaternion(*motion.q[k, [6, 3, 4, 5]]) for k in (10, 11))
    mid = pin.Quaternion(*r[21, [6, 3, 4, 5]])
    assert mid.angularDistance(qa) == pytest.approx(mid.angularDistance(qb), abs=1e-9)
    assert np.allclose(r[21, 7:], 0.5 * (motion.q[10, 7:] + motion.q[11, 7:]), atol=1e-12)
