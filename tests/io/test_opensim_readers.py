"""OpenSim readers (coordinates, GRF, TRC) on synthetic files whose values are known in closed
form, and on the shipped 3-D walk against OpenSim's own inverse dynamics and the measured
markers."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from gdimitate.errors import (
    CoordinateMismatchError,
    CoordinateMismatchWarning,
    ForceDataError,
    MarkerGapWarning,
    OpenSimDataError,
    TimeGridError,
    UnitError,
)
from gdimitate.io.opensim.coordinates import read_coordinates
from gdimitate.io.opensim.grf import read_external_loads, read_grf
from gdimitate.model.osim.trc import read_trc
from gdimitate.model.robot import Robot
from tests.helpers import ROOT, TESTS

DATA = TESTS / "data" / "opensim_files"
Y_UP = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # OpenSim (X, Y, Z) → ours (x, y, z)


@functools.cache
def biped() -> Robot:
    """A hand-written URDF whose joints are named after OpenSim coordinates."""
    legs = {s: {"hip": f"hip_flexion_{c}", "knee": f"knee_angle_{c}",
                "ankle": f"ankle_angle_{c}", "sole": f"sole_{c}"}
            for s, c in (("left", "l"), ("right", "r"))}
    return Robot.from_urdf(DATA / "biped.urdf", legs)


def write_table(path: Path, names, data, header=("version=1", "inDegrees=yes")) -> Path:
    data = np.asarray(data, dtype=float)
    lines = [path.name, *header, f"nRows={data.shape[0]}", f"nColumns={data.shape[1]}",
             "endheader", "\t".join(names)]
    lines += ["\t".join(f"{v:.17g}" for v in row) for row in data]
    path.write_text("\n".join(lines) + "\n")
    return path


# ====================================================================== coordinates
def _angles(t):
    return {"hip_flexion_r": 30 * np.sin(2 * np.pi * t), "hip_adduction_r": 5 * np.cos(t),
            "knee_angle_r": -40 + 10 * t, "ankle_angle_r": 8 * t,
            "hip_flexion_l": -20 * t, "hip_adduction_l": np.full_like(t, 2.0),
            "knee_angle_l": -10 * t, "ankle_angle_l": 3 * np.sin(t),
            "lumbar_rotation": 170 + 30 * t}


def test_mot_in_degrees_plain_names(tmp_path):
    t = np.linspace(0.5, 1.5, 31)
    a = _angles(t)
    names = ["time", *a, "spine_tz"]
    data = np.column_stack([t, *a.values(), 0.02 * t])
    p = write_table(tmp_path / "ik.mot", names, data)
    r = biped()
    m = read_coordinates(p, r)
    np.testing.assert_array_equal(m.t, t)
    for c, deg in a.items():
        if c == "lumbar_rotation":  # unbounded joint: (cos, sin) of the angle
            i = r.idx_q(c)
            np.testing.assert_allclose(m.q[:, i], np.cos(np.radians(deg)), atol=1e-12)
            np.testing.assert_allclose(m.q[:, i + 1], np.sin(np.radians(deg)), atol=1e-12)
        else:
            np.testing.assert_allclose(m.column(c), np.radians(deg), atol=1e-12)
    np.testing.assert_allclose(m.column("spine_tz"), 0.02 * t, atol=1e-12)  # metres, unscaled
    assert m.base_nq == 7 and m.q.shape == (31, r.model.nq)


def test_sto_radians_jointset_paths_and_ignored_states(tmp_path):
    t = np.linspace(0.0, 1.0, 21)
    a = {k: np.radians(v) for k, v in _angles(t).items() if k != "lumbar_rotation"}
    joint_of = {"hip": "hip", "knee": "knee", "ankle": "ankle"}
    names = ["time"]
    cols = [t]
    for c, v in a.items():
        j = f"{joint_of[c.split('_')[0]]}_{c[-1]}"
        names += [f"/jointset/{j}/{c}/value", f"/jointset/{j}/{c}/speed"]
        cols += [v, np.gradient(v, t)]
    names += ["/forceset/soleus_r/activation"]
    cols += [np.full_like(t, 0.1)]
    p = write_table(tmp_path / "states.sto", names, np.column_stack(cols),
                    header=("version=1", "inDegrees=no"))
    with pytest.warns(CoordinateMismatchWarning) as rec:
        m = read_coordinates(p, biped())
    msg = str(rec[0].message)
    # the model coordinates the file lacks are named, and the ignored state columns counted
    assert "spine_tz" in msg and "lumbar_rotation" in msg and "9 (" in msg
    for c, v in a.items():
        np.testing.assert_allclose(m.column(c), v, atol=1e-12)
    np.testing.assert_allclose(m.column("spine_tz"), 0.0)  # neutral where the file lacks it


def test_columns_the_model_lacks_are_listed(tmp_path):
    t = np.linspace(0, 1, 11)
    p = write_table(tmp_path / "x.mot", ["time", "knee_angle_r", "subtalar_angle_r", "mtp_x"],
                    np.column_stack([t, 10 * t, t, t]))
    with pytest.warns(CoordinateMismatchWarning, match=r"subtalar_angle_r.*mtp_x|mtp_x.*subt"):
        m = read_coordinates(p, biped())
    np.testing.assert_allclose(m.column("knee_angle_r"), np.radians(10 * t), atol=1e-12)


@pytest.mark.filterwarnings("ignore::gdimitate.errors.CoordinateMismatchWarning")
def test_unit_flag_contradicting_values(tmp_path):
    t = np.linspace(0, 1, 11)
    p = write_table(tmp_path / "bad.mot", ["time", "knee_angle_r", "hip_flexion_r"],
                    np.column_stack([t, -60 * t, 20 * t]), header=("inDegrees=no",))
    with pytest.raises(UnitError, match="inDegrees=yes"):
        read_coordinates(p, biped())
    p2 = write_table(tmp_path / "flagless.mot", ["time", "knee_angle_r"],
                     np.column_stack([t, -60 * t]), header=("version=1",))
    with pytest.raises(UnitError, match="no inDegrees flag"):
        read_coordinates(p2, biped())


def test_coordinate_file_for_another_model(tmp_path):
    t = np.linspace(0, 1, 11)
    p = write_table(tmp_path / "arm.mot", ["time", "elbow_flex_r", "wrist_dev_r"],
                    np.column_stack([t, t, t]))
    with pytest.raises(CoordinateMismatchError, match="elbow_flex_r"):
        read_coordinates(p, biped())


@pytest.mark.parametrize("bad", ["nan", "time", "ragged", "noheader", "dup"])
def test_malformed_coordinate_files(tmp_path, bad):
    t = np.linspace(0, 1, 11)
    data = np.column_stack([t, 10 * t])
    names = ["time", "knee_angle_r"]
    if bad == "nan":
        data[4, 1] = np.nan
    if bad == "time":
        data[5, 0] = data[4, 0]
    if bad == "dup":
        names = ["time", "knee_angle_r", "/jointset/knee_r/knee_angle_r/value"]
        data = np.column_stack([t, t, t])
    p = write_table(tmp_path / "m.mot", names, data)
    if bad == "ragged":
        p.write_text(p.read_text() + "1.5\t3\t4\n")
    if bad == "noheader":
        p.write_text(p.read_text().replace("endheader\n", ""))
    err = TimeGridError if bad == "time" else OpenSimDataError
    with pytest.raises(err) as e:
        read_coordinates(p, biped())
    assert str(p) in str(e.value)
    hint = {"nan": "NaN", "time": "strictly increasing", "ragged": "one value per column",
            "noheader": "endheader", "dup": "appears twice"}[bad]
    assert hint in str(e.value)


# ====================================================================== GRF
def _foot_signals(t):
    """Closed-form plate data (OpenSim Y-up lab): right stance 0–0.6 s, left 0.4–1.0 s."""
    out = {}
    for side, t0 in (("right", 0.0), ("left", 0.4)):
        s = np.clip((t - t0) / 0.6, 0, 1)
        fy = 700 * np.sin(np.pi * s)
        fx = 80 * np.sin(2 * np.pi * s)
        fz = (-30 if side == "right" else 30) * np.sin(np.pi * s)
        px = 0.2 + 0.25 * s
        pz = 0.09 if side == "right" else -0.09
        out[side] = dict(v=np.column_stack([fx, fy, fz]),
                         p=np.column_stack([px, np.full_like(t, 0.01), np.full_like(t, pz)]),
                         m=np.column_stack([0 * t, 3 * np.sin(np.pi * s), 0 * t]))
    return out


def _grf_file(path, t, sig, convention, up="Y"):
    names, cols = ["time"], [t]
    pre = {"l_prefix": {"right": ("", ""), "left": ("l_", "")},
           "rl_infix": {"right": ("", "r_"), "left": ("", "l_")},
           "numbered": {"right": ("", ""), "left": ("1_", "")},
           "plates": {"right": ("2_", ""), "left": ("1_", "")}}[convention]
    for side in ("right", "left"):
        a, b = pre[side]
        v, p, m = sig[side]["v"], sig[side]["p"], sig[side]["m"]
        if up == "Z":  # a Z-up lab with Y to the left: (X, Y, Z) = (x, y, z) = Y_UP·(X, Y, Z)
            v, p, m = v @ Y_UP.T, p @ Y_UP.T, m @ Y_UP.T
        for k, ax in enumerate("xyz"):
            names.append(f"{a}ground_force_{b}v{ax}")
            cols.append(v[:, k])
        for k, ax in enumerate("xyz"):
            names.append(f"{a}ground_force_{b}p{ax}")
            cols.append(p[:, k])
        for k, ax in enumerate("xyz"):
            names.append(f"{a}ground_torque_{b}{ax}")
            cols.append(m[:, k])
    return write_table(path, names, np.column_stack(cols), header=("version=1",))


@pytest.mark.parametrize("convention", ["l_prefix", "rl_infix", "numbered"])
@pytest.mark.parametrize("up", ["Y", "Z"])
def test_grf_naming_conventions_and_frames(tmp_path, convention, up):
    t = np.linspace(0, 1, 601)
    sig = _foot_signals(t)
    p = _grf_file(tmp_path / "grf.mot", t, sig, convention, up)
    cf = read_grf(p, biped())
    assert ("y = −Z" in cf.frame_note) == (up == "Y")
    for side in ("left", "right"):
        f = cf[side]
        np.testing.assert_allclose(f.force, sig[side]["v"] @ Y_UP.T, atol=1e-6)
        np.testing.assert_allclose(f.torque, sig[side]["m"] @ Y_UP.T, atol=1e-6)
        stance = (sig[side]["v"][:, 1] > 20.0)
        np.testing.assert_array_equal(f.contact, stance)
        np.testing.assert_allclose(f.cop[stance], (sig[side]["p"] @ Y_UP.T)[stance], atol=1e-9)
        assert np.isnan(f.cop[~stance]).all()
    # our world: the right foot is on the right (y < 0), vertical force up
    assert np.nanmean(cf["right"].cop[:, 1]) < 0 < np.nanmean(cf["left"].cop[:, 1])


def test_grf_resampled_onto_motion_times(tmp_path):
    t = np.linspace(0, 1, 601)
    sig = _foot_signals(t)
    p = _grf_file(tmp_path / "grf.mot", t, sig, "l_prefix")
    tm = np.arange(0.1, 0.9, 1 / 60)
    cf = read_grf(p, biped(), t=tm)
    np.testing.assert_array_equal(cf.t, tm)
    ref = _foot_signals(tm)  # the closed form at the motion times; linear interpolation error
    for side in ("left", "right"):  # of 600 Hz samples is below (dt²/8)·|f''| ≈ 0.03 N
        np.testing.assert_allclose(cf[side].force, ref[side]["v"] @ Y_UP.T, atol=0.05)
    with pytest.raises(OpenSimDataError, match="covers"):
        read_grf(p, biped(), t=np.array([0.5, 1.2]))


def _external_loads(path, forces):
    items = "".join(
        f"<ExternalForce name=\"{n}\"><applied_to_body>{b}</applied_to_body>"
        f"<force_expressed_in_body>ground</force_expressed_in_body>"
        f"<point_expressed_in_body>ground</point_expressed_in_body>"
        f"<force_identifier>{f}ground_force_v</force_identifier>"
        f"<point_identifier>{f}ground_force_p</point_identifier>"
        f"<torque_identifier>{f}ground_torque_</torque_identifier></ExternalForce>"
        for n, b, f in forces)
    path.write_text(f'<?xml version="1.0"?><OpenSimDocument Version="40000"><ExternalLoads>'
                    f"<objects>{items}</objects></ExternalLoads></OpenSimDocument>")
    return path


def test_grf_feet_from_external_loads(tmp_path):
    t = np.linspace(0, 1, 301)
    sig = _foot_signals(t)
    p = _grf_file(tmp_path / "grf.mot", t, sig, "plates")  # 2_ = right, 1_ = left plate
    with pytest.raises(ForceDataError, match="external_loads"):
        read_grf(p, biped())  # numbered plates: no side in the names
    xml = _external_loads(tmp_path / "loads.xml", [("A", "calcn_l", "1_"), ("B", "calcn_r", "2_")])
    cf = read_grf(p, biped(), xml)
    for side in ("left", "right"):
        np.testing.assert_allclose(cf[side].force, sig[side]["v"] @ Y_UP.T, atol=1e-6)
    assert "A→calcn_l→left" in cf.frame_note
    specs = read_external_loads(xml)
    assert [(s.name, s.body) for s in specs] == [("A", "calcn_l"), ("B", "calcn_r")]
    bad = _external_loads(tmp_path / "bad.xml", [("A", "femur_q", "1_"), ("B", "calcn_r", "2_")])
    with pytest.raises(ForceDataError, match="femur_q"):
        read_grf(p, biped(), bad)
    evil = tmp_path / "evil.xml"
    evil.write_text('<?xml version="1.0"?><!DOCTYPE x [<!ENTITY a "b">]>' + xml.read_text()
                    .split("?>", 1)[1])
    with pytest.raises(OpenSimDataError, match="DOCTYPE"):
        read_grf(p, biped(), evil)


def test_two_plates_on_one_foot_combine(tmp_path):
    """One foot's force split over two plates at two points: the combined centre of pressure is
    the force-weighted mean of the points (vertical forces, closed form), torques add."""
    t = np.linspace(0, 1, 101)
    w = 0.3 + 0.4 * t  # share of plate 1
    fy = 600 + 100 * t
    p1, p2 = np.array([0.3, 0.0, 0.1]), np.array([0.5, 0.0, 0.12])
    names, cols = ["time"], [t]
    for pre, share, pt, tz in (("1_", w, p1, 2.0), ("2_", 1 - w, p2, 1.0)):
        names += [f"{pre}ground_force_v{a}" for a in "xyz"]
        cols += [0 * t, share * fy, 0 * t]
        names += [f"{pre}ground_force_p{a}" for a in "xyz"]
        cols += [np.full_like(t, c) for c in pt]
        names += [f"{pre}ground_torque_{a}" for a in "xyz"]
        cols += [0 * t, np.full_like(t, tz), 0 * t]
    names += [f"3_ground_force_v{a}" for a in "xyz"] + [f"3_ground_force_p{a}" for a in "xyz"]
    cols += [0 * t, 650 + 0 * t, 0 * t, 0.4 + 0 * t, 0 * t, -0.1 + 0 * t]
    p = write_table(tmp_path / "g.mot", names, np.column_stack(cols), header=())
    xml = _external_loads(tmp_path / "x.xml", [("a", "calcn_r", "1_"), ("b", "calcn_r", "2_"),
                                                ("c", "calcn_l", "3_")])
    xml.write_text(xml.read_text().replace("<torque_identifier>3_ground_torque_</torque_"
                                           "identifier>", ""))
    with pytest.warns(CoordinateMismatchWarning, match="3_ground_force_v.*free torque"):
        cf = read_grf(p, biped(), xml)
    cop = (w[:, None] * p1 + (1 - w)[:, None] * p2) @ Y_UP.T
    np.testing.assert_allclose(cf["right"].cop[:, [0, 1]], cop[:, [0, 1]], atol=1e-12)
    np.testing.assert_allclose(cf["right"].force[:, 2], fy, atol=1e-9)
    np.testing.assert_allclose(cf["right"].torque, np.tile([0, 0, 3.0], (t.size, 1)), atol=1e-9)
    np.testing.assert_allclose(cf["left"].torque, 0.0)  # plate 3 has no torque identifier


@pytest.mark.parametrize("bad", ["noforce", "nan", "time", "mm", "down", "nocop"])
def test_malformed_grf_files(tmp_path, bad):
    t = np.linspace(0, 1, 101)
    sig = _foot_signals(t)
    p = _grf_file(tmp_path / "g.mot", t, sig, "rl_infix")
    text = p.read_text()
    lines = text.splitlines()
    names = lines[5].split("\t")
    data = np.loadtxt(lines[6:])
    if bad == "noforce":
        names = ["time"] + [f"marker_{i}" for i in range(1, len(names))]
    if bad == "nan":
        data[50, 2] = np.nan
    if bad == "time":
        data[[20, 21], 0] = data[[21, 20], 0]
    if bad == "mm":
        data[:, [n.endswith(("px", "py", "pz")) for n in names]] *= 1000
    if bad == "down":
        data[:, 1:] *= -1
    if bad == "nocop":
        keep = [i for i, n in enumerate(names) if "_l_p" not in n]
        names, data = [names[i] for i in keep], data[:, keep]
    write_table(p, names, data, header=("version=1",))
    err = {"noforce": ForceDataError, "nan": OpenSimDataError, "time": TimeGridError,
           "mm": UnitError, "down": ForceDataError, "nocop": ForceDataError}[bad]
    hint = {"noforce": "no ground-force columns", "nan": "NaN", "time": "strictly increasing",
            "mm": "metres", "down": "negated", "nocop": "centre-of-pressure"}[bad]
    with pytest.raises(err, match=hint):
        read_grf(p, biped())


def test_grf_shipped_sagittal_file_numbered_convention():
    """OpenSim's gait10dof18musc GRF file (``ground_force_*`` right, ``1_ground_force_*`` left)
    against its own columns read with numpy."""
    from gdimitate.io.gait import human_walk_path

    p = human_walk_path().parent / "walk_gait1018_subject01_grf.mot"
    lines = p.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip() == "endheader")
    names = lines[i + 1].split("\t")
    raw = np.loadtxt(lines[i + 2:])
    col = {n: raw[:, k] for k, n in enumerate(names)}
    cf = read_grf(p, biped())
    for side, pre in (("right", ""), ("left", "1_")):
        v = np.column_stack([col[f"{pre}ground_force_v{a}"] for a in "xyz"])
        np.testing.assert_allclose(cf[side].force, v @ Y_UP.T, atol=1e-9)
        np.testing.assert_array_equal(cf[side].contact, v[:, 1] > 20.0)


# ====================================================================== TRC
def _trc(path, t, names, xyz_lab, units="mm", drop=None):
    n = len(names)
    head = ["PathFileType\t4\t(X/Y/Z)\t" + path.name,
            "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\t"
            "OrigDataStartFrame\tOrigNumFrames",
            f"60.00\t60.00\t{t.size}\t{n}\t{units}\t60.00\t1\t{t.size}",
            "Frame#\tTime\t" + "\t\t\t".join(names) + "\t\t",
            "\t\t" + "\t".join(f"{a}{i + 1}" for i in range(n) for a in "XYZ"), ""]
    rows = []
    for k in range(t.size):
        vals = [f"{v:.6f}" for v in xyz_lab[k].ravel()]
        if drop and k in drop[1]:
            i = names.index(drop[0])
            vals[3 * i:3 * i + 3] = ["", "", ""]
        rows.append(f"{k + 1}\t{t[k]:.6f}\t" + "\t".join(vals) + "\t")
    path.write_text("\n".join(head + rows) + "\n")
    return path


def _body_markers(t):
    """A standing body's markers in an OpenSim Y-up lab [m]: head, hips, heels, toes."""
    base = np.array([[0.0, 1.7, 0.0], [0.0, 0.95, 0.1], [0.0, 0.95, -0.1],
                     [-0.05, 0.05, 0.1], [0.15, 0.02, 0.1]])
    return base[None] + np.column_stack([1.2 * t, 0 * t, 0 * t])[:, None, :]


@pytest.mark.parametrize("units,scale", [("mm", 1000.0), ("cm", 100.0), ("m", 1.0)])
def test_trc_units_frame_and_gaps(tmp_path, units, scale):
    t = np.arange(12) / 60
    names = ["Top.Head", "R.ASIS", "L.ASIS", "R.Heel", "R.Toe.Tip"]
    lab = _body_markers(t)
    p = _trc(tmp_path / "m.trc", t, names, lab * scale, units, drop=("R.Heel", [3, 4]))
    with pytest.warns(MarkerGapWarning, match="R.Heel"):
        mk = read_trc(p)
    assert mk.names == tuple(names) and "Y up" in mk.frame_note
    ref = lab @ Y_UP.T
    ref[[3, 4], 3] = np.nan
    np.testing.assert_allclose(mk.xyz, ref, atol=1e-9)
    # our world: head above the heel, R.ASIS (OpenSim +Z = right) at y < 0
    assert mk["Top.Head"][0, 2] > 1.6 and mk["R.ASIS"][0, 1] < 0
    pz = _trc(tmp_path / "z.trc", t, names, (lab @ Y_UP.T) * scale, units)
    np.testing.assert_allclose(read_trc(pz).xyz, lab @ Y_UP.T, atol=1e-9)  # Z-up detected


@pytest.mark.parametrize("bad", ["units", "count", "time", "notrc"])
def test_malformed_trc(tmp_path, bad):
    t = np.arange(6) / 60
    names = ["Top.Head", "R.ASIS", "L.ASIS", "R.Heel", "R.Toe.Tip"]
    p = _trc(tmp_path / "m.trc", t, names, _body_markers(t) * 1000, "furlongs" if bad == "units"
             else "mm")
    text = p.read_text()
    if bad == "count":
        text = text.replace("\t5\tmm", "\t6\tmm")
    if bad == "time":
        text = text.replace(f"\t{t[3]:.6f}\t", f"\t{t[1]:.6f}\t")
    if bad == "notrc":
        text = text.replace("PathFileType", "Hello")
    p.write_text(text)
    err = {"units": UnitError, "count": OpenSimDataError, "time": TimeGridError,
           "notrc": OpenSimDataError}[bad]
    with pytest.raises(err, match={"units": "furlongs", "count": "NumMarkers",
                                   "time": "strictly increasing", "notrc": "PathFileType"}[bad]):
        read_trc(p)


def test_sagittal_reader_refuses_full_body_files(tmp_path):
    from gdimitate.io.gait import read_opensim

    t = np.linspace(0, 1, 11)
    a = _angles(t)
    cols = ["pelvis_tilt", "pelvis_list", "hip_flexion_r", "hip_adduction_r", "knee_angle_r",
            "ankle_angle_r", "hip_flexion_l", "knee_angle_l", "ankle_angle_l"]
    data = np.column_stack([t] + [a.get(c, 0 * t) for c in cols])
    p = write_table(tmp_path / "full.mot", ["time", *cols], data)
    with pytest.raises(OpenSimDataError, match="read_coordinates"):
        read_opensim(p)



# ====================================================================== the shipped 3-D walk
WALK = ROOT / "gdimitate" / "data" / "gait" / "opensim_subject01_walk1_3d"
LEG_MOMENTS = [f"{c}_{s}" for c in ("hip_flexion", "hip_adduction", "knee_angle", "ankle_angle")
               for s in "rl"]


@functools.cache
def treadmill_walk():
    """(robot, motion, forces) of the shipped trial, NOT turned overground (OpenSim's inverse
    dynamics used the treadmill kinematics)."""
    from gdimitate.io.gait import human_walk_3d

    return human_walk_3d(overground=False)


def opensim_id_comparison(apply_forces: bool = True):
    """Pinocchio RNEA of the converted model on the IK angles (6 Hz low-pass, as the trial's
    InverseDynamics setup), measured forces applied at their centres of pressure plus free
    torques on the ExternalLoads bodies, against OpenSim's own result
    ``std_subject01_InverseDynamics.sto``: ``{coordinate: (r, rmse [N·m], range [N·m])}``."""
    import pinocchio as pin

    from gdimitate.model.motion import differentiate
    from gdimitate.model.osim._table import read_table

    robot, motion, forces = treadmill_walk()
    m = differentiate(robot.model, motion, cutoff_hz=6)
    bodies = {("right" if s.body.endswith("_r") else "left"): s.body
              for s in read_external_loads(WALK / "subject01_walk1_grf.xml")}
    assert bodies == {"right": "calcn_r", "left": "calcn_l"}
    model, data = robot.model, robot.model.createData()
    tau = np.empty((m.T, model.nv))
    for k in range(m.T):
        pin.forwardKinematics(model, data, m.q[k])
        fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            fext.append(pin.Force.Zero())
        for side, body in bodies.items():
            f = forces[side]
            if not (apply_forces and f.contact[k]):
                continue
            jid = model.frames[model.getFrameId(body)].parentJoint
            w = pin.Force(f.force[k], np.cross(f.cop[k], f.force[k]) + f.torque[k])  # at 0
            fext[jid] = fext[jid] + data.oMi[jid].actInv(w)
        tau[k] = pin.rnea(model, data, m.q[k], m.v[k], m.a[k], fext)
    ref = read_table(WALK / "std_subject01_InverseDynamics.sto")
    sel = (m.t >= ref.t[0]) & (m.t <= ref.t[-1])
    out = {}
    for c in LEG_MOMENTS:
        r_ = np.interp(m.t[sel], ref.t, ref.column(f"{c}_moment"))
        ours = tau[sel, robot.idx_v(c)]
        out[c] = (float(np.corrcoef(r_, ours)[0, 1]), float(np.sqrt(np.mean((ours - r_) ** 2))),
                  float(np.ptp(r_)))
    return out, int(sel.sum())


def test_inverse_dynamics_against_opensim():
    res, n = opensim_id_comparison()
    assert n >= 60  # t = 0.5–1.6 s at 60 Hz
    for c, (r, rmse, rng) in res.items():
        assert r >= 0.95, f"{c}: correlation {r:.3f}"
        assert rmse <= 0.10 * rng, f"{c}: RMSE {rmse:.2f} N·m over a range of {rng:.1f} N·m"
    # negative control: without the measured forces the same criteria fail for every moment
    bad, _ = opensim_id_comparison(apply_forces=False)
    failing = [c for c, (r, rmse, rng) in bad.items() if r < 0.95 or rmse > 0.10 * rng]
    assert failing == list(bad), failing


def marker_distances():
    """Model marker frames (the .osim MarkerSet in the converted URDF) against the measured
    TRC markers at the common times 0.5–2.5 s: ``{marker: (T,) distance [m]}``."""
    import pinocchio as pin

    robot, motion, _ = treadmill_walk()
    mk = read_trc(WALK / "subject01_walk1.trc")
    data = robot.model.createData()
    names = [f"{s}.{p}" for s in "RL" for p in ("Heel", "Toe.Tip", "Toe.Lat", "Toe.Med")]
    out = {n: [] for n in names}
    for k, tk in enumerate(motion.t):
        j = int(np.argmin(np.abs(mk.t - tk)))
        if abs(mk.t[j] - tk) > 2e-3:  # the TRC's times are rounded to 1 ms
            continue
        pin.framesForwardKinematics(robot.model, data, motion.q[k])
        for n in names:
            x = data.oMf[robot.frame_id(n)].translation
            out[n].append(float(np.linalg.norm(x - mk[n][j])))
    return {n: np.array(v) for n, v in out.items()}


def test_model_markers_follow_measured_markers():
    d = marker_distances()
    for n, v in d.items():
        assert v.size >= 120, n  # 0.5–2.5 s at 60 Hz
        assert v.max() <= 0.03, f"{n}: {100 * v.max():.1f} cm from the measured marker"


def test_human_walk_3d_overground():
    from gdimitate.io.gait import human_walk_3d

    robot, motion, forces = human_walk_3d()
    assert "turned overground" in forces.frame_note
    _, tread, tforces = treadmill_walk()
    # heel strikes (vertical force > 20 N) as the data's README lists them, within a frame
    on = {s: motion.t[1:][np.diff(motion.contact[s].astype(int)) == 1] for s in motion.contact}
    np.testing.assert_allclose(on["right"], [0.62, 1.85, 3.08], atol=1 / 60 + 1e-9)
    np.testing.assert_allclose(on["left"], [1.25, 2.46, 3.68], atol=1 / 60 + 1e-9)
    for s in ("left", "right"):
        np.testing.assert_array_equal(motion.contact[s], forces[s].contact)
    # the belt speed against an independent estimate: the measured heel markers' backward
    # speed in mid-stance (TRC, 0.5–2.5 s)
    speed = float(forces.frame_note.split("belt speed ")[1].split(" m/s")[0])
    mk = read_trc(WALK / "subject01_walk1.trc")
    vm = []
    for s, n in (("right", "R.Heel"), ("left", "L.Heel")):
        stance = np.interp(mk.t, motion.t, tforces[s].contact.astype(float)) > 0.99
        vm.append(-np.gradient(mk[n][:, 0], mk.t)[stance])
    ref = float(np.median(np.concatenate(vm)))
    assert 0.8 < speed < 2.0 and speed == pytest.approx(ref, rel=0.05)
    # base x gained speed·(t − t0); the rest of q and the forces themselves are unchanged
    from gdimitate.io.opensim.treadmill import belt_speed

    exact = belt_speed(robot, tread, tforces.contact)
    assert speed == pytest.approx(exact, abs=5e-4)  # the note rounds to 1 mm/s
    np.testing.assert_allclose(motion.q[:, 0] - tread.q[:, 0], exact * (motion.t - motion.t[0]),
                               atol=1e-12)
    st = tforces["right"].contact
    np.testing.assert_allclose(forces["right"].cop[st, 0] - tforces["right"].cop[st, 0],
                               exact * (motion.t - motion.t[0])[st], atol=1e-12)
    np.testing.assert_array_equal(forces["left"].force, tforces["left"].force)
    np.testing.assert_array_equal(motion.q[:, 1:], tread.q[:, 1:])
    # consistency: in stance the centre of pressure lies under the foot (between heel and toe
    # markers' reach, ±0.2 m of the sole frame), for the overground kinematics and forces
    import pinocchio as pin

    data = robot.model.createData()
    for s in ("left", "right"):
        fid = robot.frame_id(robot.contacts[s].frame)
        k = np.flatnonzero(forces[s].contact)
        gap = []
        for i in k:
            pin.framesForwardKinematics(robot.model, data, motion.q[i])
            gap.append(forces[s].cop[i, :2] - data.oMf[fid].translation[:2])
        assert np.max(np.abs(gap)) < 0.2, s


def test_overground_needs_forces_on_the_motion_times():
    from gdimitate.errors import InvalidInputError
    from gdimitate.io.opensim.treadmill import treadmill_to_overground

    robot, motion, forces = treadmill_walk()
    cf = read_grf(WALK / "subject01_walk1_grf.mot", robot, WALK / "subject01_walk1_grf.xml")
    with pytest.raises(InvalidInputError, match="t=motion.t"):
        treadmill_to_overground(robot, motion, cf)


def test_sagittal_reader_refuses_the_shipped_3d_file():
    from gdimitate.io.gait import read_opensim

    with pytest.raises(OpenSimDataError, match="read_coordinates"):
        read_opensim(WALK / "subject01_walk1_ik.mot")
