"""Issue 11, security: confined mesh files, loopback servers, no orphans or litter, bounds.

Every test here failed on the code before the fix (checked against a copy of that tree):
outside meshes loaded and were embedded, a FIFO outside the URDF's folder was opened (the load
blocked), the web server listened on 0.0.0.0, an interrupted start left the server running,
deep or huge URDFs and millisecond time axes were accepted.
"""

from __future__ import annotations

import contextlib
import os
import signal
import struct
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import psutil
import pytest

import gdimitate as gd
from gdimitate.errors import (
    MeshPathError,
    OscillatorError,
    ResourceLimitError,
    URDFError,
    URDFLimitError,
)
from gdimitate.model.library import library_entry
from gdimitate.model.robot import Robot
from gdimitate.model.urdfgen import PLANAR_MODELS, planar_biped_urdf
from gdimitate.safety import (
    MAX_URDF_DEPTH,
    MAX_URDF_LINKS,
    atomic_write,
)
from gdimitate.viz.server import MeshcatServer
from tests.helpers import shared


# ------------------------------------------------------------------------- URDF helpers
def _stl(path: Path, marker: bytes = b"gdimitate test mesh") -> Path:
    """A one-triangle binary STL whose 80-byte header carries ``marker``."""
    tri = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 0.05, 0, 0, 0, 0.05, 0, 0)
    path.write_bytes(marker.ljust(80, b" ")[:80] + struct.pack("<I", 1) + tri)
    return path


def _urdf_with_mesh(folder: Path, filename: str) -> Path:
    """The planar HOAP-2 URDF with one extra visual mesh ``filename`` on its torso."""
    text = planar_biped_urdf(PLANAR_MODELS["hoap2"])
    mesh = f'<visual><geometry><mesh filename="{filename}"/></geometry></visual>'
    text = text.replace("</inertial>", "</inertial>" + mesh, 1)
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / "robot.urdf"
    p.write_text(text)
    return p


@pytest.fixture
def outside(tmp_path):
    """A mesh file outside the robot's folder."""
    (tmp_path / "outside").mkdir()
    return _stl(tmp_path / "outside" / "secret.stl", b"SECRET-OUTSIDE-MESH")


# ------------------------------------------------------------------------- 1. confinement
@pytest.mark.parametrize("kind", ["package_dotdot", "absolute", "file_url", "relative_dotdot",
                                  "symlink", "etc_passwd"])
def test_mesh_outside_the_urdf_folder_is_refused(tmp_path, outside, kind):
    robot_dir = tmp_path / "pkg" / "robot"
    robot_dir.mkdir(parents=True)
    if kind == "symlink":
        (robot_dir / "link.stl").symlink_to(outside)
    ref = {"package_dotdot": "package://robot/../../outside/secret.stl",
           "absolute": str(outside),
           "file_url": f"file://{outside}",
           "relative_dotdot": "../../outside/secret.stl",
           "symlink": "link.stl",
           "etc_passwd": "/etc/passwd"}[kind]
    urdf = _urdf_with_mesh(robot_dir, ref)
    with pytest.raises(MeshPathError) as e:
        Robot.from_urdf(urdf, package_dir=tmp_path / "pkg")
    assert isinstance(e.value, URDFError)
    msg = str(e.value)
    assert ref in msg and "outside the folders" in msg and "'torso'" in msg


def test_mesh_outside_is_never_opened(tmp_path):
    """A FIFO outside the folder blocks whoever opens it: the load must fail at once."""
    fifo = tmp_path / "trap.stl"
    os.mkfifo(fifo)
    urdf = _urdf_with_mesh(tmp_path / "robot", str(fifo))
    code = textwrap.dedent(f"""
        from gdimitate.errors import MeshPathError
        from gdimitate.model.robot import Robot
        try:
            Robot.from_urdf({str(urdf)!r})
        except MeshPathError as e:
            print("refused:", e)
    """)
    try:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             timeout=60)
    except subprocess.TimeoutExpired:
        # unblock whoever opened the FIFO (and fail)
        fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
        os.close(fd)
        pytest.fail("the outside FIFO was opened (the load blocked on it)")
    assert "refused:" in out.stdout, out.stdout + out.stderr
    assert str(fifo) in out.stdout


def test_mesh_inside_loads_and_missing_mesh_is_named(tmp_path):
    robot_dir = tmp_path / "pkg" / "robot"
    robot_dir.mkdir(parents=True)
    _stl(robot_dir / "torso.stl")
    for ref in ("torso.stl", "package://robot/torso.stl", "package:///robot/torso.stl",
                f"file://{robot_dir / 'torso.stl'}"):
        r = Robot.from_urdf(_urdf_with_mesh(robot_dir, ref), package_dir=tmp_path / "pkg")
        paths = [g.meshPath for g in r.visual_model.geometryObjects if g.meshPath.endswith("stl")]
        assert paths == [str((robot_dir / "torso.stl").resolve())]
        # Pinocchio read the very triangle we wrote (z of the three vertices: 0)
        (g,) = [g for g in r.visual_model.geometryObjects if g.meshPath.endswith("stl")]
        assert np.allclose(np.asarray(g.geometry.vertices())[:, 2], 0.0)
    # today a missing mesh silently dropped every visual; now it is an error naming the file
    with pytest.raises(MeshPathError, match="nope.stl.*not found"):
        Robot.from_urdf(_urdf_with_mesh(robot_dir, "nope.stl"))
    (robot_dir / "bad.stl").write_bytes(b"solid x\nnot an stl\n")
    with pytest.raises(URDFError, match="bad.stl"):
        Robot.from_urdf(_urdf_with_mesh(robot_dir, "bad.stl"))


@pytest.mark.parametrize("name", ["human", "talos", "romeo", "icub", "g1"])
def test_library_robots_load_as_pinocchio_loads_them(name):
    """Confinement, bounds and physics checks keep example-robot-data's robots loading, with
    the model and the mesh files Pinocchio's own loader finds."""
    robot = Robot.from_library(name)
    path, pkg = library_entry(name)
    model, collision, visual = pin.buildModelsFromUrdf(str(path), [str(pkg)],
                                                       pin.JointModelFreeFlyer())
    assert list(robot.model.names) == list(model.names)
    assert robot.mass == pytest.approx(pin.computeTotalMass(model), rel=1e-12)
    for ours, ref in ((robot.visual_model, visual), (robot.collision_model, collision)):
        n_ref = ref.ngeoms
        assert (ours.ngeoms if ours is not None else 0) == n_ref
        if n_ref:
            mine = sorted(os.path.realpath(g.meshPath) for g in ours.geometryObjects)
            theirs = sorted(os.path.realpath(g.meshPath) for g in ref.geometryObjects)
            assert mine == theirs


# ------------------------------------------------------------------------- 2. loopback
def _listening(pid: int) -> list[tuple[str, int]]:
    return sorted((c.laddr.ip, c.laddr.port) for c in psutil.Process(pid).net_connections("tcp")
                  if c.status == psutil.CONN_LISTEN)


def test_servers_listen_on_loopback_only():
    with MeshcatServer.start() as s:
        socks = _listening(s.proc.pid)
        assert {ip for ip, _ in socks} == {"127.0.0.1"}, socks
        assert s.port in {p for _, p in socks}
    with MeshcatServer.start(host="0.0.0.0") as s:  # explicit: the page for the network
        socks = dict((p, ip) for ip, p in _listening(s.proc.pid))
        assert socks[s.port] == "0.0.0.0"
        assert set(socks.values()) == {"0.0.0.0", "127.0.0.1"}  # zmq stays local


# ------------------------------------------------------------------------- 3. signals
def _env(tmp: Path) -> dict[str, str]:
    """Environment of a child run: its own TMPDIR, so litter is visible."""
    tmp.mkdir(exist_ok=True)
    return {**os.environ, "TMPDIR": str(tmp), "PYTHONUNBUFFERED": "1"}


def _servers(proc: psutil.Process) -> list[psutil.Process]:
    try:
        kids = proc.children(recursive=True)
    except psutil.NoSuchProcess:
        return []
    return [k for k in kids if any("_serve.py" in a for a in _cmdline(k))]


def _cmdline(p: psutil.Process) -> list[str]:
    try:
        return p.cmdline()
    except (psutil.NoSuchProcess, psutil.ZombieProcess):
        return []


def _wait_for_server(proc: subprocess.Popen, timeout: float = 90.0) -> psutil.Process:
    ps = psutil.Process(proc.pid)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = _servers(ps)
        if found:
            return found[0]
        if proc.poll() is not None:
            pytest.fail(f"exited ({proc.returncode}) before starting a server: "
                        f"{proc.stdout.read() if proc.stdout else ''}")
        time.sleep(0.01)
    pytest.fail("no meshcat server appeared")


def _gone(p: psutil.Process, timeout: float = 10.0) -> bool:
    try:
        p.wait(timeout=timeout)
    except psutil.TimeoutExpired:
        p.kill()
        return False
    except psutil.NoSuchProcess:
        pass
    return True


@pytest.mark.slow
def test_ctrl_c_during_viewer_start_leaves_no_server(tmp_path, spawn):
    # Ctrl-C raises KeyboardInterrupt, as in a Python started from a terminal (a shell's
    # background job starts with SIGINT ignored, and Python then keeps it ignored)
    code = ("import signal, time\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "from gdimitate.viz import Viewer\nprint('starting', flush=True)\n"
            "v = Viewer.start()\ntime.sleep(60)\n")
    tmp = tmp_path / "tmp"
    proc = spawn(["-c", code], tmp)
    server = _wait_for_server(proc)
    proc.send_signal(signal.SIGINT)  # at once: the server is still starting (importing meshcat)
    proc.wait(timeout=30)
    assert _gone(server), "the meshcat server outlived its parent"
    assert list(tmp.iterdir()) == []  # no logs, no ready files


def test_ctrl_c_while_the_server_process_is_created_acts_after_it():
    """Ctrl-C (and SIGTERM) arriving while ``subprocess.Popen`` creates the server — it runs
    once forked, before Popen returns its handle — is held until the handle exists, then
    raised through the handler that was there (``KeyboardInterrupt``): the start's clean-up
    then has the process to stop. The handlers are the previous ones afterwards."""
    from gdimitate.viz.server import _signals_held

    outer = signal.signal(signal.SIGINT, signal.default_int_handler)  # as from a terminal
    try:
        before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
        reached = False
        with pytest.raises(KeyboardInterrupt):
            with _signals_held():
                signal.raise_signal(signal.SIGINT)
                time.sleep(0.05)  # a handler that raised would have raised by now
                reached = True
        assert reached
        assert {s: signal.getsignal(s) for s in before} == before
    finally:
        signal.signal(signal.SIGINT, outer)


def test_server_exits_when_its_parent_is_killed(tmp_path, spawn):
    code = ("import time\nfrom gdimitate.viz import Viewer\nv = Viewer.start()\n"
            "print('started', flush=True)\ntime.sleep(60)\n")
    proc = spawn(["-c", code], tmp_path / "tmp")
    server = _wait_for_server(proc)
    _wait_for_line(proc, "started")
    proc.kill()  # SIGKILL: no clean-up runs in the parent
    proc.wait(timeout=10)
    assert _gone(server, timeout=10), "the meshcat server was orphaned"
    assert list((tmp_path / "tmp").iterdir()) == []  # it took our temporary log along


@pytest.fixture
def spawn():
    """Start child processes; whatever is left at the end (a failed test) is killed."""
    procs: list[subprocess.Popen] = []

    def start(argv: list[str], tmp: Path) -> subprocess.Popen:
        p = subprocess.Popen([sys.executable, *argv], env=_env(tmp), stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, cwd=tmp.parent)
        procs.append(p)
        return p

    yield start
    for p in procs:
        with contextlib.suppress(psutil.NoSuchProcess):
            for k in psutil.Process(p.pid).children(recursive=True):
                k.kill()
        p.kill()
        p.wait()


def _wait_for_line(proc: subprocess.Popen, text: str) -> str:
    seen = ""
    while text not in seen:
        line = proc.stdout.readline()
        assert line, f"exited before printing {text!r}: {seen}"
        seen += line
    return seen


@pytest.mark.slow
def test_demo_terminated_leaves_no_output(tmp_path, spawn):
    out = tmp_path / "demo-out"
    proc = spawn(["-m", "gdimitate.apps.cli", "demo", "--method", "analytic", "--out", str(out)],
                 tmp_path / "tmp")
    text = _wait_for_line(proc, "[1/")  # loading the walk; the output folder is made
    assert out.is_dir()
    proc.send_signal(signal.SIGTERM)
    rest, _ = proc.communicate(timeout=60)
    assert proc.returncode == 143, text + rest
    assert "terminated" in rest
    assert not out.exists(), sorted(p.name for p in out.iterdir())
    assert list((tmp_path / "tmp").iterdir()) == []


@pytest.mark.slow
def test_view_stops_on_sigint_and_fails_when_its_server_dies(tmp_path, spawn):
    # a feasible example: since issue 22 the exit status after Ctrl-C is the verdict's
    view = ["-m", "gdimitate.apps.cli", "view", "--example", "case-I", "--method", "analytic",
            "--seconds", "120"]
    proc = spawn(view, tmp_path / "tmp")
    server = _wait_for_server(proc)
    _wait_for_line(proc, "press Ctrl-C")
    proc.send_signal(signal.SIGINT)  # the documented way to stop a live viewer
    text, _ = proc.communicate(timeout=30)
    assert proc.returncode == 0, text
    assert _gone(server)
    # a live viewer whose server dies exits non-zero with a message
    proc = spawn(view, tmp_path / "tmp")
    server = _wait_for_server(proc)
    _wait_for_line(proc, "press Ctrl-C")
    server.kill()
    text, _ = proc.communicate(timeout=30)
    assert proc.returncode == 2, text
    assert "meshcat server" in text and "exited" in text
    assert list((tmp_path / "tmp").iterdir()) == []


def test_atomic_write_replaces_whole_or_not_at_all(tmp_path):
    p = tmp_path / "report.json"
    p.write_text("old")
    for exc in (RuntimeError, KeyboardInterrupt):
        with pytest.raises(exc), atomic_write(p) as tmp:
            tmp.write_text("half")
            raise exc
        assert p.read_text() == "old"
        assert sorted(f.name for f in tmp_path.iterdir()) == ["report.json"]
    with atomic_write(tmp_path / "m.npz") as tmp:
        assert tmp.suffix == ".npz" and tmp.parent == tmp_path
        np.savez(tmp, a=np.arange(3))
    assert np.load(tmp_path / "m.npz")["a"].tolist() == [0, 1, 2]
    umask = os.umask(0o022)
    os.umask(umask)
    assert (tmp_path / "m.npz").stat().st_mode & 0o777 == 0o666 & ~umask


# ------------------------------------------------------------------------- 4. bounds
def _chain_urdf(path: Path, n: int, branching: bool = False) -> Path:
    links = [f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" '
             'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>' for i in range(n + 1)]
    joints = [f'<joint name="j{i}" type="revolute"><parent link="l{0 if branching else i}"/>'
              f'<child link="l{i + 1}"/><origin xyz="0 0 0.01"/><axis xyz="0 1 0"/>'
              '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>' for i in range(n)]
    path.write_text(f'<robot name="c">{"".join(links)}{"".join(joints)}</robot>')
    return path


def test_urdf_size_and_depth_are_bounded_before_parsing(tmp_path):
    t0 = time.perf_counter()
    with pytest.raises(URDFLimitError, match=f"joints deep; the limit is {MAX_URDF_DEPTH:,}"):
        Robot.from_urdf(_chain_urdf(tmp_path / "deep.urdf", MAX_URDF_DEPTH + 200))
    with pytest.raises(URDFLimitError, match=f"links; the limit is {MAX_URDF_LINKS:,}"):
        Robot.from_urdf(_chain_urdf(tmp_path / "wide.urdf", MAX_URDF_LINKS + 10, True))
    big = tmp_path / "big.urdf"
    big.write_text('<robot name="b"><link name="a"/>' + "<!--" + "x" * (17 * 2**20) + "-->"
                   "</robot>")
    with pytest.raises(URDFLimitError, match="bytes; the limit is"):
        Robot.from_urdf(big)
    assert time.perf_counter() - t0 < 5.0  # refused, not parsed
    assert isinstance(URDFLimitError("x"), ResourceLimitError)
    bomb = tmp_path / "bomb.urdf"
    bomb.write_text('<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
                    '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]><robot name="&b;"/>')
    with pytest.raises(URDFError, match="DOCTYPE"):
        Robot.from_urdf(bomb)


def _hoap2_walk(t: np.ndarray) -> tuple[Robot, gd.Motion]:
    robot = shared.library_robot("hoap2")
    q = np.tile(robot.neutral, (t.size, 1))
    w = 2 * np.pi * 0.8 * (t - t[0]) / (t[-1] - t[0]) * 2.0
    for side, phase in (("left", 0.0), ("right", np.pi)):
        q[:, robot.idx_q(f"{side}_hip")] += 0.3 * np.sin(w + phase)
        q[:, robot.idx_q(f"{side}_knee")] += -0.4 - 0.3 * np.sin(w + phase + 1.0)
    return robot, gd.Motion(t, robot.joint_names, q)


def test_millisecond_time_axis_is_refused_before_allocating():
    """entrain() of a 60 Hz clip whose time is in milliseconds grew to 22 GB; now refused."""
    import tracemalloc

    import gdimitate.oscillator.replay  # noqa: F401 — its imports (numba, SciPy: ~56 MB of module code) are not the clip's

    robot, motion = _hoap2_walk(np.arange(150) * (1000.0 / 60))
    tracemalloc.start()
    t0 = time.perf_counter()
    with pytest.raises(ResourceLimitError, match="milliseconds"):
        gd.entrain(robot, motion)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 20e6 and time.perf_counter() - t0 < 2.0
    # the oscillator alone: the step budget is checked before integrating
    t = np.arange(150) * (1000.0 / 60)
    with pytest.raises(ResourceLimitError, match="integration steps"):
        gd.oscillator.self_adjust(t, np.sin(2 * np.pi * t / 1250.0))


@pytest.mark.parametrize("option, value", [("harmonics", 10_000), ("teach_cycles", 10**7),
                                           ("free_cycles", 10**7)])
def test_oscillator_counts_have_stated_bounds(option, value):
    t = np.arange(0, 2.5, 1 / 60)
    x = np.sin(2 * np.pi * 0.8 * t)
    t0 = time.perf_counter()
    with pytest.raises(ResourceLimitError, match="exceeds the limit"):
        gd.oscillator.self_adjust(t, x, **{option: value})
    assert time.perf_counter() - t0 < 1.0


def test_harmonics_need_enough_samples():
    t = np.arange(50) / 60
    with pytest.raises(OscillatorError, match="harmonics = 30 needs at least 61 samples"):
        gd.oscillator.fit_teacher(t, np.sin(2 * np.pi * t), harmonics=30)


def test_replay_duration_and_rate_are_bounded():
    robot, motion = _hoap2_walk(np.arange(150) / 60.0)
    with pytest.raises(ResourceLimitError, match="duration"):
        gd.entrain(robot, motion, duration=1e7)
    with pytest.raises(ResourceLimitError, match="frames; the limit"):
        gd.entrain(robot, motion, duration=100.0, rate=1e6)



# ----------------------------------------------- issue 22: one bound on user-sized arrays
@contextlib.contextmanager
def _bounded(peak_bytes: float = 50e6, seconds: float = 3.0):
    """The block must finish within ``seconds`` and allocate at most ``peak_bytes``."""
    import tracemalloc

    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        yield
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peak < peak_bytes, f"allocated {peak / 1e6:.0f} MB before refusing"
    assert time.perf_counter() - t0 < seconds


def _bvh(frames: str = "3", frame_time: str = "0.0083333", depth: int = 3,
         rows: int = 3) -> str:
    """A chain skeleton ``depth`` joints deep with a 6-channel root and 3 channels per joint."""
    head = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 90 0",
            "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for k in range(1, depth):
        head += [f"JOINT J{k}", "{", "OFFSET 0 -1 0", "CHANNELS 3 Zrotation Xrotation Yrotation"]
    head += ["End Site", "{", "OFFSET 0 -1 0", "}"] + ["}"] * depth
    n = 6 + 3 * (depth - 1)
    return "\n".join(head + ["MOTION", f"Frames: {frames}", f"Frame Time: {frame_time}"]
                     + [" ".join(["0"] * n)] * rows) + "\n"


@pytest.mark.parametrize("frames", ["100000000", "1000000000000"])
def test_bvh_frame_count_is_bounded_before_allocating(tmp_path, frames):
    """A header claiming 1e8 or 1e12 frames raised numpy's bare MemoryError."""
    from gdimitate.io.bvh.parse import parse_bvh

    p = tmp_path / "big.bvh"
    for frame_time in ("0.0083333", "0.00001"):  # over the duration bound, or the array bound
        p.write_text(_bvh(frames, frame_time))
        with _bounded(), pytest.raises(ResourceLimitError, match="limit"):
            parse_bvh(p)


def test_bvh_hierarchy_depth_is_bounded():
    """A 1500-deep chain raised RecursionError; the bound is stated and a deep chain within it
    parses with every joint."""
    import tempfile

    from gdimitate.io.bvh.parse import MAX_BVH_DEPTH, parse_bvh

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "deep.bvh"
        p.write_text(_bvh(depth=1500))
        with _bounded(), pytest.raises(ResourceLimitError, match="joints deep; the limit"):
            parse_bvh(p)
        p.write_text(_bvh(depth=MAX_BVH_DEPTH))
        assert len(parse_bvh(p).joints) == MAX_BVH_DEPTH


@pytest.mark.parametrize("frame_time", ["1000000", "2.5", "1e-9"])
def test_bvh_frame_time_is_bounded(tmp_path, frame_time):
    from gdimitate.io.bvh.parse import parse_bvh

    p = tmp_path / "slow.bvh"
    p.write_text(_bvh(frame_time=frame_time))
    with pytest.raises(ResourceLimitError, match="Frame Time"):
        parse_bvh(p)


def _walk_with_contacts(t: np.ndarray) -> tuple[Robot, gd.Motion]:
    from gdimitate.model.kinematics import kinematic_contact

    robot, motion = _hoap2_walk(t)
    return robot, motion.replace(contact=kinematic_contact(robot, motion.q))


@pytest.mark.parametrize("step", [1e6, 2.0])
def test_adapt_of_a_motion_on_seconds_apart_frames_is_refused(step):
    """A BVH frame time of 1e6 s followed by adapt allocated 44 GiB (the knot grid); a motion
    whose frames are seconds apart is refused by every method before any work."""
    robot, motion = _walk_with_contacts(np.arange(40) * step)
    for method in ("optimal", "analytic"):
        with _bounded(), pytest.raises(ResourceLimitError, match="time step"):
            gd.adapt(motion, robot, robot, method)


@pytest.mark.parametrize("rate, says", [(1e6, "exceeds the limit 1000"),
                                        (float("inf"), "finite")])
def test_adapt_knot_rate_is_bounded(rate, says):
    """adapt(..., rate=1e6) was still running after 90 s."""
    from gdimitate.errors import InvalidInputError

    robot, motion = _walk_with_contacts(np.arange(60) / 60.0)
    with _bounded(), pytest.raises(InvalidInputError, match=says):
        gd.adapt(motion, robot, robot, rate=rate)


def test_a_long_motion_at_a_legal_rate_is_bounded_by_its_knot_array():
    from gdimitate.safety import MAX_ARRAY_BYTES

    robot, motion = _walk_with_contacts(np.arange(0, 3500, 0.5))
    g1 = shared.library_robot("g1")
    knots_fit = MAX_ARRAY_BYTES / 8 / (g1.model.nq + 2 * g1.model.nv)
    assert 3500 * 1000 > knots_fit  # the grid below is beyond the bound
    with _bounded(), pytest.raises(ResourceLimitError, match="knot grid"):
        gd.adapt(motion, robot, g1, rate=1000.0)


def test_export_frame_rate_is_bounded(tmp_path):
    """export_motion(..., 'lafan1_csv', fps=1e9) wrote 15.5 GB in 90 s."""
    from gdimitate.errors import ExportError
    from gdimitate.export.writers import export_motion

    g1 = shared.library_robot("g1")
    t = np.arange(30) / 30.0
    motion = gd.Motion(t, g1.joint_names, np.tile(g1.neutral, (t.size, 1)), base_nq=7,
                       joint_nq=tuple(g1.model.joints[j].nq for j in range(1, g1.model.njoints)))
    out = tmp_path / "m.csv"
    with _bounded(), pytest.raises(ResourceLimitError, match="lafan1_csv at 1e"):
        export_motion(g1, motion, out, "lafan1_csv", fps=1e9)
    for bad in (0.0, -30.0, float("nan")):
        with pytest.raises(ExportError, match="fps"):
            export_motion(g1, motion, out, "lafan1_csv", fps=bad)
    assert not out.exists()
    export_motion(g1, motion, out, "lafan1_csv", fps=60.0)  # within the bound: written
    assert len(out.read_text().splitlines()) == 59


@pytest.mark.parametrize("shape", [(10**6, 10**4), (10**12,), (2**40, 2**40)])
def test_oscillator_bank_shape_is_bounded(shape):
    """MatsuokaBank(..., shape=(10**6, 10**4)) raised a bare MemoryError."""
    p = gd.oscillator.MatsuokaParams(tau_r=0.1, tau_a=0.4, b=2.5, w=2.5, s=1.0)
    with _bounded(), pytest.raises(ResourceLimitError, match="MAX_ARRAY_BYTES"):
        gd.oscillator.MatsuokaBank(p, shape=shape)
    bank = gd.oscillator.MatsuokaBank(p, shape=(1000,))
    with _bounded(), pytest.raises(ResourceLimitError, match="run of a bank"):
        bank.simulate(np.arange(200_000) * 1e-3)


# ------------------------------------------- issue 22: nothing written outside the output
def test_a_diverging_simulation_writes_no_mujoco_log(tmp_path, monkeypatch):
    """MuJoCo appends its warnings to MUJOCO_LOG.TXT in the working folder; a simulation that
    goes to NaN (here: a 1e30 N push) left one there. Now the warning is a Python warning."""
    from gdimitate.apps.baselines import kinematic_plan
    from gdimitate.errors import GdimitateWarning
    from gdimitate.sim import simulate
    from gdimitate.sim.simulate import Push

    monkeypatch.chdir(tmp_path)
    robot = shared.library_robot("hoap2")
    T = 30
    motion = gd.Motion(np.arange(T) / 60, robot.joint_names, np.tile(robot.neutral, (T, 1)),
                       contact={s: np.ones(T, bool) for s in ("left", "right")}, base_nq=3)
    plan = kinematic_plan(robot, motion, "copy", 0.0)
    with pytest.warns(GdimitateWarning, match="MuJoCo: Nan, Inf or huge value"):
        res = simulate(robot, plan, push=Push(0.05, 0.1, (1e30, 0.0, 0.0)), stop_on_fall=False)
    assert res.metrics.fell
    assert list(tmp_path.iterdir()) == []
    import mujoco

    assert mujoco.get_mju_user_warning() is None  # MuJoCo's own handler is back


def test_opensim_model_loads_leave_nothing_in_the_temp_folder(tmp_path, monkeypatch):
    """Every Robot.from_osim left a gdimitate_osim_* folder in the system temp directory (68
    after one afternoon)."""
    import tempfile

    from gdimitate.io.gait import human_walk_3d_folder

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    robot = Robot.from_osim(human_walk_3d_folder() / "subject01.osim")
    assert robot.model.nq > 20 and robot.urdf_path is None
    assert list(tmp_path.iterdir()) == []
