"""The parametric NLP: one knot's functions (:mod:`.knot`, :mod:`.tasks`,
:mod:`.constraints`) mapped over the knots with ``casadi.Function.map``, assembled once per
problem *shape* and cached; a demonstration only fills parameters and bounds.

Shape = (the imitator's fingerprint, number of knots T, :class:`~.knot.Flags`, mapped segment
frames, IPOPT options). The contact schedule, targets, weights, limits, sole sizes and μ are
numbers (parameter values and bounds: a row the schedule does not impose gets infinite bounds,
which IPOPT drops), so a second demonstration of the same shape skips the build
(:data:`BUILD_COUNT` counts builds).
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..robot import Robot
from ..symbolic import SymbolicModel
from . import tasks
from .constraints import PER_KNOT, cone, contact, force, integration, swing
from .interrupt import Progress
from .knot import Flags, Knot, base_dofs

__all__ = ["Spec", "Compiled", "compiled", "clear_cache", "BUILD_COUNT", "CACHE_SIZE",
           "fingerprint", "row_bounds", "row_scale"]

CACHE_SIZE = 8
_CACHE: OrderedDict[tuple, Compiled] = OrderedDict()
_SYM: OrderedDict[str, SymbolicModel] = OrderedDict()
BUILD_COUNT = 0
"""How many NLPs this process has built (a cached call leaves it unchanged)."""

IPOPT_DEFAULTS = {
    "print_level": 0, "sb": "yes", "tol": 1e-8, "constr_viol_tol": 1e-8,
    "acceptable_tol": 1e-6, "acceptable_constr_viol_tol": 1e-7, "acceptable_iter": 5,
    "max_iter": 500, "mu_strategy": "adaptive", "linear_solver": "mumps",
    "fixed_variable_treatment": "make_parameter", "bound_relax_factor": 0.0,
}
"""IPOPT options (MUMPS, the solver of the PyPI CasADi wheel); ``ipopt=`` adds to them."""


def fingerprint(robot: Robot) -> str:
    """A digest of everything in the imitator the NLP's expressions depend on (joint
    placements, inertias, contact frames, leg lengths)."""
    m = robot.model
    h = hashlib.sha1()
    h.update(repr((robot.name, m.nq, m.nv, tuple(m.names), robot.base)).encode())
    for i in range(1, m.njoints):
        h.update(np.asarray(m.jointPlacements[i].homogeneous).tobytes())
        h.update(np.asarray(m.inertias[i].toDynamicParameters()).tobytes())
    for _side, c in sorted(robot.require_contacts().items()):
        fr = m.frames[m.getFrameId(c.frame)]
        h.update(f"{_side}:{c.frame}:{fr.parentJoint}".encode())
        h.update(np.asarray(fr.placement.homogeneous).tobytes())
    for _, leg in sorted(robot.legs.items()):
        h.update(repr(leg).encode())
    return h.hexdigest()


def symbolic_model(robot: Robot) -> SymbolicModel:
    """The (cached) :class:`SymbolicModel` of a robot."""
    key = fingerprint(robot)
    if key not in _SYM:
        _SYM[key] = SymbolicModel(robot.model)
        while len(_SYM) > CACHE_SIZE:
            _SYM.popitem(last=False)
    _SYM.move_to_end(key)
    return _SYM[key]


def clear_cache() -> None:
    """Forget every cached NLP and symbolic model."""
    _CACHE.clear()
    _SYM.clear()


@dataclass(frozen=True)
class Spec:
    """The numbers that decide the bounds of one demonstration's rows."""

    T: int
    stance: dict
    swing: dict
    liftoff: dict
    goal_active: dict
    planar: bool
    free: bool
    cone: bool
    clearance: float
    leg_length: float
    n_base: int
    n_act: int


def slack_rows(robot: Robot, flags: Flags) -> int:
    planar = robot.base == "planar"
    _, act = base_dofs(robot)
    return len(act) + 2 * (cone.rows_per_side(planar) + swing.rows_per_side(planar)
                           + force.rows_per_side(flags.cone))


@dataclass
class Compiled:
    """A built NLP: ``solver`` (``nlpsol``), ``knot`` (the per-knot :class:`Knot`),
    ``g_fun`` ``(z, P) -> g`` and ``parts`` ``(z, P) -> (G_knot, tau, R)`` for reports,
    ``T``, ``nx``, ``ng_knot``, ``ng``, ``progress`` (the iteration callback)."""

    solver: ca.Function
    knot: Knot
    g_fun: ca.Function
    tau_fun: ca.Function
    T: int
    nx: int
    ng_knot: int
    ng: int
    progress: Progress
    segment_frames: tuple[str, ...]
    knot_fun: ca.Function


def _freeze(d: dict) -> tuple:
    return tuple(sorted((k, repr(v)) for k, v in d.items()))


def compiled(robot: Robot, flags: Flags, segment_frames: tuple[str, ...], q_index: tuple,
             T: int, ipopt: dict | None = None) -> tuple[Compiled, bool]:
    """The NLP of this shape, built now or taken from the cache; ``(compiled, cached)``."""
    key = (fingerprint(robot), T, flags, tuple(segment_frames), tuple(q_index),
           _freeze(ipopt or {}))
    if key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key], True
    c = _build(robot, flags, tuple(segment_frames), tuple(q_index), T, ipopt or {})
    _CACHE[key] = c
    while len(_CACHE) > CACHE_SIZE:
        _CACHE.popitem(last=False)
    return c, False


def _pair_functions(k: Knot) -> ca.Function:
    """Rows linking knot k − 1 (``x0``) to knot k (``x``): integration, then contact hold."""
    step = integration.step_function(k)
    x0 = ca.SX.sym("x_prev", k.var.size)
    hold = ca.Function("hold", [k.x], [contact.hold_quantities(k)])
    rows = ca.vertcat(step(x0, k.x, k.p), contact.hold_rows(hold(x0), hold(k.x), k.planar))
    return ca.Function("pair", [x0, k.x, k.p], [rows])


def _blockdiag(M: ca.MX, n: int) -> ca.MX:
    """``(r, n·m)`` horizontally stacked blocks → their ``(r·m, n·m)`` block diagonal."""
    return ca.diagcat(*ca.horzsplit(M, n))


def _pair_spread(nx: int, T: int) -> ca.DM:
    """``(2·nx·(T−1), nx·T)``: the columns of pair j = (knot j, knot j + 1) → those knots."""
    rows, cols = [], []
    for j in range(T - 1):
        for i in range(2 * nx):
            rows.append(2 * nx * j + i)
            cols.append(nx * j + i)
    sp = ca.Sparsity.triplet(2 * nx * (T - 1), nx * T, rows, cols)
    return ca.DM(sp, 1.0)


def _build(robot: Robot, flags: Flags, segment_frames: tuple[str, ...], q_index: tuple,
           T: int, ipopt: dict) -> Compiled:
    """Build the NLP of one shape. The derivatives IPOPT needs are written per knot (SX:
    constraint Jacobian, cost gradient, Hessian of the knot's Lagrangian) and per pair of
    knots, mapped over the knots and assembled into the sparse block structure; CasADi's
    MX-level differentiation of the mapped graph is never used (it is two orders of magnitude
    slower here)."""
    global BUILD_COUNT
    sym = symbolic_model(robot)
    k = Knot(robot, sym, flags, slack_rows(robot, flags))
    nx = k.var.size
    # ---- one knot: constraint rows, cost, hold quantities
    base_rows, tau_rows = PER_KNOT[0].expr(k)
    g_parts = [base_rows, tau_rows] + [m.expr(k) for m in PER_KNOT[1:]]
    g_parts.append(integration.quaternion_row(k))
    gk = ca.vertcat(*g_parts)
    res = ca.vertcat(tasks.keypoints.residual(k, segment_frames),
                     tasks.joints.residual(k, q_index), tasks.smoothness.residual(k),
                     tasks.wrench.residual(k))
    l1 = k.weight(8) * (ca.sum1(k.s_plus) + ca.sum1(k.s_minus))
    fk = (ca.sumsqr(res) + l1) / T
    ngk = int(gk.shape[0])
    lam_k, sigma = ca.SX.sym("lam", ngk), ca.SX.sym("sigma")
    hk = ca.triu(ca.hessian(sigma * fk + ca.dot(lam_k, gk), k.x)[0])
    knot_fun = ca.Function("knot", [k.x, k.p], [gk, res, l1, contact.hold_quantities(k)])
    kf = ca.Function("knot_f", [k.x, k.p], [fk, ca.gradient(fk, k.x)])
    kg = ca.Function("knot_g", [k.x, k.p], [gk, ca.jacobian(gk, k.x)])
    kh = ca.Function("knot_h", [k.x, k.p, sigma, lam_k], [hk])
    tau_fun = ca.Function("tau", [k.x, k.p], [PER_KNOT[0].torques(k)])
    # ---- pairs of knots
    pair = _pair_functions(k)
    x0s, x1s = ca.SX.sym("x0", nx), ca.SX.sym("x1", nx)
    gs = pair(x0s, x1s, k.p)
    ns = int(gs.shape[0])
    mu = ca.SX.sym("mu", ns)
    xx = ca.vertcat(x0s, x1s)
    pg = ca.Function("pair_g", [x0s, x1s, k.p], [gs, ca.jacobian(gs, xx)])
    ph = ca.Function("pair_h", [x0s, x1s, k.p, mu], [ca.hessian(ca.dot(mu, gs), xx)[0]])
    # ---- all knots (MX): values and the assembled derivatives
    X = ca.MX.sym("X", nx, T)
    P = ca.MX.sym("P", k.par.size, T)
    z, p = ca.vec(X), ca.vec(P)
    F, GF = kf.map(T)(X, P)
    Gk, JK = kg.map(T)(X, P)
    g_list, j_list = [ca.vec(Gk)], [_blockdiag(JK, nx)]
    ng = ngk * T + ns * (T - 1)
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", ng)
    H = _blockdiag(kh.map(T)(X, P, lam_f, ca.reshape(lam_g[:ngk * T], ngk, T)), nx)
    if T > 1:
        E = _pair_spread(nx, T)
        Gs, JS = pg.map(T - 1)(X[:, :-1], X[:, 1:], P[:, 1:])
        g_list.append(ca.vec(Gs))
        j_list.append(ca.mtimes(_blockdiag(JS, 2 * nx), E))
        HS = ph.map(T - 1)(X[:, :-1], X[:, 1:], P[:, 1:],
                           ca.reshape(lam_g[ngk * T:], ns, T - 1))
        H = H + ca.triu(ca.mtimes([E.T, _blockdiag(HS, 2 * nx), E]))
    G, JG, f = ca.vertcat(*g_list), ca.vertcat(*j_list), ca.sum2(F)
    grad_f = ca.Function("grad_f", [z, p], [f, ca.vec(GF)], ["x", "p"], ["f", "grad_f_x"])
    jac_g = ca.Function("jac_g", [z, p], [G, JG], ["x", "p"], ["g", "jac_g_x"])
    hess = ca.Function("hess_lag", [z, p, lam_f, lam_g], [ca.triu(H)],
                       ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    progress = Progress(f"progress_{BUILD_COUNT}", int(z.shape[0]), ng, int(p.shape[0]))
    opts = {"print_time": False, "iteration_callback": progress, "grad_f": grad_f,
            "jac_g": jac_g, "hess_lag": hess, "ipopt": {**IPOPT_DEFAULTS, **ipopt}}
    solver = ca.nlpsol(f"retarget_{BUILD_COUNT}", "ipopt", {"x": z, "p": p, "f": f, "g": G},
                       opts)
    g_fun = ca.Function("g", [z, p], [G])
    BUILD_COUNT += 1
    return Compiled(solver, k, g_fun, tau_fun, T, nx, ngk, ng, progress, segment_frames,
                    knot_fun)


def row_scale(c: Compiled, ng: int) -> np.ndarray:
    """``(ng,)`` divisors putting each row in scaled units: m·g for the base rows of the
    dynamics (in N and N·m, made exact after the solve by :mod:`.polish`), 1 elsewhere."""
    scale = np.ones(ng)
    nb = len(c.knot.base_idx)
    scale[: c.T * c.ng_knot].reshape(c.T, c.ng_knot)[:, :nb] = c.knot.mg
    return scale


def row_bounds(c: Compiled, spec: Spec) -> tuple[np.ndarray, np.ndarray]:
    """``(lbg, ubg)`` of every row for a demonstration (see :class:`Spec`)."""
    parts = [m.bounds(spec) for m in PER_KNOT] + [integration.quaternion_bounds(spec)]
    lo = np.concatenate([p[0] for p in parts], axis=1).ravel()
    hi = np.concatenate([p[1] for p in parts], axis=1).ravel()
    los, his = [lo], [hi]
    if spec.T > 1:  # per pair of knots: integration rows (= 0), then the hold rows
        n_step = c.knot.sym.nq + c.knot.sym.nv
        hl, hh = contact.hold_bounds(spec)
        z = np.zeros((spec.T - 1, n_step))
        los.append(np.concatenate([z, hl], axis=1).ravel())
        his.append(np.concatenate([z, hh], axis=1).ravel())
    return np.concatenate(los), np.concatenate(his)
