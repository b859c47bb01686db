"""One thread for the linear algebra during a solve.

IPOPT's MUMPS in the CasADi wheel calls the wheel's own OpenBLAS (``libcasadi-tp-openblas``)
and OpenMP (``libgomp``); NumPy and SciPy carry OpenBLAS builds of their own. On a busy
machine their spinning worker threads double the wall time of a solve, and make NumPy's
products of the streaming mode's small matrices ten times slower (12.8 → 1.4 ms per frame
QP on HOAP-2; docs/design.md §6, "the solver"); the knot-sized dense blocks gain nothing from
them. :func:`single_thread` sets each to one thread for the duration of a ``with`` block and
restores the previous counts after; a library it cannot find is left alone.

:func:`hold_one_thread` does the same from a call to its release, for an object that runs
many small blocks (the streaming mode's frames): setting OpenBLAS back to two threads after
every frame woke its worker threads, which then spun — 10–15 % more CPU than the frames' own,
taken from the core the verdict worker runs on. Holds nest (the counts come back at the last
release).
"""

from __future__ import annotations

import ctypes
import glob
import os
import threading
from collections.abc import Callable
from contextlib import contextmanager

__all__ = ["single_thread", "hold_one_thread"]

_LIBS: list | None = None
#: :func:`hold_one_thread`'s open holds and the counts its first one found
_HOLDS: list[int] = [0]
_SAVED: list[int] = []
_LOCK = threading.Lock()


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


def hold_one_thread() -> Callable[[], None]:
    """Set one OpenBLAS and one OpenMP thread until the returned function is called (it
    restores the previous counts at the last open hold's release; calling it again does
    nothing)."""
    with _LOCK:
        if _HOLDS[0] == 0:
            libs = _libs()
            _SAVED[:] = [g() for g, _ in libs]
            for _, s in libs:
                s(1)
        _HOLDS[0] += 1
    done = [False]

    def release() -> None:
        with _LOCK:
            if done[0]:
                return
            done[0] = True
            _HOLDS[0] -= 1
            if _HOLDS[0] == 0:
                for (_, s), n in zip(_libs(), _SAVED):
                    s(max(int(n), 1))

    return release
