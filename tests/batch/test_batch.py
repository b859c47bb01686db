"""gdimitate.batch: a folder of demonstrations through a process pool and a real local Dask
cluster (2 workers). The reference for every number is the same file adapted directly in this
process with ``gd.adapt`` (and ``gd.sim.simulate``): a batch must reproduce it exactly."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

import gdimitate as gd
from gdimitate import errors
from gdimitate.batch import BatchOptions, BatchRow, output_paths, process_file, run_batch
from gdimitate.batch.run import find_inputs
from gdimitate.errors import (
    BatchError,
    InvalidInputError,
    UnknownNameError,
    UnknownRobotError,
)
from tests.helpers import ROOT, shared

ANALYTIC = BatchOptions("hoap2", method="analytic")


def _mot_slices(folder: Path, starts: list[int], rows: int, prefix: str = "walk") -> list[Path]:
    """Slices of the shipped sagittal walk (60 Hz) as OpenSim .mot files."""
    lines = gd.gait.human_walk_path().read_text().splitlines()
    end = next(i for i, line in enumerate(lines) if line.strip().lower() == "endheader")
    head, data = lines[: end + 2], [line for line in lines[end + 2:] if line.strip()]
    out = []
    for k, s in enumerate(starts):
        p = folder / f"{prefix}{k}.mot"
        p.write_text("\n".join(head + data[s: s + rows]) + "\n")
        out.append(p)
    return out


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("demos")
    _mot_slices(d, [0, 30, 60], 60)
    (d / "broken.mot").write_text("not an OpenSim file\n")
    (d / "notes.txt").write_text("not a demonstration: ignored\n")
    return d


def _direct(path: Path, method: str = "analytic"):
    robot, motion = gd.gait.read_opensim(path)
    return gd.adapt(motion, robot, shared.library_robot("hoap2"), method, verbose=False) \
        if method == "optimal" else gd.adapt(motion, robot, shared.library_robot("hoap2"),
                                             method)


def _check_against_direct(res, inputs: Path, out: Path) -> None:
    done = res.by_status("done") + res.by_status("skipped")
    assert sorted(r.file for r in done) == ["walk0.mot", "walk1.mot", "walk2.mot"]
    for r in done:
        ref = _direct(inputs / r.file)
        got = gd.Motion.from_npz(out / r.output)
        assert got.joint_names == ref.motion.joint_names
        np.testing.assert_array_equal(got.t, ref.motion.t)
        np.testing.assert_allclose(got.q, ref.motion.q, rtol=0, atol=1e-12)
        for s in ("left", "right"):
            np.testing.assert_array_equal(got.contact[s], ref.motion.contact[s])
        rep = ref.report
        assert r.feasible == ref.feasible
        assert r.frames == ref.motion.T == 60
        assert r.infeasible_frames == sum(rep.infeasible_frames.values())
        assert r.force_direction_error_max_rad == pytest.approx(rep.force_direction_error_max,
                                                                abs=1e-12)
        assert r.joint_limit_violation_max_rad == pytest.approx(rep.joint_limit_violation_max,
                                                                abs=1e-12)
        assert r.ground_penetration_max_m == pytest.approx(rep.ground_penetration_max,
                                                           abs=1e-12)
        assert r.audit_binding is None and r.sim_fell is None  # not applicable here
    (bad,) = res.by_status("failed")
    assert bad.file == "broken.mot" and bad.output == ""
    assert _is_input_error(bad.error) and "endheader" in bad.error


def _read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_process_pool_batch_matches_direct_adaptation(inputs, tmp_path, capsys):
    out = tmp_path / "out"
    res = run_batch(inputs, out, ANALYTIC, workers=2)
    assert [r.file for r in res.rows] == ["broken.mot", "walk0.mot", "walk1.mot", "walk2.mot"]
    _check_against_direct(res, inputs, out)
    # the files ran in worker processes (not here), at most 2 of them, all ended now
    pids = {int(r.worker.rsplit(":", 1)[1]) for r in res.rows}
    assert os.getpid() not in pids and 1 <= len(pids) <= 2 and res.workers == 2
    time.sleep(0.5)
    assert not [p for p in pids if psutil.pid_exists(p)
                and psutil.Process(p).status() != psutil.STATUS_ZOMBIE]
    # summary table: CSV and JSON hold the same rows as the result
    table = _read_csv(res.summary_csv)
    assert [t["file"] for t in table] == [r.file for r in res.rows]
    assert list(table[0]) == list(BatchRow.columns())
    for t, r in zip(table, res.rows):
        assert t["status"] == r.status and t["error"] == r.error
        if r.status == "done":
            assert float(t["force_direction_error_max_rad"]) == r.force_direction_error_max_rad
            assert float(t["seconds"]) == r.seconds > 0
            assert t["feasible"] == str(r.feasible) and t["sim_fell"] == ""
    js = json.loads(res.summary_json.read_text())
    assert js["rows"] == [r.to_dict() for r in res.rows]
    assert js["meta"]["complete"] is True and js["meta"]["inputs"] == 4
    # the progress bar (tqdm) on stderr reaches 4/4 with the failure counted
    err = capsys.readouterr().err
    assert "4/4" in err and "1 failed" in err


def _is_input_error(message: str) -> bool:
    """A batch row's error names the exception class first: an InvalidInputError (the one
    OpenSim table reader says OpenSimDataError, its subclass, for a file without 'endheader')."""
    cls = getattr(errors, message.split(":", 1)[0], None)
    return isinstance(cls, type) and issubclass(cls, InvalidInputError)


def test_resume_skips_finished_outputs_and_retries_the_rest(inputs, tmp_path):
    out = tmp_path / "out"
    first = run_batch(inputs, out, ANALYTIC, workers=1, progress=False)
    stamps = {r.file: (out / r.output).stat().st_mtime_ns for r in first.by_status("done")}
    again = run_batch(inputs, out, ANALYTIC, workers=1, progress=False)
    assert [r.status for r in again.rows] == ["failed", "skipped", "skipped", "skipped"]
    for r, r0 in zip(again.rows[1:], first.rows[1:]):  # the earlier run's row, kept
        assert r.seconds == r0.seconds and r.feasible == r0.feasible
        assert (out / r.output).stat().st_mtime_ns == stamps[r.file]
    # incomplete outputs are redone: an NPZ without its record (interrupted before the record
    # was renamed into place), a corrupt record, a record of other options
    npz1, rec1 = output_paths(inputs / "walk1.mot", out, ANALYTIC)
    rec1.unlink()
    _, rec2 = output_paths(inputs / "walk2.mot", out, ANALYTIC)
    rec2.write_text("{not json")
    third = run_batch(inputs, out, ANALYTIC, workers=1, progress=False)
    assert [r.status for r in third.rows] == ["failed", "skipped", "done", "done"]
    _check_against_direct(third, inputs, out)
    assert not list(out.glob(".*.tmp*"))  # atomic writes leave no temporary files
    # other options: other outputs, nothing reused
    copy = run_batch(inputs, out, BatchOptions("hoap2", method="copy"), workers=1,
                     progress=False)
    assert [r.status for r in copy.rows] == ["failed", "done", "done", "done"]
    assert npz1.is_file() and all(r.output.endswith(".hoap2.copy.npz")
                                  for r in copy.by_status("done"))


def test_local_dask_cluster_two_workers(inputs, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        worker_pids = set(client.run(os.getpid).values())
        assert len(worker_pids) == 2
        out = tmp_path / "dask"
        res = run_batch(inputs, out, ANALYTIC, executor="dask",
                        address=cluster.scheduler_address, progress=False)
        assert res.workers == 2 and res.executor == "dask"
        _check_against_direct(res, inputs, out)
        used = {int(r.worker.rsplit(":", 1)[1]) for r in res.rows}
        assert used <= worker_pids  # every file ran on the cluster's workers
        js = json.loads(res.summary_json.read_text())
        assert js["meta"]["address"] == cluster.scheduler_address


def test_optimal_with_simulation_row_matches_direct_run(tmp_path):
    (path,) = _mot_slices(tmp_path, [0], 40)
    opts = BatchOptions("hoap2", method="optimal", simulate=True)
    row = process_file(path, tmp_path, opts)
    assert row.status == "done", row.error
    ref = _direct(path, "optimal")
    a = ref.audit
    assert row.feasible == ref.feasible == bool(a.feasible)
    assert row.audit_binding == ";".join(a.binding)
    assert row.torque_ratio_max == pytest.approx(max(j.torque_ratio for j in a.joints
                                                     if np.isfinite(j.torque_ratio)), rel=1e-9)
    assert row.base_residual_max == pytest.approx(a.base_residual.value, abs=1e-9)
    assert row.penetration_max_m == pytest.approx(a.penetration.depth, abs=1e-12)
    assert row.cop_margin_min_m == pytest.approx(min(f.cop.value for f in a.feet.values()
                                                     if f.stance_knots), abs=1e-12)
    m = gd.sim.simulate(ref.robot, ref).metrics
    assert row.sim_fell == m.fell and row.sim_qp_failures == m.qp_failures
    assert row.sim_slip_max_m == pytest.approx(m.slip_max, abs=1e-9)
    assert row.sim_joint_rmse == pytest.approx(m.joint_rmse, abs=1e-9)
    # the NPZ carries the plan: Motion.from_npz reads it; v, a and wrenches ride along
    npz, _ = output_paths(path, tmp_path, opts)
    np.testing.assert_allclose(gd.Motion.from_npz(npz).q, ref.motion.q, atol=1e-9)
    with np.load(npz) as z:
        np.testing.assert_allclose(z["v"], ref.motion.v, atol=1e-9)
        np.testing.assert_allclose(z["wrench_left"], ref.wrenches["left"], atol=1e-6)


def test_bad_options_and_folders(inputs, tmp_path):
    with pytest.raises(InvalidInputError, match="needs method='optimal'"):
        BatchOptions("hoap2", method="analytic", simulate=True)
    with pytest.raises(UnknownNameError, match="valid methods"):
        BatchOptions("hoap2", method="fast")
    with pytest.raises(UnknownNameError, match="valid executors: 'process', 'dask'"):
        run_batch(inputs, tmp_path / "o", ANALYTIC, executor="ray")
    with pytest.raises(BatchError, match="address= is for executor 'dask'"):
        run_batch(inputs, tmp_path / "o", ANALYTIC, address="tcp://127.0.0.1:8786")
    with pytest.raises(UnknownRobotError, match="hoap2"):
        run_batch(inputs, tmp_path / "o", BatchOptions("no_such_robot", method="analytic"))
    (tmp_path / "empty").mkdir()
    with pytest.raises(BatchError, match="no demonstration files"):
        run_batch(tmp_path / "empty", tmp_path / "o", ANALYTIC)
    with pytest.raises(BatchError, match="does not exist"):
        run_batch(tmp_path / "missing", tmp_path / "o", ANALYTIC)
    with pytest.raises(BatchError, match="is the input folder"):
        run_batch(inputs, inputs, ANALYTIC)
    with pytest.raises(InvalidInputError, match="workers must be >= 1"):
        run_batch(inputs, tmp_path / "o", ANALYTIC, workers=0)
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def _session_processes(sid: int) -> list[psutil.Process]:
    alive = []
    for p in psutil.process_iter(["pid", "status"]):
        try:
            if os.getsid(p.pid) == sid and p.info["status"] != psutil.STATUS_ZOMBIE:
                alive.append(p)
        except (ProcessLookupError, PermissionError, psutil.Error):
            pass
    return alive


@pytest.mark.slow
@pytest.mark.parametrize(("executor", "sig"), [("process", signal.SIGINT),
                                               ("process", signal.SIGTERM),
                                               ("dask", signal.SIGTERM)])
def test_cli_ctrl_c_stops_workers_and_keeps_finished_files(tmp_path, executor, sig):
    """Ctrl-C (130) and SIGTERM (143) stop the workers, the pool's fork server and resource
    tracker, and leave nothing in the temporary folder (a local Dask cluster's scratch space
    was left there)."""
    demos = tmp_path / "demos"
    demos.mkdir()
    _mot_slices(demos, [0, 10, 20, 30, 40, 50, 60, 70], 40)
    out = tmp_path / "out"
    err = tmp_path / "stderr.txt"
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    with open(err, "w") as fe:
        proc = subprocess.Popen(
            [sys.executable, "-m", "gdimitate.apps.cli", "batch", str(demos), "--imitator", "hoap2",
             "--out", str(out), "--workers", "2", "--executor", executor],
            stdout=subprocess.DEVNULL, stderr=fe, env={**os.environ, "TMPDIR": str(tmp)},
            start_new_session=True)
    try:
        deadline = time.monotonic() + 90
        while "1/8 [" not in err.read_text() and time.monotonic() < deadline:
            assert proc.poll() is None, err.read_text()
            time.sleep(0.1)
        assert "1/8 [" in err.read_text(), "no file finished in 90 s"
        kids = psutil.Process(proc.pid).children(recursive=True)
        # the workers: all but multiprocessing's resource tracker and the pool's fork server
        # (whose children, the pool's workers, carry its command line too)
        workers = [c.pid for c in kids if "resource_tracker" not in " ".join(c.cmdline())
                   and not (c.ppid() == proc.pid and "forkserver" in " ".join(c.cmdline()))]
        assert len(workers) >= 2, [c.cmdline() for c in kids]
        os.kill(proc.pid, sig)
        rc = proc.wait(30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert rc == {signal.SIGINT: 130, signal.SIGTERM: 143}[sig], err.read_text()
    assert ("interrupted" if sig == signal.SIGINT else "terminated") in err.read_text()
    assert not [w for w in workers if psutil.pid_exists(w)
                and psutil.Process(w).status() != psutil.STATUS_ZOMBIE]  # stopped, not left
    # no orphan: the workers were ended; the fork server (pool) exits once it sees its parent
    # gone (it unloads gdimitate's native libraries first, which can take a second)
    deadline = time.monotonic() + 15
    while _session_processes(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _session_processes(proc.pid)
    js = json.loads((out / "summary.json").read_text())
    assert js["meta"]["complete"] is False
    done = [r for r in js["rows"] if r["status"] == "done"]
    assert 1 <= len(done) < 8
    for r in done:  # what finished is complete and readable; nothing half-written remains
        t = gd.Motion.from_npz(out / r["output"]).t  # the optimal method's 50 Hz knots
        assert abs(t[-1] - t[0] - r["duration_s"]) <= 1 / 50 + 1e-9
    assert not list(out.glob(".*.tmp*"))
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == []  # no lock
    assert list(tmp.iterdir()) == []


@pytest.mark.xfail(strict=False, reason="in a fresh clone's suite run in two workers (empty "
                   "caches, heavy load) the stopped worker's file once completed: the SIGTERM "
                   "was not delivered as SystemExit; cause not found")
def test_a_worker_stopped_during_a_file_does_not_take_the_next(tmp_path):
    """SIGTERM to a pool worker in the middle of a file (how a stopped batch ends its
    workers): the file's temporary is removed and the worker exits. The executor's own loop
    caught the job's ``SystemExit`` and took the next queued file, so a stop that waited 5 s
    for it and then killed it could leave that file's temporary in the output folder (seen
    once under load). Here the next file is never started."""
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    from gdimitate.batch.run import _context, _pool_job, _worker_init

    demos, out = tmp_path / "demos", tmp_path / "out"
    demos.mkdir()
    out.mkdir()
    warm, nxt = _mot_slices(demos, [0, 20], 60)
    (slow,) = _mot_slices(demos, [0], 151, prefix="whole")  # the whole walk: seconds
    opts = BatchOptions("hoap2", method="optimal", simulate=True)
    with ProcessPoolExecutor(1, mp_context=_context(), initializer=_worker_init) as ex:
        row = ex.submit(_pool_job, str(warm), str(out), ANALYTIC).result(120)
        pid = int(row.worker.rsplit(":", 1)[1])  # the one worker
        assert row.status == "done" and pid > 1 and pid != os.getpid()
        assert pid in {c.pid for c in psutil.Process().children(recursive=True)}
        first = ex.submit(_pool_job, str(slow), str(out), opts)
        second = ex.submit(_pool_job, str(nxt), str(out), ANALYTIC)
        time.sleep(0.3)  # into the slow file
        assert not first.done()
        os.kill(pid, signal.SIGTERM)
        with pytest.raises(BrokenProcessPool):
            first.result(60)
        with pytest.raises(BrokenProcessPool):
            second.result(60)
    assert not output_paths(nxt, out, ANALYTIC)[0].exists()  # the next file never started
    assert not output_paths(slow, out, opts)[0].exists()
    assert not list(out.glob(".*.tmp*"))


def test_a_temporary_folder_too_long_for_the_forkservers_socket(tmp_path):
    """A ``$TMPDIR`` whose path leaves no room for multiprocessing's forkserver socket
    (``/pymp-XXXXXXXX/listener-XXXXXXXX`` after it, at most 107 bytes in all on Linux) made
    ``gdimitate batch`` with worker processes fail at its first file with ``OSError: AF_UNIX
    path too long`` (Python < 3.14; a cluster job's ``$TMPDIR`` is often that long): the
    batch now starts its workers by spawning there, and runs every file in them."""
    from gdimitate.batch.run import SUN_PATH_MAX, forkserver_fits

    assert forkserver_fits("/" + "x" * (SUN_PATH_MAX - 33)) is True  # 75 bytes: just fits
    assert forkserver_fits("/" + "x" * (SUN_PATH_MAX - 32)) is False
    demos = tmp_path / "demos"
    demos.mkdir()
    _mot_slices(demos, [0, 30], 40)
    tmp = tmp_path / ("t" * max(1, 90 - len(str(tmp_path))))
    tmp.mkdir()
    assert not forkserver_fits(str(tmp))
    out = tmp_path / "out"
    p = subprocess.Popen([sys.executable, "-m", "gdimitate.apps.cli", "batch", str(demos),
                          "--imitator", "hoap2", "--method", "analytic", "--out", str(out),
                          "--workers", "2", "--executor", "process", "--quiet"],
                         env={**os.environ, "TMPDIR": str(tmp)}, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    _, err = p.communicate(timeout=300)
    assert "AF_UNIX" not in err and p.returncode in (0, 3), err[-2000:]
    rows = _read_csv(out / "summary.csv")
    assert sorted(r["file"] for r in rows) == ["walk0.mot", "walk1.mot"]
    assert {r["status"] for r in rows} == {"done"}
    assert p.pid not in {int(r["worker"].rsplit(":", 1)[1]) for r in rows}  # in workers
    assert list(tmp.iterdir()) == []  # nothing left in the temporary folder


def test_cli_batch_exit_status_and_table(inputs, tmp_path, capsys):
    from gdimitate.apps.cli import main

    out = tmp_path / "cli"
    args = ["batch", str(inputs), "--imitator", "hoap2", "--out", str(out), "--method",
            "analytic", "--workers", "2", "--quiet"]
    assert main(args) == 1  # finished, but broken.mot failed
    text = capsys.readouterr().out
    assert "3 done, 0 skipped, 1 failed" in text and "OpenSimDataError" in text
    assert issubclass(errors.OpenSimDataError, InvalidInputError)
    assert len(_read_csv(out / "summary.csv")) == 4
    good = tmp_path / "good"
    good.mkdir()
    for name in ("walk0.mot", "walk1.mot", "walk2.mot"):
        (good / name).write_bytes((inputs / name).read_bytes())
    # exit 3 (issue 22): every file done, but Eq. (1) results exceed HOAP-2's knee limit
    assert main([*args[:1], str(good), *args[2:]]) == 3
    assert "3 not feasible" in capsys.readouterr().out
    assert main([*args[:1], str(good), *args[2:]]) == 3  # all skipped now
    assert "0 done, 3 skipped, 0 failed" in capsys.readouterr().out
    assert main(["batch", str(good), "--imitator", "nobody", "--out", str(out)]) == 2
    assert "unknown robot 'nobody'" in capsys.readouterr().err


def test_measured_forces_beside_a_demonstration_are_used(tmp_path):
    from gdimitate.io.demonstration import load_demonstration

    folder = gd.gait.human_walk_path().parent
    demos = tmp_path / "demos"
    demos.mkdir()
    (demos / "walk.mot").write_bytes(gd.gait.human_walk_path().read_bytes())
    (demos / "walk_grf.mot").write_bytes((folder / "walk_gait1018_subject01_grf.mot")
                                         .read_bytes())
    res = run_batch(demos, tmp_path / "out", ANALYTIC, progress=False)
    assert [r.file for r in res.rows] == ["walk.mot"]  # the GRF file is no input of its own
    (row,) = res.rows
    assert row.status == "done", row.error
    d = load_demonstration(demos / "walk.mot", grf=demos / "walk_grf.mot")
    assert "measured vertical GRF" in d.note  # the sagittal reader: stance from the GRF
    ref = gd.adapt(d.motion, d.robot, shared.library_robot("hoap2"), "analytic")
    got = gd.Motion.from_npz(tmp_path / "out" / row.output)
    np.testing.assert_allclose(got.q, ref.motion.q, rtol=0, atol=1e-12)
    for s in ("left", "right"):  # the measured stance, not the kinematic one
        np.testing.assert_array_equal(got.contact[s], d.motion.contact[s])
    plain = load_demonstration(demos / "walk.mot")
    assert any(not np.array_equal(plain.motion.contact[s], d.motion.contact[s])
               for s in ("left", "right"))


def _bvh_slices(folder: Path, starts: list[int], frames: int) -> list[Path]:
    """Slices of the shipped CMU walk (BVH, 120 Hz; frame 0 is its T-pose, left out)."""
    src = (Path(gd.__file__).parent / "data" / "gait" / "cmu_02_01" / "cmu_02_01.bvh"
           ).read_text().splitlines()
    i = next(k for k, line in enumerate(src) if line.startswith("Frames:"))
    rows = src[i + 2:]
    out = []
    for k, s in enumerate(starts):
        p = folder / f"cmu{k}.bvh"
        p.write_text("\n".join(src[:i] + [f"Frames: {frames}", src[i + 1]]
                               + rows[s: s + frames]) + "\n")
        out.append(p)
    return out


@pytest.mark.slow
def test_bvh_batch_optimal_matches_direct_adaptation(tmp_path):
    from gdimitate.io.demonstration import load_demonstration

    demos = tmp_path / "demos"
    demos.mkdir()
    _bvh_slices(demos, [1, 41, 81], 40)
    opts = BatchOptions("hoap2", method="optimal")
    res = run_batch(demos, tmp_path / "out", opts, workers=2, progress=False)
    assert [r.status for r in res.rows] == ["done"] * 3, [r.error for r in res.rows]
    hoap2 = shared.library_robot("hoap2")
    for r in res.rows:
        d = load_demonstration(demos / r.file)
        ref = gd.adapt(d.motion, d.robot, hoap2, "optimal", verbose=False)
        got = gd.Motion.from_npz(tmp_path / "out" / r.output)
        assert r.feasible == ref.feasible and r.audit_binding == ";".join(ref.audit.binding)
        np.testing.assert_allclose(got.q, ref.motion.q, rtol=0, atol=1e-8)


def test_imitator_model_file_named_relative_runs_by_absolute_path(inputs, tmp_path,
                                                                  monkeypatch):
    repo = ROOT
    monkeypatch.chdir(repo)
    res = run_batch(inputs, tmp_path / "urdf", BatchOptions("urdf/hoap2.urdf",
                                                            method="analytic"),
                    workers=2, progress=False)
    done = res.by_status("done")
    assert len(done) == 3
    assert {r.imitator for r in done} == {str(repo / "urdf" / "hoap2.urdf")}
    for r in done:  # the same model as the library's hoap2: the same motion
        assert r.output == f"{r.file}.hoap2.analytic.npz"
        np.testing.assert_allclose(gd.Motion.from_npz(tmp_path / "urdf" / r.output).q,
                                   _direct(inputs / r.file).motion.q, rtol=0, atol=1e-12)


@pytest.mark.parametrize("pattern", ["/etc/*", "../*", "sub/*.mot", "..", "*/../*"])
def test_the_pattern_never_leaves_the_input_folder(tmp_path, pattern):
    """`--pattern '/etc/*'` raised NotImplementedError and `'../*'` picked up files of the
    folder above: a pattern is a file-name glob, matched in the input folder only."""
    demos = tmp_path / "demos"
    (demos / "sub").mkdir(parents=True)
    _mot_slices(demos, [0], 40)
    _mot_slices(tmp_path, [10], 40)  # beside the input folder: never an input
    with pytest.raises(BatchError, match="not a file-name glob"):
        find_inputs(demos, pattern)
    assert [p.parent for p in find_inputs(demos, "*.mot")] == [demos]
