"""The OpenSim reader and the shipped real walk, checked against the files' own numbers."""

import numpy as np
import pytest

from gdimitate import InvalidInputError, TimeGridError
from gdimitate.assess.metrics import foot_heights
from gdimitate.io.gait import human_walk, human_walk_path, read_mot, read_opensim
from gdimitate.model.sagittal import leg_angles
from gdimitate.model.urdfgen import human_spec

GRF = human_walk_path().parent / "walk_gait1018_subject01_grf.mot"


@pytest.fixture(scope="module")
def walk(walk_sagittal):
    return walk_sagittal


def _table(path):
    """Independent reader: numpy on the lines after 'endheader'."""
    lines = path.read_text().splitlines()
    i = lines.index("endheader")
    return np.loadtxt(lines[i + 2:])


def test_angles_match_the_file(walk):
    robot, motion = walk
    raw = np.radians(_table(human_walk_path()))
    tilt, hip_r, knee_r, ank_r, hip_l, knee_l, ank_l = (raw[:, k] for k in (1, 4, 5, 6, 7, 8, 9))
    torso, ang = leg_angles(robot, motion.q)
    np.testing.assert_allclose(torso, tilt, atol=1e-12)
    np.testing.assert_allclose(ang["right"], np.column_stack([tilt + hip_r, knee_r, ank_r]),
                               atol=1e-12)
    np.testing.assert_allclose(ang["left"], np.column_stack([tilt + hip_l, knee_l, ank_l]),
                               atol=1e-12)
    assert motion.T == 151 and motion.dt == pytest.approx(1 / 60, rel=1e-6)


def test_human_proportions_scale_with_height():
    for h in (1.5, 1.75, 1.9):
        s = human_spec(h)
        assert (s.thigh / h, s.shank / h, s.foot / h) == pytest.approx((0.245, 0.246, 0.039))
    with pytest.raises(InvalidInputError, match="height"):
        human_spec(175.0)  # centimetres by mistake


def test_contact_from_measured_grf(walk):
    robot, motion = walk
    # README of the data: right heel strikes at ~0.62 s and ~1.85 s, left at ~0.03 s, ~1.25 s
    on_r = motion.t[1:][np.diff(motion.contact["right"].astype(int)) == 1]
    on_l = motion.t[1:][np.diff(motion.contact["left"].astype(int)) == 1]
    assert on_r == pytest.approx([0.62, 1.85], abs=0.04)
    assert on_l[0] == pytest.approx(1.25, abs=0.04)  # (the first, at 0.03 s, is before t=0)
    stride = np.diff(on_r)[0]
    assert 1.18 < stride < 1.27  # README: stride 1.22–1.23 s
    # mass from the mean measured vertical force / g, 60–90 kg for an adult
    assert 60 < robot.mass < 90


def test_ground_base_keeps_stance_soles_on_the_ground(walk):
    robot, motion = walk
    fh = foot_heights(robot, motion)
    low = np.minimum(np.where(motion.contact["left"], fh["left"], np.inf),
                     np.where(motion.contact["right"], fh["right"], np.inf))
    np.testing.assert_allclose(low[np.isfinite(low)], 0.0, atol=1e-12)
    speed = (motion.q[-1, 0] - motion.q[0, 0]) / motion.t[-1]
    assert 0.8 < speed < 1.4  # README: treadmill belt ~1.2 m/s, a normal walking speed


def test_kinematic_contact_without_grf():
    robot, motion = read_opensim(human_walk_path())
    with_grf = human_walk()[1]
    agree = np.mean([np.mean(motion.contact[s] == with_grf.contact[s]) for s in ("left", "right")])
    assert agree > 0.8


def test_bad_files(tmp_path):
    with pytest.raises(InvalidInputError, match="no such"):
        read_mot(tmp_path / "x.mot")
    p = tmp_path / "a.mot"
    p.write_text("no header here\n1 2 3\n")
    with pytest.raises(InvalidInputError, match="endheader"):
        read_mot(p)
    p.write_text("inDegrees=yes\nendheader\ntime\tpelvis_tilt\n0\t1\n")
    with pytest.raises(InvalidInputError, match="missing columns"):
        read_opensim(p)
    text = human_walk_path().read_text().splitlines()
    i = text.index("endheader")
    rows = text[i + 2:]
    rows[3], rows[4] = rows[4], rows[3]  # time goes backwards
    p.write_text("\n".join(text[: i + 2] + rows))
    with pytest.raises(TimeGridError, match="strictly increasing"):
        read_opensim(p)
    with pytest.raises(InvalidInputError, match="base"):
        read_opensim(human_walk_path(), base="treadmill")
