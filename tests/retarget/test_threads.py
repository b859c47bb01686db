"""retarget/threads.single_thread acts on the BLAS that IPOPT's MUMPS really runs: the CasADi
wheel ships its OpenBLAS as three separate files (.so, .so.0, .so.0.3, no symlinks), and the
dynamic loader maps the one named by the soname MUMPS links against. The reference is the
process's own memory map (/proc/self/maps), not the module's choice of file."""

from __future__ import annotations

import ctypes
import sys

import casadi as ca
import pytest

from gdimitate.retarget.threads import single_thread

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self/maps")


def _mapped_openblas() -> list[str]:
    with open("/proc/self/maps") as fh:
        paths = {line.split()[-1] for line in fh if "libcasadi-tp-openblas" in line}
    return sorted(paths)


def test_single_thread_sets_the_openblas_ipopt_loads():
    x = ca.SX.sym("x")  # loading IPOPT maps MUMPS's OpenBLAS
    ca.nlpsol("s", "ipopt", {"x": x, "f": x**2}, {"print_time": False, "ipopt.sb": "yes",
                                                 "ipopt.print_level": 0})
    with single_thread():
        mapped = _mapped_openblas()
        assert mapped, "IPOPT's OpenBLAS is not mapped"
        for path in mapped:  # every copy in the process, the one MUMPS calls included
            lib = ctypes.CDLL(path)
            lib.openblas_get_num_threads.restype = ctypes.c_int
            assert lib.openblas_get_num_threads() == 1, path


def _counts() -> list[int]:
    from gdimitate.retarget.threads import _libs

    return [g() for g, _ in _libs()]


def test_a_hold_keeps_one_thread_until_its_last_release():
    """hold_one_thread: every library at one thread while any hold is open (the libraries'
    own getters are the reference); the counts found come back at the last release; a second
    release of one hold changes nothing."""
    from gdimitate.retarget.threads import _libs, hold_one_thread

    libs = _libs()
    assert libs, "no BLAS library found"
    for _, s in libs:
        s(2)
    before = _counts()
    first = hold_one_thread()
    second = hold_one_thread()
    assert _counts() == [1] * len(libs)
    first()
    first()  # idempotent: the second hold is still open
    assert _counts() == [1] * len(libs)
    with single_thread():  # a block inside a hold leaves it at one
        pass
    assert _counts() == [1] * len(libs)
    second()
    assert _counts() == before


def test_a_streaming_adaptor_holds_one_thread_while_open():
    """StreamingAdaptor: one BLAS thread from construction to close() (the frames' small
    products; setting the count back every frame woke OpenBLAS's spinning threads); a later
    step still runs, and garbage collection releases an adaptor never closed."""
    import gc

    import numpy as np

    import gdimitate as gd
    from gdimitate.retarget.threads import _libs

    for _, s in _libs():
        s(2)
    before = _counts()
    h, m, f = gd.gait.human_walk_3d()
    robot = gd.Robot.from_library("g1")
    flags = {s: bool(m.contact[s][0]) for s in ("left", "right")}
    sa = gd.retarget.StreamingAdaptor(h, robot, dt=m.dt, audit=False)
    assert _counts() == [1] * len(before)
    sa.step(m.q[0], flags)
    sa.close()
    assert _counts() == before
    r = sa.step(m.q[1], {s: bool(m.contact[s][1]) for s in ("left", "right")})
    assert np.all(np.isfinite(r.q)) and _counts() == before
    sa = gd.retarget.StreamingAdaptor(h, robot, dt=m.dt, audit=False)
    assert _counts() == [1] * len(before)
    del sa
    gc.collect()
    assert _counts() == before
