"""The parametric NLP, assembled from a list of parts (:mod:`..parts`).

Two levels, each cached:

- :class:`Formulation` — one knot's functions (constraint rows, their Jacobian, the cost and
  its gradient, the Hessian of the knot's Lagrangian; the same for the rows between two
  knots), written in SX from the parts and compiled to C once per robot and list of parts
  (:mod:`.codegen`: kept on disk, loaded by later processes without building anything);
- :class:`Compiled` — those functions mapped over ``T`` knots (``casadi.Function.map``) and
  assembled into the sparse block structure IPOPT needs, keeping only the rows the
  demonstration's schedule bounds (a row with infinite bounds on both sides is left out of
  the KKT system, not carried with infinite bounds). Key: the formulation, ``T``, the kept
  rows and IPOPT's options; a demonstration only fills parameters and bounds
  (:data:`BUILD_COUNT` counts builds).
"""

from __future__ import annotations

import functools
import hashlib
import os
import sys
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ...model import contact, footsteps, kinematics, selfcollision, symbolic
from ...model import robot as robot_module
from ...model.robot import Robot
from ...model.symbolic import SymbolicModel
from .. import bodymap
from .. import context as context_module
from .. import knot as knot_module
from .. import parts as parts_module
from ..knot import Flags, Knot
from ..params import IPOPT_DEFAULTS
from ..parts import Constraint, Cost, PairConstraint, Part, Spec
from ..parts.seam import SeamConstraint, seam_functions
from . import codegen
from .interrupt import Progress

__all__ = ["Formulation", "Compiled", "formulation", "compiled", "clear_cache", "BUILD_COUNT",
           "CACHE_SIZE", "fingerprint", "Spec", "IPOPT_DEFAULTS"]

CACHE_SIZE = 8
_CACHE: OrderedDict[tuple, Compiled] = OrderedDict()
_FORM: OrderedDict[tuple, Formulation] = OrderedDict()
_SYM: OrderedDict[str, SymbolicModel] = OrderedDict()
BUILD_COUNT = 0
"""How many NLPs this process has built (a cached call leaves it unchanged)."""



def fingerprint(robot: Robot) -> str:
    """A digest of everything in the imitator the NLP's expressions depend on (joint types
    and axes, joint placements, inertias, contact frames, leg lengths)."""
    m = robot.model
    h = hashlib.sha1()
    h.update(repr((robot.name, m.nq, m.nv, tuple(m.names), robot.base)).encode())
    for i in range(1, m.njoints):
        axis = getattr(m.joints[i].extract(), "axis", None)  # unaligned joints: type says nothing
        h.update(f"{m.joints[i].shortname()}:{None if axis is None else list(axis)}".encode())
        h.update(np.asarray(m.jointPlacements[i].homogeneous).tobytes())
        h.update(np.asarray(m.inertias[i].toDynamicParameters()).tobytes())
    for _side, c in sorted(robot.require_contacts().items()):
        fr = m.frames[m.getFrameId(c.frame)]
        h.update(f"{_side}:{c.frame}:{fr.parentJoint}".encode())
        h.update(np.asarray(fr.placement.homogeneous).tobytes())
    for _, leg in sorted(robot.legs.items()):
        h.update(repr(leg).encode())
    return h.hexdigest()


def _lru(cache: OrderedDict, key, make):
    if key not in cache:
        cache[key] = make()
        while len(cache) > CACHE_SIZE:
            cache.popitem(last=False)
    cache.move_to_end(key)
    return cache[key]


def symbolic_model(robot: Robot) -> SymbolicModel:
    """The (cached) :class:`SymbolicModel` of a robot."""
    return _lru(_SYM, fingerprint(robot), lambda: SymbolicModel(robot.model))


def clear_cache() -> None:
    """Forget every cached NLP, formulation and symbolic model (not the compiled libraries on
    disk: :func:`gdimitate.retarget.trajectory.codegen.cache_dir`)."""
    _CACHE.clear()
    _FORM.clear()
    _SYM.clear()


# ---------------------------------------------------------------------- one knot
@dataclass
class Formulation:
    """One knot's functions from a list of parts (module docstring).

    ``knot``: the :class:`Knot` (layouts of variables and parameters); ``parts``; per-knot
    constraint parts ``cons`` with their row ``slices``; ``pairs`` with ``pair_slices``;
    ``labels`` ``(ngk,)`` and ``scale`` ``(ngk,)`` (each row's divisor into scaled units) of
    the per-knot rows; ``fun``: the functions by name — ``kg (x, p) -> g``,
    ``kjac (x, p) -> ∂g/∂x``, ``kf (x, p) -> f`` (the knot's cost, not divided by T), ``kgrad``,
    ``kh0, kh1, … (x, p, σ, λ)`` -> triu ∇²(σf + λᵀg) in pieces, summed
    (:func:`.codegen.pieces`),
    ``pg (x₀, x₁, p₁) -> rows``,
    ``pjac``, ``ph (x₀, x₁, p₁, μ)``, ``kres (x, p) -> weighted residuals`` and
    ``kresjac`` (their Jacobian: the streaming mode's Gauss-Newton model),
    ``tau (x, p) -> τ (nv,)``; ``compiled``: whether they run as compiled C."""

    knot: Knot
    parts: tuple[Part, ...]
    cons: list[Constraint]
    slices: list[slice]
    pairs: list[PairConstraint]
    pair_slices: list[slice]
    labels: list[str]
    scale: np.ndarray
    fun: dict[str, ca.Function]
    compiled: bool
    seam: dict[str, ca.Function] | None = None
    """Rows between the last knot and the first (:class:`.parts.seam.SeamConstraint`: a
    periodic cycle): ``sg (x_first, x_last, p_first)``, ``sjac``, ``sh``; ``None``: none."""
    seam_labels: list[str] = field(default_factory=list)
    seam_sizes: list[int] = field(default_factory=list)

    @property
    def relax_rows(self) -> np.ndarray:
        """``(n_slack,)``: the per-knot row each elastic slack pair relaxes."""
        return np.concatenate([np.arange(s.start, s.stop) for c, s in
                               zip(self.cons, self.slices) if c.relaxable] or [np.zeros(0)]
                              ).astype(int)

    def slack_bounds(self, lbg: np.ndarray, ubg: np.ndarray, T: int
                     ) -> tuple[np.ndarray, np.ndarray]:
        """Upper bounds ``(n_slack, T)`` of ``s⁺`` and ``s⁻`` in the least-infeasible solve: a
        slack is free (∞) only where its row has the bound it relaxes (``s⁺`` a lower bound,
        ``s⁻`` an upper one) at that knot, else fixed at 0 (so it leaves the problem)."""
        n = self.ngk
        rr = self.relax_rows
        lo = lbg[: n * T].reshape(T, n)[:, rr].T
        hi = ubg[: n * T].reshape(T, n)[:, rr].T
        return (np.where(np.isfinite(lo), np.inf, 0.0), np.where(np.isfinite(hi), np.inf, 0.0))

    @property
    def nx(self) -> int:
        return self.knot.var.size

    @property
    def ngk(self) -> int:
        return len(self.labels)

    @property
    def ns(self) -> int:
        return self.pair_slices[-1].stop if self.pair_slices else 0

    @property
    def nseam(self) -> int:
        return len(self.seam_labels)

    def rows_of(self, kind: type) -> slice:
        """The per-knot row slice of the first constraint part of type ``kind``."""
        return next(s for c, s in zip(self.cons, self.slices) if isinstance(c, kind))


def _weights(parts) -> tuple[str, ...]:
    out: list[str] = []
    for p in parts:
        if isinstance(p, Cost) and p.weight and p.weight not in out:
            out.append(p.weight)
    return tuple(out)


def _knot_expressions(k: Knot, parts) -> tuple:
    """``(cons, slices, rows, labels, scale, pairs, pair rows (x0 symbol), costs)``."""
    cons = [p for p in parts if isinstance(p, Constraint)]
    pairs = [p for p in parts if isinstance(p, PairConstraint)]
    costs = [p for p in parts if isinstance(p, Cost)]
    stated = [c.at(k) for c in cons]
    n_relax = sum(rows.n for c, rows in zip(cons, stated) if c.relaxable)
    k.add_slacks(n_relax)
    out: list[ca.SX] = []
    labels: list[str] = []
    scale: list[float] = []
    slices: list[slice] = []
    o = used = 0
    for c, rows in zip(cons, stated):
        n, r = rows.n, rows.expr
        if c.relaxable:  # the elastic pair s⁺ − s⁻ of each row (0 outside the fallback)
            r = r + k.s_plus[used:used + n] - k.s_minus[used:used + n]
            used += n
        out.append(r)
        labels += rows.labels
        scale += [rows.scale] * n
        slices.append(slice(o, o + n))
        o += n
    x0 = ca.SX.sym("x_prev", k.var.size)
    prow, pslices, o = [], [], 0
    for pp in pairs:
        carry = ca.Function("carry", [k.x], [pp.carry(k)])
        r = pp.rows(k, carry(x0), pp.carry(k))
        prow.append(r)
        pslices.append(slice(o, o + int(r.shape[0])))
        o += int(r.shape[0])
    return cons, slices, out, labels, np.array(scale), pairs, pslices, prow, x0, costs


def _functions(k: Knot, g_rows, slices, costs, prow, x0) -> list[ca.Function]:
    """The knot's functions (:class:`Formulation`); the Lagrangian's Hessian in pieces of
    rows (:func:`.codegen.split_rows`: ``kh0, …``, summed; ``kh0`` holds the cost's). Not the
    Jacobian: its pieces, stacked, ran 1.5–1.9× slower (Talos) and it compiles in a sixth of
    the Hessian's time (docs/design.md §6)."""
    gk = ca.vertcat(*g_rows)
    res = ca.vertcat(*[(k.weight(c.weight) if c.weight else 1) * c.residual(k) for c in costs])
    fk = ca.sumsqr(res) + k.P("elastic")[0] * (ca.sum1(k.s_plus) + ca.sum1(k.s_minus))
    lam, sigma = ca.SX.sym("lam", gk.shape[0]), ca.SX.sym("sigma")
    gs = ca.vertcat(*prow) if prow else ca.SX(0, 1)
    mu = ca.SX.sym("mu", gs.shape[0])
    xx = ca.vertcat(x0, k.x)
    x, p = k.x, k.p
    ng = gk.shape[0]
    jac = ca.jacobian(gk, x)
    weight = np.array([jac[i, :].nnz() + 1 for i in range(ng)])

    def hess(a: int, b: int) -> list[ca.SX]:  # items: the cost, then the rows
        lag = (sigma * fk if a == 0 else 0) + ca.dot(lam[max(a - 1, 0):b - 1],
                                                     gk[max(a - 1, 0):b - 1])
        return [ca.triu(ca.hessian(lag, x)[0])]

    cuts = tuple(s.start for s in slices)  # where one part's rows end and the next's begin
    return [ca.Function("kg", [x, p], [gk]), ca.Function("kjac", [x, p], [jac]),
            ca.Function("kf", [x, p], [fk]), ca.Function("kgrad", [x, p], [ca.gradient(fk, x)]),
            *codegen.split_rows("kh", ng + 1, np.r_[len(costs) + 1, weight], hess,
                                [x, p, sigma, lam], (1, *(c + 1 for c in cuts))),
            ca.Function("pg", [x0, x, p], [gs]),
            ca.Function("pjac", [x0, x, p], [ca.jacobian(gs, xx)]),
            ca.Function("ph", [x0, x, p, mu], [ca.hessian(ca.dot(mu, gs), xx)[0]]),
            ca.Function("kres", [x, p], [res]),
            ca.Function("kresjac", [x, p], [ca.jacobian(res, x)]),
            ca.Function("tau", [x, p], [k.torques()])]


def formulation(robot: Robot, flags: Flags, parts: tuple[Part, ...]) -> Formulation:
    """The (cached) :class:`Formulation` of a robot and a list of parts."""
    parts = tuple(parts)
    key = (fingerprint(robot), flags, repr(parts))

    def make() -> Formulation:
        sym = symbolic_model(robot)
        extra: dict[str, int] = {}
        k = Knot(robot, sym, flags, _weights(parts), extra)
        for p in parts:
            extra.update(p.params(k))
        if extra:
            k = Knot(robot, sym, flags, _weights(parts), extra)
        cons, slices, g_rows, labels, scale, pairs, pslices, prow, x0, costs = \
            _knot_expressions(k, parts)
        fun, comp = codegen.compiled_functions(
            digest, lambda: _functions(k, g_rows, slices, costs, prow, x0), f"{robot.name}'s")
        seams = [p for p in parts if isinstance(p, SeamConstraint)]
        seam, seam_labels, seam_sizes = seam_functions(k, seams) if seams else (None, [], [])
        return Formulation(k, parts, cons, slices, pairs, pslices, labels, scale, fun, comp,
                           seam, seam_labels, seam_sizes)

    digest = hashlib.sha1(repr((key, _SOURCE)).encode()).hexdigest()
    form = _FORM.get(key)
    if form is not None and not form.compiled and codegen.library(digest).exists():
        del _FORM[key]  # its library has come (compiled in the background): load it now
    return _lru(_FORM, key, make)


# what the compiled functions' layout and expressions come from: this module (their layout),
# codegen (how they are generated), the parts, the knot, the context the parts read, the
# symbolic model and the contact wrench cone the cone part evaluates
# (contact.wrench_cone_rows); every module these import from gdimitate is listed
# (tests/retarget/trajectory/test_codegen.py checks it)
SOURCE_MODULES = (parts_module, knot_module, context_module, symbolic, codegen, contact,
                  robot_module, selfcollision, bodymap, kinematics, footsteps,
                  sys.modules[__name__])
_SOURCE = codegen.source_digest(*SOURCE_MODULES)


# ---------------------------------------------------------------------- all knots
@dataclass
class Compiled:
    """A built NLP over ``T`` knots: ``solver`` (``nlpsol``), ``form`` (the
    :class:`Formulation`), ``keep`` (indices of the rows of :func:`row_bounds` the solver
    sees), ``g_fun`` ``(z, P) -> g`` of every row (for reports), ``tau_fun``, ``progress``
    (the iteration callback), ``labels`` (one per row of :func:`row_bounds`)."""

    solver: ca.Function
    form: Formulation
    g_fun: ca.Function
    T: int
    keep: np.ndarray
    progress: Progress
    labels: list[str]

    @property
    def knot(self) -> Knot:
        return self.form.knot

    @property
    def nx(self) -> int:
        return self.form.nx

    @property
    def ng_knot(self) -> int:
        return self.form.ngk

    @property
    def ng(self) -> int:
        return self.form.ngk * self.T + self.form.ns * (self.T - 1) + self.form.nseam


def _freeze(d: dict) -> tuple:
    return tuple(sorted((k, repr(v)) for k, v in d.items()))


def compiled(form: Formulation, T: int, keep: np.ndarray, ipopt: dict | None = None
             ) -> tuple[Compiled, bool]:
    """The NLP over ``T`` knots keeping rows ``keep``, built now or taken from the cache;
    ``(compiled, cached)``."""
    keep = np.asarray(keep, int)
    key = (id(form), T, hashlib.sha1(keep.tobytes()).hexdigest(), _freeze(ipopt or {}))
    if key in _CACHE and _CACHE[key].form is form:
        _CACHE.move_to_end(key)
        return _CACHE[key], True
    _CACHE[key] = c = _build(form, T, keep, ipopt or {})
    while len(_CACHE) > CACHE_SIZE:
        _CACHE.popitem(last=False)
    return c, False


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
    return ca.DM(ca.Sparsity.triplet(2 * nx * (T - 1), nx * T, rows, cols), 1.0)


def _seam_spread(nx: int, T: int) -> ca.DM:
    """``(2·nx, nx·T)``: the columns of (first knot, last knot) → those knots."""
    cols = list(range(nx)) + list(range(nx * (T - 1), nx * T))
    return ca.DM(ca.Sparsity.triplet(2 * nx, nx * T, list(range(2 * nx)), cols), 1.0)


def _select(keep: np.ndarray, ng: int) -> ca.DM:
    """``(len(keep), ng)`` selection matrix."""
    sp = ca.Sparsity.triplet(len(keep), ng, list(range(len(keep))), keep.tolist())
    return ca.DM(sp, 1.0)


def _parallel(form: Formulation) -> tuple:
    """How the knots' Jacobian and Hessian are mapped: uncompiled (CasADi's virtual machine,
    while the library is built in the background — which waits for this run, leaving its
    cores free), in one thread per core; compiled, serially (a solve stays on one core: a
    batch runs one per core). G1's stride in the virtual machine, 2 cores: 30 → 20 s."""
    return () if form.compiled else ("thread", max(1, os.cpu_count() or 1))


def _build(form: Formulation, T: int, keep: np.ndarray, ipopt: dict) -> Compiled:
    """Map the knot's functions over ``T`` knots and assemble values and derivatives (never
    CasADi's MX-level differentiation of the mapped graph: two orders of magnitude slower)."""
    global BUILD_COUNT
    f, nx, ngk, ns = form.fun, form.nx, form.ngk, form.ns
    X = ca.MX.sym("X", nx, T)
    P = ca.MX.sym("P", form.knot.par.size, T)
    z, p = ca.vec(X), ca.vec(P)
    g_list = [ca.vec(f["kg"].map(T)(X, P))]
    par = _parallel(form)
    j_list = [_blockdiag(f["kjac"].map(T, *par)(X, P), nx)]
    ng = ngk * T + ns * (T - 1) + form.nseam
    S = _select(keep, ng)
    lam_f, lam_s = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", len(keep))
    lam_g = ca.mtimes(S.T, lam_s)
    lam_k = ca.reshape(lam_g[:ngk * T], ngk, T)
    hs = [h.map(T, *par)(X, P, lam_f / T, lam_k) for h in codegen.pieces(f, "kh")]
    H = _blockdiag(functools.reduce(ca.plus, hs), nx)  # (never 0 + H: that fills H)
    if T > 1 and ns:
        E = _pair_spread(nx, T)
        args = (X[:, :-1], X[:, 1:], P[:, 1:])
        g_list.append(ca.vec(f["pg"].map(T - 1)(*args)))
        j_list.append(ca.mtimes(_blockdiag(f["pjac"].map(T - 1)(*args), 2 * nx), E))
        HS = f["ph"].map(T - 1)(*args, ca.reshape(lam_g[ngk * T:ngk * T + ns * (T - 1)],
                                                      ns, T - 1))
        H = H + ca.triu(ca.mtimes([E.T, _blockdiag(HS, 2 * nx), E]))
    if form.seam is not None:  # rows between the last knot and the first (periodic cycle)
        sf, args = form.seam, (X[:, 0], X[:, T - 1], P[:, 0])
        Es = _seam_spread(nx, T)
        g_list.append(sf["sg"](*args))
        j_list.append(ca.mtimes(sf["sjac"](*args), Es))
        HS = sf["sh"](*args, lam_g[ngk * T + ns * (T - 1):])
        H = H + ca.triu(ca.mtimes([Es.T, HS, Es]))
    G = ca.vertcat(*g_list)
    Gs, Js = ca.mtimes(S, G), ca.mtimes(S, ca.vertcat(*j_list))
    F = ca.sum2(f["kf"].map(T)(X, P)) / T
    grad_f = ca.Function("grad_f", [z, p], [F, ca.vec(f["kgrad"].map(T)(X, P)) / T],
                         ["x", "p"], ["f", "grad_f_x"])
    jac_g = ca.Function("jac_g", [z, p], [Gs, Js], ["x", "p"], ["g", "jac_g_x"])
    hess = ca.Function("hess_lag", [z, p, lam_f, lam_s], [ca.triu(H)],
                       ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    progress = Progress(f"progress_{BUILD_COUNT}", int(z.shape[0]), len(keep),
                        int(p.shape[0]))
    opts: dict[str, Any] = {
        "print_time": False, "iteration_callback": progress, "grad_f": grad_f,
        "calc_lam_p": False, "no_nlp_grad": True,
        "jac_g": jac_g, "hess_lag": hess, "ipopt": {**IPOPT_DEFAULTS, **ipopt}}
    nlp: dict[str, Any] = {"x": z, "p": p, "f": F, "g": Gs}
    solver = ca.nlpsol(f"retarget_{BUILD_COUNT}", "ipopt", nlp, opts)
    g_fun = ca.Function("g", [z, p], [G])
    BUILD_COUNT += 1
    return Compiled(solver, form, g_fun, T, keep, progress, row_labels(form, T))


def row_bounds(form: Formulation, spec: Spec) -> tuple[np.ndarray, np.ndarray]:
    """``(lbg, ubg)`` of every row for a demonstration: per knot the constraint parts' rows in
    list order, then per pair of knots the pair parts' rows."""
    lo = np.concatenate([c.bounds(spec)[0] for c in form.cons], axis=1).ravel()
    hi = np.concatenate([c.bounds(spec)[1] for c in form.cons], axis=1).ravel()
    los, his = [lo], [hi]
    if spec.T > 1 and form.pairs:
        b = [pp.bounds(spec, s.stop - s.start) for pp, s in zip(form.pairs, form.pair_slices)]
        los.append(np.concatenate([x[0] for x in b], axis=1).ravel())
        his.append(np.concatenate([x[1] for x in b], axis=1).ravel())
    if form.nseam:
        b = [sp.bounds(spec, n) for sp, n in
             zip([p for p in form.parts if isinstance(p, SeamConstraint)], form.seam_sizes)]
        los.append(np.concatenate([x[0] for x in b]))
        his.append(np.concatenate([x[1] for x in b]))
    return np.concatenate(los), np.concatenate(his)


def row_scale(form: Formulation, T: int) -> np.ndarray:
    """``(ng,)`` divisors putting each row in scaled units (:meth:`Constraint.scale`)."""
    return np.r_[np.tile(form.scale, T), np.ones(form.ns * max(T - 1, 0) + form.nseam)]


def row_labels(form: Formulation, T: int) -> list[str]:
    """A label for each of the ``ng`` rows (per-knot rows, then pair rows)."""
    out = form.labels * T
    for _ in range(T - 1):
        for pp, s in zip(form.pairs, form.pair_slices):
            out += [pp.name] * (s.stop - s.start)
    return out + list(form.seam_labels)
