"""Issue 33, data lost: a command removes only what it wrote itself, two runs on one output
folder do not mix, and a run stopped by a signal ends with its documented status and leaves
no half-written result.

Before: a failing ``gdimitate adapt --out O`` deleted every file under ``O`` that had changed
while it ran — another run's results, another program's log, a source file being edited with
``--out .`` — and SIGTERM during the optimal solve was swallowed inside the solver's callback
(the run wrote a least-infeasible result and exited 3, not 143).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from gdimitate.apps.cli import main
from gdimitate.errors import OutputError
from gdimitate.io.gait import human_walk_path
from gdimitate.safety import LOCK_NAME, atomic_write, output_job
from tests.helpers import shared

SAG = human_walk_path()
SAG_GRF = SAG.parent / "walk_gait1018_subject01_grf.mot"


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


# ------------------------------------------------------------------ the job, in-process
def test_a_failed_job_undoes_exactly_what_it_wrote(tmp_path):
    """Created files removed, replaced files put back, files others wrote or changed while
    it ran kept, folders it made removed when empty, nothing else touched."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("before")
    (out / "report.json").write_text('{"run": "previous"}')
    (out / "log.txt").write_text("line 1\n")
    with pytest.raises(KeyboardInterrupt), output_job(out):
        with atomic_write(out / "report.json") as tmp:
            tmp.write_text('{"run": "this"}')
        with atomic_write(out / "new.csv") as tmp:
            tmp.write_text("1,2")
        (out / "sub").mkdir()
        with atomic_write(out / "sub" / "x.png") as tmp:
            tmp.write_bytes(b"png")
        with atomic_write(out / "theirs_later.txt") as tmp:
            tmp.write_text("ours first")
        # another program, meanwhile: appends to its log, writes its own file, and rewrites
        # one the job had written
        with open(out / "log.txt", "a") as f:
            f.write("line 2\n")
        (out / "other_run.npz").write_bytes(b"PK...")
        time.sleep(0.01)
        (out / "theirs_later.txt").write_text("theirs, written after ours")
        raise KeyboardInterrupt
    assert _files(out) == {
        "keep.txt": b"before", "report.json": b'{"run": "previous"}',
        "log.txt": b"line 1\nline 2\n", "other_run.npz": b"PK...",
        "theirs_later.txt": b"theirs, written after ours"}
    assert sorted(p.name for p in out.iterdir()) == sorted(_files(out))  # no lock, no backup


def test_a_job_that_made_its_folder_removes_it_and_a_good_job_keeps_everything(tmp_path):
    fresh = tmp_path / "a" / "b"
    with pytest.raises(RuntimeError), output_job(fresh):
        with atomic_write(fresh / "r.json") as tmp:
            tmp.write_text("{}")
        raise RuntimeError
    assert list(tmp_path.iterdir()) == []
    out = tmp_path / "ok"
    out.mkdir()
    (out / "r.json").write_text("old")
    with output_job(out):
        with atomic_write(out / "r.json") as tmp:
            tmp.write_text("new")
    assert _files(out) == {"r.json": b"new"}
    assert sorted(p.name for p in out.iterdir()) == ["r.json"]  # backup and lock gone


def test_two_jobs_on_one_folder_do_not_mix(tmp_path):
    """The second run on a held folder is refused (also from another process), and the
    folder is free again once the first ends — even when it was killed (SIGKILL)."""
    out = tmp_path / "o"
    with output_job(out):
        assert (out / LOCK_NAME).read_text() == str(os.getpid())
        with pytest.raises(OutputError, match=rf"in use by another gdimitate run \(process "
                                              rf"{os.getpid()}\)"), output_job(out):
            pass
        assert (out / LOCK_NAME).exists()  # the refused run did not release the lock
    holder = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import time
        from gdimitate.safety import output_job
        with output_job({str(out)!r}):
            print("held", flush=True)
            time.sleep(60)
        """)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(OutputError, match=f"process {holder.pid}"), output_job(out):
            pass
    finally:
        holder.kill()
        holder.wait()
    with output_job(out):  # the kernel released the killed holder's lock
        pass


# ------------------------------------------------------------------ the commands
def test_a_failing_command_leaves_others_files_alone(tmp_path, monkeypatch, capsys):
    """The issue's case: a failing run into a folder that holds another run's results, a log
    another program appends to, and (``--out .``) a project's source files."""
    project = tmp_path / "project"
    project.mkdir()
    (project / "model.py").write_text("x = 1\n")
    (project / "results").mkdir()
    (project / "results" / "report.json").write_text('{"from": "another run"}')
    (project / "run.log").write_text("started\n")
    before = _files(project)
    monkeypatch.chdir(project)
    for out in (".", "results"):
        assert main(["adapt", "missing.mot", "--out", out]) == 2
        assert main(["adapt", str(SAG), "--imitator", "nobody", "--out", out]) == 2
    assert _files(project) == before
    assert sorted(p.name for p in project.rglob("*")) == sorted(
        ["model.py", "results", "report.json", "run.log"])
    capsys.readouterr()


def test_a_second_command_on_a_busy_folder_is_refused(tmp_path, capsys):
    out = tmp_path / "busy"
    with output_job(out):
        (out / "partial.csv").write_text("the first run's")
        assert main(["adapt", str(SAG), "--grf", str(SAG_GRF), "--imitator", "hoap2",
                     "--method", "analytic", "--out", str(out)]) == 2
        assert _files(out) == {"partial.csv": b"the first run's", LOCK_NAME:
                               str(os.getpid()).encode()}
    assert "in use by another gdimitate run" in capsys.readouterr().err


def _start_adapt(out: Path) -> subprocess.Popen:
    p = subprocess.Popen([sys.executable, "-m", "gdimitate.apps.cli", "adapt", str(SAG), "--grf",
                          str(SAG_GRF), "--imitator", "hoap2", "--out", str(out)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    line = ""
    while "iter" not in line and time.time() - t0 < 300:  # the solve is running
        line = p.stderr.readline()
        if not line and p.poll() is not None:
            break
    assert "iter" in line, p.stderr.read()
    return p


@pytest.mark.slow
@pytest.mark.parametrize(("sig", "status"), [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_during_the_solve_ends_the_run_with_its_status(tmp_path, sig, status):
    """SIGTERM reached the solver's callback and was lost (exit 3, a least-infeasible result
    written); now both signals stop the solve, nothing is written, the folder the run made
    is gone and a folder that was there keeps exactly its files."""
    for out in (tmp_path / "made" / "o", tmp_path / "there"):
        if out.name == "there":
            out.mkdir()
            (out / "notes.txt").write_text("mine")
        p = _start_adapt(out)
        p.send_signal(sig)
        _, err = p.communicate(timeout=120)
        assert p.returncode == status, err
        assert "Traceback" not in err and "SystemError" not in err, err
        if out.name == "there":
            assert sorted(x.name for x in out.iterdir()) == ["notes.txt"]
        else:
            assert not (tmp_path / "made").exists()


@pytest.mark.slow
def test_a_run_killed_mid_write_leaves_no_half_written_result(tmp_path):
    """SIGKILL at several moments of a run: every result file in the folder is whole
    (written under a temporary name and renamed), and the next run on the folder is not
    refused."""
    out = tmp_path / "k"
    for delay in (0.5, 2.5):
        p = _start_adapt(out)
        time.sleep(delay)
        p.kill()
        p.communicate(timeout=60)
        for f in (x for x in out.iterdir() if not x.name.startswith(".")):
            if f.suffix == ".json":
                json.loads(f.read_text())
            elif f.suffix == ".npz":
                with np.load(f) as z:
                    assert "q" in z.files
    r = subprocess.run([sys.executable, "-m", "gdimitate.apps.cli", "adapt", str(SAG), "--grf",
                        str(SAG_GRF), "--imitator", "hoap2", "--method", "analytic", "--out",
                        str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode in (0, 3), r.stderr
    assert json.loads((out / "report.json").read_text())["method"] == "analytic"


# ------------------------------------------------------------------ nothing left behind
def test_a_viewer_never_closed_leaves_no_log(tmp_path):
    """`Viewer.start()` without `close()` left `gdimitate-meshcat-*.log` in the temporary
    folder; the server's own log is now removed with it at interpreter exit."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    r = subprocess.run([sys.executable, "-c", "from gdimitate.viz import Viewer\n"
                        "v = Viewer.start(quiet=True)\nprint(v.server.log_path)"],
                       capture_output=True, text=True, timeout=120,
                       env={**os.environ, "TMPDIR": str(tmp)})
    assert r.returncode == 0, r.stderr
    assert str(tmp) in r.stdout  # the log was there while the server ran
    deadline = time.time() + 10
    while list(tmp.iterdir()) and time.time() < deadline:
        time.sleep(0.1)
    assert list(tmp.iterdir()) == []


def test_an_npz_whose_header_promises_more_than_it_holds_is_refused(tmp_path):
    """A member's .npy header claiming shape (10¹¹,) asked NumPy for 745 GiB; every member's
    header is now checked against what the member holds before anything is loaded."""
    import io
    import zipfile

    import gdimitate as gd
    from gdimitate.errors import FileFormatError
    from gdimitate.model.motion import Motion

    robot = shared.library_robot("hoap2")
    good = tmp_path / "good.npz"
    gd.adapt(*_sagittal(robot), "analytic").motion.to_npz(good, robot=robot)
    with zipfile.ZipFile(good) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    for shape in [(10**11,), (10**6, 10**6), (2**62,)]:
        buf = io.BytesIO()
        np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False,
                                                   "shape": shape})
        buf.write(b"\0" * 64)
        p = tmp_path / "forged.npz"
        with zipfile.ZipFile(p, "w") as zf:  # a real motion file, its q replaced
            for n, data in members.items():
                zf.writestr(n, buf.getvalue() if n == "q.npy" else data)
        with pytest.raises(FileFormatError, match="truncated or forged"):
            Motion.from_npz(p)


def _sagittal(robot):
    from gdimitate.io.gait import human_walk

    human, walk = human_walk()
    return walk, human, robot
