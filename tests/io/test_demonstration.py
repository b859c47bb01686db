"""load_demonstration: every format against the file's own numbers; NPZ files that carry their
robot (library, URDF, .osim) and refuse a changed one; Robot.load, fingerprints, sensor frames."""

from __future__ import annotations

import functools
import json
import re
import shutil
import warnings

import numpy as np
import pytest

from gdimitate import Robot
from gdimitate.errors import (
    DemonstrationFormatError,
    InvalidInputError,
    MeshPathError,
    RobotMismatchError,
    UnknownRobotError,
)
from gdimitate.io.demonstration import SUPPORTED, load_demonstration
from gdimitate.io.gait import human_walk_3d_folder, human_walk_path
from gdimitate.model.library import list_robots
from gdimitate.model.motion import Motion, RobotRecord

D3 = human_walk_3d_folder()
BVH = human_walk_path().parents[1] / "cmu_02_01" / "cmu_02_01.bvh"
SAG_GRF = human_walk_path().parent / "walk_gait1018_subject01_grf.mot"


def _mot_columns(path) -> dict[str, np.ndarray]:
    """An OpenSim .mot read with plain Python (the independent reference): column → values."""
    lines = path.read_text().splitlines()
    i = next(k for k, s in enumerate(lines) if s.strip().lower() == "endheader")
    names = lines[i + 1].split()
    data = np.array([[float(x) for x in s.split()] for s in lines[i + 2:] if s.strip()])
    short = [n.split("/")[-2] if n.endswith("/value") else n for n in names]  # 4.x paths
    return {n: data[:, k] for k, n in enumerate(short)}


@functools.cache
def _osim_demo():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_demonstration(D3 / "subject01.osim", coordinates=D3 / "subject01_walk1_ik.mot",
                                  grf=D3 / "subject01_walk1_grf.mot")


def test_unknown_extension_lists_supported(tmp_path):
    with pytest.raises(DemonstrationFormatError) as e:
        load_demonstration(tmp_path / "walk.c3d")
    for ext in SUPPORTED:
        assert ext in str(e.value)
    with pytest.raises(DemonstrationFormatError, match="coordinates="):
        load_demonstration(D3 / "subject01.osim")
    with pytest.raises(DemonstrationFormatError, match="grf= goes with"):
        load_demonstration(BVH, grf=SAG_GRF)


def test_osim_with_coordinates_and_grf_matches_the_files():
    d = _osim_demo()
    cols = _mot_columns(D3 / "subject01_walk1_ik.mot")  # degrees (inDegrees=yes)
    assert d.motion.T == cols["time"].size and np.allclose(d.motion.t, cols["time"])
    for c in ("knee_angle_r", "hip_flexion_l", "ankle_angle_r", "lumbar_extension"):
        assert np.max(np.abs(d.motion.column(c) - np.deg2rad(cols[c]))) < 1e-9
    # stance = measured vertical force > 20 N (the GRF file, Y up, resampled on the motion's t)
    g = _mot_columns(D3 / "subject01_walk1_grf.mot")
    xml = (D3 / "subject01_walk1_grf.xml").read_text()
    assert "ExternalLoads" in xml and "subject01_walk1_grf.xml" in d.note
    for side, key in (("right", "ground_force_vy"), ("left", "l_ground_force_vy")):
        fy = np.interp(d.motion.t, g["time"], g[key])
        assert np.array_equal(d.motion.contact[side], fy > 20.0)
        assert np.allclose(d.forces[side].force[:, 2], fy, atol=1e-9)
    # overground: the belt speed times t added to the pelvis x (treadmill trial)
    x_tread = np.asarray(load_demonstration(D3 / "subject01.osim",
                                            coordinates=D3 / "subject01_walk1_ik.mot",
                                            grf=D3 / "subject01_walk1_grf.mot",
                                            overground=False).motion.q[:, 0])
    shift = d.motion.q[:, 0] - x_tread
    speed = np.polyfit(d.motion.t, shift, 1)[0]
    assert 0.9 < speed < 1.4 and np.allclose(shift, speed * (d.motion.t - d.motion.t[0]))


def test_full_body_mot_needs_its_model():
    with pytest.raises(DemonstrationFormatError, match="--osim"):
        load_demonstration(D3 / "subject01_walk1_ik.mot")
    d = _osim_demo()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        k = load_demonstration(D3 / "subject01_walk1_ik.mot", robot=d.robot, overground=False)
    assert k.forces is None and "no forces given" in k.note
    x = load_demonstration(D3 / "subject01.osim", coordinates=D3 / "subject01_walk1_ik.mot",
                           grf=D3 / "subject01_walk1_grf.mot", overground=False)
    assert np.allclose(k.motion.q, x.motion.q, atol=1e-12)
    # contacts from the feet alone agree with the force plates on most frames
    for s in ("left", "right"):
        agree = np.mean(k.motion.contact[s] == x.motion.contact[s])
        assert agree > 0.6, (s, agree)


def test_sagittal_mot_and_bvh():
    d = load_demonstration(human_walk_path(), grf=SAG_GRF)
    cols = _mot_columns(human_walk_path())
    assert d.robot.base == "planar" and d.motion.T == cols["time"].size
    assert np.allclose(d.motion.column("left_knee"), np.deg2rad(cols["knee_angle_l"]), atol=1e-9)
    b = load_demonstration(BVH)
    frames = int(re.search(r"Frames:\s*(\d+)", BVH.read_text()).group(1))
    assert b.motion.T in (frames, frames - 1)  # CMU's T-pose frame dropped
    assert b.robot.base == "free" and all(c.any() for c in b.motion.contact.values())


def test_npz_round_trip_without_naming_the_robot(tmp_path):
    # a library robot
    d = load_demonstration(human_walk_path(), grf=SAG_GRF)
    hoap = Robot.load("hoap2")
    m = Motion(d.motion.t, hoap.joint_names, np.tile(hoap.neutral, (d.motion.T, 1)),
               d.motion.contact, base_nq=3)
    m.to_npz(tmp_path / "a.npz", robot=hoap)
    back = load_demonstration(tmp_path / "a.npz")
    assert back.robot.name == "hoap2" and back.robot.fingerprint == hoap.fingerprint
    assert np.array_equal(back.motion.q, m.q) and back.motion.contact.keys() == m.contact.keys()
    # a URDF path with legs= and contacts= given: both recorded and used again
    urdf = tmp_path / "bot.urdf"
    shutil.copy(_write_hoap(tmp_path), urdf)
    legs = {s: {"hip": f"{s}_hip", "knee": f"{s}_knee", "ankle": f"{s}_ankle",
                "sole": f"{s}_sole"} for s in ("left", "right")}
    contacts = {s: {"half_length": 0.05, "half_width": 0.03} for s in ("left", "right")}
    r = Robot.load(urdf, legs=legs, contacts=contacts)
    m2 = m.replace(joint_names=r.joint_names, q=np.tile(r.neutral, (m.T, 1)))
    m2.to_npz(tmp_path / "b.npz", robot=r)
    rec = RobotRecord.from_npz(tmp_path / "b.npz")
    assert rec.kind == "urdf" and rec.source == str(urdf.resolve())
    back = load_demonstration(tmp_path / "b.npz")
    assert back.robot.contacts["left"].half_length == 0.05
    assert back.robot.legs["right"].knee == "right_knee"
    # the model file changed: a mass edited → the fingerprint differs → an error, not a guess
    text = urdf.read_text()
    first = re.search(r'<mass value="([0-9.eE+-]+)"', text)
    urdf.write_text(text[:first.start(1)] + str(float(first.group(1)) * 1.01)
                    + text[first.end(1):])
    with pytest.raises(RobotMismatchError, match="fingerprint"):
        load_demonstration(tmp_path / "b.npz")
    # an .osim robot is rebuilt from the model file
    o = _osim_demo()
    o.motion.to_npz(tmp_path / "c.npz", robot=o.robot)
    assert RobotRecord.from_npz(tmp_path / "c.npz").kind == "osim"
    back = load_demonstration(tmp_path / "c.npz")
    assert back.robot.fingerprint == o.robot.fingerprint
    assert np.array_equal(back.motion.q, o.motion.q)


def _write_hoap(tmp_path):
    from gdimitate.model.urdfgen import PLANAR_MODELS, planar_biped_urdf

    p = tmp_path / "hoap2_src.urdf"
    p.write_text(planar_biped_urdf(PLANAR_MODELS["hoap2"]))
    return p


def test_npz_without_a_record_or_with_a_wrong_robot(tmp_path):
    hoap = Robot.load("hoap2")
    m = Motion(np.arange(3) * 0.1, hoap.joint_names, np.tile(hoap.neutral, (3, 1)), base_nq=3)
    m.to_npz(tmp_path / "plain.npz")
    with pytest.raises(RobotMismatchError, match="records no robot"):
        load_demonstration(tmp_path / "plain.npz")
    assert load_demonstration(tmp_path / "plain.npz", robot=hoap).robot is hoap
    m.to_npz(tmp_path / "rec.npz", robot=hoap)
    with pytest.raises(RobotMismatchError):
        load_demonstration(tmp_path / "rec.npz", robot=Robot.load("case1_demonstrator"))
    other = tmp_path / "other.urdf"
    other.write_text(_leg_urdf(imu=False))
    with pytest.raises(InvalidInputError, match="not this motion's robot"):
        m.to_npz(tmp_path / "x.npz", robot=Robot.load(other))


def test_robot_load_and_fingerprint(tmp_path):
    assert {"alexander", "icub_full", "g1_hands"} <= set(list_robots())
    alex = Robot.load("alexander")
    assert alex.base == "free" and set(alex.contacts) == {"left", "right"}
    assert alex.legs["left"].knee == "LEFT_KNEE_Y"
    assert alex.fingerprint == Robot.from_library("alexander").fingerprint
    assert alex.fingerprint != Robot.load("hoap2").fingerprint
    with pytest.raises(UnknownRobotError, match="hoap2"):
        Robot.load("no_such_robot")
    with pytest.raises(InvalidInputError, match=r"\.urdf or \.osim"):
        Robot.load(tmp_path / "model.sdf")
    with pytest.raises(InvalidInputError, match="own legs"):
        Robot.load(D3 / "subject01.osim", legs={})


def _leg_urdf(imu: bool) -> str:
    """A floating biped (pelvis, legs of hip/knee/ankle pitch joints about y) whose feet carry
    an IMU link 5 cm below the foot when ``imu``."""
    def link(name, m=1.0):
        return (f'<link name="{name}"><inertial><mass value="{m}"/><inertia ixx="0.01" '
                'ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>')

    def joint(name, parent, child, xyz, kind="revolute"):
        lim = '<limit lower="-2" upper="2" effort="50" velocity="5"/>' if kind != "fixed" else ""
        ax = '<axis xyz="0 1 0"/>' if kind != "fixed" else ""
        return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
                f'<child link="{child}"/><origin xyz="{xyz}"/>{ax}{lim}</joint>')

    parts = [link("pelvis", 5.0)]
    for s, y in (("left", 0.1), ("right", -0.1)):
        parts += [link(f"{s}_thigh"), link(f"{s}_shank"), link(f"{s}_foot", 0.5),
                  joint(f"{s}_hip", "pelvis", f"{s}_thigh", f"0 {y} 0"),
                  joint(f"{s}_knee", f"{s}_thigh", f"{s}_shank", "0 0 -0.4"),
                  joint(f"{s}_ankle", f"{s}_shank", f"{s}_foot", "0 0 -0.4")]
        if imu:
            parts += [link(f"{s}_foot_imu_link", 0.01),
                      joint(f"{s}_foot_imu_joint", f"{s}_foot", f"{s}_foot_imu_link",
                            "0 0 -0.05", "fixed")]
    return '<robot name="imu_biped">' + "".join(parts) + "</robot>"


def test_sole_detection_never_picks_a_sensor_frame(tmp_path):
    p = tmp_path / "biped.urdf"
    p.write_text(_leg_urdf(imu=True))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = Robot.load(p)
    # the IMU link is the lowest frame whose name says "foot": it must not be the sole
    assert r.legs["left"].sole == "left_foot" and r.legs["right"].sole == "right_foot"
    assert r.legs["left"].foot == pytest.approx(0.0)  # sole at the ankle, not 5 cm below


def test_missing_mesh_names_the_file_and_suggests_package_dir(tmp_path):
    p = tmp_path / "m.urdf"
    p.write_text('<robot name="m"><link name="a"><inertial><mass value="1"/><inertia ixx="1" '
                 'ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial><visual><geometry>'
                 '<mesh filename="package://mypkg/meshes/a.stl"/></geometry></visual></link>'
                 '</robot>')
    with pytest.raises(MeshPathError, match="package_dir") as e:
        Robot.from_urdf(p)
    assert "a.stl" in str(e.value) and "--package-dir" in str(e.value)
    json.dumps(str(e.value))
