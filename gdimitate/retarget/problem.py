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
           "fingerprint"]

CACHE_SIZE = 8
_CACHE: OrderedDict[tuple, Compiled] = OrderedDict()
_SYM: OrderedDict[str, SymbolicModel] = OrderedDict()
BUILD_COUNT = 0
EXPAND = True
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
    for s, leg in sorted(robot.legs.items()):
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


def _build(robot: Robot, flags: Flags, segment_frames: tuple[str, ...], q_index: tuple,
           T: int, ipopt: dict) -> Compiled:
    global BUILD_COUNT
    sym = symbolic_model(robot)
    k = Knot(robot, sym, flags, slack_rows(robot, flags))
    # ---- one knot: constraint rows, cost residuals, L1 penalty, hold quantities
    base_rows, tau_rows = PER_KNOT[0].expr(k)
    g_parts = [base_rows, tau_rows] + [m.expr(k) for m in PER_KNOT[1:]]
    g_parts.append(integration.quaternion_row(k))
    gk = ca.vertcat(*g_parts)
    res = ca.vertcat(tasks.keypoints.residual(k, segment_frames),
                     tasks.joints.residual(k, q_index), tasks.smoothness.residual(k),
                     tasks.wrench.residual(k))
    l1 = k.weight(8) * (ca.sum1(k.s_plus) + ca.sum1(k.s_minus))
    hq = contact.hold_quantities(k)
    knot_fun = ca.Function("knot", [k.x, k.p], [gk, res, l1, hq])
    tau_fun = ca.Function("tau", [k.x, k.p], [PER_KNOT[0].torques(k)])
    step = integration.step_function(k)
    # ---- all knots
    X = ca.MX.sym("X", k.var.size, T)
    P = ca.MX.sym("P", k.par.size, T)
    Gk, R, L1, H = knot_fun.map(T)(X, P)
    g = [ca.vec(Gk)]
    if T > 1:
        g.append(ca.vec(step.map(T - 1)(X[:, :-1], X[:, 1:], P[:, 1:])))
        g.append(ca.vec(contact.hold_rows(H[:, :-1], H[:, 1:], k.planar)))
    G = ca.vertcat(*g)
    f = (ca.sumsqr(R) + ca.sum2(L1)) / T
    z, p = ca.vec(X), ca.vec(P)
    progress = Progress(f"progress_{BUILD_COUNT}", int(z.shape[0]), int(G.shape[0]),
                        int(p.shape[0]))
    opts = {"print_time": False, "iteration_callback": progress, "expand": EXPAND,
            "ipopt": {**IPOPT_DEFAULTS, **ipopt}}
    solver = ca.nlpsol(f"retarget_{BUILD_COUNT}", "ipopt", {"x": z, "p": p, "f": f, "g": G},
                       opts)
    g_fun = ca.Function("g", [z, p], [G])
    BUILD_COUNT += 1
    return Compiled(solver, k, g_fun, tau_fun, T, k.var.size, int(gk.shape[0]),
                    int(G.shape[0]), progress, segment_frames, knot_fun)


def row_bounds(c: Compiled, spec: Spec) -> tuple[np.ndarray, np.ndarray]:
    """``(lbg, ubg)`` of every row for a demonstration (see :class:`Spec`)."""
    parts = [m.bounds(spec) for m in PER_KNOT] + [integration.quaternion_bounds(spec)]
    lo = np.concatenate([p[0] for p in parts], axis=1).ravel()
    hi = np.concatenate([p[1] for p in parts], axis=1).ravel()
    los, his = [lo], [hi]
    if spec.T > 1:
        n_step = c.knot.sym.nq + c.knot.sym.nv
        los.append(np.zeros(n_step * (spec.T - 1)))
        his.append(np.zeros(n_step * (spec.T - 1)))
        hl, hh = contact.hold_bounds(spec)
        # hold rows are stacked (n_hold, T − 1) column-major: knot by knot
        los.append(hl.ravel())
        his.append(hh.ravel())
    return np.concatenate(los), np.concatenate(his)
