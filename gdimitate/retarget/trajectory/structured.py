"""The whole-body problem handed to a structure-exploiting solver: CasADi's ``fatrop`` plugin
(issue 37; docs/design.md §6, "what was tried for speed").

The same parts, rows, bounds, cost and start as :mod:`.problem`'s NLP, declared as an optimal
control problem of ``T`` stages, as fatrop's Riccati recursion needs it:

- **stage k's variables**: its state ``x_k`` = the knot's free ``q``, ``v``; its controls
  ``u_k`` = the knot's other free variables (``a``, the wrenches, the free elastic slacks).
  Variables whose bounds meet (a swing foot's wrench, the fixed slacks, frozen joints, the
  start's base position) are parameters, as IPOPT's ``fixed_variable_treatment`` makes them;
  stage sizes differ from knot to knot.
- **gap-closing rows**: :class:`~..parts.integration.Integration`'s rows written as
  ``x_{k+1} − F(x_k, u_k)`` with ``v_{k+1} = v_k + h a_k`` substituted into
  ``q_{k+1} = q_k ⊕ h v_{k+1}`` (the same two equations, the coefficient of ``x_{k+1}`` the
  identity, as fatrop requires).
- **stage rows**: the knot's rows the IPOPT solve keeps (``Numbers.keep``), then the rows of
  any other :class:`~..parts.PairConstraint` (the contact hold) between knots k and k + 1,
  written at stage k with ``x_{k+1} = F(x_k, u_k)`` substituted (equal to the originals
  wherever the integration rows hold). A pair part whose rows need the next knot's controls
  cannot be written so: :func:`supported` says no.
- **cost**: the knot's cost over ``T``, times IPOPT's ``obj_scaling_factor``.

fatrop's CasADi plugin differentiates its oracle itself and takes no derivative functions
(no ``jac_g``/``hess_lag`` options, unlike IPOPT's), and CasADi's virtual machine running
those derivatives did not finish one G1 solve in 18 minutes. So the stage functions are
compiled to C with the derivatives CasADi's AD of ``f.map(T)`` looks up by name in an
external library (``jac_f``, ``adj1_f``, ``jac_adj1_f``: :func:`_with_derivatives`), kept on
disk as :mod:`.codegen` keeps the knot's (G1: 0.89 M instructions, 223 s the first time).

Measured (``python benchmarks/adaptor.py --robots g1,talos --structured``; docs/design.md §6):
13–27× IPOPT's CPU time — fatrop crawls to the 150-iteration budget after reaching
feasibility (every step's Hessian regularised by 0.03–0.16 for inertia, its monotone barrier
parameter stuck at 2·10⁻⁶), its Riccati step on these wide stages costs what IPOPT's MUMPS
iteration does, and CasADi's AD of the oracle costs 25–40× the knot's own compiled
derivatives. Not used by :func:`gdimitate.adapt`; kept to reproduce the measurement.
"""

from __future__ import annotations

import hashlib
import inspect
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..knot import Knot
from ..params import IPOPT_DEFAULTS
from ..parts.integration import Integration
from . import codegen
from . import problem as pb

__all__ = ["Stages", "stage_functions", "stages", "supported", "run_fatrop", "hard_problem",
           "hard_solve", "FATROP_DEFAULTS"]

FATROP_DEFAULTS = {"print_level": 0, "tolerance": 1e-6, "tol_acceptable": 1e-5,
                   "acceptable_iter": 5, "constr_viol_tol": 1e-6, "mu_init": 0.1}
"""fatrop's options (its own names): IPOPT's stopping tolerances where fatrop has them."""

_FUN: OrderedDict[int, dict] = OrderedDict()
_STAGES: OrderedDict[tuple, Stages] = OrderedDict()


def supported(form: pb.Formulation) -> bool:
    """Whether a formulation can be written stage-wise: no seam between the last knot and
    the first (a periodic cycle couples them) and pair rows that the next knot's controls do
    not enter once its state is substituted."""
    return form.seam is None and any(isinstance(p, Integration) for p in form.pairs) and \
        _sx_cached(form) is not None


def _sx_cached(form: pb.Formulation) -> list[ca.Function] | None:
    """:func:`_sx_functions` of a formulation, built once per formulation."""
    key = id(form)
    if not (key in _FUN and _FUN[key]["form"] is form):
        _FUN[key] = {"form": form, "sx": _sx_functions(form)}
        while len(_FUN) > pb.CACHE_SIZE:
            _FUN.popitem(last=False)
    return _FUN[key]["sx"]


def _fresh_knot(form: pb.Formulation) -> tuple[Knot, tuple]:
    """A knot with the formulation's layout and its SX expressions (:func:`.problem.
    _knot_expressions`), built anew so that the cached formulation's symbols are untouched."""
    k0 = form.knot
    extra: dict[str, int] = {}
    k = Knot(k0.robot, k0.sym, k0.flags, k0.weight_names, extra)
    for p in form.parts:
        extra.update(p.params(k))
    if extra:
        k = Knot(k0.robot, k0.sym, k0.flags, k0.weight_names, extra)
    return k, pb._knot_expressions(k, form.parts)


PIECE_LIMIT = 2000
"""SX instructions of a piece of the knot's rows above which :func:`.codegen.split_rows` cuts
it at a part's first row (rows that share the inverse dynamics stay together)."""
_DIFF = {"is_diff_in": [True, False]}  # parameters are never differentiated


def _with_derivatives(f: ca.Function) -> list[ca.Function]:
    """``f`` with the derivatives CasADi looks up by name in an external library
    (``jac_f``, ``adj1_f``, ``jac_adj1_f``): the MX derivatives the solver's oracle takes of
    ``f.map(T)`` then call compiled C, never CasADi's virtual machine."""
    adj = f.reverse(1)
    return [f, f.jacobian(), adj, adj.jacobian()]


def _sx_functions(form: pb.Formulation) -> list[ca.Function] | None:
    """The stage functions in SX (:func:`stage_functions`); ``None`` when a pair part needs
    the next knot's controls."""
    k, (cons, slices, g_rows, labels, scale, pairs, pslices, prow, x0, costs) = \
        _fresh_knot(form)
    x, p = k.x, k.p
    res = ca.vertcat(*[(k.weight(c.weight) if c.weight else 1) * c.residual(k) for c in costs])
    # the knot's cost exactly as problem._functions writes it (kf; tests compare the two)
    fk = ca.sumsqr(res) + k.P("elastic")[0] * (ca.sum1(k.s_plus) + ca.sum1(k.s_minus))
    nq, nv = k.sym.nq, k.sym.nv
    xp = ca.SX.sym("x_prev", x.shape[0])
    q0, v0, a0 = xp[:nq], xp[nq:nq + nv], xp[nq + nv:nq + 2 * nv]
    h = k.P("h")[0]
    v1 = v0 + h * a0
    q1 = k.sym.integrate(q0, h * v1)
    # the next knot: its state substituted, its controls symbols that must not matter
    x1 = ca.vertcat(q1, v1, x[nq + nv:])
    rows = []
    for pp in form.pairs:
        if isinstance(pp, Integration):
            continue
        carry = ca.Function("carry", [x], [pp.carry(k)])
        r = pp.rows(k, carry(xp), carry(x1))
        if ca.depends_on(r, x):
            return None
        rows.append(r)
    gk = ca.vertcat(*g_rows)
    ng = int(gk.shape[0])
    weight = np.ones(ng)
    cuts = tuple(s.start for s in slices)
    pieces = codegen.split_rows("g", ng, weight, lambda a, b: [gk[a:b]], [x, p], cuts,
                                limit=PIECE_LIMIT)
    out = [ca.Function(f.name(), [x, p], f.call([x, p]), _DIFF) for f in pieces]
    return out + [ca.Function("f", [x, p], [fk], _DIFF),
                  ca.Function("dyn", [xp, p], [ca.vertcat(q1, v1)], _DIFF),
                  ca.Function("pair", [xp, p], [ca.vertcat(*rows) if rows else ca.SX(0, 1)],
                              _DIFF)]


def stage_functions(form: pb.Formulation) -> dict[str, ca.Function] | None:
    """The stage functions of a formulation (cached; compiled to C with their derivatives
    once per robot and parts, kept on disk as :mod:`.codegen` keeps the knot's):
    ``g0, g1, …`` ``(x, p)`` the knot's rows in pieces (stacked: ``kg``), ``f (x, p)`` its
    cost (``kf``), ``dyn (x, p₁) -> [q₁; v₁]`` and ``pair (x, p₁)`` the other pair parts'
    rows with the next state substituted (``p₁``: the next knot's parameters); ``None``
    when a pair part needs the next knot's controls."""
    sx = _sx_cached(form)
    memo = _FUN[id(form)]
    if "fun" in memo:
        return memo["fun"]
    fun = None
    if sx is not None:
        k = form.knot
        own = "".join(inspect.getsource(f) for f in (_fresh_knot, _sx_functions,
                                                       _with_derivatives)) + repr(PIECE_LIMIT)
        digest = hashlib.sha1(repr((pb.fingerprint(k.robot), k.flags, repr(form.parts),
                                    pb._SOURCE, own)).encode()).hexdigest()
        every, _ = codegen.compiled_functions(
            "stages-" + digest, lambda: [d for f in sx for d in _with_derivatives(f)],
            f"{k.robot.name}'s stage-wise")
        fun = {f.name(): every[f.name()] for f in sx}
    memo["fun"] = fun
    return fun


@dataclass
class Stages:
    """fatrop's problem for one pattern of free variables and kept rows: ``solver``,
    ``free`` ``(n_x, T)`` bool (the knot variables the solver sees), ``rows`` (indices into
    the stacked rows ``[dynamics (nq+nv, T−1); knot rows (ngk, T); pair rows (np, T−1)]``,
    column-major each, in the solver's order), ``lbg``/``ubg`` builders' index maps and the
    stage sizes ``nx``, ``nu``, ``ng``; ``build_s`` how long building took."""

    solver: ca.Function
    free: np.ndarray
    rows: np.ndarray
    kind: np.ndarray
    """Per solver row: 0 dynamics, 1 knot row, 2 pair row."""
    src: np.ndarray
    """Per solver row: its index in :func:`.problem.row_bounds`' rows (−1: a dynamics row)."""
    nx: list[int]
    nu: list[int]
    ng: list[int]
    build_s: float


def _pair_rows(form: pb.Formulation, T: int) -> np.ndarray:
    """``(n_pair, T − 1)`` row indices (in :func:`.problem.row_bounds`' order) of the
    non-integration pair parts' rows between knots j and j + 1."""
    idx = [np.arange(s.start, s.stop) for pp, s in zip(form.pairs, form.pair_slices)
           if not isinstance(pp, Integration)]
    r = np.concatenate(idx) if idx else np.zeros(0, int)
    return form.ngk * T + form.ns * np.arange(T - 1)[None, :] + r[:, None]


def stages(form: pb.Formulation, T: int, free: np.ndarray, keep: np.ndarray,
           opts: dict | None = None) -> Stages:
    """fatrop's problem (cached by the pattern of ``free`` variables and ``keep`` rows)."""
    fun = stage_functions(form)
    assert fun is not None, "the formulation cannot be written stage-wise (supported())"
    key = (id(form), T, hashlib.sha1(free.tobytes()).hexdigest(),
           hashlib.sha1(np.asarray(keep, int).tobytes()).hexdigest(),
           repr(sorted((opts or {}).items())))
    if key in _STAGES:
        _STAGES.move_to_end(key)
        return _STAGES[key]
    t0 = time.perf_counter()
    nx, ngk = form.nx, form.ngk
    nxs = form.knot.sym.nq + form.knot.sym.nv
    flat = free.T.ravel()  # knot-major, as z = vec(X)
    sel = np.flatnonzero(flat)
    nz = sel.size
    E = ca.DM(ca.Sparsity.triplet(nx * T, nz, sel.tolist(), list(range(nz))), 1.0)
    z = ca.MX.sym("z", nz)
    fixed = ca.MX.sym("fixed", nx * T)  # the fixed variables' values (0 where free)
    P = ca.MX.sym("P", form.knot.par.size, T)
    X = ca.reshape(fixed + ca.mtimes(E, z), nx, T)
    D = X[:nxs, 1:] - fun["dyn"].map(T - 1)(X[:, :-1], P[:, 1:])
    G = ca.vertcat(*[g.map(T)(X, P) for g in codegen.pieces(fun, "g")])
    H = fun["pair"].map(T - 1)(X[:, :-1], P[:, 1:])
    npair = int(H.shape[0])
    stacked = ca.vertcat(ca.vec(D), ca.vec(G), ca.vec(H))
    jsp = ca.jacobian_sparsity(stacked, z)
    touches = np.diff(np.asarray(jsp.T.colind())) > 0  # rows some free variable enters
    kept = np.zeros(ngk * T + form.ns * (T - 1), bool)
    kept[np.asarray(keep, int)] = True
    prow = _pair_rows(form, T)
    rows: list[int] = []
    kind: list[int] = []
    src: list[int] = []
    nxk, nuk, ngs = [], [], []

    def add(r: int, what: int, origin: int) -> None:
        rows.append(r)
        kind.append(what)
        src.append(origin)

    nD, nG = nxs * (T - 1), ngk * T
    for k in range(T):
        nxk.append(int(free[:nxs, k].sum()))
        nuk.append(int(free[nxs:, k].sum()))
        n0 = len(rows)
        if k < T - 1:
            nxt = np.arange(nxs) + nxs * k
            for r in nxt[free[:nxs, k + 1]]:  # the next knot's free states: gap-closing rows
                add(int(r), 0, -1)
            n0 = len(rows)
            # a fixed next state: its row an equality of this stage where free variables
            # enter it, else left out (its fixed values integrate: a frozen joint at rest)
            for r in nxt[~free[:nxs, k + 1] & touches[nxt]]:
                add(int(r), 0, -1)
        for i in np.flatnonzero(kept[k * ngk:(k + 1) * ngk]):
            add(nD + int(i) + ngk * k, 1, k * ngk + int(i))
        if k < T - 1:
            for i in np.flatnonzero(kept[prow[:, k]]):
                add(nD + nG + int(i) + npair * k, 2, int(prow[i, k]))
        ngs.append(len(rows) - n0)
    rows_a = np.asarray(rows, int)
    S = ca.DM(ca.Sparsity.triplet(rows_a.size, int(stacked.shape[0]), list(range(rows_a.size)),
                                  rows_a.tolist()), 1.0)
    g = ca.mtimes(S, stacked)
    scale = float(IPOPT_DEFAULTS["obj_scaling_factor"])  # type: ignore[arg-type]
    f = scale * ca.sum2(fun["f"].map(T)(X, P)) / T
    nlp: dict[str, Any] = {"x": z, "p": ca.vertcat(ca.vec(P), fixed), "f": f, "g": g}
    o: dict[str, Any] = {"print_time": False, "structure_detection": "manual", "N": T - 1,
                         "nx": nxk, "nu": nuk, "ng": ngs,
                         "fatrop": {**FATROP_DEFAULTS, **(opts or {})}}
    solver = ca.nlpsol("structured", "fatrop", nlp, o)
    st = Stages(solver, free.copy(), rows_a, np.asarray(kind), np.asarray(src), nxk, nuk, ngs,
                time.perf_counter() - t0)
    _STAGES[key] = st
    while len(_STAGES) > pb.CACHE_SIZE:
        _STAGES.popitem(last=False)
    return st


def run_fatrop(form: pb.Formulation, T: int, P: np.ndarray, x0: np.ndarray, lbx: np.ndarray,
               ubx: np.ndarray, lbg: np.ndarray, ubg: np.ndarray, keep: np.ndarray,
               opts: dict | None = None) -> tuple[np.ndarray, dict, Stages]:
    """One fatrop solve of the problem :mod:`.solve` hands IPOPT: parameters ``P``
    ``(n_p, T)``, start and variable bounds ``(n_x, T)``, every row's bounds ``lbg``,
    ``ubg`` (:func:`.problem.row_bounds`) of which the rows ``keep`` count. Returns ``(z``
    ``(n_x·T,)`` knot-major as IPOPT's, ``stats``, the :class:`Stages`)."""
    free = lbx != ubx
    st = stages(form, T, free, keep, opts)
    fixed = np.where(free, 0.0, lbx).T.ravel()
    sel = free.T.ravel()
    lo = np.zeros(st.rows.size)
    hi = np.zeros(st.rows.size)
    m = st.kind > 0
    lo[m], hi[m] = lbg[st.src[m]], ubg[st.src[m]]
    x = np.clip(x0, lbx, ubx).T.ravel()
    sol = st.solver(x0=x[sel], p=np.r_[P.T.ravel(), fixed], lbx=lbx.T.ravel()[sel],
                    ubx=ubx.T.ravel()[sel], lbg=lo, ubg=hi)
    stats = dict(st.solver.stats())
    z = fixed.copy()
    z[sel] = np.asarray(sol["x"]).ravel()
    return z, stats, st


def hard_problem(c: pb.Compiled, num) -> tuple[np.ndarray, ...]:
    """``(P, x0, lbx, ubx)`` ``(·, T)`` of the hard solve :func:`.solve.run_solver` hands IPOPT
    for ``c`` (an IPOPT :class:`~.problem.Compiled`) and ``num`` (:class:`~.solve.Numbers`):
    the free goal slacks started at their rows' violations, the goal's L1 price
    :data:`~.solve.GOAL_WEIGHT`."""
    from . import solve as S

    free = S._free_slacks(c, num, goal_only=True)
    lbx, ubx = num.lbx.copy(), num.ubx.copy()
    for name, fr in zip(("s_plus", "s_minus"), free):
        ubx[c.knot.var[name]] = fr
    P = num.P.copy()
    P[c.knot.par["elastic"]] = S.GOAL_WEIGHT
    return P, S._slack_start(c, num, num.x0, free), lbx, ubx


def hard_solve(c: pb.Compiled, num, opts: dict | None = None
               ) -> tuple[np.ndarray, dict, Stages]:
    """fatrop on the hard solve IPOPT gets (:func:`hard_problem`: the same start, bounds,
    kept rows and cost). Returns :func:`run_fatrop`'s ``(z, stats, stages)`` with the elastic
    slacks of ``z`` at 0 (the motion's own row values)."""
    from . import solve as S

    P, x0, lbx, ubx = hard_problem(c, num)
    z, stats, st = run_fatrop(c.form, c.T, P, x0, lbx, ubx, num.lbg, num.ubg, num.keep, opts)
    return S._zero_slacks(c, z, c.T), stats, st
