"""Compiled (numba) fast path of the RK4 integration in :mod:`gdimitate.oscillator.bank`.

Same arithmetic as the NumPy reference ``bank._rk4_numpy`` (the tests hold the two equal to
round-off). Layout: oscillators are flattened to ``(n, B)`` — ``n`` coupled oscillators, ``B``
independent copies — with ``B`` contiguous, so the innermost loops run over copies and
vectorise. Copies are processed in chunks of ``CHUNK`` (state kept in L1 cache for all time
steps of a chunk); chunks run in parallel threads.
"""

from __future__ import annotations

import numpy as np

try:  # numba is a dependency, but keep the NumPy path usable without it
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False

CHUNK = 256

__all__ = ["HAVE_NUMBA", "rk4_numba", "rk4_uncoupled_numba", "CHUNK"]


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


def _rk4(t, g, has_g, P, W, x0, rec_all, Y, XE, XF, VE, VF, final):
    """Integrate; P = (1/tau_r, 1/tau_a, b, w, s, k) as (6, n, B); g (T, n, B) or dummy."""
    T = t.shape[0]
    n = x0.shape[1]
    B = x0.shape[2]
    L = CHUNK
    nchunks = (B + L - 1) // L
    for ch in numba.prange(nchunks):
        l0 = ch * L
        m = min(L, B - l0)
        xe = np.empty((n, L))
        xf = np.empty((n, L))
        ve = np.empty((n, L))
        vf = np.empty((n, L))
        sxe = np.empty((n, L))
        sxf = np.empty((n, L))
        sve = np.empty((n, L))
        svf = np.empty((n, L))
        axe = np.empty((n, L))
        axf = np.empty((n, L))
        ave = np.empty((n, L))
        avf = np.empty((n, L))
        dxe = np.empty((n, L))
        dxf = np.empty((n, L))
        dve = np.empty((n, L))
        dvf = np.empty((n, L))
        ye = np.empty((n, L))
        yf = np.empty((n, L))
        gv = np.zeros((n, L))
        for i in range(n):
            for l in range(m):
                xe[i, l] = x0[0, i, l0 + l]
                xf[i, l] = x0[1, i, l0 + l]
                ve[i, l] = x0[2, i, l0 + l]
                vf[i, l] = x0[3, i, l0 + l]
                Y[0, i, l0 + l] = max(xe[i, l], 0.0) - max(xf[i, l], 0.0)
                if rec_all:
                    XE[0, i, l0 + l] = xe[i, l]
                    XF[0, i, l0 + l] = xf[i, l]
                    VE[0, i, l0 + l] = ve[i, l]
                    VF[0, i, l0 + l] = vf[i, l]
        for kk in range(T - 1):
            h = t[kk + 1] - t[kk]
            h2 = 0.5 * h
            # stage 1
            if has_g:
                for i in range(n):
                    for l in range(m):
                        gv[i, l] = g[kk, i, l0 + l]
            _deriv(xe, xf, ve, vf, gv, has_g, P, W, l0, m, n, ye, yf, dxe, dxf, dve, dvf)
            for i in range(n):
                for l in range(m):
                    axe[i, l] = dxe[i, l]
                    axf[i, l] = dxf[i, l]
                    ave[i, l] = dve[i, l]
                    avf[i, l] = dvf[i, l]
                    sxe[i, l] = xe[i, l] + h2 * dxe[i, l]
                    sxf[i, l] = xf[i, l] + h2 * dxf[i, l]
                    sve[i, l] = ve[i, l] + h2 * dve[i, l]
                    svf[i, l] = vf[i, l] + h2 * dvf[i, l]
            # stages 2 and 3 (input at the midpoint, linearly interpolated)
            if has_g:
                for i in range(n):
                    for l in range(m):
                        gv[i, l] = 0.5 * (g[kk, i, l0 + l] + g[kk + 1, i, l0 + l])
            for stage in range(2):
                _deriv(sxe, sxf, sve, svf, gv, has_g, P, W, l0, m, n, ye, yf, dxe, dxf, dve, dvf)
                c = h2 if stage == 0 else h
                for i in range(n):
                    for l in range(m):
                        axe[i, l] += 2.0 * dxe[i, l]
                        axf[i, l] += 2.0 * dxf[i, l]
                        ave[i, l] += 2.0 * dve[i, l]
                        avf[i, l] += 2.0 * dvf[i, l]
                        sxe[i, l] = xe[i, l] + c * dxe[i, l]
                        sxf[i, l] = xf[i, l] + c * dxf[i, l]
                        sve[i, l] = ve[i, l] + c * dve[i, l]
                        svf[i, l] = vf[i, l] + c * dvf[i, l]
            # stage 4
            if has_g:
                for i in range(n):
                    for l in range(m):
                        gv[i, l] = g[kk + 1, i, l0 + l]
            _deriv(sxe, sxf, sve, svf, gv, has_g, P, W, l0, m, n, ye, yf, dxe, dxf, dve, dvf)
            h6 = h / 6.0
            for i in range(n):
                for l in range(m):
                    xe[i, l] += h6 * (axe[i, l] + dxe[i, l])
                    xf[i, l] += h6 * (axf[i, l] + dxf[i, l])
                    ve[i, l] += h6 * (ave[i, l] + dve[i, l])
                    vf[i, l] += h6 * (avf[i, l] + dvf[i, l])
                    Y[kk + 1, i, l0 + l] = max(xe[i, l], 0.0) - max(xf[i, l], 0.0)
            if rec_all:
                for i in range(n):
                    for l in range(m):
                        XE[kk + 1, i, l0 + l] = xe[i, l]
                        XF[kk + 1, i, l0 + l] = xf[i, l]
                        VE[kk + 1, i, l0 + l] = ve[i, l]
                        VF[kk + 1, i, l0 + l] = vf[i, l]
        for i in range(n):
            for l in range(m):
                final[0, i, l0 + l] = xe[i, l]
                final[1, i, l0 + l] = xf[i, l]
                final[2, i, l0 + l] = ve[i, l]
                final[3, i, l0 + l] = vf[i, l]


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


if HAVE_NUMBA:
    _deriv = numba.njit(cache=True, inline="always", fastmath=True)(_deriv)
    rk4_numba = numba.njit(cache=True, parallel=True, fastmath=True)(_rk4)
    _f1 = numba.njit(cache=True, inline="always", fastmath=True)(_f1)
    rk4_uncoupled_numba = numba.njit(cache=True, parallel=True, fastmath=True)(_rk4_uncoupled)
else:  # pragma: no cover
    rk4_numba = rk4_uncoupled_numba = None
