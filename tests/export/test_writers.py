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
from gdimitate.errors import ExportError, FileFormatError
from gdimitate.export.writers import (
    BASE_COLUMNS,
    FORMATS,
    export_motion,
    read_csv,
    read_lafan1_csv,
    read_mujoco,
    read_wrenches,
)
from gdimitate.io.demonstration import load_demonstration
from gdimitate.io.gait import human_walk
from gdimitate.model.motion import Motion, differentiate
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


def _rnea_torques(robot: Robot, motion: Motion, wrenches: dict) -> np.ndarray:
    """The actuated joints' torques ``(T, nv − base)``: Pinocchio's RNEA with each sole wrench
    applied as an external force on its frame's parent joint (an independent route from the
    exporter's ``rnea − Σ Jᵀw``)."""
    m, d = robot.model, robot.model.createData()
    frames = {s: m.frames[m.getFrameId(robot.contacts[s].frame)] for s in wrenches}
    out = []
    for k in range(motion.T):
        fext = [pin.Force.Zero() for _ in range(m.njoints)]
        for s, fr in frames.items():
            fext[fr.parentJoint] = fext[fr.parentJoint] + fr.placement.act(
                pin.Force(wrenches[s][k]))
        out.append(pin.rnea(m, d, motion.q[k], motion.v[k], motion.a[k], fext).copy())
    return np.array(out)[:, {"free": 6, "planar": 3}.get(robot.base, 0):]


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
        # the joint torques the wrenches imply (issue 36): Pinocchio's RNEA with external forces
        np.testing.assert_allclose(z["joint_torque"], _rnea_torques(hoap, motion, wrenches),
                                   rtol=0, atol=1e-9)
        assert list(z["joint_torque_names"]) == [
            n for n in hoap.joint_names if hoap.model.joints[hoap.model.getJointId(n)].idx_v
            >= {"free": 6, "planar": 3}.get(hoap.base, 0)]
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


# ---------------------------------------------------------------------- gmr, isaaclab_amp
def _fk(robot, q, ids):
    """Pinocchio's world placements of frames ``ids`` at each q: positions (N, B, 3),
    rotations (N, B, 3, 3)."""
    m, d = robot.model, robot.model.createData()
    p = np.empty((len(q), len(ids), 3))
    R = np.empty((len(q), len(ids), 3, 3))
    for k, qk in enumerate(q):
        pin.framesForwardKinematics(m, d, qk)
        for b, i in enumerate(ids):
            p[k, b], R[k, b] = d.oMf[i].translation, d.oMf[i].rotation
    return p, R


def test_gmr_pickle_round_trip_and_body_positions(tmp_path):
    """The GMR pickle read with plain pickle: its keys and shapes; root_rot x y z w; every
    local_body_pos equals Pinocchio's forward kinematics of the file's own root and dof_pos
    (1e-9 m), in the root frame; at the motion's own rate the frames are the motion's; bodies
    depth-first, as MuJoCo numbers the bodies of the model gdimitate.sim builds."""
    import pickle

    from gdimitate.export.writers import body_links, read_gmr

    g1, motion = _g1_motion()
    p = export_motion(g1, motion, tmp_path / "walk.pkl", "gmr", fps=60.0)
    with open(p, "rb") as f:
        d = pickle.load(f)
    assert {"fps", "root_pos", "root_rot", "dof_pos", "local_body_pos",
            "link_body_list"} <= set(d)
    N, B = motion.T, len(d["link_body_list"])
    assert d["fps"] == 60.0 and d["root_pos"].shape == (N, 3) and d["dof_pos"].shape == (N, 29)
    assert d["local_body_pos"].shape == (N, B, 3) and d["body_order"] == "depth"
    np.testing.assert_allclose(d["root_pos"], motion.q[:, :3], atol=1e-12)
    np.testing.assert_allclose(np.abs(np.sum(d["root_rot"] * motion.q[:, 3:7], axis=1)), 1.0,
                               atol=1e-12)  # x y z w, as Pinocchio's q
    assert list(d["dof_pos"][0]) == [motion.q[0, g1.idx_q(j)] for j in G1_CSV_JOINTS]
    back = read_gmr(p, g1)
    np.testing.assert_allclose(back.q, motion.q, atol=1e-12)
    links = body_links(g1, "depth")
    assert d["link_body_list"] == [n for n, _ in links]
    pw, _ = _fk(g1, back.q, [i for _, i in links])
    for k in range(N):
        root = pin.XYZQUATToSE3(back.q[k, :7])
        local = (pw[k] - root.translation) @ root.rotation
        np.testing.assert_allclose(d["local_body_pos"][k], local, atol=1e-9)
    sim = build_model(g1)
    mj_bodies = [mujoco.mj_id2name(sim.mj, mujoco.mjtObj.mjOBJ_BODY, i)
                 for i in range(1, sim.mj.nbody)]
    m = g1.model
    assert [m.names[m.frames[i].parentJoint] for _, i in links] == mj_bodies


def test_isaaclab_amp_npz_round_trip_body_order_and_velocities(tmp_path):
    """Isaac Lab's AMP motion NPZ: its keys; body positions and rotations (w x y z) equal
    Pinocchio's forward kinematics of the file's own root body pose and dof_positions (1e-9)
    and MuJoCo's (1e-9); bodies breadth-first by default (each body's depth in the tree never
    decreases), depth-first on request; velocities equal central differences of the
    positions (O(h²) at 60 Hz); read back to the motion's q."""
    from gdimitate.export.writers import body_links, read_isaaclab_amp

    g1, motion = _g1_motion()
    p = export_motion(g1, motion, tmp_path / "walk.npz", "isaaclab_amp", fps=60)
    z = np.load(p)
    keys = {"fps", "dof_names", "body_names", "dof_positions", "dof_velocities",
            "body_positions", "body_rotations", "body_linear_velocities",
            "body_angular_velocities"}
    assert keys <= set(z.files) and z["fps"].dtype == np.int64 and int(z["fps"]) == 60
    assert str(z["body_order"]) == "breadth"
    links = body_links(g1, "breadth")
    assert [str(n) for n in z["body_names"]] == [n for n, _ in links]
    m = g1.model
    depth = []
    for _, i in links:
        j, n = m.frames[i].parentJoint, 0
        while j > 0:
            j, n = m.parents[j], n + 1
        depth.append(n)
    assert depth == sorted(depth) and depth[0] == 1
    back = read_isaaclab_amp(p, g1)
    np.testing.assert_allclose(back.q, motion.q, atol=1e-12)
    pw, Rw = _fk(g1, back.q, [i for _, i in links])
    np.testing.assert_allclose(z["body_positions"], pw, atol=1e-9)
    R_file = np.array([[pin.Quaternion(w[0], w[1], w[2], w[3]).matrix() for w in wk]
                       for wk in z["body_rotations"]])  # Quaternion(w, x, y, z)
    np.testing.assert_allclose(R_file, Rw, atol=1e-9)
    # MuJoCo's own kinematics of the same poses (an independent forward kinematics)
    sim = build_model(g1)
    data = mujoco.MjData(sim.mj)
    ids = [mujoco.mj_name2id(sim.mj, mujoco.mjtObj.mjOBJ_BODY, m.names[m.frames[i].parentJoint])
           for _, i in links]
    for k in range(0, motion.T, 10):
        data.qpos[:] = sim.qpos_from_q(back.q[k])
        mujoco.mj_kinematics(sim.mj, data)
        np.testing.assert_allclose(data.xpos[ids], z["body_positions"][k], atol=1e-9)
    # velocities: central differences of positions (interior frames)
    h = 1 / 60
    fd = (z["body_positions"][2:] - z["body_positions"][:-2]) / (2 * h)
    err = np.abs(fd - z["body_linear_velocities"][1:-1]).max()
    assert err < 0.02 * np.abs(fd).max(), err
    dof = [str(n) for n in z["dof_names"]]
    assert dof == list(g1.joint_names[1:])
    fdq = (z["dof_positions"][2:] - z["dof_positions"][:-2]) / (2 * h)
    np.testing.assert_allclose(z["dof_velocities"][1:-1], fdq, atol=1e-9)
    # the other order on request: same bodies, depth-first
    p2 = export_motion(g1, motion, tmp_path / "walk_d.npz", "isaaclab_amp", fps=60,
                       body_order="depth")
    z2 = np.load(p2)
    assert [str(n) for n in z2["body_names"]] == [n for n, _ in body_links(g1, "depth")]
    assert sorted(z2["body_names"]) == sorted(z["body_names"])
    with pytest.raises(ExportError, match="body_order"):
        export_motion(g1, motion, tmp_path / "x.npz", "isaaclab_amp", body_order="random")
    with pytest.raises(ExportError, match="integer"):
        export_motion(g1, motion, tmp_path / "x.npz", "isaaclab_amp", fps=29.97)


def test_cli_exports_gmr_and_isaaclab_amp(tmp_path):
    from gdimitate.apps.cli import main
    from gdimitate.export.writers import read_gmr

    g1, motion = _g1_motion()
    npz = tmp_path / "g1.npz"
    export_motion(g1, motion, npz, "npz")
    assert main(["export", str(npz), "--format", "gmr", "--fps", "60"]) == 0
    back = read_gmr(tmp_path / "g1.gmr.pkl", g1)
    np.testing.assert_allclose(back.q, motion.q, atol=1e-12)
    assert main(["export", str(npz), "--format", "isaaclab_amp", "--body-order", "depth",
                 "--out", str(tmp_path / "a.npz")]) == 0
    assert str(np.load(tmp_path / "a.npz")["body_order"]) == "depth"
    from gdimitate.export.writers import read_beyondmimic_npz

    assert main(["export", str(npz), "--format", "beyondmimic_npz", "--fps", "60"]) == 0
    bm = read_beyondmimic_npz(tmp_path / "g1.beyondmimic.npz")
    np.testing.assert_allclose(bm.joint_pos, motion.q[:, 7:], atol=1e-12)


def test_beyondmimic_npz_keys_and_bodies_match_pinocchio(tmp_path):
    """BeyondMimic's motion NPZ (the file its whole_body_tracking, mjlab and holosoma train
    from; made elsewhere by replaying a CSV through Isaac Sim): its keys, shapes and dtypes;
    quaternions w, x, y, z; every MuJoCo body's world position, rotation and the velocity of
    its frame origin equal Pinocchio's kinematics of the same links (another engine, 1e-9);
    the joints in MuJoCo's order equal the motion's resampled joint angles; and the contact
    wrenches we computed ride along under documented names."""
    import mujoco

    from gdimitate.export.writers import read_beyondmimic_npz
    from gdimitate.sim import build_model

    g1, motion = _g1_motion()
    wrenches = {s: np.tile(np.arange(6.0), (motion.T, 1)) for s in ("left", "right")}
    p = export_motion(g1, motion, tmp_path / "walk.npz", "beyondmimic_npz", fps=60,
                      wrenches=wrenches)
    z = np.load(p)
    N, J = motion.T, len(g1.joint_names) - 1
    mj = build_model(g1).mj
    B = mj.nbody - 1
    shapes = {"fps": (1,), "joint_pos": (N, J), "joint_vel": (N, J), "body_pos_w": (N, B, 3),
              "body_quat_w": (N, B, 4), "body_lin_vel_w": (N, B, 3),
              "body_ang_vel_w": (N, B, 3), "contact_wrench_left": (N, 6)}
    for k, shape in shapes.items():
        assert z[k].shape == shape and z[k].dtype == np.float64, k
    assert float(z["fps"][0]) == 60.0 and str(z["contact_frame_left"]) == \
        g1.contacts["left"].frame
    np.testing.assert_allclose(z["contact_wrench_right"], wrenches["right"], atol=1e-12)
    back = read_beyondmimic_npz(p)
    # the joint torques the wrenches imply, each column under its joint_names entry (60 Hz:
    # the motion's own frames, so no interpolation)
    tau = _rnea_torques(g1, motion, wrenches)
    cols = [g1.model.joints[g1.model.getJointId(str(n))].idx_v - 6 for n in z["joint_names"]]
    assert z["joint_torque"].shape == (N, J) and z["joint_torque"].dtype == np.float64
    np.testing.assert_allclose(z["joint_torque"], tau[:, cols], rtol=0, atol=1e-9)
    names = list(back.body_names)
    assert names == [mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(1, B + 1)]
    assert list(back.joint_names) == list(g1.joint_names[1:])  # MuJoCo's order is the URDF's
    np.testing.assert_allclose(back.joint_pos, motion.q[:, 7:], atol=1e-12)
    m, d = g1.model, g1.model.createData()
    ids = [m.getFrameId(n) for n in names]
    from gdimitate.model.motion import differentiate

    v = differentiate(m, motion).v  # the writer's own velocities (the same 60 Hz grid)
    for k in range(N):
        pin.forwardKinematics(m, d, motion.q[k], v[k])
        pin.updateFramePlacements(m, d)
        for b, i in enumerate(ids):
            np.testing.assert_allclose(back.body_pos_w[k, b], d.oMf[i].translation, atol=1e-9)
            w = back.body_quat_w[k, b]
            np.testing.assert_allclose(pin.Quaternion(w[0], w[1], w[2], w[3]).matrix(),
                                       d.oMf[i].rotation, atol=1e-9)
            nu = pin.getFrameVelocity(m, d, i, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(back.body_lin_vel_w[k, b], nu.linear, atol=1e-9)
            np.testing.assert_allclose(back.body_ang_vel_w[k, b], nu.angular, atol=1e-9)
