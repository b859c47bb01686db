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
