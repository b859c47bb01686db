"""Compiled (numba) fast path of the RK4 integration in :mod:`gdimitate.oscillator.bank`.

Same arithmetic as the NumPy reference ``bank._rk4_numpy`` (the tests hold the two equal to
round-off). Layout: oscillators are flattened to ``(n, B)`` — ``n`` coupled oscillators, ``B``
independent copies — with ``B`` contiguous, so the innermost loops run over copies and
vectorise. Copies are processed in chunks of ``CHUNK`` (state kept in L1 cache for all time
steps of a chunk); chunks run in parallel threads where there is more than one chunk.

Each kernel is compiled twice from one definition: a parallel build (``numba.prange`` over
chunks) for batches of more than ``CHUNK`` copies, and a serial build for one chunk, where
threads have nothing to share out. A fresh install compiles only what it calls: numba's
parallel build of the coupled kernel took 67 s on the loaded 2 cores, the serial one 19 s,
and every run of the demo's entrainment is one chunk.
"""

from __future__ import annotations

import os
import sys
import types
from collections.abc import Callable
from typing import Any

import numpy as np

try:  # numba is a dependency, but keep the NumPy path usable without it
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False

CHUNK = 256

__all__ = ["HAVE_NUMBA", "rk4_numba", "rk4_uncoupled_numba", "rk4_numba_serial",
           "rk4_uncoupled_numba_serial", "kernel", "CHUNK", "first_compile",
           "announce_first_compile"]


def _deriv(sxe, sxf, sve, svf, gv, has_g, P, W, l0, m, n, ye, yf, dxe, dxf, dve, dvf):
    """Derivative of the stage state (all arrays (n, L); first m columns valid)."""
    for i in range(n):
        for l in range(m):
            ye[i, l] = max(sxe[i, l], 0.0)
            yf[i, l] = max(sxf[i, l], 0.0)
    for i in range(n):
        for l in range(m):
            c = l0 + l
            b = P[2, i, c]
            w = P[3, i, c]
            s = P[4, i, c]
            dxe[i, l] = s - sxe[i, l] - w * yf[i, l] - b * sve[i, l]
            dxf[i, l] = s - sxf[i, l] - w * ye[i, l] - b * svf[i, l]
        for j in range(n):
            wij = W[i, j]
            if wij != 0.0:
                for l in range(m):
                    dxe[i, l] -= wij * ye[j, l]
                    dxf[i, l] -= wij * yf[j, l]
        if has_g:
            for l in range(m):
                k = P[5, i, l0 + l]
                g = gv[i, l]
                dxe[i, l] -= k * max(g, 0.0)
                dxf[i, l] -= k * max(-g, 0.0)
        for l in range(m):
            c = l0 + l
            itr = P[0, i, c]
            ita = P[1, i, c]
            dxe[i, l] *= itr
            dxf[i, l] *= itr
            dve[i, l] = (ye[i, l] - sve[i, l]) * ita
            dvf[i, l] = (yf[i, l] - svf[i, l]) * ita


def _gather(g, k0, k1, l0, m, n, gv):
    """The chunk's input: ``g`` at step ``k0`` (``k1 == k0``) or midway between steps ``k0``
    and ``k1`` (linear interpolation), into ``gv`` (n, L)."""
    for i in range(n):
        for l in range(m):
            if k1 == k0:
                gv[i, l] = g[k0, i, l0 + l]
            else:
                gv[i, l] = 0.5 * (g[k0, i, l0 + l] + g[k1, i, l0 + l])


def _stage(first, c, x, d, acc, sx, m, n):
    """One RK4 stage's bookkeeping on (4, n, L) arrays: ``acc`` collects the stage's
    derivative ``d`` (weight 1 for the first stage, 2 for the middle two) and ``sx`` becomes
    the next stage's state ``x + c·d``."""
    for q in range(4):
        for i in range(n):
            for l in range(m):
                if first:
                    acc[q, i, l] = d[q, i, l]
                else:
                    acc[q, i, l] += 2.0 * d[q, i, l]
                sx[q, i, l] = x[q, i, l] + c * d[q, i, l]


def _deriv4(sx, gv, has_g, P, W, l0, m, n, y, d):
    """:func:`_deriv` on (4, n, L) stage state ``sx`` and derivative ``d``, (2, n, L) ``y``."""
    _deriv(sx[0], sx[1], sx[2], sx[3], gv, has_g, P, W, l0, m, n, y[0], y[1],
           d[0], d[1], d[2], d[3])


def _record(k, x, l0, m, n, rec_all, Y, XE, XF, VE, VF):
    """Write the chunk's state ``x`` (4, n, L) at step ``k``: the output ``y = [x_e]+ − [x_f]+``
    always, the four states when ``rec_all``."""
    for i in range(n):
        for l in range(m):
            Y[k, i, l0 + l] = max(x[0, i, l], 0.0) - max(x[1, i, l], 0.0)
            if rec_all:
                XE[k, i, l0 + l] = x[0, i, l]
                XF[k, i, l0 + l] = x[1, i, l]
                VE[k, i, l0 + l] = x[2, i, l]
                VF[k, i, l0 + l] = x[3, i, l]


def _step(kk, t, g, has_g, P, W, l0, m, n, x, sx, acc, d, y, gv):
    """One classical RK4 step of the chunk's state ``x`` (4, n, L) from ``t[kk]`` to
    ``t[kk + 1]``; the input at the step's ends and linearly interpolated at its midpoint."""
    h = t[kk + 1] - t[kk]
    h2 = 0.5 * h
    if has_g:
        _gather(g, kk, kk, l0, m, n, gv)
    _deriv4(x, gv, has_g, P, W, l0, m, n, y, d)
    _stage(True, h2, x, d, acc, sx, m, n)
    if has_g:  # stages 2 and 3: the input at the midpoint
        _gather(g, kk, kk + 1, l0, m, n, gv)
    _deriv4(sx, gv, has_g, P, W, l0, m, n, y, d)
    _stage(False, h2, x, d, acc, sx, m, n)
    _deriv4(sx, gv, has_g, P, W, l0, m, n, y, d)
    _stage(False, h, x, d, acc, sx, m, n)
    if has_g:
        _gather(g, kk + 1, kk + 1, l0, m, n, gv)
    _deriv4(sx, gv, has_g, P, W, l0, m, n, y, d)
    h6 = h / 6.0
    for q in range(4):
        for i in range(n):
            for l in range(m):
                x[q, i, l] += h6 * (acc[q, i, l] + d[q, i, l])


def _rk4(t, g, has_g, P, W, x0, rec_all, Y, XE, XF, VE, VF, final):
    """Integrate; P = (1/tau_r, 1/tau_a, b, w, s, k) as (6, n, B); g (T, n, B) or dummy.

    Per chunk of ``CHUNK`` copies (in parallel): the state ``x`` (x_e, x_f, v_e, v_f) and the
    scratch arrays of a step, each (4, n, L), stay in cache for all ``T`` steps."""
    T = t.shape[0]
    n = x0.shape[1]
    B = x0.shape[2]
    L = CHUNK
    nchunks = (B + L - 1) // L
    for ch in numba.prange(nchunks):
        l0 = ch * L
        m = min(L, B - l0)
        x = np.empty((4, n, L))  # state
        sx = np.empty((4, n, L))  # a stage's state
        acc = np.empty((4, n, L))  # the weighted sum of the stages' derivatives
        d = np.empty((4, n, L))  # a stage's derivative
        y = np.empty((2, n, L))  # a stage's [x_e]+, [x_f]+
        gv = np.zeros((n, L))  # a stage's input
        for q in range(4):
            for i in range(n):
                for l in range(m):
                    x[q, i, l] = x0[q, i, l0 + l]
        _record(0, x, l0, m, n, rec_all, Y, XE, XF, VE, VF)
        for kk in range(T - 1):
            _step(kk, t, g, has_g, P, W, l0, m, n, x, sx, acc, d, y, gv)
            _record(kk + 1, x, l0, m, n, rec_all, Y, XE, XF, VE, VF)
        for q in range(4):
            for i in range(n):
                for l in range(m):
                    final[q, i, l0 + l] = x[q, i, l]


def _f1(xe, xf, ve, vf, g, has_g, itr, ita, b, w, s, k):
    """Derivative of one uncoupled oscillator (scalars)."""
    ye = max(xe, 0.0)
    yf = max(xf, 0.0)
    dxe = s - xe - w * yf - b * ve
    dxf = s - xf - w * ye - b * vf
    if has_g:
        dxe -= k * max(g, 0.0)
        dxf -= k * max(-g, 0.0)
    return dxe * itr, dxf * itr, (ye - ve) * ita, (yf - vf) * ita


def _rk4_uncoupled(t, g, has_g, P, x0, rec_all, Y, XE, XF, VE, VF, final):
    """Same as ``_rk4`` for oscillators without coupling, flattened to (1, B): each
    oscillator's whole RK4 step is done in registers; the loop over oscillators vectorises."""
    T = t.shape[0]
    B = x0.shape[2]
    L = CHUNK
    nchunks = (B + L - 1) // L
    for ch in numba.prange(nchunks):
        l0 = ch * L
        m = min(L, B - l0)
        xe = np.empty(L)
        xf = np.empty(L)
        ve = np.empty(L)
        vf = np.empty(L)
        for l in range(m):
            c = l0 + l
            xe[l] = x0[0, 0, c]
            xf[l] = x0[1, 0, c]
            ve[l] = x0[2, 0, c]
            vf[l] = x0[3, 0, c]
            Y[0, 0, c] = max(xe[l], 0.0) - max(xf[l], 0.0)
            if rec_all:
                XE[0, 0, c] = xe[l]
                XF[0, 0, c] = xf[l]
                VE[0, 0, c] = ve[l]
                VF[0, 0, c] = vf[l]
        for kk in range(T - 1):
            h = t[kk + 1] - t[kk]
            h2 = 0.5 * h
            h6 = h / 6.0
            for l in range(m):
                c = l0 + l
                itr = P[0, 0, c]
                ita = P[1, 0, c]
                b = P[2, 0, c]
                w = P[3, 0, c]
                s = P[4, 0, c]
                k = P[5, 0, c]
                g0 = 0.0
                g1 = 0.0
                if has_g:
                    g0 = g[kk, 0, c]
                    g1 = g[kk + 1, 0, c]
                gm = 0.5 * (g0 + g1)
                a0, a1, a2, a3 = xe[l], xf[l], ve[l], vf[l]
                k10, k11, k12, k13 = _f1(a0, a1, a2, a3, g0, has_g, itr, ita, b, w, s, k)
                k20, k21, k22, k23 = _f1(
                    a0 + h2 * k10, a1 + h2 * k11, a2 + h2 * k12, a3 + h2 * k13,
                    gm, has_g, itr, ita, b, w, s, k,
                )
                k30, k31, k32, k33 = _f1(
                    a0 + h2 * k20, a1 + h2 * k21, a2 + h2 * k22, a3 + h2 * k23,
                    gm, has_g, itr, ita, b, w, s, k,
                )
                k40, k41, k42, k43 = _f1(
                    a0 + h * k30, a1 + h * k31, a2 + h * k32, a3 + h * k33,
                    g1, has_g, itr, ita, b, w, s, k,
                )
                a0 += h6 * ((k10 + 2.0 * k20 + 2.0 * k30) + k40)
                a1 += h6 * ((k11 + 2.0 * k21 + 2.0 * k31) + k41)
                a2 += h6 * ((k12 + 2.0 * k22 + 2.0 * k32) + k42)
                a3 += h6 * ((k13 + 2.0 * k23 + 2.0 * k33) + k43)
                xe[l] = a0
                xf[l] = a1
                ve[l] = a2
                vf[l] = a3
                Y[kk + 1, 0, c] = max(a0, 0.0) - max(a1, 0.0)
                if rec_all:
                    XE[kk + 1, 0, c] = a0
                    XF[kk + 1, 0, c] = a1
                    VE[kk + 1, 0, c] = a2
                    VF[kk + 1, 0, c] = a3
        for l in range(m):
            c = l0 + l
            final[0, 0, c] = xe[l]
            final[1, 0, c] = xf[l]
            final[2, 0, c] = ve[l]
            final[3, 0, c] = vf[l]


def _renamed(f: Callable[..., Any], name: str) -> Callable[..., Any]:
    """``f`` under another name. numba's on-disk cache is one file per function name and
    line, keyed by the signature and the code but not by the compile flags: a serial and a
    parallel build of one function would load each other's machine code."""
    g = types.FunctionType(f.__code__, f.__globals__, name, f.__defaults__, f.__closure__)
    g.__qualname__ = name
    return g


rk4_numba: Callable[..., Any] | None
rk4_uncoupled_numba: Callable[..., Any] | None
rk4_numba_serial: Callable[..., Any] | None
rk4_uncoupled_numba_serial: Callable[..., Any] | None
if HAVE_NUMBA:
    _deriv = numba.njit(cache=True, inline="always", fastmath=True)(_deriv)
    _gather = numba.njit(cache=True, inline="always", fastmath=True)(_gather)
    _stage = numba.njit(cache=True, inline="always", fastmath=True)(_stage)
    _deriv4 = numba.njit(cache=True, inline="always", fastmath=True)(_deriv4)
    _record = numba.njit(cache=True, inline="always", fastmath=True)(_record)
    _step = numba.njit(cache=True, inline="always", fastmath=True)(_step)
    rk4_numba = numba.njit(cache=True, parallel=True, fastmath=True)(_rk4)
    _f1 = numba.njit(cache=True, inline="always", fastmath=True)(_f1)
    rk4_uncoupled_numba = numba.njit(cache=True, parallel=True, fastmath=True)(_rk4_uncoupled)
    rk4_numba_serial = numba.njit(cache=True, fastmath=True)(_renamed(_rk4, "_rk4_serial"))
    rk4_uncoupled_numba_serial = numba.njit(cache=True, fastmath=True)(
        _renamed(_rk4_uncoupled, "_rk4_uncoupled_serial"))
else:  # pragma: no cover
    rk4_numba = rk4_uncoupled_numba = rk4_numba_serial = rk4_uncoupled_numba_serial = None


def kernel(coupled: bool, copies: int) -> Callable[..., Any] | None:
    """The compiled kernel for ``copies`` independent copies (the ``B`` of the layout):
    the coupled one (``_rk4``) or the uncoupled one, parallel over chunks only where there is
    more than one chunk of ``CHUNK`` copies."""
    if copies > CHUNK:
        return rk4_numba if coupled else rk4_uncoupled_numba
    return rk4_numba_serial if coupled else rk4_uncoupled_numba_serial


def first_compile(dispatcher: Any) -> bool:
    """Whether calling numba ``dispatcher`` now compiles it for the first time on this machine:
    nothing compiled or loaded in this process, and no on-disk cache index for it (numba's
    ``cache=True`` files). False where numba's cache layout cannot be read."""
    if dispatcher is None or getattr(dispatcher, "signatures", None):
        return False
    try:
        index = dispatcher._cache._cache_file._index_path
    except AttributeError:
        return False
    return not os.path.exists(index)


_ANNOUNCED = False


def announce_first_compile(dispatcher: Any) -> None:
    """Say once per process, on stderr, that numba is compiling the oscillator network's
    kernels (a fresh install's first demo spends 10–20 s on 2 cores there, silent before;
    a batch of more than ``CHUNK`` copies compiles the parallel build too, about a minute)."""
    global _ANNOUNCED
    if not _ANNOUNCED and first_compile(dispatcher):
        print("gdimitate: compiling the oscillator network's kernels with numba, once for this "
              "install (about 10-60 s on 2 cores; later runs load them) …", file=sys.stderr,
              flush=True)
        _ANNOUNCED = True
