"""OpenSim model → URDF conversion, checked against OpenSim itself.

OpenSim (``opensim`` 4.6) cannot share a process with casadi (hence with gdimitate), so
``tests/opensim_ref/osim_kinematics.py`` runs in a subprocess, once per module per model, and
writes every body origin/orientation, marker and the centre of mass at every frame to a .npz.

Bounds: exact joints (every rotation and translation that is a slope ±1 LinearFunction, all
offsets, Pin/Weld/Ball/Universal joints) to 1 µm / 1 µrad. Where a coupled motion is
approximated (the gait2354 knee's spline translation; the walker knee's spline rotations; a
patella on its own coordinate; a slope-0.5 elbow), a body's error is bounded by what the
converter reports for each approximated joint j above it: e_j + θ_j·|p_b − p_j| (position
error of j's child plus its orientation error times the lever arm), and the report must not
be vacuous (OpenSim's error reaches at least half of it on the sampled poses).
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gdimitate import Robot
from gdimitate.errors import OsimError, URDFError
from gdimitate.io.opensim import WORLD_FROM_OPENSIM as C
from gdimitate.io.opensim import (
    convert_osim,
    follow_coordinates,
    opensim_to_urdf,
    pelvis_to_freeflyer,
    read_osim,
)
from tests.helpers import ROOT, TESTS

DATA = ROOT / "gdimitate/data/gait/opensim_subject01_walk1_3d"
if not (DATA / "subject01.osim").is_file():  # the package copy, else the shared data folder
    DATA = ROOT.parent / "shared/data/gait/opensim_subject01_walk1_3d"
SUBJECT = DATA / "subject01.osim"
IK = DATA / "subject01_walk1_ik.mot"
SYNTH = TESTS / "data/osim/rajagopal_like.osim"
MINIMAL = TESTS / "data/osim/minimal_prefixed.osim"
SCRIPT = TESTS / "opensim_ref/osim_kinematics.py"

needs_opensim = pytest.mark.skipif(importlib.util.find_spec("opensim") is None,
                                   reason="the OpenSim reference needs the `opensim` wheel")
needs_data = pytest.mark.skipif(not SUBJECT.is_file(), reason="subject01 data not present")


def _reference(model: Path, out: Path, *args: str) -> dict:
    subprocess.run([sys.executable, str(SCRIPT), str(model), str(out), *args], check=True,
                   capture_output=True, timeout=120)
    d = np.load(out)
    return {k: d[k] for k in d.files}


@pytest.fixture(scope="module")
def subject(tmp_path_factory):
    if importlib.util.find_spec("opensim") is None or not SUBJECT.is_file():
        pytest.skip("needs opensim and the subject01 data")
    tmp = tmp_path_factory.mktemp("osim01")
    ref = _reference(SUBJECT, tmp / "ref.npz", "--mot", str(IK))
    return convert_osim(SUBJECT, tmp / "subject01.urdf"), ref


def _random_reference(tmp_path_factory, path: Path, seed: int):
    """Random poses within every coordinate's range (free-flyer near the origin), OpenSim's
    kinematics of them, and the conversion."""
    if importlib.util.find_spec("opensim") is None:
        pytest.skip("needs opensim")
    tmp = tmp_path_factory.mktemp(path.stem)
    model = read_osim(path)
    rng = np.random.default_rng(seed)
    names = [c.name for c in model.coordinates]
    lo = np.array([c.range[0] for c in model.coordinates])
    hi = np.array([c.range[1] for c in model.coordinates])
    q = lo + (hi - lo) * rng.random((80, len(names)))
    root = {c.name for c in model.joints[0].coordinates}
    for k, n in enumerate(names):  # keep the free-flyer near the origin
        if n in root:
            q[:, k] = rng.uniform(-0.6, 0.6, len(q))
    np.savez(tmp / "q.npz", names=np.array(names), q=q)
    ref = _reference(path, tmp / "ref.npz", "--q", str(tmp / "q.npz"))
    return convert_osim(path, tmp / f"{path.stem}.urdf"), ref


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    return _random_reference(tmp_path_factory, SYNTH, 7)


@pytest.fixture(scope="module")
def minimal(tmp_path_factory):
    return _random_reference(tmp_path_factory, MINIMAL, 3)


def _pin_trajectory(conv, ref):
    """Pinocchio model of the URDF and the reference's coordinates as its q (T, nq)."""
    m = pin.buildModelFromUrdf(str(conv.urdf), pin.JointModelFreeFlyer())
    names = [str(n) for n in ref["names"]]
    q = ref["q"]
    root = [c.name for c in conv.model.joint(conv.root_joint).coordinates]
    Q = np.zeros((len(q), m.nq))
    Q[:, :7] = pelvis_to_freeflyer({n: q[:, names.index(n)] for n in root}, conv.model)
    for k, n in enumerate(names):
        if n not in root and m.existJointName(n):
            Q[:, m.joints[m.getJointId(n)].idx_q] = q[:, k]
    follow_coordinates(conv.plans, Q, lambda j: m.joints[m.getJointId(j)].idx_q)
    return m, Q


def _errors(conv, ref):
    """Per frame and body: position error [m], orientation error [rad], the bound (see the
    module docstring); per frame and marker: error and bound; CoM error [m]."""
    m, Q = _pin_trajectory(conv, ref)
    d = m.createData()
    bodies = [str(b) for b in ref["bodies"]]
    approx = {a.joint: a for a in conv.approximations}
    above = {}  # body -> approximated joints on its path from the root (joint, its child)
    for b in bodies:
        chain, x = [], b
        while x != conv.root:
            j = conv.model.joint_of(x)
            if j.name in approx:
                chain.append((approx[j.name], j.child))
            x = j.parent
        above[b] = chain
    T = len(Q)
    out = {k: np.zeros((T, len(bodies))) for k in ("pos", "rot", "bound")}
    marks = [str(x) for x in ref["markers"]]
    mk_err, mk_bound = np.zeros((T, len(marks))), np.zeros((T, len(marks)))
    com = np.zeros(T)
    fid = {b: m.getFrameId(b, pin.BODY) for b in bodies}
    for t in range(T):
        pin.framesForwardKinematics(m, d, Q[t])
        P = {b: d.oMf[fid[b]].translation.copy() for b in bodies}

        def bound(b, p, P=P):
            return 1e-6 + sum(a.max_position_error + a.max_rotation_error *
                              np.linalg.norm(p - P[child]) for a, child in above[b])

        for i, b in enumerate(bodies):
            M = d.oMf[fid[b]]
            out["pos"][t, i] = np.linalg.norm(M.translation - C @ ref["body_p"][t, i])
            Rr = C @ ref["body_R"][t, i] @ C.T  # angle via ‖ΔR‖_F = 2√2 sin(θ/2)
            out["rot"][t, i] = 2 * np.arcsin(min(np.linalg.norm(Rr - M.rotation) / 8**0.5, 1))
            out["bound"][t, i] = bound(b, M.translation)
        for i, n in enumerate(marks):
            p = d.oMf[m.getFrameId(n)].translation
            mk_err[t, i] = np.linalg.norm(p - C @ ref["marker_p"][t, i])
            mk_bound[t, i] = bound(conv.model.markers[i].body, p)
        com[t] = np.linalg.norm(pin.centerOfMass(m, d, Q[t]) - C @ ref["com"][t])
    return bodies, out, mk_err, mk_bound, com, m


# ------------------------------------------------------------------ subject01 (gait2354)
@needs_opensim
@needs_data
def test_subject01_mass_and_structure(subject):
    conv, ref = subject
    m = pin.buildModelFromUrdf(str(conv.urdf), pin.JointModelFreeFlyer())
    assert pin.computeTotalMass(m) == pytest.approx(float(ref["mass"]), abs=1e-9)
    assert float(ref["mass"]) == pytest.approx(72.6, abs=1e-6)
    coords = [c.name for c in conv.model.coordinates if c.name not in
              [c.name for c in conv.model.joint(conv.root_joint).coordinates]]
    assert sorted(list(m.names)[2:]) == sorted(coords)  # one URDF joint per coordinate
    for b in conv.model.bodies:
        assert m.existFrame(b.name, pin.BODY)
    assert m.nq == 7 + 17


@needs_opensim
@needs_data
def test_subject01_ik_frames_match_opensim(subject):
    """All 211 IK frames: body origins within 1 mm except below the knees, whose spline
    translation is approximated by a fixed hinge (bounded by its reported error, < 3.5 mm
    over the whole knee range); orientations exact; centre of mass within 2 mm."""
    conv, ref = subject
    assert ref["q"].shape == (211, 23)
    bodies, e, mk_err, mk_bound, com, _ = _errors(conv, ref)
    knees = {a.joint: a for a in conv.approximations}
    assert set(knees) == {"knee_r", "knee_l"}
    for a in knees.values():
        assert a.method == "fixed-centre fit"
        assert a.max_position_error < 3.5e-3  # as the joints module docstring states
    assert np.all(e["pos"] <= e["bound"])
    assert np.all(e["rot"] < 1e-6)
    exact = [i for i, b in enumerate(bodies) if not b.startswith(("tibia", "talus", "calcn",
                                                                  "toes"))]
    assert e["pos"][:, exact].max() < 1e-6
    assert e["pos"].max() < 3.5e-3
    assert com.max() < 2e-3
    print(f"\nsubject01, 211 IK frames: body origins max {e['pos'].max() * 1e3:.2f} mm "
          f"(knee hinge bound {knees['knee_r'].max_position_error * 1e3:.2f} mm), CoM max "
          f"{com.max() * 1e3:.3f} mm, markers max {mk_err.max() * 1e3:.2f} mm")


@needs_opensim
@needs_data
def test_subject01_centroidal_inertia_and_limits(subject):
    """Whole-body inertia about the centre of mass (Pinocchio's ccrba) equals the one summed
    from OpenSim's per-body masses, centres of mass, inertias and poses, up to what the knee
    approximation moves: a body shifted by δ at distance r from the centre of mass changes an
    entry by at most 2m(2rδ + δ²). Joint limits are OpenSim's coordinate ranges."""
    conv, ref = subject
    bodies, e, _, _, com_err, m = _errors(conv, ref)
    _, Q = _pin_trajectory(conv, ref)
    d = m.createData()
    worst = 0.0
    for t in range(0, len(Q), 5):
        pin.ccrba(m, d, Q[t], np.zeros(m.nv))
        c = ref["com"][t]
        I_os, bound = np.zeros((3, 3)), 1e-9
        for i in range(len(bodies)):
            R, mb = ref["body_R"][t, i], float(ref["body_mass"][i])
            r = R @ ref["body_com"][i] + ref["body_p"][t, i] - c
            I_os += R @ ref["body_inertia"][i] @ R.T + mb * (r @ r * np.eye(3) - np.outer(r, r))
            delta = e["bound"][t, i] + com_err[t]
            bound += 2 * mb * (2 * np.linalg.norm(r) * delta + delta**2)
        err = np.abs(d.Ig.inertia - C @ I_os @ C.T).max()
        assert err <= bound, (t, err, bound)
        worst = max(worst, err / np.trace(I_os))
    assert worst < 1e-3
    coords = [str(n) for n in ref["coordinates"]]
    for n, (lo, hi) in zip(coords, ref["ranges"]):
        if m.existJointName(n):
            j = m.joints[m.getJointId(n)]
            assert m.lowerPositionLimit[j.idx_q] == pytest.approx(lo, abs=1e-12)
            assert m.upperPositionLimit[j.idx_q] == pytest.approx(hi, abs=1e-12)


@needs_opensim
@needs_data
def test_subject01_marker_frames(subject):
    conv, ref = subject
    assert len(conv.markers) == 39
    assert list(conv.markers) == [str(x) for x in ref["markers"]]
    _, _, mk_err, mk_bound, _, m = _errors(conv, ref)
    for n in conv.markers:
        assert m.existFrame(n)
    assert np.all(mk_err <= mk_bound)
    on_exact = [i for i, mk in enumerate(conv.model.markers)
                if not mk.body.startswith(("tibia", "talus", "calcn", "toes"))]
    assert mk_err[:, on_exact].max() < 1e-6


@needs_data
def test_robot_from_osim_legs_and_soles():
    t0 = time.perf_counter()
    robot = Robot.from_osim(SUBJECT)
    seconds = time.perf_counter() - t0
    assert robot.base == "free"
    assert robot.mass == pytest.approx(72.6, abs=1e-9)
    for s, x in (("left", "l"), ("right", "r")):
        leg = robot.legs[s]
        assert (leg.hip, leg.knee, leg.ankle) == (f"hip_flexion_{x}", f"knee_angle_{x}",
                                                 f"ankle_angle_{x}")
        assert leg.sole == f"calcn_{x}_sole"
        assert robot.contacts[s].frame == f"calcn_{x}_contact"
        assert 0.25 < 2 * robot.contacts[s].half_length < 0.32  # adult foot (shod)
        assert 0.08 < 2 * robot.contacts[s].half_width < 0.13
    # upright at q = 0: the measured base rotation is within 1° of identity
    assert np.degrees(np.arccos((np.trace(robot.base_rotation) - 1) / 2)) < 1.0
    print(f"\nRobot.from_osim(subject01): {seconds * 1e3:.0f} ms (convert + load)")


@needs_data
def test_declared_soles_match_the_feet_geometry():
    """Robot's own sole measurement from the URDF's visual geometry (gdimitate.contact) finds
    the rectangles the converter declares: the foot boxes and sole frames agree."""
    conv = convert_osim(SUBJECT)
    legs = {s: {k: conv.legs[s][k] for k in ("hip", "knee", "ankle", "sole")}
            for s in ("left", "right")}
    robot = Robot.from_urdf(conv.urdf, legs, floating=True)  # soles measured, not passed
    assert robot.visual_model is not None
    for s in ("left", "right"):
        c = robot.contacts[s]
        assert c.half_length == pytest.approx(conv.soles[s][0], abs=1e-4)
        assert c.half_width == pytest.approx(conv.soles[s][1], abs=1e-4)
        pin.framesForwardKinematics(robot.model, robot.data, robot.neutral)
        measured = robot.data.oMf[robot.frame_id(c.frame)].translation
        declared = robot.data.oMf[robot.frame_id(conv.legs[s]["contact"])].translation
        assert np.linalg.norm(measured - declared) < 1e-3


@needs_data
def test_subject01_cop_inside_sole_rectangles():
    """Measured centres of pressure (force plates, independent of the model) fall inside the
    converted sole rectangles at every IK frame with more than 200 N on that foot."""
    robot = Robot.from_osim(SUBJECT)
    lines = (DATA / "subject01_walk1_grf.mot").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.strip().lower() == "endheader")
    cols, G = lines[k + 1].split(), np.loadtxt(lines[k + 2:])
    lines_ik = (DATA / "subject01_walk1_ik.mot").read_text().splitlines()
    k2 = next(i for i, ln in enumerate(lines_ik) if ln.strip().lower() == "endheader")
    ik_cols, ik = lines_ik[k2 + 1].split(), np.loadtxt(lines_ik[k2 + 2:])
    m, d = robot.model, robot.data
    model = robot.osim.model
    rad = {c.name: (np.pi / 180 if c.motion_type == "rotational" else 1.0)
           for c in model.coordinates}
    vals = {n: ik[:, ik_cols.index(n)] * rad[n] for n in ik_cols[1:]}
    Q = np.zeros((len(ik), m.nq))
    root = [c.name for c in model.joint(robot.osim.root_joint).coordinates]
    Q[:, :7] = pelvis_to_freeflyer({n: vals[n] for n in root}, model)
    for n, v in vals.items():
        if n not in root:
            Q[:, robot.idx_q(n)] = v
    for side, pre in (("right", "ground_"), ("left", "l_ground_")):
        fy = np.interp(ik[:, 0], G[:, 0], G[:, cols.index(pre + "force_vy")])
        cop = np.column_stack([np.interp(ik[:, 0], G[:, 0], G[:, cols.index(pre + f"force_p{a}")])
                               for a in "xyz"])
        c = robot.contacts[side]
        fid = robot.frame_id(c.frame)
        n = 0
        for t in np.flatnonzero(fy > 200):
            pin.framesForwardKinematics(m, d, Q[t])
            loc = d.oMf[fid].actInv(C @ cop[t])
            assert abs(loc[0]) <= c.half_length and abs(loc[1]) <= c.half_width, (side, t, loc)
            n += 1
        assert n > 80


@needs_data
def test_subject01_feet_on_the_force_plate_floor():
    """Issue 20: with the subject's marker trial, each converted sole lies on the floor below
    the foot's markers; at mid-stance (the middle frame of every complete stance, measured
    contact) the sole rectangle's centre is within 1 cm of the force plates' surface (the
    height of the measured centres of pressure). Measured: left 5.4 / 6.0 mm above, right
    −1.3…+0.2 mm. From the bones alone (no markers) the soles stood 4.6–5.4 cm above it."""
    from gdimitate.io.opensim import read_coordinates, read_grf

    def heights(robot):
        motion = read_coordinates(IK, robot)
        forces = read_grf(DATA / "subject01_walk1_grf.mot", robot, DATA / "subject01_walk1_grf.xml",
                          t=motion.t)
        out = []
        for s in ("left", "right"):
            f = forces[s]
            d = np.diff(np.r_[0, f.contact.astype(int), 0])
            fid = robot.frame_id(robot.contacts[s].frame)
            for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)):
                if a > 0 and b < motion.T:
                    k = (a + b) // 2
                    pin.framesForwardKinematics(robot.model, robot.data, motion.q[k])
                    out.append(robot.data.oMf[fid].translation[2] - f.cop[k, 2])
        return np.array(out)

    on_floor = heights(Robot.from_osim(SUBJECT, markers=DATA / "subject01_walk1.trc"))
    assert on_floor.size >= 4 and np.all(np.abs(on_floor) <= 0.01), on_floor
    assert np.all(heights(Robot.from_osim(SUBJECT)) > 0.035)  # the bones' sole, as before
    print(f"\nsoles at mid-stance: {np.round(on_floor * 1e3, 1)} mm from the force-plate floor")


# ------------------------------------------------------------------ synthetic Rajagopal-like
@needs_opensim
def test_synthetic_rajagopal_like_matches_opensim(synthetic):
    conv, ref = synthetic
    m = pin.buildModelFromUrdf(str(conv.urdf), pin.JointModelFreeFlyer())
    assert pin.computeTotalMass(m) == pytest.approx(float(ref["mass"]), abs=1e-9)
    approx = {a.joint: a for a in conv.approximations}
    assert set(approx) == {"walker_knee_r", "patellofemoral_r", "knee_l", "elbow_r"}
    # issue 20: the walker knee's coupled axes are spline-driven joints (was "fixed-axis fit +
    # fixed-centre fit", 5.5 mm / 0.9° off): exact up to round-off
    assert approx["walker_knee_r"].method == "spline-driven joints"
    assert approx["walker_knee_r"].max_position_error < 1e-9
    assert approx["walker_knee_r"].max_rotation_error < np.radians(1.0)
    assert approx["patellofemoral_r"].method == "held at default"
    assert approx["elbow_r"].method == "held at default"
    # exact: BallJoint shoulder, UniversalJoint wrist, PinJoints, WeldJoint toes, slope -1 hip
    for c in ("arm_flex_r", "arm_add_r", "arm_rot_r", "wrist_flex_r", "wrist_dev_r",
              "ankle_angle_r", "subtalar_angle_l", "hip_adduction_l", "hip_rotation_l",
              "lumbar_extension", "knee_angle_r", "knee_angle_l"):
        assert m.existJointName(c)
    assert not m.existJointName("knee_angle_r_beta") and not m.existJointName("elbow_flex_r")
    bodies, e, mk_err, mk_bound, com, _ = _errors(conv, ref)
    assert np.all(e["pos"] <= e["bound"]), np.max(e["pos"] - e["bound"])
    assert np.all(mk_err <= mk_bound)
    exact = ["pelvis", "femur_r", "femur_l", "torso", "humerus_r"]
    for b in exact:
        i = bodies.index(b)
        assert e["pos"][:, i].max() < 1e-6 and e["rot"][:, i].max() < 1e-6, b
    for j, a in approx.items():  # the reported errors are reached (not vacuous)
        i = bodies.index(conv.model.joint(j).child)
        assert e["pos"][:, i].max() >= 0.5 * a.max_position_error, j
        assert e["rot"][:, i].max() <= a.max_rotation_error + 1e-9, j
        if a.max_rotation_error > 1e-9:
            assert e["rot"][:, i].max() >= 0.5 * a.max_rotation_error, j
    print("\nrajagopal_like: " + "; ".join(
        f"{a.joint} {a.method}: {a.max_position_error * 1e3:.1f} mm, "
        f"{np.degrees(a.max_rotation_error):.1f} deg" for a in conv.approximations))


@needs_opensim
def test_walker_knee_sweep_matches_opensim(tmp_path):
    """Issue 20: the synthetic model's walker knee (flexion positive, range 0…120°; its
    ab/adduction, axial rotation and translations splines of the flexion) swept from −10° to
    120° (OpenSim's extrapolation beyond the range included), every other coordinate at its
    default: every body origin within 5 mm of OpenSim's and every orientation within 0.1°
    (measured: 1e-7 m, 1e-7 rad — spline-driven joints; the fixed-axis fit they replace was
    5.5 mm / 0.9° off at the tibia, 8.2 mm at the ankle), and the conversion reports it in
    ``robot.osim.approximations``."""
    model = read_osim(SYNTH)
    names = [c.name for c in model.coordinates]
    sweep = np.radians(np.linspace(-10.0, 120.0, 27))
    q = np.tile([c.default for c in model.coordinates], (sweep.size, 1))
    q[:, names.index("knee_angle_r")] = sweep
    np.savez(tmp_path / "q.npz", names=np.array(names), q=q)
    ref = _reference(SYNTH, tmp_path / "ref.npz", "--q", str(tmp_path / "q.npz"))
    approx = {a.joint: a for a in Robot.from_osim(SYNTH).osim.approximations}
    assert approx["walker_knee_r"].method == "spline-driven joints"
    bodies, e, *_ = _errors(convert_osim(SYNTH, tmp_path / "rl.urdf"), ref)
    leg = [bodies.index(b) for b in ("tibia_r", "talus_r", "calcn_r", "toes_r")]
    assert e["pos"][:, leg].max() < 5e-3 and e["rot"][:, leg].max() < np.radians(0.1)
    assert e["pos"][:, leg].max() < 1e-5  # in fact exact: round-off
    print(f"\nwalker knee −10…120°: max body-origin error {e['pos'][:, leg].max():.2e} m, "
          f"orientation {e['rot'][:, leg].max():.2e} rad")


def test_synthetic_converts_without_opensim(tmp_path):
    robot = Robot.from_osim(SYNTH)
    assert robot.base == "free"
    assert robot.legs["right"].knee == "knee_angle_r"
    assert robot.legs["left"].ankle == "ankle_angle_l"
    # knee positive in flexion (Rajagopal): flexing moves the ankle backwards (-x)
    q = robot.neutral.copy()
    pin.forwardKinematics(robot.model, robot.data, q)
    a0 = robot.data.oMi[robot.model.getJointId("ankle_angle_r")].translation.copy()
    q[robot.idx_q("knee_angle_r")] = 0.5
    pin.forwardKinematics(robot.model, robot.data, q)
    a1 = robot.data.oMi[robot.model.getJointId("ankle_angle_r")].translation
    assert a1[0] < a0[0] - 0.1
    assert opensim_to_urdf(SYNTH, tmp_path / "x.urdf") == tmp_path / "x.urdf"


@needs_opensim
def test_minimal_free_gimbal_slider_model_is_exact(minimal):
    """FreeJoint root, GimbalJoint hips, SliderJoint, sockets naming bodies directly: no
    approximation, every body and marker within 1 µm of OpenSim."""
    conv, ref = minimal
    assert conv.approximations == ()
    assert conv.root_joint == "root"
    bodies, e, mk_err, _, com, m = _errors(conv, ref)
    assert e["pos"].max() < 1e-6 and e["rot"].max() < 1e-6 and mk_err.max() < 1e-6
    assert com.max() < 1e-6
    assert m.joints[m.getJointId("pack_slide")].shortname().startswith("JointModelP")
    robot = Robot.from_osim(MINIMAL)
    assert (robot.legs["right"].hip, robot.legs["right"].knee, robot.legs["right"].ankle) == (
        "r_hip_z", "r_knee_angle", "r_ankle_angle")
    assert robot.legs["left"].sole == "l_foot_sole"


# ------------------------------------------------------------------ malformed files
@pytest.mark.parametrize("pattern,new,message", [
    (r'<Body name="tibia_r">.*?</Body>', "", "child 'tibia_r', which is no body"),
    (r'(name="pelvis_offset_hip_r"><socket_parent>)/bodyset/pelvis',
     r"\1/bodyset/nonexistent", "joint 'hip_r' has parent 'nonexistent'"),
    (r"<LinearFunction><coefficients>1 0</coefficients></LinearFunction>",
     "<StepFunction><transition_start_time>0</transition_start_time></StepFunction>",
     "unsupported function type <StepFunction>"),
    (r"<mass>9.0</mass>", "<mass>nan</mass>", "body 'femur_r' has mass 'nan'"),
    (r'(<Coordinate name="hip_flexion_r">)',
     r'<Coordinate name="hip_extra_r"><default_value>0</default_value></Coordinate>\1',
     "coordinate 'hip_extra_r' is referenced by no TransformAxis"),
    (r'<PinJoint name="ankle_l">(.*?)</PinJoint>', r'<EllipsoidJoint name="ankle_l">\1'
     "</EllipsoidJoint>", "unsupported joint type <EllipsoidJoint>"),
    (r"<coordinates>hip_flexion_r</coordinates>", "<coordinates>hip_flex_typo</coordinates>",
     "does not define"),
    (r'(<\?xml[^>]*\?>)', r'\1<!DOCTYPE x [<!ENTITY a "b">]>', "DOCTYPE"),
])
def test_malformed_models_raise_osim_error(tmp_path, pattern, new, message):
    text = SYNTH.read_text()
    bad_text, n = re.subn(pattern, new, text, count=1, flags=re.S)
    assert n == 1
    bad = tmp_path / "bad.osim"
    bad.write_text(bad_text)
    with pytest.raises(OsimError, match=re.escape(message)) as info:
        opensim_to_urdf(bad, tmp_path / "bad.urdf")
    assert isinstance(info.value, URDFError)


def test_missing_file_and_bodies(tmp_path):
    with pytest.raises(OsimError, match="not found"):
        read_osim(tmp_path / "none.osim")
    p = tmp_path / "empty.osim"
    p.write_text('<OpenSimDocument Version="40000"><Model name="x"><BodySet><objects/>'
                 "</BodySet></Model></OpenSimDocument>")
    with pytest.raises(OsimError, match="no bodies"):
        read_osim(p)
