"""C3D files: markers and force plates read with ezc3d, checked against OpenSim's own reading
of OpenSim's ``walking2.c3d`` (its ``C3DFileAdapter`` output, shipped in
``tests/data/c3d/opensim_walking2``); a write → read round trip of synthetic trials; force
plates assigned to the feet of subject01's marker-based motion, checked against the per-foot
forces the plates were made from; a plate under both feet refused; ``gdimitate adapt
trial.c3d --osim model.osim`` end to end.

Tolerances: plate forces and moments are stored as float32 in C3D analog channels (~1e-7
relative); OpenSim's ``.sto`` prints 8 decimals; its ``.trc`` 0.1 mm-ish rounding (markers
within 0.1 mm).
"""

from __future__ import annotations

import functools
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from gdimitate import Robot
from gdimitate.apps.cli import main
from gdimitate.errors import FileFormatError, ForceDataError
from gdimitate.io.c3d import ForcePlate, read_c3d, write_c3d
from gdimitate.io.c3d.plates import assign_plates
from gdimitate.io.demonstration import load_demonstration
from gdimitate.io.opensim import Markers, read_grf, read_trc
from tests.helpers import ROOT, TESTS

W2 = TESTS / "data/c3d/opensim_walking2"
D3 = ROOT / "gdimitate/data/gait/opensim_subject01_walk1_3d"


def _sto(path: Path) -> tuple[list[str], np.ndarray]:
    lines = path.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip() == "endheader")
    return lines[i + 1].split(), np.loadtxt(lines[i + 2:], ndmin=2)


@functools.cache
def _walking2():
    return read_c3d(W2 / "walking2.c3d")


def test_walking2_plates_equal_opensims_reading():
    """Forces, centres of pressure and free moments of both plates vs OpenSim's
    C3DFileAdapter (every 100th analog sample, as OpenSim's test wrote them)."""
    trial = _walking2()
    names, ref = _sto(W2 / "std_walking2_grfs.sto")
    _, cop = _sto(W2 / "std_cop_walking2_grfs.sto")
    k = np.round(ref[:, 0] * 2000).astype(int)
    assert len(trial.plates) == 2
    for p in trial.plates:
        col = {a: names.index(f"{a}{p.index}_1") for a in "fpm"}
        F = ref[:, col["f"]:col["f"] + 3]
        np.testing.assert_allclose(p.force[k], F, atol=1e-6)  # N
        loaded = F[:, 2] > p.threshold
        assert loaded.sum() >= 9
        np.testing.assert_allclose(p.cop[k][loaded], cop[loaded, col["p"]:col["p"] + 3] / 1000,
                                   atol=1e-9)  # m
        np.testing.assert_allclose(p.free_moment[k][loaded],
                                   cop[loaded, col["m"]:col["m"] + 3] / 1000, atol=1e-8)  # N·m
        assert np.isnan(p.cop[k][~loaded]).all()
        # the reaction on the subject: up under load; the plate's surface at z = 0
        assert p.force[:, 2].max() > 700 and np.allclose(p.corners[:, 2], 0)
    assert trial.plates[0].rate == pytest.approx(2000.0)


def test_walking2_markers_equal_opensims_reading():
    trial = _walking2()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = read_trc(W2 / "std_walking2_markers.trc", up="Z")  # every 10th frame, mm
    mk = trial.markers
    assert mk.names == ref.names and len(mk.names) == 44 and mk.rate == pytest.approx(250.0)
    idx = np.append(np.arange(0, mk.t.size, 10), mk.t.size - 1)  # OpenSim kept the last frame
    ours = mk.xyz[idx]
    assert ours.shape == ref.xyz.shape
    np.testing.assert_array_equal(np.isnan(ours), np.isnan(ref.xyz))
    ok = ~np.isnan(ours)
    np.testing.assert_allclose(ours[ok], ref.xyz[ok], atol=1e-4)
    np.testing.assert_allclose(mk.t[idx], ref.t, atol=1e-9)
    assert "lab Z up" in trial.note


def _synthetic(T=40, rate=100.0, ratio=10):
    t = np.arange(T) / rate
    xyz = np.array([[0.0, 0.1, 1.7], [0.1, 0.1, 1.0], [0.2, -0.1, 0.05]])[None] + \
        np.column_stack([t, 0 * t, 0 * t])[:, None]
    ta = np.arange(T * ratio) / (rate * ratio)
    F = np.column_stack([30 * np.sin(5 * ta), -20 + 0 * ta, 600 + 100 * np.sin(3 * ta)])
    cop = np.column_stack([0.5 + 0.1 * ta, 0.2 - 0.05 * ta, 0 * ta])
    tz = np.column_stack([0 * ta, 0 * ta, 3 * np.cos(4 * ta)])
    corners = np.array([[0.2, 0, 0], [0.8, 0, 0], [0.8, 0.5, 0], [0.2, 0.5, 0]])
    return Markers(t, ("head", "hip", "heel"), xyz), ForcePlate(ta, F, cop, tz, corners)


def test_write_read_round_trip(tmp_path):
    mk, plate = _synthetic()
    trial = read_c3d(write_c3d(tmp_path / "s.c3d", mk, [plate]))
    np.testing.assert_allclose(trial.markers.xyz, mk.xyz, atol=1e-6)
    p = trial.plates[0]
    np.testing.assert_allclose(p.force, plate.force, rtol=1e-6, atol=1e-4)  # float32
    np.testing.assert_allclose(p.cop, plate.cop, atol=1e-6)
    np.testing.assert_allclose(p.free_moment, plate.free_moment, atol=1e-5)
    np.testing.assert_allclose(np.sort(p.corners, axis=0), np.sort(plate.corners, axis=0))


def test_bad_files(tmp_path):
    with pytest.raises(FileFormatError, match="no such C3D"):
        read_c3d(tmp_path / "none.c3d")
    (tmp_path / "x.c3d").write_bytes(b"not a c3d file at all" * 10)
    with pytest.raises(FileFormatError, match="not a readable C3D"):
        read_c3d(tmp_path / "x.c3d")


# ---------------------------------------------------------------------- plates → feet
@functools.cache
def _subject01():
    robot = Robot.from_osim(D3 / "subject01.osim")
    forces = read_grf(D3 / "subject01_walk1_grf.mot", robot, D3 / "subject01_walk1_grf.xml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        markers = read_trc(D3 / "subject01_walk1.trc")
    ta = np.arange(int(2.5 * 600) + 1) / 600  # the plates' own uniform 600 Hz grid
    feet = {}
    for s in ("right", "left"):
        f = forces[s]
        M0 = np.cross(np.nan_to_num(f.cop), f.force) + f.torque  # moment about the origin
        feet[s] = tuple(np.column_stack([np.interp(ta, forces.t, x[:, k]) for k in range(3)])
                        for x in (f.force, M0))
    return robot, markers, ta, feet


def _plates(ta, feet, sides=("right", "left")):
    plates = []
    for k, s in enumerate(sides, start=1):
        F, M = feet[s] if isinstance(s, str) else tuple(sum(feet[x][i] for x in s)
                                                          for i in range(2))
        cop = np.full_like(F, np.nan)
        on = F[:, 2] > 20
        z = -0.0075
        cop[on, 0] = (-M[on, 1] + z * F[on, 0]) / F[on, 2]
        cop[on, 1] = (M[on, 0] + z * F[on, 1]) / F[on, 2]
        cop[:, 2] = z
        tz = M - np.cross(np.where(on[:, None], cop, 0), F)
        tz[~on] = M[~on]
        c = cop[on]
        lo, hi = c.min(0) - 0.1, c.max(0) + 0.1
        corners = np.array([[lo[0], lo[1], z], [hi[0], lo[1], z], [hi[0], hi[1], z],
                            [lo[0], hi[1], z]])
        plates.append(ForcePlate(ta, F, cop, tz, corners, k))
    return plates


@pytest.fixture(scope="module")
def subject01_c3d(tmp_path_factory):
    robot, markers, ta, feet = _subject01()
    path = tmp_path_factory.mktemp("c3d") / "subject01_walk1.c3d"
    return write_c3d(path, markers, _plates(ta, feet))


def test_plates_to_feet_by_proximity(subject01_c3d):
    """subject01's treadmill walk as a C3D (its markers, one plate per foot's measured force):
    marker-based IK, then each plate's loaded intervals go to the nearest foot. Each foot's
    force and moment about the origin equal the measured ones on the motion's times."""
    robot, markers, ta, feet = _subject01()
    demo = load_demonstration(D3 / "subject01.osim", markers=subject01_c3d, overground=False)
    assert demo.ik is not None and demo.forces is not None
    t = demo.motion.t
    for s in ("left", "right"):
        F, M = (np.column_stack([np.interp(t, ta, x[:, k]) for k in range(3)]) for x in feet[s])
        ff = demo.forces[s]
        on = ff.contact
        assert 0.2 < on.mean() < 0.8
        np.testing.assert_array_equal(on, F[:, 2] > 20)
        np.testing.assert_allclose(ff.force[on], F[on], atol=2e-3)  # float32 channels
        M_ours = np.cross(ff.cop[on], ff.force[on]) + ff.torque[on]
        np.testing.assert_allclose(M_ours, M[on], atol=2e-3)


def test_plate_under_both_feet_is_refused(tmp_path):
    robot, markers, ta, feet = _subject01()
    path = write_c3d(tmp_path / "one.c3d", markers, _plates(ta, feet, [("right", "left")]))
    trial = read_c3d(path)
    from gdimitate.io.opensim import inverse_kinematics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        motion = inverse_kinematics(robot, trial.markers)
    with pytest.raises(ForceDataError, match="plate 1 is stepped on by both feet"):
        assign_plates(trial.plates, robot, motion)


def test_cli_adapt_c3d_end_to_end(subject01_c3d, tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(["adapt", str(subject01_c3d), "--osim", str(D3 / "subject01.osim"),
               "--imitator", "g1", "--method", "copy", "--out", str(out)])
    said = capsys.readouterr().out
    assert "marker-based IK" in said and "force plate" in said
    rep = json.loads((out / "report.json").read_text())
    assert rep["frames"] == 151
    assert rc == (0 if rep["verdict"]["ok"] else 3)  # written; the exit status tells the verdict


def test_y_up_lab_and_non_marker_points(tmp_path):
    """A lab whose vertical is Y (some systems write it so) is turned as OpenSim's .trc files
    are (x = X, y = −Z, z = Y) and says so; points the lab's software lists under
    POINT:ANGLES (computed joint angles stored as points) are not markers."""
    import ezc3d

    from gdimitate.model.osim.joints import ground_to_world

    mk, _ = _synthetic()
    R = ground_to_world("Y")  # ours from a Y-up lab
    lab = mk.xyz @ R  # the same markers in a Y-up lab frame
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = np.array([mk.rate])
    c["parameters"]["POINT"]["LABELS"]["value"] = [*mk.names, "LKneeAngles"]
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    pts = np.ones((4, 4, mk.t.size))
    pts[:3, :3] = lab.transpose(2, 1, 0) * 1000
    pts[:3, 3] = 12.0  # degrees, not millimetres
    c["data"]["points"] = pts
    c.add_parameter("POINT", "ANGLES", ["LKneeAngles"])
    c.write(str(tmp_path / "y.c3d"))
    trial = read_c3d(tmp_path / "y.c3d")
    assert trial.markers.names == mk.names and "lab Y up" in trial.note
    np.testing.assert_allclose(trial.markers.xyz, mk.xyz, atol=1e-6)
    assert trial.plates == ()
