"""One thread for the linear algebra during a solve.

IPOPT's MUMPS in the CasADi wheel calls the wheel's own OpenBLAS (``libcasadi-tp-openblas``)
and OpenMP (``libgomp``); NumPy and SciPy carry OpenBLAS builds of their own. On a busy
machine their spinning worker threads double the wall time of a solve, and make NumPy's
products of the streaming mode's small matrices ten times slower (12.8 → 1.4 ms per frame
QP on HOAP-2; docs/design.md §6, "the solver"); the knot-sized dense blocks gain nothing from
them. :func:`single_thread` sets each to one thread for the duration of a ``with`` block and
restores the previous counts after; a library it cannot find is left alone.
"""

from __future__ import annotations

import ctypes
import glob
import os
from contextlib import contextmanager

__all__ = ["single_thread"]

_LIBS: list | None = None


_TARGETS = (
    # (package whose folder holds the library, glob, get, set)
    # the wheel ships .so, .so.0 and .so.0.3 as three copies (no symlinks): IPOPT's MUMPS
    # loads the one its soname names, and a thread count set on another copy changes nothing
    ("casadi", "libcasadi-tp-openblas.so.0", "openblas_get_num_threads",
     "openblas_set_num_threads"),
    ("casadi", "libgomp*.so*", "omp_get_max_threads", "omp_set_num_threads"),
    ("numpy", "../numpy.libs/libscipy_openblas*.so*", "scipy_openblas_get_num_threads64_",
     "scipy_openblas_set_num_threads64_"),
    ("scipy", "../scipy.libs/libscipy_openblas*.so*", "scipy_openblas_get_num_threads",
     "scipy_openblas_set_num_threads"),
)


def _libs() -> list:
    """``[(get, set)]`` thread-count functions of the BLAS and OpenMP libraries found."""
    global _LIBS
    if _LIBS is None:
        import importlib

        _LIBS = []
        for pkg, pattern, get, set_ in _TARGETS:
            try:
                file = importlib.import_module(pkg).__file__
            except ImportError:
                continue
            if file is None:  # a namespace package: no library beside it
                continue
            root = os.path.dirname(file)
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
