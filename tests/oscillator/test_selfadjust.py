"""The self-adjusting adaptor on the shipped real walk and on synthetic targets."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gdimitate.errors import OscillatorError
from gdimitate.io.gait import human_walk_path, read_mot
from gdimitate.oscillator import SelfAdjustResult, fit_teacher, self_adjust

JOINTS = ["hip_flexion_r", "knee_angle_r", "hip_flexion_l", "knee_angle_l"]


@pytest.fixture(scope="module")
def walk():
    d = read_mot(human_walk_path())
    return d["time"], np.deg2rad(np.stack([d[j] for j in JOINTS], axis=1))


@pytest.fixture(scope="module")
def tuned(walk):
    t, x = walk
    return self_adjust(t, x, joint_names=JOINTS, initial_frequency=0.7)


def test_teacher_fits_the_walk(walk):
    t, x = walk
    teacher = fit_teacher(t, x)
    assert 0.79 < teacher.frequency < 0.83  # stride ≈ 1.23 s
    assert np.all(teacher.fit_nrmse < 0.02)
    ph = teacher.fundamental_phase()
    assert np.cos(ph[0] - ph[2]) < -0.9 and np.cos(ph[1] - ph[3]) < -0.9  # left/right anti-phase


def test_real_walk_targets(tuned):
    f_teacher = tuned.teacher.frequency
    assert tuned.frequency == pytest.approx(f_teacher, rel=0.005)  # learned from 0.7 Hz
    assert tuned.frequency_history[0] < 0.75
    for name in JOINTS:
        rep = tuned.report[name]
        assert rep["nrmse_entrained"] <= 0.05, (name, rep)
        assert rep["freq_error_after"] <= 0.02, (name, rep)
        assert rep["nrmse_free"] <= 0.08, (name, rep)
    # left/right pairs are coupled, hip-knee pairs are not
    assert tuned.coupling[0, 2] > 0 and tuned.coupling[1, 3] > 0 and tuned.coupling[0, 1] == 0


def test_replay_keeps_the_learned_frequency_and_round_trips_json(tuned):
    t_out = np.arange(0, 15, 0.01)
    q = tuned.replay(t_out)
    assert q.shape == (t_out.size, 4)
    back = SelfAdjustResult.from_dict(json.loads(json.dumps(tuned.to_dict())))
    np.testing.assert_array_equal(back.replay(t_out), q)
    # the replayed hip follows the teacher's shape up to a time shift
    P = 1 / tuned.teacher.frequency
    shifts = np.linspace(0, P, 100, endpoint=False)
    ref = [tuned.teacher(t_out + d)[:, 0] for d in shifts]
    err = min(np.sqrt(np.mean((q[:, 0] - r) ** 2)) for r in ref) / np.ptp(ref[0])
    assert err < 0.05
    # taught replay: phase tied to the teacher while the input is on
    q2 = tuned.replay(t_out, teach_until=10.0)
    late = (t_out > 6) & (t_out < 10)
    e2 = np.sqrt(np.mean((q2[late] - tuned.teacher(t_out[late])) ** 2, 0)) / np.ptp(ref[0])
    assert np.all(e2 < 0.1)


def test_synthetic_targets_with_known_frequency():
    t = np.arange(0, 6, 0.01)
    f = 1.4
    base = np.sin(2 * np.pi * f * t) + 0.3 * np.sin(4 * np.pi * f * t + 1)
    x = np.stack([0.4 * base + 0.1, -0.4 * base, 0.2 * np.cos(2 * np.pi * f * t)], axis=1)
    res = self_adjust(t, x, teach_cycles=20, free_cycles=12)
    assert res.teacher.frequency == pytest.approx(f, rel=1e-6)
    assert res.frequency == pytest.approx(f, rel=0.005)
    for rep in res.report.values():
        assert rep["nrmse_entrained"] < 0.05 and rep["freq_error_after"] < 0.02
    assert res.coupling[0, 1] > 0 and res.coupling[0, 2] == 0


def test_bad_targets_raise():
    t = np.linspace(0, 2, 100)
    with pytest.raises(OscillatorError, match="constant"):
        self_adjust(t, np.stack([np.sin(t), np.ones_like(t)], 1))
    with pytest.raises(OscillatorError, match="sample 3, joint 1"):
        x = np.stack([np.sin(t), np.cos(t)], 1)
        x[3, 1] = np.nan
        self_adjust(t, x)
    with pytest.raises(OscillatorError, match="joint_names"):
        self_adjust(t, np.stack([np.sin(5 * t), np.cos(5 * t)], 1), joint_names=["a"])
