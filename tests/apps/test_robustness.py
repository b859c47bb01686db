"""Issue 11, robustness: the model's physics is checked, and every entry point raises our own
exceptions with a message that says what to fix (each case failed before the fix: a −6.98 kg
robot loaded, bare KeyError/EOFError/UnicodeDecodeError/OverflowError escaped, reordered
joints and NaN options were accepted silently)."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.apps.cli import main
from gdimitate.errors import (
    FileFormatError,
    InvalidInputError,
    OscillatorError,
    UnitsWarning,
    URDFError,
    ViewerError,
)
from gdimitate.io.gait import human_walk_path, read_mot
from gdimitate.model.motion import Motion
from gdimitate.model.robot import Robot
from gdimitate.model.urdfgen import PLANAR_MODELS, planar_biped_urdf
from gdimitate.viz import Viewer
from gdimitate.viz.server import MeshcatServer
from tests.helpers import shared

HOAP2 = planar_biped_urdf(PLANAR_MODELS["hoap2"])


# ------------------------------------------------------------------------- 5. model physics
def _link_block(text: str, link: str) -> tuple[int, int]:
    i = text.index(f'<link name="{link}">')
    return i, text.index("</link>", i)


def _edit_link(link: str, old: str, new: str, text: str = HOAP2) -> str:
    i, j = _link_block(text, link)
    block, n = re.subn(old, new, text[i:j], count=1)
    assert n == 1, (old, text[i:j])
    return text[:i] + block + text[j:]


def _load(tmp_path, text: str) -> Robot:
    p = tmp_path / "robot.urdf"
    p.write_text(text)
    return Robot.from_urdf(p)


def _urdf_mass(text: str) -> float:
    return sum(float(m) for m in re.findall(r'<mass value="([^"]+)"', text))


@pytest.mark.parametrize("link, old, new, says", [
    ("left_thigh", r'<mass value="[^"]+"/>', '<mass value="-6.98"/>', "mass -6.98 kg"),
    ("left_thigh", r'<mass value="[^"]+"/>', '<mass value="nan"/>', "must be finite"),
    ("torso", r'ixx="[^"]+"', 'ixx="-0.001"', "not positive semi-definite"),
    ("torso", r'izz="[^"]+"', 'izz="0.2"', "triangle inequality"),
    ("torso", r'iyy="[^"]+"', 'iyy="inf"', "must be finite"),
    ("torso", r'<origin xyz="[^"]+"', '<origin xyz="0 nan 0"', "three finite numbers"),
])
def test_impossible_inertial_data_is_refused_naming_the_link(tmp_path, link, old, new, says):
    with pytest.raises(URDFError, match=re.escape(says)) as e:
        _load(tmp_path, _edit_link(link, old, new))
    assert repr(link) in str(e.value)


def test_massless_moving_leaf_is_refused_massless_frames_are_fine(tmp_path):
    zero = ('<mass value="0"/>\n      <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" '
            'izz="0"/>')
    pattern = r'<mass value="[^"]+"/>\s*<inertia [^>]*/>'
    # the foot hangs on the (revolute) ankle with nothing below it: the ankle moves nothing
    with pytest.raises(URDFError, match="link 'left_foot' on joint 'left_ankle' \\(revolute\\)"):
        _load(tmp_path, _edit_link("left_foot", pattern, zero))
    # a massless shank is fine: the foot below it has mass
    text = _edit_link("left_shank", pattern, zero)
    # and so is a massless frame on a fixed joint (a sole marker)
    text = text.replace("</robot>", '<link name="left_marker"/><joint name="left_marker_fix" '
                        'type="fixed"><parent link="left_foot"/><child link="left_marker"/>'
                        '<origin xyz="0 0 -0.01"/></joint></robot>')
    robot = _load(tmp_path, text)
    assert robot.mass == pytest.approx(_urdf_mass(text), rel=1e-12)
    assert robot.mass == pytest.approx(pin.computeTotalMass(pin.buildModelFromXML(text)),
                                       rel=1e-12)
    # an explicit exemption, for models that are massless on purpose
    robot = Robot.from_urdf(_write(tmp_path, _edit_link("left_foot", pattern, zero)),
                            massless_joints=("left_ankle",))
    assert robot.legs["left"].ankle == "left_ankle"


def _write(tmp_path, text: str):
    p = tmp_path / "exempt.urdf"
    p.write_text(text)
    return p


# ------------------------------------------------------------------------- 6. entry points
def _motion(robot: Robot, T: int = 150, rate: float = 60.0, amp: float = 0.3) -> Motion:
    t = np.arange(T) / rate
    q = np.tile(robot.neutral, (T, 1))
    w = 2 * np.pi * 0.8 * t
    for side, phase in (("left", 0.0), ("right", np.pi)):
        q[:, robot.idx_q(f"{side}_hip")] += amp * np.sin(w + phase)
        q[:, robot.idx_q(f"{side}_knee")] += -0.4 - amp * np.sin(w + phase + 1.0)
    return Motion(t, robot.joint_names, q)


@pytest.fixture(scope="module")
def hoap2(robot) -> Robot:
    return robot("hoap2")


def test_npz_files_that_are_not_motions(tmp_path, hoap2):
    good = tmp_path / "good.npz"
    _motion(hoap2).to_npz(good)
    assert Motion.from_npz(good).T == 150
    cases = {
        "empty.npz": (b"", "is empty"),
        "table.npz": (b"time,left_hip\n0,0.1\n0.1,0.2\n", "looks like text"),
        "short.npz": (b"PK\x03\x04\x14\x00", "not a readable NPZ"),
    }
    for name, (data, says) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(FileFormatError, match=says):
            Motion.from_npz(tmp_path / name)
    z = dict(np.load(good))
    np.savez(tmp_path / "nokey.npz", **{k: v for k, v in z.items() if k != "q"})
    with pytest.raises(FileFormatError, match=r"lacks the keys \['q'\]"):
        Motion.from_npz(tmp_path / "nokey.npz")
    np.savez(tmp_path / "pickled.npz", **{**z, "joint_names": np.array([{"a": 1}])})
    with pytest.raises(FileFormatError, match="pickled Python objects"):
        Motion.from_npz(tmp_path / "pickled.npz")
    with pytest.raises(FileFormatError, match="no such NPZ file"):
        Motion.from_npz(tmp_path / "absent.npz")


def test_binary_and_empty_mot_files(tmp_path):
    p = tmp_path / "walk.mot"
    p.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(FileFormatError, match="not UTF-8 text"):
        read_mot(p)
    p.write_text("Coordinates\nendheader\n")
    with pytest.raises(FileFormatError, match="no column names"):
        read_mot(p)
    p.write_text("Coordinates\nendheader\ntime\ta\ta\n0\t1\t2\n")
    with pytest.raises(FileFormatError, match="repeated column names"):
        read_mot(p)


def _mot(path, degrees: bool, values) -> None:
    rows = "\n".join(f"{i / 60:.4f}\t{v:.6f}\t{0.9:.3f}" for i, v in enumerate(values))
    path.write_text(f"Coordinates\nversion=1\ninDegrees={'yes' if degrees else 'no'}\n"
                    f"endheader\ntime\thip_flexion_r\tpelvis_ty\n{rows}\n")


def test_in_degrees_flag_that_contradicts_the_values_warns(tmp_path):
    p = tmp_path / "x.mot"
    deg = 30 * np.sin(np.linspace(0, 2 * np.pi, 60))
    _mot(p, degrees=False, values=deg)
    with pytest.warns(UnitsWarning, match="inDegrees=no.*30"):
        read_mot(p)
    _mot(p, degrees=True, values=np.radians(deg))
    with pytest.warns(UnitsWarning, match="inDegrees=yes"):
        read_mot(p)
    for degrees, v in ((True, deg), (False, np.radians(deg))):
        _mot(p, degrees=degrees, values=v)
        with warnings.catch_warnings():
            warnings.simplefilter("error", UnitsWarning)
            read_mot(p)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnitsWarning)
        assert bool(read_mot(human_walk_path())["__in_degrees__"])


def test_entrain_refuses_another_robots_or_reordered_joints(hoap2):
    m = _motion(hoap2)
    names = list(m.joint_names)
    order = [names.index(n) for n in [*names[:3], names[4], names[3], *names[5:]]]
    reordered = Motion(m.t, tuple(names[i] for i in order), m.q[:, order])
    with pytest.raises(InvalidInputError, match="same names in another order"):
        gd.entrain(hoap2, reordered)
    renamed = Motion(m.t, (*names[:-1], "tail"), m.q)
    with pytest.raises(InvalidInputError, match=rf"missing \['{names[-1]}'\], unknown \['tail'\]"):
        gd.entrain(hoap2, renamed)
    with pytest.raises(InvalidInputError, match="motion is constant"):
        gd.entrain(hoap2, Motion(m.t, m.joint_names, np.tile(hoap2.neutral, (m.T, 1))))


@pytest.mark.parametrize("kw, says", [
    ({"duration": float("nan")}, "duration"), ({"duration": math.inf}, "duration"),
    ({"duration": 0.0}, "duration"), ({"rate": 0.0}, "rate"), ({"rate": float("nan")}, "rate"),
    ({"dt": 0.0}, "dt"), ({"adapt_rate": float("nan")}, "adapt_rate"),
    ({"ratio": -0.2}, "ratio"), ({"ratio": float("nan")}, "ratio"),
    ({"harmonics": 2.5}, "harmonics must be an integer"),
])
def test_entrain_options_are_validated(hoap2, kw, says):
    with pytest.raises(InvalidInputError, match=says) as e:
        gd.entrain(hoap2, _motion(hoap2), **kw)
    assert "tau_r is NaN" not in str(e.value)


def test_targets_whose_scale_overflows_are_refused():
    t = np.arange(0, 2.5, 1 / 60)
    x = np.stack([np.sin(2 * np.pi * 0.8 * t), np.cos(2 * np.pi * 0.8 * t)], 1)
    with pytest.raises(OscillatorError, match="rescale"):
        gd.oscillator.self_adjust(t, 1e200 * x)


def test_cli_out_must_be_a_writable_folder(tmp_path, capsys):
    file = tmp_path / "taken"
    file.write_text("mine")
    assert main(["adapt", "--out", str(file)]) == 2
    assert "is an existing file" in capsys.readouterr().err
    assert file.read_text() == "mine"
    assert main(["entrain", "--out", str(file / "sub")]) == 2
    assert "cannot write to output folder" in capsys.readouterr().err


def test_ports_outside_the_tcp_range(capsys):
    for bad in ("0", "70000", "-1", "http"):
        with pytest.raises(SystemExit) as e:
            main(["view", "--port", bad])
        assert e.value.code == 2
        assert "--port" in capsys.readouterr().err
    for bad in (0, 70000, -5, 2**70, "x", 1.5):
        with pytest.raises(ViewerError, match="1-65535"):
            MeshcatServer.start(port=bad)
    with pytest.raises(ViewerError, match="1-65535"):
        Viewer.start(port=65536)


@pytest.mark.parametrize("bad", ["0.3", 0.3 + 0.1j, ["0.1", 0.2], None, {"a": 1}])
def test_eq1_refuses_strings_and_complex_numbers(bad):
    with pytest.raises(InvalidInputError, match="real numbers"):
        gd.planar.eq1(bad, -0.2)
    with pytest.raises(InvalidInputError):
        gd.planar.eq1(0.2, -0.2, demonstrator=("0.4", 0.6))
    # real input keeps working and matches the closed form of a same-sized leg (identity)
    r = gd.planar.eq1(np.array([0.2, -0.1]), np.array([-0.3, -0.5]), (0.4, 0.6), (0.4, 0.6))
    assert np.allclose(r.theta1, [0.2, -0.1]) and np.allclose(r.theta2, [-0.3, -0.5])



# ============================================================ issue 22: real files must load
def _grf_table(path, t, unloaded_cop: float, scale: float = 1.0, up: str = "Y"):
    """A two-plate GRF file (``ground_force_*`` right, ``l_ground_force_*`` left) whose plates
    carry a half-sine load in turn and hold ``unloaded_cop`` as centre of pressure (and a
    ~0 N force) where unloaded — what force-plate exports write there (a division by ~0).
    Loaded centres of pressure are in metres times ``scale``."""
    names, cols = ["time"], [t]
    truth = {}
    for side, pre, t0, z in (("right", "", 0.0, 0.09), ("left", "l_", 0.5, -0.09)):
        s = (t - t0) / 0.6
        on = (s > 0) & (s < 1)
        fy = np.where(on, 700 * np.sin(np.pi * np.clip(s, 0, 1)), 1e-3)
        p = np.column_stack([0.2 + 0.25 * np.clip(s, 0, 1), np.zeros_like(t), np.full_like(t, z)])
        truth[side] = (fy, p.copy())
        p = p * scale
        p[~on] = unloaded_cop * np.array([1.0, -0.7, 0.3])
        v = np.column_stack([0 * t, fy, 0 * t])
        if up == "Z":  # lab Z up, Y left: (X, Y, Z) = (X, −Z_ogl, Y_ogl)
            R = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
            v, p = v @ R.T, p @ R.T
        for stem, arr in ((f"{pre}ground_force_v", v), (f"{pre}ground_force_p", p)):
            for k, ax in enumerate("xyz"):
                names.append(stem + ax)
                cols.append(arr[:, k])
        for ax in "xyz":
            names.append(f"{pre}ground_torque_{ax}")
            cols.append(0 * t)
    data = np.column_stack(cols)
    lines = [path.name, "version=1", f"nRows={len(t)}", f"nColumns={data.shape[1]}",
             "endheader", "\t".join(names)]
    lines += ["\t".join(f"{v:.17g}" for v in row) for row in data]
    path.write_text("\n".join(lines) + "\n")
    return truth


@pytest.mark.parametrize("up", ["Y", "Z"])
@pytest.mark.parametrize("garbage", [495.9, -330.0, 1e6])
def test_grf_unloaded_rows_with_arbitrary_cop_load_loaded_mm_refused(tmp_path, up, garbage):
    """DESIGN pitfall: OpenSim's own grf_walk.mot holds centre-of-pressure values of 330 and
    −496 "m" where the plate carries no load. Units are judged on loaded rows only: such a
    file loads (its loaded centres of pressure exact), one whose loaded rows are in mm is
    refused."""
    from gdimitate.errors import UnitError
    from gdimitate.io.opensim import read_grf

    robot = shared.library_robot("hoap2")
    t = np.linspace(0, 1.2, 241)
    truth = _grf_table(tmp_path / "grf.mot", t, garbage, up=up)
    cf = read_grf(tmp_path / "grf.mot", robot)
    for side, (fy, p) in truth.items():
        stance = fy > 20.0
        np.testing.assert_array_equal(cf[side].contact, stance)
        world = p @ np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]).T
        np.testing.assert_allclose(cf[side].cop[stance], world[stance], atol=1e-9)
        assert np.isnan(cf[side].cop[~stance]).all()
    _grf_table(tmp_path / "mm.mot", t, garbage, scale=1000.0, up=up)
    with pytest.raises(UnitError, match=r"metres .*divide by 1000"):
        read_grf(tmp_path / "mm.mot", robot)


def test_every_shipped_grf_file_loads():
    from pathlib import Path

    from gdimitate.io.gait import human_walk, human_walk_3d_folder
    from gdimitate.io.opensim import read_grf

    robot = shared.library_robot("hoap2")
    files = sorted(Path(human_walk_path()).parent.glob("*grf*.mot")) + sorted(
        human_walk_3d_folder().glob("*grf*.mot"))
    assert len(files) == 2
    for f in files:
        cf = read_grf(f, robot)
        assert all(cf[s].contact.any() for s in ("left", "right"))
    human_walk()


def test_adapt_of_read_coordinates_motion_says_how_to_get_contacts():
    """adapt() of a motion read by gd.opensim.read_coordinates (no contact schedule yet)
    failed with "motion.contact has no 'left' schedule"; now the message says what to do —
    for every method, and for a motion that lacks one side only."""
    from gdimitate.io.gait import human_walk_3d_folder
    from gdimitate.io.opensim import read_coordinates

    folder = human_walk_3d_folder()
    human = Robot.from_osim(folder / "subject01.osim")
    motion = read_coordinates(folder / "subject01_walk1_ik.mot", human)
    g1 = shared.library_robot("g1")
    for method in ("optimal", "analytic", "copy"):
        with pytest.raises(InvalidInputError, match=r"load_demonstration\(path, grf=") as e:
            gd.adapt(motion, human, g1, method)
        assert "['left', 'right']" in str(e.value) and "contact=" in str(e.value)
    half = motion.replace(contact={"left": np.ones(motion.T, bool)})
    with pytest.raises(InvalidInputError, match=r"for \['right'\]"):
        gd.adapt(half, human, g1)


@pytest.fixture(scope="module")
def g1(robot) -> Robot:
    return robot("g1")


def _g1_motion(g1: Robot, quat) -> Motion:
    t = np.arange(20) / 30.0
    q = np.tile(g1.neutral, (t.size, 1))
    q[5:9, 3:7] = quat
    return Motion(t, g1.joint_names, q, base_nq=7,
                  joint_nq=tuple(g1.model.joints[j].nq for j in range(1, g1.model.njoints)))


@pytest.mark.parametrize("quat", [(0, 0, 0, 0), (0, 0, 0, 2.0), (0.1, 0, 0, 1.0)])
def test_non_unit_base_quaternion_is_refused_on_reading(tmp_path, g1, quat, capsys):
    """A motion NPZ with a zero (or non-unit) base quaternion passed Motion.from_npz,
    load_demonstration, export (writing [0,0,0,0]) and simulate (ran on NaN, printed "FELL",
    exit 0); now every reader refuses it, naming the frame."""
    from gdimitate.export.writers import export_motion, read_csv, read_lafan1_csv

    bad = _g1_motion(g1, quat)
    p = tmp_path / "bad.npz"
    bad.to_npz(p, robot=g1)
    with pytest.raises(InvalidInputError, match="at frame 5 .*unit quaternion"):
        Motion.from_npz(p)
    with pytest.raises(InvalidInputError, match="at frame 5"):
        gd.load_demonstration(p)
    for argv in (["export", str(p), "--out", str(tmp_path / "x.csv")],
                 ["simulate", str(p), "--out", str(tmp_path / "sim")]):
        assert main(argv) == 2
        assert "unit quaternion" in capsys.readouterr().err
    assert not (tmp_path / "x.csv").exists() and not (tmp_path / "sim").exists()
    # the CSV formats: written from a good motion, the quaternion spoiled in the file
    good = _g1_motion(g1, g1.neutral[3:7])
    for fmt, reader, col in (("csv", read_csv, 4), ("lafan1_csv", read_lafan1_csv, 3)):
        f = tmp_path / f"m.{fmt}.csv"
        export_motion(g1, good, f, fmt)
        lines = f.read_text().splitlines()
        head = 1 if fmt == "csv" else 0
        row = lines[head + 5].split(",")
        row[col:col + 4] = [str(v) for v in quat]
        lines[head + 5] = ",".join(row)
        f.write_text("\n".join(lines) + "\n")
        with pytest.raises(InvalidInputError, match="unit quaternion"):
            reader(f, g1)
    Motion.from_npz(_saved(good, tmp_path / "good.npz", g1))  # a unit quaternion reads


def _saved(motion: Motion, path, robot) -> str:
    motion.to_npz(path, robot=robot)
    return str(path)


def test_export_onto_a_folder_or_into_a_missing_one_names_the_problem(tmp_path, hoap2):
    """export/save to a missing folder or onto a folder raised bare FileNotFoundError /
    IsADirectoryError; now OutputError saying which."""
    from gdimitate.errors import OutputError
    from gdimitate.export.writers import FORMATS, export_motion

    robot, motion = hoap2, _motion(hoap2, T=20)
    (tmp_path / "folder.csv").mkdir()
    for fmt in FORMATS:
        if fmt == "lafan1_csv":
            continue  # needs a free-flyer; the path is checked the same way first
        with pytest.raises(OutputError, match="it is a folder"):
            export_motion(robot, motion, tmp_path / "folder.csv", fmt)
        with pytest.raises(OutputError, match="does not exist"):
            export_motion(robot, motion, tmp_path / "no" / "such" / "m.out", fmt)
    res = gd.adapt(motion.replace(contact={"left": np.ones(20, bool),
                                           "right": np.ones(20, bool)}), robot, robot, "copy")
    with pytest.raises(OutputError, match="does not exist"):
        res.save(tmp_path / "missing" / "m.npz")
    assert list(tmp_path.iterdir()) == [tmp_path / "folder.csv"]


# ------------------------------------------------ issue 22: URDFs that cannot be right
def _hoap2_edit(pattern: str, repl: str, count: int = 1) -> str:
    text, n = re.subn(pattern, repl, HOAP2, count=count, flags=re.S)
    assert n == count, pattern
    return text


@pytest.mark.parametrize("joint", ["left_knee", "right_hip", "base_z"])
def test_urdf_lower_limit_above_upper_is_refused(tmp_path, joint):
    """A joint with lower > upper was accepted, and the audit then checked no position of that
    joint (it skips lo >= hi) and called motions feasible."""
    block = re.search(rf'<joint name="{joint}".*?</joint>', HOAP2, re.S).group(0)
    lo, hi = re.search(r'lower="([^"]+)" upper="([^"]+)"', block).groups()
    swapped = block.replace(f'lower="{lo}" upper="{hi}"', f'lower="{float(hi) + 0.5:g}" '
                                                         f'upper="{float(lo) - 0.5:g}"')
    with pytest.raises(URDFError, match=rf"joint '{joint}' has lower limit .* > upper limit"):
        _load(tmp_path, HOAP2.replace(block, swapped))


def test_urdf_zero_effort_or_velocity_warns_and_stays_unchecked(tmp_path):
    """0 means "unknown" in many URDFs: a warning names the joints; the audit still lists them
    in ``unlimited`` (no torque/velocity check is made against 0)."""
    from gdimitate.assess.audit import audit
    from gdimitate.errors import UnlimitedJointWarning

    text = _hoap2_edit(r'(<joint name="left_knee".*?)effort="[^"]+"', r'\1effort="0"')
    text = re.sub(r'(<joint name="right_ankle".*?)velocity="[^"]+"', r'\1velocity="0.0"', text,
                  count=1, flags=re.S)
    with pytest.warns(UnlimitedJointWarning) as rec:
        robot = _load(tmp_path, text)
    said = " ".join(str(w.message) for w in rec)
    assert "effort limit 0" in said and "left_knee" in said
    assert "velocity limit 0" in said and "right_ankle" in said
    T = 5
    t = np.arange(T) / 50.0
    m = Motion(t, robot.joint_names, np.tile(robot.neutral, (T, 1)),
               contact={s: np.ones(T, bool) for s in ("left", "right")}, base_nq=3)
    m = m.replace(v=np.zeros((T, robot.model.nv)), a=np.zeros((T, robot.model.nv)))
    rep = audit(robot, m, {s: np.zeros((T, 6)) for s in ("left", "right")})
    assert ("left_knee", "effort") in rep.unlimited
    assert ("right_ankle", "velocity") in rep.unlimited
    assert "torque:left_knee" not in [c.name for c in rep.checks]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the unchanged model loads without the warning
        _load(tmp_path, HOAP2)


@pytest.mark.parametrize("pattern, repl, says", [
    (r'(<joint name="left_knee".*?<origin xyz=")[^"]+"', r'\1nan 0 -0.1"',
     r"joint 'left_knee': <origin xyz='nan 0 -0.1'> must be three finite numbers"),
    (r'(<joint name="right_hip".*?<origin xyz="[^"]+" rpy=")[^"]+"', r'\1 0 inf 0"',
     r"joint 'right_hip': <origin rpy="),
    (r'(<joint name="left_ankle".*?<axis xyz=")[^"]+"', r'\1 0 1"',
     r"joint 'left_ankle': <axis xyz="),
    (r'(<link name="left_shank">.*?<visual>\s*<origin xyz=")[^"]+"', r'\g<1>0 nan 0"',
     r"link 'left_shank' <visual>: <origin xyz="),
    (r'<link name="left_thigh">', r'<link name="left_thigh"/><link name="left_thigh">',
     r"link names must be unique; repeated: \['left_thigh'\]"),
    (r'<joint name="left_hip" type', r'<joint name="right_hip" type',
     r"joint names must be unique; repeated: \['right_hip'\]"),
    (r'(<joint name="left_knee".*?)lower="[^"]+"', r'\1lower="nan"',
     r"joint 'left_knee': <limit lower='nan'> must be a finite number"),
])
def test_urdf_faults_are_named_not_left_to_pinocchio(tmp_path, pattern, repl, says):
    """A NaN in an origin or a duplicate link got Pinocchio's "not a valid URDF model"."""
    text, n = re.subn(pattern, repl, HOAP2, count=1, flags=re.S)
    assert n == 1
    with pytest.raises(URDFError, match=says):
        _load(tmp_path, text)


@pytest.mark.parametrize("entry, says", [
    (["left_hip", "big", 0.0], "scale must be a finite number"),
    (["left_hip", 1.0, "x"], r"offset \[rad\] must be a finite number"),
    (["left_hip", float("nan")], "scale must be a finite number"),
    (["left_hip", True], "scale must be a finite number"),
    (["left_hip", 1.0, 0.0, 5.0], r"\[name, scale, offset\]"),
    (5, r"\[name, scale, offset\]"),
    ([1.0, "left_hip"], r"\[name, scale, offset\]"),
    ({"name": "left_hip"}, r"\[name, scale, offset\]"),
])
def test_body_map_entries_of_the_wrong_kind_are_named(tmp_path, entry, says):
    """A body-map entry with a non-numeric scale or the wrong shape raised a bare ValueError
    (or TypeError)."""
    import json

    from gdimitate.retarget.bodymap import BodyMap

    d = {"joints": {"hip_flexion_l": entry}}
    with pytest.raises(InvalidInputError, match=rf"body map joint 'hip_flexion_l': .*{says}"):
        BodyMap.from_dict(d)
    p = tmp_path / "map.json"
    p.write_text(json.dumps(d, allow_nan=True))
    # from a file, a NaN is refused as it is read (JSON has no NaN), the rest per entry
    nan = isinstance(entry, list) and any(isinstance(x, float) and x != x for x in entry)
    with pytest.raises(InvalidInputError, match="body map .*NaN" if nan else "body map joint"):
        BodyMap.from_json(p)


@pytest.mark.parametrize("d, says", [({"joints": ["a", "b"]}, "'joints' must be a dict"),
                                     ({"segments": {"torso": 3}}, "segment 'torso'")])
def test_body_map_sections_of_the_wrong_kind_are_named(d, says):
    from gdimitate.retarget.bodymap import BodyMap

    with pytest.raises(InvalidInputError, match=says):
        BodyMap.from_dict(d)
    good = BodyMap.from_dict({"joints": {"a": ["b", -1, 0.25], "c": "d"}})
    assert good.joints == {"a": ("b", -1.0, 0.25), "c": ("d", 1.0, 0.0)}


def test_every_shipped_data_file_loads():
    """On a fresh install every shipped file loads through the public readers: the sagittal
    walk with its forces, the 3-D walk (model, IK angles, forces with their ExternalLoads,
    markers, OpenSim's inverse dynamics table), the CMU BVH clip."""
    from pathlib import Path

    from gdimitate.io.gait import human_walk_3d_folder
    from gdimitate.model.osim._table import read_table
    from gdimitate.model.osim.trc import read_trc

    d3 = human_walk_3d_folder()
    sag = Path(human_walk_path())
    data = sag.parents[1]
    files = sorted(p for p in data.rglob("*") if p.suffix.lower() in
                   (".mot", ".sto", ".osim", ".trc", ".bvh", ".xml"))
    seen = set()
    d = gd.load_demonstration(sag, grf=sag.parent / "walk_gait1018_subject01_grf.mot")
    assert d.motion.T == 151 and d.motion.contact["left"].any()  # contacts from the plates
    seen |= {sag, sag.parent / "walk_gait1018_subject01_grf.mot"}
    d = gd.load_demonstration(d3 / "subject01.osim", coordinates=d3 / "subject01_walk1_ik.mot",
                              grf=d3 / "subject01_walk1_grf.mot")
    assert d.motion.T == 211 and d.forces is not None
    seen |= {d3 / f for f in ("subject01.osim", "subject01_walk1_ik.mot",
                              "subject01_walk1_grf.mot", "subject01_walk1_grf.xml")}
    assert read_trc(d3 / "subject01_walk1.trc").xyz.shape[1] == 41
    assert read_table(d3 / "std_subject01_InverseDynamics.sto").data.shape[0] > 50
    seen |= {d3 / "subject01_walk1.trc", d3 / "std_subject01_InverseDynamics.sto",
             d3 / "subject01_Setup_InverseDynamics.xml"}  # the tool's setup: read by OpenSim
    bvh = data / "cmu_02_01" / "cmu_02_01.bvh"
    assert gd.load_demonstration(bvh).motion.T > 60
    seen.add(bvh)
    assert set(files) <= seen, sorted(set(files) - seen)
