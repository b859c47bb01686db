"""The streaming mode's per-frame solve: one quadratic program over the same parts, linearised.

Frame k is the two-knot window (k − 1, k) of the trajectory problem (:mod:`.streaming`). Around
a guess ``Z₀`` (the previous frame's committed knot and its constant-velocity prediction) every
part is linearised with the compiled per-knot functions of the
:class:`~.problem.Formulation` (rows ``g`` and their Jacobian ``J``; the cost residuals ``r``
and their Jacobian ``J_r``), and one QP in the step ``δ`` of the free variables is solved
(DAQP, dense):

    min ½ δᵀ (J_rᵀ J_r + εI) δ + (J_rᵀ r)ᵀ δ
    s.t. lbx − z₀ ≤ δ ≤ ubx − z₀,   lbg − g ≤ J δ ≤ ubg − g

— a Gauss–Newton step of the window's problem. Every row is hard except the goal's
(:class:`~.parts.force.ForceDirection`: DAQP's soft constraints, violated only where nothing
else is possible): a frame that cannot meet its goal still meets its physics. Where the
physical rows themselves cannot hold, every row a part declares relaxable becomes soft, and
where even the contact rows cannot (a touch-down out of reach) every row but the dynamics' base
rows and the integration: the QP answers without an elastic re-solve, and the audit says which
frames it could not make feasible.

Then the window's equalities are made exact on the step's own numbers, as the trajectory
mode's polish does (:mod:`.polish`): the quaternion normalised, ``v_k`` and ``a_{k−1}`` rebuilt
from ``q`` by the integration rule, and knot k − 1's wrenches chosen by a small QP of their own
(:func:`wrench_qp`): the base rows of ``rnea − Σ J_cᵀ w`` exactly zero, every actuated torque
within its limit, each stance wrench inside its cone (with a small inner margin) and along the
goal direction where the goal is the contact force — as close as possible to the step's
wrenches. A frame whose wrench QP has no solution keeps the least-squares correction and the
audit says so.
"""

from __future__ import annotations

import daqp
import numpy as np
import pinocchio as pin
import scipy.linalg

from ..robot import SIDES
from .parts.base_dynamics import BaseDynamics
from .parts.cone import cone_rows
from .parts.force import ForceDirection
from .parts.integration import Integration

__all__ = ["qp_step", "wrench_qp", "CONE_MARGIN"]

#: Inner margin of the step's inequality rows [their scaled units], above DAQP's primal
#: tolerance (1e-6), so that the polish finds its wrenches inside the cones.
INNER = 1e-5
#: Inner margin of the wrench QP's cone rows, relative to m·g (keeps the audit's 1e-6
#: tolerances clear of round-off).
CONE_MARGIN = 1e-7
_SOFT, _EQ = 8, 5
SOLVED = (1, 2)
"""DAQP's exit flags of a solved QP (2: optimal with some soft rows relaxed)."""


class _Fast:
    """A ``casadi.Function`` of dense inputs called through CasADi's buffer interface (the
    NumPy arrays are read and written in place: converting sparse ``DM`` outputs with
    ``.full()`` cost 60 ms per Talos frame, the evaluations themselves 3 ms). ``(*args) ->
    [dense output arrays]``."""

    def __init__(self, f, cols: np.ndarray | None = None):
        self.buf, self._ret = f.buffer()
        self.args = [np.zeros(f.nnz_in(i)) for i in range(f.n_in())]
        self.res = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
        for i, a in enumerate(self.args):
            self.buf.set_arg(i, memoryview(a))
        for i, r in enumerate(self.res):
            self.buf.set_res(i, memoryview(r))
        self.shape, self.idx, self.sel = [], [], []
        for k in range(f.n_out()):  # keep only the columns ``cols`` (of a matrix output)
            i, j = (np.array(t, int) for t in f.sparsity_out(k).get_triplet())
            shape = f.size_out(k)
            sel = np.ones(i.size, bool)
            if cols is not None and shape[1] > 1:
                new = np.full(shape[1], -1)
                new[cols] = np.arange(len(cols))
                j, sel = new[j], new[j] >= 0
                i, j, shape = i[sel], j[sel], (shape[0], len(cols))
            self.shape.append(shape)
            self.idx.append((i, j))
            self.sel.append(sel)

    def __call__(self, *args) -> list[np.ndarray]:
        for a, v in zip(self.args, args):
            a[:] = v
        self.buf._eval()
        out = []
        for r, shape, (i, j), sel in zip(self.res, self.shape, self.idx, self.sel):
            M = np.zeros(shape)
            M[i, j] = r[sel]
            out.append(M)
        return out


_FAST: dict = {}


def _core(form) -> np.ndarray:
    """Indices of a knot's variables other than the elastic slacks (fixed at 0 here)."""
    var = form.knot.var
    return np.array([i for n, sl in var.slices.items() if not n.startswith("s_")
                     for i in range(sl.start, sl.stop)], int)


def _fast(form, name: str) -> _Fast:
    key = (id(form), name)
    if key not in _FAST or _FAST[key][0] is not form:
        core = _core(form)
        cols = np.r_[core, form.nx + core] if name in ("pjac",) else core
        _FAST[key] = (form, _Fast(form.fun[name], cols))
    return _FAST[key][1]


def _dense(f, *args) -> np.ndarray:
    return f(*args)[0]


def qp_step(form, Z0: np.ndarray, P: np.ndarray, lbx: np.ndarray, ubx: np.ndarray,
            lbg: np.ndarray, ubg: np.ndarray, reg: float = 1e-6
            ) -> tuple[np.ndarray, int]:
    """One linearised step of the two-knot window (module docstring).

    ``Z0``, ``lbx``, ``ubx`` ``(n_x, 2)``; ``P`` ``(n_p, 2)``; ``lbg``, ``ubg``: bounds of
    every row of the window (:func:`~.problem.row_bounds`). Returns ``(Z (n_x, 2), DAQP's exit
    flag)`` (:data:`SOLVED`: 1 every row met, 2 some soft rows relaxed)."""
    f = {n: _fast(form, n) for n in ("kg", "kjac", "pg", "pjac", "kres", "kresjac")}
    core = _core(form)  # the QP's columns: every variable but the slacks (fixed at 0)
    nx = core.size
    Z0 = np.clip(Z0, lbx, ubx)  # fixed variables at their values, the rest inside bounds
    x0, x1, p0, p1 = Z0[:, 0], Z0[:, 1], P[:, 0], P[:, 1]
    G = np.concatenate([_dense(f["kg"], x0, p0).ravel(), _dense(f["kg"], x1, p1).ravel(),
                        _dense(f["pg"], x0, x1, p1).ravel()])
    ngk = form.ngk
    J = np.zeros((G.size, 2 * nx))
    J[:ngk, :nx] = _dense(f["kjac"], x0, p0)
    J[ngk:2 * ngk, nx:] = _dense(f["kjac"], x1, p1)
    J[2 * ngk:] = _dense(f["pjac"], x0, x1, p1)
    Jr = [_dense(f["kresjac"], x, p) for x, p in ((x0, p0), (x1, p1))]
    r = [_dense(f["kres"], x, p).ravel() for x, p in ((x0, p0), (x1, p1))]
    z0 = Z0[core].T.ravel()
    lo, hi = lbx[core].T.ravel(), ubx[core].T.ravel()
    free = np.flatnonzero(lo != hi)
    H = np.zeros((2 * nx, 2 * nx))
    g = np.zeros(2 * nx)
    for i in range(2):
        s = slice(i * nx, (i + 1) * nx)
        H[s, s] = Jr[i].T @ Jr[i]
        g[s] = Jr[i].T @ r[i]
    # rows some bound applies to and some free variable moves (a row of fixed variables only,
    # e.g. knot k − 1's pose, was settled by the previous frame)
    moved = np.any(J[:, free] != 0.0, axis=1)
    keep = np.flatnonzero((np.isfinite(lbg) | np.isfinite(ubg)) & moved)
    goal = np.zeros(ngk, bool)
    for c, sl in zip(form.cons, form.slices):
        goal[sl] = isinstance(c, ForceDirection)
    relax = np.zeros(G.size, bool)
    relax[:2 * ngk] = np.tile(goal, 2)
    A = J[np.ix_(keep, free)]
    bu = np.concatenate([hi[free] - z0[free], ubg[keep] - G[keep]])
    bl = np.concatenate([lo[free] - z0[free], lbg[keep] - G[keep]])
    sense = np.zeros(bu.size, np.intc)
    rows_eq = np.isfinite(lbg[keep]) & (lbg[keep] == ubg[keep])
    sense[free.size:][rows_eq] = _EQ
    ineq = free.size + np.flatnonzero(~rows_eq)  # a margin inside DAQP's tolerance
    bu[ineq] -= INNER
    bl[ineq] += INNER
    sense[free.size:][relax[keep]] = _SOFT
    eq = np.flatnonzero(sense == _EQ)
    if eq.size:  # linearly dependent equalities (e.g. a stance foot's pose and hold rows)
        R, piv = scipy.linalg.qr(A[eq - free.size].T, mode="r", pivoting=True)
        diag = np.abs(np.diag(R)) if R.size else np.zeros(0)
        rank = int(np.sum(diag > 1e-9 * max(diag.max(initial=0.0), 1.0)))
        sense[eq[piv[rank:]]] = _SOFT
    Hf = H[np.ix_(free, free)] + reg * np.eye(free.size)
    big = 1e30
    bu, bl = np.minimum(bu, big), np.maximum(bl, -big)
    d, _, flag, _ = daqp.solve(Hf, g[free], A, bu, bl, sense)
    if flag not in SOLVED:  # the physical rows cannot all hold: every relaxable row soft
        allr = np.zeros(G.size, bool)
        allr[form.relax_rows] = allr[ngk + form.relax_rows] = True
        sense[free.size:][allr[keep]] = _SOFT
        d, _, flag, _ = daqp.solve(Hf, g[free], A, bu, bl, sense)
    if flag not in SOLVED:  # nor the contact rows (a touch-down out of reach): all but the
        hard = np.zeros(G.size, bool)  # dynamics' base rows and the integration soft
        for c, sl in zip(form.cons, form.slices):
            if isinstance(c, BaseDynamics):
                hard[sl] = hard[ngk + sl.start:ngk + sl.stop] = True
        for pp, sl in zip(form.pairs, form.pair_slices):
            if isinstance(pp, Integration):
                hard[2 * ngk + sl.start:2 * ngk + sl.stop] = True
        sense[free.size:][~hard[keep]] = _SOFT
        d, _, flag, _ = daqp.solve(Hf, g[free], A, bu, bl, sense)
    z = z0.copy()
    if flag in SOLVED:
        z[free] += np.asarray(d)
    Z = Z0.copy()
    Z[core] = z.reshape(2, nx).T
    return Z, int(flag)


def _cone_matrix(X, Y, mu, Xc, Yc, planar: bool) -> np.ndarray:
    """``(n, 6)`` with rows ``A w ≤ b`` of :func:`.cone.cone_rows` (f_min row excluded; it is
    the constant part handled by the caller)."""
    zero = cone_rows(np.zeros(6), X, Y, mu, Xc, Yc, 0.0, planar)
    return np.array([[float(a - b) for a, b in zip(cone_rows(e, X, Y, mu, Xc, Yc, 0.0, planar),
                                                    zero)] for e in np.eye(6)]).T


def wrench_qp(robot, q: np.ndarray, v: np.ndarray, a: np.ndarray, W: dict, stance: dict,
              contacts: dict, base_idx: np.ndarray, act_idx: np.ndarray,
              inv_effort: np.ndarray, f_min: float, cop_margin: float,
              goal: dict | None = None) -> tuple[dict, bool]:
    """Knot wrenches ``{side: (6,)}`` [N, N·m] (sole frames) closest to ``W`` with the base
    rows of ``rnea(q, v, a) − Σ J_cᵀ w`` exactly zero, torques within limits, cones met and,
    with ``goal`` ``{side: (e1, e2) or None}`` (world axes), the force along the goal;
    ``(wrenches, solved)``. Planar robots: the x, z, pitch components only."""
    m, d = robot.model, robot.data
    sides = [s for s in SIDES if stance[s]]
    comp = [0, 2, 4] if robot.base == "planar" else list(range(6))
    nc = len(comp)
    tau = pin.rnea(m, d, q, v, a).copy()
    if not sides:
        ok = bool(np.all(np.abs(tau[base_idx]) <= 1e-6))
        return {s: np.zeros(6) for s in SIDES}, ok
    pin.computeJointJacobians(m, d, q)
    pin.updateFramePlacements(m, d)
    Jt, w0, rows_A, rows_u, rows_l, sense = [], [], [], [], [], []
    n = nc * len(sides)
    mg = robot.mass * 9.81
    for i, s in enumerate(sides):
        c = contacts[s]
        fid = m.getFrameId(c.frame)
        Jt.append(pin.getFrameJacobian(m, d, fid, pin.LOCAL)[comp].T)
        w0.append(W[s][comp])
        C = _cone_matrix(c.half_length, c.half_width, c.mu, c.half_length - cop_margin,
                         c.half_width - cop_margin, robot.base == "planar")[:, comp]
        blk = np.zeros((C.shape[0], n))
        blk[:, i * nc:(i + 1) * nc] = C
        rows_A.append(blk)
        up = np.full(C.shape[0], -CONE_MARGIN * mg)
        up[-1] = -f_min - CONE_MARGIN * mg  # f_min − f_z ≤ 0 row
        rows_u.append(up)
        rows_l.append(np.full(C.shape[0], -1e30))
        sense.append(np.zeros(C.shape[0], np.intc))
        if goal is not None and goal.get(s) is not None:
            R = d.oMf[fid].rotation
            for e in goal[s]:
                row = np.zeros(n)
                fw = e @ R  # e · (R f)
                row[i * nc:(i + 1) * nc] = [fw[j] if j < 3 else 0.0 for j in comp]
                rows_A.append(row[None])
                rows_u.append(np.zeros(1))
                rows_l.append(np.zeros(1))
                sense.append(np.full(1, _SOFT, np.intc))
    Jt = np.hstack(Jt)  # (nv, n): τ = rnea − Jt w
    A = np.vstack([Jt[base_idx], Jt[act_idx] * inv_effort[:, None]] + rows_A)
    lim = np.where(inv_effort > 0, 1.0, 1e30)
    ta = tau[act_idx] * inv_effort
    bu = np.concatenate([tau[base_idx], ta + lim] + rows_u)
    bl = np.concatenate([tau[base_idx], ta - lim] + rows_l)
    sense = np.concatenate([np.full(len(base_idx), _EQ, np.intc),
                            np.zeros(len(act_idx), np.intc)] + sense)
    scale = 1.0 / mg
    H = np.eye(n) * scale**2
    w0 = np.concatenate(w0)
    x, _, flag, _ = daqp.solve(H, -H @ w0, A, bu, bl, sense)
    out = {s: np.zeros(6) for s in SIDES}
    if flag not in SOLVED:  # least-squares correction of the base rows only
        x = w0 + np.linalg.lstsq(Jt[base_idx], tau[base_idx] - Jt[base_idx] @ w0,
                                 rcond=None)[0]
    for i, s in enumerate(sides):
        out[s][comp] = np.asarray(x)[i * nc:(i + 1) * nc]
    return out, flag in SOLVED
