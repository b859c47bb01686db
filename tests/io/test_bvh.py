"""gdimitate.io.bvh: BVH → Robot + Motion.

References: the kinematics are checked against a few-line forward kinematics written here
(offsets and per-channel rotations composed with numpy, from the skeleton and the numbers the
test itself wrote, or from this file's own tiny reader for the CMU clip); masses against de
Leva's (1996) Table 4 values typed in here; contacts against the CMU clip's documented cadence
(README: ~109 steps/min) and a synthetic clip whose stance phases are known by construction.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.errors import BVHError
from gdimitate.io.bvh import read_bvh
from tests.helpers.bvh import write_bvh

CMU = Path(gd.__file__).parent / "data" / "gait" / "cmu_02_01" / "cmu_02_01.bvh"
# x_ours = C x_bvh
C_Y = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
C_Z = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
FK_TOL = 1e-9  # m


# ----------------------------------------------------------------------------- reference FK
def rot(axis: str, deg: np.ndarray) -> np.ndarray:
    a = np.deg2rad(deg)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    m = {"X": [[o, z, z], [z, c, -s], [z, s, c]], "Y": [[c, z, s], [z, o, z], [-s, z, c]],
         "Z": [[c, -s, z], [s, c, z], [z, z, o]]}[axis]
    return np.moveaxis(np.array(m), (0, 1), (-2, -1))


def reference_fk(joints, values):
    """joints: [(name, parent, offset, channels, end_offsets)]; values (T, n) as in the file.
    Local transform = translate(offset + position channels) · Π rotations in channel order.
    Returns {name: (p (T,3), R (T,3,3))} in the file's axes and units (end sites too)."""
    T = values.shape[0]
    out, col = {}, 0
    for name, parent, offset, channels, ends in joints:
        p = np.tile(np.asarray(offset, float), (T, 1))
        R = np.tile(np.eye(3), (T, 1, 1))
        for c in channels:
            if c.endswith("position"):
                p[:, "XYZ".index(c[0])] += values[:, col]
            else:
                R = R @ rot(c[0], values[:, col])
            col += 1
        if parent is not None:
            pp, Rp = out[parent]
            p = pp + np.einsum("tij,tj->ti", Rp, p)
            R = Rp @ R
        out[name] = (p, R)
        for k, e in enumerate(ends):
            out[f"{name}_end" + (str(k + 1) if k else "")] = (
                p + np.einsum("tij,j->ti", R, np.asarray(e, float)), R)
    return out


def tiny_reader(path: Path):
    """An independent few-line BVH reader for well-formed files (the reference for the CMU
    clip): joints as reference_fk wants them, the frame values, the frame time."""
    toks = path.read_text().split()
    joints, stack, i = [], [], 0
    while toks[i] != "MOTION":
        t = toks[i]
        if t in ("ROOT", "JOINT"):
            joints.append([toks[i + 1], stack[-1] if stack else None, None, [], []])
            i += 2
        elif t == "End":
            joints[[j[0] for j in joints].index(stack[-1])][4].append(
                [float(x) for x in toks[i + 4:i + 7]])
            i += 8
        elif t == "{":
            stack.append(joints[-1][0])
            i += 1
        elif t == "}":
            stack.pop()
            i += 1
        elif t == "OFFSET":
            joints[-1][2] = [float(x) for x in toks[i + 1:i + 4]]
            i += 4
        elif t == "CHANNELS":
            n = int(toks[i + 1])
            joints[-1][3] = toks[i + 2:i + 2 + n]
            i += 2 + n
        else:
            i += 1
    lines = path.read_text().splitlines()
    k = next(n for n, s in enumerate(lines) if s.startswith("Frame Time"))
    return joints, np.loadtxt(lines[k + 1:], ndmin=2), float(lines[k].split()[-1])


def check_fk(robot, motion, joints, values, C, scale, tol=FK_TOL):
    """Pinocchio (through the Robot) vs reference_fk on every frame, the reference lowered by
    the floor height the reader reports (read_bvh(ground=True) puts the floor at z = 0);
    returns the max error."""
    ref = reference_fk(joints, values)
    m, d = robot.model, robot.data
    fids = {n: m.getFrameId(n) for n in ref}
    assert all(m.frames[f].name == n for n, f in fids.items())
    worst = 0.0
    root = joints[0][0]
    info = robot.bvh_info
    floor = info.floor if info.grounded else 0.0
    for k, q in enumerate(motion.q):
        pin.framesForwardKinematics(m, d, q)
        for n, f in fids.items():
            p, R = ref[n]
            M = d.oMf[f]
            err = np.abs(M.translation - (scale * C @ p[k] - [0.0, 0.0, floor])).max()
            Rw = C @ R[k] @ C.T if n == root else C @ R[k]
            worst = max(worst, err, np.abs(M.rotation - Rw).max())
    assert worst < tol, f"FK differs from the reference by {worst:.3g}"
    return worst


# ----------------------------------------------------------------------------- synthetic files
def skeleton_m(prefix="", knee_channels=None, orders=("ZXY",), shoulder_pos=False):
    """A human-like skeleton in metres, Y up, facing +Z: [(name, parent, offset, channels,
    ends)]; joint i gets rotation order orders[i % len(orders)]."""
    P = prefix
    j = []

    def add(name, parent, off, n_rot=3, ends=()):
        i = len(j)
        order = orders[i % len(orders)]
        ch = [f"{a}rotation" for a in order][:n_rot] if n_rot else []
        j.append([P + name, P + parent if parent else None, off, ch, list(ends)])

    add("Hips", None, [0.0, 0.0, 0.0])
    for side, sx in (("Left", 1.0), ("Right", -1.0)):
        add(f"{side}UpLeg", "Hips", [0.09 * sx, -0.05, 0.0])
        add(f"{side}Leg", f"{side}UpLeg", [0.0, -0.42, 0.01])
        if knee_channels:
            j[-1][3] = list(knee_channels)
        add(f"{side}Foot", f"{side}Leg", [0.0, -0.40, -0.01])
        add(f"{side}ToeBase", f"{side}Foot", [0.0, -0.07, 0.13], ends=[[0.0, 0.0, 0.05]])
    add("Spine", "Hips", [0.0, 0.10, 0.0])
    add("Spine1", "Spine", [0.0, 0.15, 0.0])
    add("Neck", "Spine1", [0.0, 0.20, 0.0])
    add("Head", "Neck", [0.0, 0.10, 0.0], ends=[[0.0, 0.15, 0.0]])
    for side, sx in (("Left", 1.0), ("Right", -1.0)):
        add(f"{side}Shoulder", "Spine1", [0.03 * sx, 0.15, 0.0])
        if shoulder_pos and side == "Left":
            j[-1][3] = ["Xposition", "Yposition", "Zposition"] + j[-1][3]
        add(f"{side}Arm", f"{side}Shoulder", [0.15 * sx, 0.0, 0.0])
        add(f"{side}ForeArm", f"{side}Arm", [0.28 * sx, 0.0, 0.0])
        add(f"{side}Hand", f"{side}ForeArm", [0.25 * sx, 0.0, 0.0], ends=[[0.08 * sx, 0, 0]])
    return j


def to_file_units(joints, scale, up="y"):
    """Offsets divided by scale [m/unit]; for up="z" expressed in Z-up file axes."""
    M = C_Z.T @ C_Y if up == "z" else np.eye(3)
    return [[n, p, list(M @ np.asarray(o) / scale), list(ch), [list(M @ np.asarray(e) / scale)
                                                               for e in ends]]
            for n, p, o, ch, ends in joints]


def synthetic_values(joints, T, dt, root_channels, scale, seed=0, up="y"):
    """Smooth motion values (T, n) in the file's units and degrees; the root walks forward
    (+Z in a Y-up file) with a yaw that crosses ±180° (written wrapped)."""
    rng = np.random.default_rng(seed)
    t = np.arange(T) * dt
    cols = []
    fwd = {"y": 2, "z": 1}[up]
    vert = {"y": 1, "z": 2}[up]
    for i, (_, _, _, ch, _) in enumerate(joints):
        for c in (root_channels if i == 0 else ch):
            if c.endswith("position"):
                a = "XYZ".index(c[0])
                if i == 0:
                    v = {fwd: (-1.0 if up == "z" else 1.0) * 1.2 * t, vert: 0.93 + 0.02 *
                         np.sin(2 * np.pi * 1.8 * t)}.get(a, 0.03 * np.sin(2 * np.pi * 0.9 * t))
                else:
                    v = 0.01 * np.sin(2 * np.pi * 1.3 * t + a)
                cols.append(v / scale)
            else:
                amp, f, ph = rng.uniform(5, 60), rng.uniform(0.5, 2.0), rng.uniform(0, 2 * np.pi)
                v = amp * np.sin(2 * np.pi * f * t + ph)
                if i == 0 and c[0] == ("Y" if up == "y" else "Z"):
                    v = 150.0 + 80.0 * t / t[-1]  # yaw from 150° to 230°, wrapped below
                    v = (v + 180.0) % 360.0 - 180.0
                cols.append(v)
    return np.column_stack(cols)


ROOT_6 = ["Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"]

CASES = {
    # name: (unit scale [m/unit], rotation orders, root channels, frame time, up, extras)
    "m_XYZ_60Hz": (1.0, ("XYZ",), ROOT_6, 1 / 60, "y", {}),
    "cm_YXZ_120Hz_rot_first": (0.01, ("YXZ",), ["Yrotation", "Xrotation", "Zrotation",
                                                 "Zposition", "Xposition", "Yposition"],
                               1 / 120, "y", {}),
    "inches_ZXY_30Hz_interleaved": (0.0254, ("ZXY",), ["Zrotation", "Yposition", "Xrotation",
                                                      "Xposition", "Yrotation", "Zposition"],
                                    1 / 30, "y", {}),
    "cmu_units_mixed_orders_100Hz_knee1": (0.056444, ("ZYX", "XZY", "YZX", "ZXY"), ROOT_6, 0.01,
                                           "y", {"knee_channels": ["Xrotation"]}),
    "mm_mixamo_prefix_positions_on_a_joint": (0.001, ("ZXY", "XYZ"), ROOT_6, 1 / 24, "y",
                                              {"prefix": "mixamorig:", "shoulder_pos": True}),
    "m_z_up": (1.0, ("XYZ", "ZYX"), ["Xposition", "Yposition", "Zposition", "Zrotation",
                                     "Yrotation", "Xrotation"], 1 / 50, "z", {}),
    "root_rotation_only": (0.01, ("ZXY",), ["Zrotation", "Xrotation", "Yrotation"], 1 / 60,
                           "y", {}),
}


def make_case(tmp_path, key, T=40, tpose=False):
    scale, orders, root_ch, dt, up, extra = CASES[key]
    joints_m = skeleton_m(extra.get("prefix", ""), extra.get("knee_channels"), orders,
                          extra.get("shoulder_pos", False))
    joints = to_file_units(joints_m, scale, up)
    values = synthetic_values(joints, T, dt, root_ch, scale, up=up)
    path = tmp_path / f"{key}.bvh"
    rows = write_bvh(path, joints, root_ch, values, dt, tpose=tpose)
    ref_joints = [[n, p, o, root_ch if p is None else ch, e] for n, p, o, ch, e in joints]
    return path, ref_joints, values, rows, scale, dt, up


# ----------------------------------------------------------------------------- tests: FK
def test_cmu_clip_fk_every_frame():
    robot, motion = read_bvh(CMU)
    joints, values, dt = tiny_reader(CMU)
    assert robot.bvh_info.skipped_first_frame  # README: frame 0 is a T-pose
    assert motion.T == values.shape[0] - 1 == 343
    assert motion.dt == pytest.approx(dt, abs=1e-12)
    assert robot.bvh_info.scale == 0.056444  # README: CMU units × 0.056444 → m
    check_fk(robot, motion, joints, values[1:], C_Y, 0.056444)
    # one URDF joint per channel, named <joint>_<channel>, in the file's order
    names = robot.joint_names
    assert "LeftUpLeg_Zrotation" in names and names[0] == "root_joint"
    n_rot = sum(len(j[3]) for j in joints[1:])
    assert robot.model.nq == 7 + n_rot


@pytest.mark.parametrize("key", sorted(CASES))
def test_synthetic_fk_units_orders_rates(tmp_path, key):
    path, joints, values, rows, scale, dt, up = make_case(tmp_path, key)
    robot, motion = read_bvh(path, up=up)
    info = robot.bvh_info
    assert info.scale == scale, f"detected {info.unit}"
    assert not info.skipped_first_frame
    np.testing.assert_allclose(np.diff(motion.t), dt, rtol=1e-12)
    check_fk(robot, motion, joints, values, C_Z if up == "z" else C_Y, scale)
    # angles in radians, unwrapped: consecutive frames never jump by more than π; the base
    # quaternion keeps its sign while the yaw crosses ±180°
    assert np.all(np.abs(np.diff(motion.q[:, 7:], axis=0)) < math.pi)
    quat = motion.q[:, 3:7]
    assert np.all(np.sum(quat[1:] * quat[:-1], axis=1) > 0)
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-12)


def test_ground_shift(tmp_path):
    """ground=True lowers the base by the floor estimate, nothing else; the lower foot's lowest
    sole corner then has median height 0 (computed here from the corners' own FK)."""
    robot, motion = read_bvh(CMU)
    raw_robot, raw = read_bvh(CMU, ground=False)
    floor = robot.bvh_info.floor
    assert raw_robot.bvh_info.floor == floor and 0.0 < floor < 0.05  # CMU's floor: ~2 cm
    np.testing.assert_array_equal(motion.q[:, [0, 1]], raw.q[:, [0, 1]])
    np.testing.assert_allclose(raw.q[:, 2] - motion.q[:, 2], floor, atol=1e-15)
    np.testing.assert_array_equal(motion.q[:, 3:], raw.q[:, 3:])
    m, d = robot.model, robot.data
    low = []
    for q in motion.q:
        pin.framesForwardKinematics(m, d, q)
        z = [(d.oMf[m.getFrameId(c.frame)].act(corner))[2] for c in robot.contacts.values()
             for corner in c.corners()]
        low.append(min(z))
    assert np.median(low) == pytest.approx(0.0, abs=1e-12)
    assert all(np.array_equal(motion.contact[s], raw.contact[s]) for s in motion.contact)


def test_explicit_scale_and_tpose(tmp_path):
    path, joints, values, rows, scale, dt, up = make_case(tmp_path, "cm_YXZ_120Hz_rot_first",
                                                          tpose=True)
    robot, motion = read_bvh(path)
    assert robot.bvh_info.skipped_first_frame and motion.T == values.shape[0]
    check_fk(robot, motion, joints, values, C_Y, scale)
    robot2, motion2 = read_bvh(path, skip_first_frame=False, scale=0.01)
    assert motion2.T == rows.shape[0] and robot2.bvh_info.unit == "given"
    check_fk(robot2, motion2, joints, rows, C_Y, 0.01)
    # a wrong scale is taken as given: FK in those units
    robot3, motion3 = read_bvh(path, scale=0.02)
    check_fk(robot3, motion3, joints, values, C_Y, 0.02)


def test_undetectable_units(tmp_path):
    joints = to_file_units(skeleton_m(), 1.0)
    joints[1][2] = [0.09, -3.0, 0.0]  # a 3.9 m leg in metres, 39 m in cm …: no human unit fits
    joints[5][2] = [-0.09, -3.0, 0.0]
    values = synthetic_values(joints, 10, 0.01, ROOT_6, 1.0)
    path = tmp_path / "giant.bvh"
    write_bvh(path, joints, ROOT_6, values, 0.01)
    with pytest.raises(BVHError, match="scale="):
        read_bvh(path)
    robot, motion = read_bvh(path, scale=1.0)
    assert robot.bvh_info.hip_height == pytest.approx(3.0 + 0.42 + 0.40 + 0.07, abs=1e-9)


# ----------------------------------------------------------------------------- tests: model
DE_LEVA = {"thigh": (0.1416, 0.4095), "shank": (0.0433, 0.4459)}  # Table 4 males: mass, CM


def test_masses_from_de_leva(tmp_path):
    robot, _ = read_bvh(CMU, mass=80.0)
    m = robot.model
    assert pin.computeTotalMass(m) == pytest.approx(80.0, abs=1e-9)
    joints, _, _ = tiny_reader(CMU)
    off = {j[0]: np.array(j[2]) * 0.056444 for j in joints}
    for link, child, seg in (("LeftUpLeg", "LeftLeg", "thigh"), ("RightLeg", "RightFoot",
                                                                   "shank")):
        frac, cm = DE_LEVA[seg]
        jid = m.frames[m.getFrameId(link)].parentJoint
        I = m.inertias[jid]
        assert I.mass == pytest.approx(frac * 80.0, rel=1e-4)  # minus the tiny link masses
        np.testing.assert_allclose(I.lever, cm * off[child], atol=1e-12)
        L = np.linalg.norm(off[child])
        # longitudinal radius of gyration 0.149 (thigh) / 0.103 (shank) of the length
        e = off[child] / L
        r_long = {"thigh": 0.149, "shank": 0.103}[seg]
        assert e @ I.inertia @ e == pytest.approx(I.mass * (r_long * L) ** 2, rel=1e-9)
    # every inertia positive definite (MuJoCo and Pinocchio need it)
    for i in range(1, m.njoints):
        assert np.linalg.eigvalsh(m.inertias[i].inertia).min() > 0


def test_unmatched_segments_warn(tmp_path):
    joints = to_file_units(skeleton_m(), 1.0)
    joints[-1][0] = "Gizmo"  # RightHand → unknown name
    values = synthetic_values(joints, 10, 0.01, ROOT_6, 1.0)
    path = tmp_path / "gizmo.bvh"
    write_bvh(path, joints, ROOT_6, values, 0.01)
    with pytest.warns(UserWarning, match="Gizmo"):
        robot, _ = read_bvh(path, mass=70.0)
    assert robot.bvh_info.unmatched == ("Gizmo",)
    assert robot.mass == pytest.approx(70.0, abs=1e-9)


def test_legs_soles_and_contact_frames():
    robot, motion = read_bvh(CMU)
    for s in ("left", "right"):
        leg = robot.legs[s]
        side = s.capitalize()
        assert (leg.hip, leg.knee, leg.ankle) == (f"{side}UpLeg_Xrotation",
                                                  f"{side}Leg_Xrotation",
                                                  f"{side}Foot_Xrotation")
        assert leg.sole == f"{s}_sole" and robot.contacts[s].frame == f"{s}_sole_contact"
        c = robot.contacts[s]
        assert c.half_width == pytest.approx(0.35 * c.half_length, rel=1e-12)
        assert 0.2 < 2 * c.half_length < 0.3  # an adult's foot, ankle to toe tip [m]
    # a shape per segment for the viewer: bones + one box per foot
    assert robot.visual_model is not None and robot.visual_model.ngeoms >= 25
    # with the legs hanging (all channels 0 but the hip rolls that undo the rest pose's 20°
    # splay: gdimitate.retarget.bodymap.legs_down; base upright) each sole plane is at the
    # height of the foot's lowest point (toe joint / toe end), the two sole frames on it
    # (issue 17: measured at the splayed zero pose, the soles stood 23° on edge in stance)
    from gdimitate.retarget.bodymap import legs_down

    m, d = robot.model, robot.data
    q = pin.neutral(m)
    hang = legs_down(robot)
    # the splay from the file's knee and ankle OFFSETs (lateral, down; cmu_02_01.bvh)
    splay = {"Left": np.arctan2(2.59720 + 2.49236, 7.13576 + 6.84770),
             "Right": -np.arctan2(2.59502 + 2.46780, 7.12977 + 6.78024)}
    for side in ("Left", "Right"):
        i = robot.idx_q(f"{side}UpLeg_Zrotation")
        assert hang[i] == pytest.approx(-splay[side], abs=1e-3)  # robot.base_rotation: 2e-4
        q[i] = -splay[side]
    pin.framesForwardKinematics(m, d, q)
    for s, side in (("left", "Left"), ("right", "Right")):
        sole = d.oMf[m.getFrameId(f"{s}_sole_contact")].translation[2]
        assert d.oMf[m.getFrameId(f"{s}_sole")].translation[2] == pytest.approx(sole, abs=1e-12)
        pts = [d.oMf[m.getFrameId(n)].translation[2]
               for n in (f"{side}Foot", f"{side}ToeBase", f"{side}ToeBase_end")]
        assert min(pts) == pytest.approx(sole, abs=1e-12)
        # the leg's sole frame is under the ankle; the rectangle's front edge under the toe
        # tip, its rear edge behind the ankle by 0.25 × the ankle-to-toe-tip distance
        ankle = d.oMf[m.getFrameId(f"{side}Foot")].translation
        tip = d.oMf[m.getFrameId(f"{side}ToeBase_end")].translation
        below = d.oMf[m.getFrameId(f"{s}_sole")].translation
        np.testing.assert_allclose(below[:2], ankle[:2], atol=1e-12)
        M = d.oMf[m.getFrameId(f"{s}_sole_contact")]
        hl = robot.contacts[s].half_length
        front = M.translation + hl * M.rotation[:, 0]
        rear = M.translation - hl * M.rotation[:, 0]
        np.testing.assert_allclose(front[:2], tip[:2], atol=1e-12)
        ahead = np.linalg.norm(tip[:2] - ankle[:2])
        assert np.linalg.norm(rear[:2] - ankle[:2]) == pytest.approx(0.25 * ahead, rel=1e-9)
    # the Robot's grounded neutral pose stands the lower sole centre on z = 0
    pin.framesForwardKinematics(m, d, robot.neutral)
    z = [d.oMf[m.getFrameId(f"{s}_sole_contact")].translation[2] for s in ("left", "right")]
    assert min(z) == pytest.approx(0.0, abs=1e-12)


def test_mujoco_loads_the_urdf(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    robot, _ = read_bvh(CMU, urdf_path=tmp_path / "cmu.urdf")
    mj = mujoco.MjModel.from_xml_path(str(robot.urdf_path))
    assert mj.nq == robot.model.nq - 7  # MuJoCo loads a URDF fixed-base
    # MuJoCo fixes the URDF's root link to its world: only the root link's mass is not counted
    root = robot.model.inertias[1].mass
    assert float(mj.body_mass.sum()) == pytest.approx(75.0 - root, abs=1e-9)


# ----------------------------------------------------------------------------- tests: contacts
def _strikes(contact):
    c = contact.astype(int)
    return np.flatnonzero(np.diff(c) == 1) + 1


def test_cmu_contacts_cadence():
    robot, motion = read_bvh(CMU)
    L, R = motion.contact["left"], motion.contact["right"]
    # a walk: never both feet off the ground (no flight phase)
    assert np.all(L | R)
    strikes = sorted([(i, "left") for i in _strikes(L)] + [(i, "right") for i in _strikes(R)])
    sides = [s for _, s in strikes]
    assert all(a != b for a, b in zip(sides, sides[1:])), "steps must alternate"
    # README: 2.87 s (2.85 s after the T-pose) at ~109 steps/min ≈ 5.2 steps (touch-downs)
    assert abs(len(strikes) - 2.85 * 109 / 60) <= 1
    cadence = 60.0 / (np.diff([i for i, _ in strikes]).mean() * motion.dt)
    assert cadence == pytest.approx(109.0, rel=0.05)  # README: cadence ~109 steps/min
    # README: ~1.18 m/s overground; BVH +Z (the subject's facing) is our +x
    travel = motion.q[-1, :3] - motion.q[0, :3]
    assert travel[0] / motion.t[-1] == pytest.approx(1.18, abs=0.03)
    assert abs(travel[1]) < 0.05 * travel[0]
    duty = (L.mean() + R.mean()) / 2
    assert 0.55 < duty < 0.70  # stance ≈ 60 % of the gait cycle in adult walking


def stepping_in_place(tmp_path, dt=1 / 100, T=300):
    """Legs lifted in turn by hip/knee flexion in known windows, the foot kept level by the
    ankle; stance = angles exactly 0. The lift ∝ √sin rises fast, like a toe-off."""
    joints_m = skeleton_m(orders=("ZYX",))
    t = np.arange(T) * dt
    names = [j[0] for j in joints_m]
    values = np.zeros((T, 6 + 3 * (len(joints_m) - 1)))
    values[:, 1] = 0.94  # hips at the standing height, feet on the floor
    truth = {"left": np.ones(T, bool), "right": np.ones(T, bool)}
    for t0, side in [(0.3, "left"), (0.9, "right"), (1.5, "left"), (2.1, "right")]:
        w = (t >= t0) & (t < t0 + 0.45)
        lift = np.where(w, np.sqrt(np.abs(np.sin(np.pi * (t - t0) / 0.45))), 0.0)
        side_c = side.capitalize()
        hip = 6 + 3 * (names.index(f"{side_c}UpLeg") - 1) + 2  # Xrotation (ZYX: third)
        knee = 6 + 3 * (names.index(f"{side_c}Leg") - 1) + 2
        ankle = 6 + 3 * (names.index(f"{side_c}Foot") - 1) + 2
        values[:, hip] += -50.0 * lift  # flexion: the thigh swings forward (+Z)
        values[:, knee] += 90.0 * lift
        values[:, ankle] += -40.0 * lift  # the foot stays level
        truth[side] &= ~w
    path = tmp_path / "steps.bvh"
    write_bvh(path, joints_m, ROOT_6, values, dt)
    return path, truth, dt


def test_synthetic_contacts_known_truth(tmp_path):
    path, truth, dt = stepping_in_place(tmp_path)
    robot, motion = read_bvh(path)
    assert robot.bvh_info.floor == pytest.approx(0.0, abs=1e-9)
    for s in ("left", "right"):
        got, want = motion.contact[s], truth[s]
        ds, ws = np.flatnonzero(np.diff(got.astype(int))), np.flatnonzero(np.diff(want.astype(int)))
        assert len(ds) == len(ws), f"{s}: {len(ds)} transitions, truth {len(ws)}"
        # lift-off and touch-down within 0.05 s of the truth
        assert np.abs(ds - ws).max() * dt <= 0.05
    given = {"left": truth["left"], "right": truth["right"]}
    _, m2 = read_bvh(path, contacts=given)
    assert all(np.array_equal(m2.contact[s], truth[s]) for s in given)


# ----------------------------------------------------------------------------- tests: bad files
def _good_text(tmp_path):
    path, *_ = make_case(tmp_path, "m_XYZ_60Hz", T=6)
    return path.read_text().splitlines()


def _line_of(lines, pattern, nth=0):
    hits = [i for i, s in enumerate(lines) if re.search(pattern, s)]
    return hits[nth]


def _bad(tmp_path, lines, name="bad.bvh"):
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n")
    return p


def _breakages(lines):
    """(what, broken lines, expected 1-based line in the message or None, message regex)."""
    out = []
    i = _line_of(lines, r"^\s*}\s*$", 3)  # drop a closing brace inside the hierarchy
    out.append(("missing brace", lines[:i] + lines[i + 1:], None, "unbalanced"))
    m = _line_of(lines, r"^MOTION")
    out.append(("extra brace", lines[:m] + ["}"] + lines[m:], m + 1, "unbalanced"))
    c = _line_of(lines, r"CHANNELS", 2)
    out.append(("no CHANNELS", lines[:c] + lines[c + 1:], c + 1, "CHANNELS"))
    f = m + 5
    short = lines[f].rsplit(" ", 1)[0]
    out.append(("short frame", lines[:f] + [short] + lines[f + 1:], f + 1, "values"))
    nan = lines[f].split()
    nan[7] = "nan"
    out.append(("NaN", lines[:f] + [" ".join(nan)] + lines[f + 1:], f + 1, "finite"))
    for dt in ("0", "-0.01", "nan"):
        out.append((f"frame time {dt}", lines[:m + 2] + [f"Frame Time: {dt}"] + lines[m + 3:],
                    m + 3, "Frame Time"))
    out.append(("truncated frames", lines[:-2], None, "truncated"))
    out.append(("extra frame", lines + [lines[-1]], len(lines) + 1, "more frame lines"))
    out.append(("no frame time", lines[:m + 2], None, "truncated"))
    out.append(("bad channel", [s.replace("Xrotation", "Wrotation", 1) for s in lines], None,
                "unknown channel"))
    out.append(("cut in hierarchy", lines[:c + 3], None, "ends"))
    out.append(("frames count", lines[:m + 1] + ["Frames: many"] + lines[m + 2:], m + 2,
                "positive integer"))
    return out


def test_malformed_files(tmp_path):
    lines = _good_text(tmp_path)
    read_bvh(_bad(tmp_path, lines, "good.bvh"))  # the unbroken file reads
    for what, broken, line, pattern in _breakages(lines):
        with pytest.raises(BVHError, match=pattern) as e:
            read_bvh(_bad(tmp_path, broken))
        msg = str(e.value)
        assert re.search(r"line \d+", msg), f"{what}: no line number in {msg!r}"
        if line is not None:
            assert f"line {line}:" in msg, f"{what}: {msg!r} (expected line {line})"
    with pytest.raises(BVHError, match="no such BVH file"):
        read_bvh(tmp_path / "missing.bvh")
    with pytest.raises(BVHError, match="line 1: .*'HIERARCHY' at the start"):
        read_bvh(_bad(tmp_path, [], "empty.bvh"))
    renamed = [re.sub(r"JOINT Spine$", "JOINT root_joint", s) for s in lines]
    assert renamed != lines
    with pytest.raises(BVHError, match="root_joint"), pytest.warns(UserWarning):
        read_bvh(_bad(tmp_path, renamed, "reserved.bvh"))  # Pinocchio's free-flyer name
    assert issubclass(BVHError, gd.GdimitateError)


# ----------------------------------------------------------------------------- tests: variety
@pytest.mark.parametrize("seed", range(4))
def test_random_channel_layouts(tmp_path, seed):
    """Random per-joint channel subsets and orders (0–3 rotations, a joint with CHANNELS 0,
    position channels on a joint), a random root channel permutation, two End Sites."""
    rng = np.random.default_rng(100 + seed)
    joints = skeleton_m()
    legs = {"UpLeg", "Leg", "Foot"}
    for j in joints[1:]:
        bare = j[0].replace("Left", "").replace("Right", "")
        n = 3 if bare in legs else int(rng.integers(0, 4))  # legs keep a lateral channel
        j[3] = [f"{a}rotation" for a in rng.permutation(list("XYZ"))[:n]]
        if bare in legs and "Xrotation" not in j[3]:
            j[3][0] = "Xrotation"
    joints[-1][3] = []  # RightHand: CHANNELS 0
    joints[-3][3] = ["Yposition"] + joints[-3][3]  # a position channel on RightArm
    head = [j[0] for j in joints].index("Head")
    joints[head][4].append([0.05, 0.05, 0.02])
    root = list(rng.permutation(ROOT_6))
    scale = [1.0, 0.01, 0.0254, 0.056444][seed]
    joints = to_file_units(joints, scale)
    values = synthetic_values(joints, 25, 1 / 90, root, scale, seed=seed)
    path = tmp_path / "random.bvh"
    write_bvh(path, joints, root, values, 1 / 90)
    robot, motion = read_bvh(path)
    assert robot.bvh_info.scale == scale
    ref = [[n, p, o, root if p is None else ch, e] for n, p, o, ch, e in joints]
    check_fk(robot, motion, ref, values, C_Y, scale)
    assert "RightHand_fixed" in [f.name for f in robot.model.frames]
    assert "Head_end2" in [f.name for f in robot.model.frames]


@pytest.mark.filterwarnings("ignore:.*segments not in the anthropometric table")
def test_legs_by_name_or_given(tmp_path):
    joints = skeleton_m()
    rename = {"LeftUpLeg": "A1", "LeftLeg": "A2", "LeftFoot": "A3", "LeftToeBase": "A4"}
    for j in joints:
        j[0] = rename.get(j[0], j[0])
        j[1] = rename.get(j[1], j[1])
    values = synthetic_values(joints, 10, 0.01, ROOT_6, 1.0)
    path = tmp_path / "odd.bvh"
    write_bvh(path, joints, ROOT_6, values, 0.01)
    with pytest.raises(gd.LegDetectionError, match="legs="):
        read_bvh(path)
    legs = {"left": {"hip": "A1", "knee": "A2", "ankle": "A3", "toe": "A4"},
            "right": {"hip": "RightUpLeg", "knee": "RightLeg", "ankle": "RightFoot"}}
    with pytest.warns(UserWarning, match="A1"):  # A1…A4 are not in the segment table
        robot, motion = read_bvh(path, legs=legs)
    assert robot.legs["left"].knee.startswith("A2_")
    assert robot.legs["right"].hip == "RightUpLeg_Xrotation"
    with pytest.raises(BVHError, match="up="):
        read_bvh(path, legs=legs, up="x")
    with pytest.raises(gd.InvalidInputError, match="contacts="):
        read_bvh(path, legs=legs, contacts={"left": np.ones(3, bool), "right": np.ones(3, bool)})


ASF = {"Hips": "root", "LeftUpLeg": "lfemur", "LeftLeg": "ltibia", "LeftFoot": "lfoot",
       "LeftToeBase": "ltoes", "RightUpLeg": "rfemur", "RightLeg": "rtibia",
       "RightFoot": "rfoot", "RightToeBase": "rtoes", "Spine": "lowerback", "Spine1": "thorax",
       "Neck": "lowerneck", "Head": "head", "LeftShoulder": "lclavicle", "LeftArm": "lhumerus",
       "LeftForeArm": "lradius", "LeftHand": "lwrist", "RightShoulder": "rclavicle",
       "RightArm": "rhumerus", "RightForeArm": "rradius", "RightHand": "rwrist"}


def test_cmu_asf_names_and_unit_report(tmp_path, caplog, recwarn):
    joints = skeleton_m()
    for j in joints:
        j[0], j[1] = ASF[j[0]], ASF.get(j[1]) if j[1] else None
    joints = to_file_units(joints, 0.056444)
    values = synthetic_values(joints, 12, 1 / 120, ROOT_6, 0.056444)
    path = tmp_path / "asf.bvh"
    write_bvh(path, joints, ROOT_6, values, 1 / 120)
    with caplog.at_level("INFO", logger="gdimitate.io.bvh"):
        robot, motion = read_bvh(path)
    assert "CMU units" in caplog.text  # the detected unit is said
    assert not [w for w in recwarn if "anthropometric" in str(w.message)]  # all names known
    leg = robot.legs["left"]
    assert (leg.hip, leg.knee, leg.ankle) == ("lfemur_Xrotation", "ltibia_Xrotation",
                                              "lfoot_Xrotation")  # X: the lateral axis
    m = robot.model
    thigh = m.inertias[m.frames[m.getFrameId("rfemur")].parentJoint].mass
    assert thigh == pytest.approx(0.1416 * 75.0, rel=1e-4)
    check_fk(robot, motion, [[n, p, o, ROOT_6 if p is None else ch, e]
                             for n, p, o, ch, e in joints], values, C_Y, 0.056444)


def test_bone_shapes_join_the_joints():
    """Each bone cylinder's end caps sit on its joint and on a child joint / End Site (zero
    pose), so the viewer draws the skeleton where the kinematics put it."""
    robot, _ = read_bvh(CMU)
    m, d, vm = robot.model, robot.data, robot.visual_model
    q = pin.neutral(m)
    pin.framesForwardKinematics(m, d, q)
    vd = vm.createData()
    pin.updateGeometryPlacements(m, d, vm, vd, q)
    points = np.array([d.oMf[i].translation for i in range(len(m.frames))
                       if m.frames[i].type == pin.FrameType.BODY])
    n = 0
    for g, M in zip(vm.geometryObjects, vd.oMg):
        if type(g.geometry).__name__ != "Cylinder":
            continue
        h = g.geometry.halfLength
        for end in (M.translation + h * M.rotation[:, 2], M.translation - h * M.rotation[:, 2]):
            assert np.min(np.linalg.norm(points - end, axis=1)) < 1e-9
        n += 1
    assert n == 23  # the CMU skeleton's non-zero segments, less the feet (boxes) and toes


@pytest.mark.parametrize("noise", [0.003, 0.006, 0.01])
def test_contacts_survive_mocap_noise(noise):
    """White noise on the CMU walk's recorded positions (``noise`` [m] on the root, twice as
    many rad on every joint angle; 120 Hz): the stance phases found are the noise-free ones —
    the same phases, each end within 6 frames (0.05 s); a phase cut by the clip's end and
    shorter than 0.1 s may be lost. Without the low-pass filter 3 mm left no stance at all
    (every sole's speed above its threshold)."""
    from gdimitate.io.bvh.contacts import detect_contacts, sole_corners
    from gdimitate.model.footsteps import stance_phases

    robot, m = gd.bvh.read_bvh(CMU)
    hh = float(np.median(m.q[:, 2]))
    clean = detect_contacts(sole_corners(robot, m.q), m.t, hh)
    rng = np.random.default_rng(0)
    q = m.q.copy()
    q[:, :3] += rng.normal(0, noise, (m.T, 3))
    q[:, 7:] += rng.normal(0, 2 * noise, (m.T, q.shape[1] - 7))
    noisy = detect_contacts(sole_corners(robot, q), m.t, hh)
    for s in ("left", "right"):
        a = [p for p in stance_phases(clean[s]) if p[1] - p[0] >= 12 or 0 < p[0] < p[1] < m.T]
        b = stance_phases(noisy[s])
        assert len(b) in (len(a), len(stance_phases(clean[s])))
        for (a0, a1), (b0, b1) in zip(a, b):
            assert abs(a0 - b0) <= 6 and abs(a1 - b1) <= 6
