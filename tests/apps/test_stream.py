"""``gdimitate stream`` (issue 35, item 3): a BVH file played live, a real Lab Streaming Layer
outlet on loopback, a real meshcat server — the shipped CMU walk (120 Hz) onto G1, about a
second of it each. What the console prints is what report.json holds; the streamed verdicts
are the audit of the written motion, recomputed here from the file; every frame received is
either adapted or counted as dropped, and a slow consumer drops instead of falling behind."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import uuid
import warnings
from pathlib import Path

import numpy as np
import pytest

import gdimitate as gd
from gdimitate.assess.audit import audit
from gdimitate.export.writers import read_wrenches
from gdimitate.io.demonstration import load_demonstration

CMU = str(gd.gait.cmu_walk_path())  # 120 Hz
PERIOD_S = 1 / 120


def _run(args: list[str], **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "gdimitate.apps.cli", "stream", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def _printed(out: str) -> dict:
    """The summary's numbers as printed (latencies with two decimals)."""
    n = r"([0-9.]+)"
    pats = {"adapted": r"streamed (\d+) frames from", "received": r"received (\d+) frames",
            "dropped": r"dropped (\d+) \(", "median": rf"median {n} ms, p95",
            "p95": rf"p95 {n} ms", "max": rf"ms, max {n} ms \(frame period",
            "step": rf"step alone: median {n} ms", "step_max": rf"step alone: median [0-9.]+ "
            rf"ms, max {n} ms",
            "feasible": r"verdicts: (\d+) of", "frames": r"verdicts: \d+ of (\d+) frames"}
    got = {}
    for k, p in pats.items():
        m = re.search(p, out)
        assert m, (k, out[-2000:])
        got[k] = float(m.group(1))
    return got


def _check_written(folder: Path, out: str) -> dict:
    """The printed numbers are report.json's; the written motion's audit (recomputed from
    imitator_motion.npz and its wrenches) is the printed verdicts, frame for frame."""
    report = json.loads((folder / "report.json").read_text())
    s = report["stream"]
    p = _printed(out)
    assert (p["adapted"], p["received"], p["dropped"]) == (
        s["frames_adapted"], s["frames_received"], s["frames_dropped"])
    assert s["frames_received"] == s["frames_adapted"] + s["frames_dropped"] + s[
        "frames_waited"]
    for k in ("median", "p95", "max"):
        assert p[k] == pytest.approx(s["latency_ms"][k], abs=0.005)  # printed to 0.01 ms
    assert p["step"] == pytest.approx(s["step_ms"]["median"], abs=0.005)
    assert p["step_max"] == pytest.approx(s["step_ms"]["max"], abs=0.005)
    assert s["step_ms"]["median"] <= s["latency_ms"]["median"]  # a latency holds its step
    verdicts = np.array(s["verdicts"]["per_frame"], bool)
    assert (p["feasible"], p["frames"]) == (verdicts.sum(), verdicts.size) == (
        s["verdicts"]["feasible"], s["frames_adapted"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        written = load_demonstration(folder / "imitator_motion.npz")
    motion, robot = written.motion, written.robot
    assert motion.T == s["frames_adapted"] and motion.v is not None and motion.a is not None
    rep = audit(robot, motion, read_wrenches(folder / "imitator_motion.npz"), robot.contacts)
    assert np.array_equal(rep.knot_feasible, verdicts)
    assert s["verdicts_are_the_audit"]
    assert {f.name for f in folder.iterdir()} >= {"imitator_joints.csv", "imitator_motion.npz",
                                                   "report.json", "gait.png"}
    return report


def test_a_bvh_file_streamed_live_stops_at_ctrl_c_and_writes_adapt_outputs(tmp_path):
    """The CMU walk (2.9 s) played at 120 Hz; Ctrl-C one second into the stream, sent as a
    terminal does, to the command's whole process group (its verdict worker too): it stops,
    writes what it streamed and exits 0 or 3 by the verdicts. Frames adapted are frames of
    the file (times on its 1/120 s grid), the others counted dropped."""
    out = tmp_path / "out"
    p = _run([CMU, "--imitator", "g1", "--out", str(out)], start_new_session=True)
    assert p.stdout is not None
    for line in p.stdout:  # the stream starts after the robot, the adaptor and its warm-up
        if line.startswith("streaming "):
            break
    time.sleep(1.0)
    os.killpg(p.pid, signal.SIGINT)
    rest, err = p.communicate(timeout=120)
    assert "stopped: Ctrl-C" in rest, (rest, err[-2000:])
    report = _check_written(out, rest)
    s = report["stream"]
    all_ok = all(s["verdicts"]["per_frame"])
    assert p.returncode == (0 if all_ok else 3), err[-2000:]
    assert 60 <= s["frames_received"] < 343  # ~1 s of 120 Hz, not the whole file
    t = load_demonstration(out / "imitator_motion.npz").motion.t
    k = t / PERIOD_S
    assert np.allclose(k, np.round(k), atol=1e-6) and np.all(np.diff(np.round(k)) >= 1)
    assert round(k[-1]) + 1 <= s["frames_received"]  # the last adapted is one received


def test_an_lsl_stream_on_loopback_with_a_slow_consumer_drops_frames_and_says_so(tmp_path):
    """A real pylsl outlet in this process (loopback) sends 120 frames of the CMU walk at
    120 Hz, without stance channels (the command detects the stance from the feet); the
    command waits 25 ms after each frame (--delay): it cannot take all 120 in the stream's
    1 s — every frame is received, the ones not adapted are counted dropped, and it never
    falls behind (were the 120 frames queued, the last would wait ~2 s: the largest latency
    stays under 0.5 s). The stream ends 2 s after its last frame (--timeout)."""
    from gdimitate.io.live.lsl import BVHOutlet

    name = f"gdimitate-test-{uuid.uuid4().hex[:8]}"
    outlet = BVHOutlet(CMU, name, frames=120, loopback=True, stance=False).start()
    out = tmp_path / "out"
    try:
        p = _run([f"lsl:{name}", "--skeleton", CMU, "--loopback", "--imitator", "g1",
                  "--timeout", "2", "--delay", "25", "--out", str(out)])
        text, err = p.communicate(timeout=180)
    finally:
        outlet.stop()
    assert p.returncode in (0, 3), err[-3000:]
    assert "stopped: no frame for 2 s" in text and f"LSL stream '{name}'" in text
    assert "stance detected from the feet" in text
    s = _check_written(out, text)["stream"]
    assert outlet.sent == 120 == s["frames_received"]
    assert s["frames_adapted"] <= 45  # 1 s / (25 ms + a step) + the first
    assert s["frames_dropped"] == 120 - s["frames_adapted"] - s["frames_waited"] >= 75
    assert 0 <= s["latency_ms"]["median"] <= s["latency_ms"]["max"] < 500
    assert p.returncode == (0 if all(s["verdicts"]["per_frame"]) else 3)


def test_the_meshcat_view_follows_the_stream(tmp_path):
    """A real meshcat server: after the stream, each of G1's visual nodes stands where the
    last frame written puts it (Pinocchio's placements of the written q, to 1e-6 m), and the
    drawings counted are printed."""
    import base64

    import umsgpack

    from gdimitate.apps.stream import run_stream, stream_lines
    from gdimitate.io.live import BVHFileSource
    from gdimitate.viz import Viewer
    from gdimitate.viz.animate import sample_frames

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g1 = gd.Robot.from_library("g1")
    with Viewer.start(quiet=True, timeout_s=60.0) as v:
        status, report = run_stream(BVHFileSource(CMU, frames=60), g1, tmp_path, viewer=v,
                                    say=lambda line: None)
        html = v.vis.static_html()  # the scene as the server holds it (html() animates)
    s = report["stream"]
    assert status == (0 if all(s["verdicts"]["per_frame"]) else 3)
    assert s["view_updates"] >= 1
    assert f"meshcat view drawn {s['view_updates']} times" in stream_lines(report)
    q = load_demonstration(tmp_path / "imitator_motion.npz").motion.q[-1]
    f = sample_frames(g1.model, g1.visual_model, np.zeros(1), q[None], 1.0)
    blobs = re.findall(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"\)',
                       html)
    placed = {}
    for c in (umsgpack.unpackb(base64.b64decode(b)) for b in blobs):
        if c["type"] == "set_transform" and c["path"].startswith("/meshcat/g1/robot/"):
            placed[c["path"]] = np.asarray(c["matrix"], float).reshape(4, 4).T
    nodes = v.tracks["g1"].nodes
    assert len(nodes) == g1.visual_model.ngeoms
    for g, node in enumerate(nodes):
        assert np.allclose(placed[f"/meshcat/g1/robot/{node}"], f.placements[0][g], atol=1e-6)


def test_no_such_lsl_stream_is_an_error_and_leaves_no_output(tmp_path):
    """An LSL stream nobody sends (on loopback, 1 s to find it): exit status 2, the message
    names it, and the output folder the command made is removed again."""
    out = tmp_path / "out"
    p = _run(["lsl:gdimitate-nobody-sends-this", "--skeleton", CMU, "--loopback",
              "--timeout", "1", "--out", str(out)])
    text, err = p.communicate(timeout=120)
    assert p.returncode == 2, (text, err[-2000:])
    assert "no LSL stream called 'gdimitate-nobody-sends-this' on this machine within 1 s" in err
    assert not out.exists()


def test_a_frame_received_is_the_configuration_read_bvh_gives_that_frame():
    """The layout's decoding of each of the CMU walk's frame lines (as a live source delivers
    them, one at a time) is read_bvh's configuration of that frame, to 1e-12, and its
    stance read_bvh's."""
    from gdimitate.io.bvh import read_bvh
    from gdimitate.io.live import BVHLayout

    layout = BVHLayout(CMU)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, motion = read_bvh(CMU)
    samples = layout.file_samples
    assert samples.shape == (motion.T, len(layout.labels)) == (343, 98)
    for k, x in enumerate(samples):
        q, contact = layout.decode(x)
        assert np.allclose(q, motion.q[k], rtol=0, atol=1e-12)
        assert contact == {s: bool(motion.contact[s][k]) for s in ("left", "right")}


def _walk_3d_samples(layout):
    """The shipped 3-D walk (60 Hz) as samples of its OpenSim model's coordinates: the IK
    file's rows (degrees, metres), pelvis_tx moved as human_walk_3d turns the treadmill trial
    overground, its measured stance; and the configurations human_walk_3d gives."""
    from gdimitate.model.osim._table import read_table

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, walk, _ = gd.gait.human_walk_3d()
        _, belt, _ = gd.gait.human_walk_3d(overground=False)
    table = read_table(gd.gait.human_walk_3d_folder() / "subject01_walk1_ik.mot")
    col = {n: i for i, n in enumerate(table.names)}
    k0 = int(np.searchsorted(table.t, walk.t[0] - 1e-9))
    rows = table.data[k0:k0 + walk.T]
    assert np.allclose(table.t[k0:k0 + walk.T], walk.t)
    x = np.column_stack([rows[:, col[c]] for c in layout.labels[:-2]]
                        + [walk.contact["left"], walk.contact["right"]]).astype(float)
    x[:, layout.labels.index("pelvis_tx")] += walk.q[:, 0] - belt.q[:, 0]
    return x, walk.q


def test_opensim_coordinates_over_lsl(tmp_path):
    """The other layout: the shipped 3-D walk's model's coordinates (degrees, metres). Each
    frame decoded is human_walk_3d's configuration of it (read_coordinates', to 1e-12); its
    first second (60 frames at 60 Hz) sent by a real outlet on loopback and streamed onto G1
    through the command with --osim (two of them not numbers: dropped and counted, the stream
    goes on), stopped by SIGTERM 1.5 s after the last frame was sent:
    every frame received, adapted or counted dropped, the printed numbers report.json's, the
    verdicts the written motion's audit."""
    from gdimitate.io.live import OpenSimLayout
    from gdimitate.io.live.lsl import LayoutOutlet

    osim = str(gd.gait.human_walk_3d_folder() / "subject01.osim")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        layout = OpenSimLayout(osim)
    samples, q = _walk_3d_samples(layout)
    for k, x in enumerate(samples):
        assert np.allclose(layout.decode(x)[0], q[k], rtol=0, atol=1e-12)
    name = f"gdimitate-test-{uuid.uuid4().hex[:8]}"
    sent = samples[:60].copy()
    sent[[20, 40], 3] = np.nan  # an occluded marker: the frame is dropped, the stream goes on
    outlet = LayoutOutlet(layout, sent, name, 60.0, loopback=True).start()
    out = tmp_path / "out"
    try:
        p = _run([f"lsl:{name}", "--osim", osim, "--loopback", "--imitator", "g1",
                  "--timeout", "60", "--out", str(out)])
        outlet.join(120)
        time.sleep(1.5)
        p.send_signal(signal.SIGTERM)
        text, err = p.communicate(timeout=180)
    finally:
        outlet.stop()
    assert p.returncode in (0, 3), err[-3000:]
    assert "stopped: SIGTERM" in text
    s = _check_written(out, text)["stream"]
    assert outlet.sent == 60 == s["frames_received"]
    assert s["frames_invalid"] <= 2 and s["frames_invalid"] <= s["frames_dropped"]
    assert (f"; {s['frames_invalid']} not numbers)" in text) == (s["frames_invalid"] > 0)
    assert p.returncode == (0 if all(s["verdicts"]["per_frame"]) else 3)


def test_the_stance_detected_frame_by_frame_is_the_recorded_one_on_nine_frames_in_ten():
    """A stream without stance channels: the stance detected causally (each frame from it
    and the ones before) agrees with read_bvh's detection over the whole CMU clip (measured
    0.945 left, 0.936 right) and with the 3-D walk's measured stance (force > 20 N; measured
    0.934, 0.938) on at least 90 % of the frames, each foot."""
    from gdimitate.io.bvh import read_bvh
    from gdimitate.io.live.stance import CausalStance

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cmu = read_bvh(CMU)
        human, walk, _ = gd.gait.human_walk_3d()
    for robot, motion in (cmu, (human, walk)):
        detect = CausalStance(robot)
        got = [detect(t, q) for t, q in zip(motion.t, motion.q, strict=True)]
        for s in ("left", "right"):
            share = np.mean([g[s] for g in got] == np.asarray(motion.contact[s], bool))
            assert share >= 0.90, (robot.name, s, share)


def test_an_lsl_outlet_that_goes_away_ends_the_stream():
    """The source reads a real outlet's frames (drained, the newest kept, the rest counted),
    and says the stream ended when the outlet is destroyed (liblsl's lost stream)."""
    from gdimitate.io.live.lsl import BVHOutlet, LSLSource

    name = f"gdimitate-test-{uuid.uuid4().hex[:8]}"
    outlet = BVHOutlet(CMU, name, frames=30, loopback=True).start()
    source = LSLSource(name, outlet.layout, timeout=5, loopback=True)
    got, dropped = [], 0
    deadline = time.monotonic() + 30
    while len(got) + dropped < 30 and time.monotonic() < deadline:
        frame, skipped = source.newest(0.1)
        if frame is not None:
            got.append(frame)
            dropped += skipped
    outlet.join(5.0)  # its counter goes up after the push: the frame can arrive first
    assert len(got) + dropped == 30 == outlet.sent
    assert np.array_equal(got[-1].sample, outlet.samples[29])
    outlet.stop()
    while source.ended is None and time.monotonic() < deadline:
        assert source.newest(0.1)[0] is None
    assert source.ended == "the LSL outlet is gone"
    source.close()
