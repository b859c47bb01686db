"""One thread for the linear algebra during a solve.

IPOPT's MUMPS in the CasADi wheel calls the wheel's own OpenBLAS (``libcasadi-tp-openblas``)
and OpenMP (``libgomp``). On a busy machine their spinning worker threads double the wall time
of a solve (docs/design.md §6, "the solver"); the knot-sized dense blocks gain nothing from
them. :func:`single_thread` sets both to one thread for the duration of a ``with`` block and
restores the previous counts after; a library it cannot find is left alone.
"""

from __future__ import annotations

import ctypes
import glob
import os
from contextlib import contextmanager

__all__ = ["single_thread"]

_LIBS: list | None = None


def _libs() -> list:
    """``[(get, set)]`` thread-count functions of the wheel's OpenBLAS and OpenMP."""
    global _LIBS
    if _LIBS is None:
        import casadi

        root = os.path.dirname(casadi.__file__)
        _LIBS = []
        for pattern, get, set_ in (("libcasadi-tp-openblas.so*", "openblas_get_num_threads",
                                    "openblas_set_num_threads"),
                                   ("libgomp*.so*", "omp_get_max_threads",
                                    "omp_set_num_threads")):
            for path in sorted(glob.glob(os.path.join(root, pattern)))[:1]:
                try:
                    lib = ctypes.CDLL(path)
                    g, s = getattr(lib, get), getattr(lib, set_)
                except (OSError, AttributeError):
                    continue
                g.restype = ctypes.c_int
                s.argtypes = [ctypes.c_int]
                _LIBS.append((g, s))
    return _LIBS


@contextmanager
def single_thread():
    """Run the block with one OpenBLAS and one OpenMP thread (module docstring)."""
    libs = _libs()
    old = [g() for g, _ in libs]
    for _, s in libs:
        s(1)
    try:
        yield
    finally:
        for (_, s), n in zip(libs, old):
            s(max(int(n), 1))
