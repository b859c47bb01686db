"""The whole-body trajectory mode of :func:`gdimitate.retarget.adapt_optimal` — targets, warm
start, the cached NLP, IPOPT, the least-infeasible fallback and the honest (recomputed)
report."""

from __future__ import annotations

import ctypes
import dataclasses
import math
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ...assess.solver import SolverInfo, Unmet
from ...errors import SolverError
from ...model.contact import ContactForces, SoleContact
from ...model.footsteps import compare_gait, leg_ratio, time_scale
from ...model.heading import forces_on_clock, on_clock, turn_forces, turn_motion, walk_heading
from ...model.kinematics import actuated_v_indices, robot_motion
from ...model.motion import Motion
from ...model.robot import SIDES, Robot
from .. import limits
from ..context import Context
from ..info import limited_robot, resolve_contacts
from ..knot import Flags
from ..params import DEFAULT_RATE, IPOPT_DEFAULTS, Contact, Limits, Weights
from ..parts import Bound, ForceDirection, OverFeet, Steps, default_parts, liftoff_knots
from ..parts.body import body_parts
from ..targets import Targets, demonstration_targets, direction_frame, resample
from ..threads import single_thread
from . import codegen, stride
from . import problem as pb
from .initial import consistent_start, initial_q, initial_wrenches
from .interrupt import guard
from .polish import make_consistent
from .stopping import MU_TOL, PLATEAU, Plateau

__all__ = ["trajectory_mode", "SolverInfo", "Unmet", "STOPS", "Numbers",
           "Context", "setup", "problem_for", "run_solver", "unmet", "package", "wrenches_of",
           "limited_robot", "resolve_contacts", "solve_budgeted", "near_bounds", "rescreen",
           "SCREEN", "SCREEN_KNOTS", "WARM_START"]

STOPS = ("settled", "converged")
"""``stop=``: ``"settled"`` (default) — the best feasible iterate once the cost has settled
(:mod:`.stopping`); ``"converged"`` — IPOPT's own convergence test (``tol`` 1e-8; often
several times slower, the same motion to within the audit's tolerances)."""

MAX_ITERATIONS = 150
"""Iterations of one adaptation, the hard solve and the least-infeasible one together (the
latter gets at least :data:`MIN_ELASTIC`)."""
MIN_ELASTIC = 30
STALLED = "Infeasible_Stalled"
"""``SolverInfo.status`` of a hard solve whose constraint violation stopped falling."""
BUDGET = "Iteration_Budget_Spent"
APPROXIMATED = ("self_collision",)
"""Audit checks whose optimiser rows are approximations (sphere covers vs collision hulls)."""


@dataclass
class Numbers:
    """One demonstration's parameter matrix ``P`` ``(n_p, T)``, variable bounds and start
    ``(n_x, T)``, bounds of every row, the per-row divisor that puts every row in scaled units
    (:func:`~.problem.row_scale`), the resolved limits, the :class:`~.problem.Spec` and
    ``keep``: the rows some bound applies to less the ``screened`` ones (the only rows the
    solver sees)."""

    P: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    x0: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    spec: pb.Spec
    lim: limits.Resolved
    row_scale: np.ndarray
    keep: np.ndarray
    screened: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, int))
    """Rows with bounds left out of the solve (:func:`near_bounds`), re-checked on the
    result (:func:`rescreen`)."""


def setup(form: pb.Formulation, tg: Targets, imitator: Robot, demonstrator: Robot,
          w: Weights, lim_opts: Limits, copts: Contact, cs: dict[str, SoleContact],
          x_start: np.ndarray | None = None) -> Numbers:
    """Parameters, bounds and warm start of a demonstration for a formulation
    (``x_start`` ``(n_x, T)``: a given start, e.g. the previous frame's in streaming); the
    rows the solve sees (``keep``): those some bound applies to, less those the start keeps
    far from their bounds (:func:`near_bounds`)."""
    k = form.knot
    lim = limits.resolve(imitator, k.act_idx, lim_opts)
    ctx = Context(tg, imitator, demonstrator, w, lim, copts, cs)
    P = _parameters(form, ctx)
    spec = _spec(form, tg, imitator, copts)
    lbx, ubx = _variable_bounds(form, ctx, spec)
    if x_start is None:
        x0 = _warm_start(form, ctx, lbx, ubx)
    else:
        x0 = np.array(x_start, dtype=float)
    # the start's horizontal base position is the motion's origin
    qs = k.var["q"].start
    base_xy = qs + np.array([0, 1] if imitator.base == "free" else [imitator.idx_q("base_x")])
    lbx[base_xy, 0] = ubx[base_xy, 0] = x0[base_xy, 0]
    lbg, ubg = pb.row_bounds(form, spec)
    bounded = np.isfinite(lbg) | np.isfinite(ubg)
    screened = np.flatnonzero(bounded & ~near_bounds(form, spec, x0, P, lbg, ubg))
    keep = np.setdiff1d(np.flatnonzero(bounded), screened)
    return Numbers(P, lbx, ubx, x0, lbg, ubg, spec, lim, pb.row_scale(form, tg.T), keep,
                   screened)


def _parameters(form: pb.Formulation, ctx: Context) -> np.ndarray:
    """The parameter matrix ``P`` ``(n_p, T)`` of a demonstration."""
    k, tg, w, copts, cs = form.knot, ctx.tg, ctx.weights, ctx.contact, ctx.cs
    T, lay = tg.T, form.knot.par
    P = np.zeros((lay.size, T))
    h = np.diff(tg.t)
    P[lay["h"]] = np.r_[h[:1] if h.size else [1.0], h]
    for s in SIDES:
        P[lay[f"height_{s}"]] = tg.height[s]
        P[lay[f"placement_{s}"]] = tg.placement[s].T
        P[lay[f"shank_{s}"]] = tg.shank[s].T
        P[lay[f"thigh_{s}"]] = tg.thigh[s].T
        P[lay[f"foot_{s}"]] = tg.foot[s].transpose(0, 2, 1).reshape(T, 9).T
        d = -tg.push[s]
        e1, e2 = direction_frame(d, k.planar)
        P[lay[f"d_{s}"]] = np.nan_to_num(d).T
        P[lay[f"e1_{s}"]] = e1.T
        P[lay[f"e2_{s}"]] = e2.T
        X, Y, m = cs[s].half_length, cs[s].half_width, copts.cop_margin
        P[lay[f"sole_{s}"]] = np.array([X, Y, _pyramid_mu(cs[s].mu, k.planar), X - m,
                                        Y - m])[:, None]
    if k.flags.segments:
        P[lay["torso"]] = np.concatenate([tg.segments[:, i].transpose(0, 2, 1).reshape(T, 9)
                                          for i in range(k.flags.segments)], axis=1).T
    lim = ctx.lim
    P[lay["joint_target"]] = tg.joints.T
    jw = np.where(tg.mapped, w.joints, w.posture) * ~lim.frozen
    P[lay["joint_weight"]] = np.sqrt(jw)[:, None]  # residuals carry √weight
    with np.errstate(divide="ignore"):
        P[lay["inv_effort"]] = np.where(np.isfinite(lim.effort), 1.0 / lim.effort, 0.0)[:, None]
    P[lay["weights"]] = np.sqrt([getattr(w, n) for n in k.weight_names])[:, None]
    P[lay["elastic"]] = w.elastic
    P[lay["tan2"]] = math.tan(copts.cone_half_angle) ** 2
    P[lay["f_min"]] = copts.f_min
    for part in form.parts:
        if not isinstance(part, Bound):  # a bound's values are its box's, not parameters
            for name, val in part.values(ctx).items():
                P[lay[name]] = np.asarray(val, float).reshape(T, -1).T
    return P


def _pyramid_mu(mu: float, planar: bool) -> float:
    """The friction coefficient of the cone's square pyramid (:mod:`.parts.cone`) that keeps
    it inside Coulomb's circle ``‖f_t‖ ≤ μ f_z``, which the audit checks: μ/√2 in 3-D (with μ
    itself the pyramid's corners admit √2·μ — CMU → G1 planned ratios of 0.99 against μ =
    0.7 where a foot was barely loaded, and the audit failed it); μ for a planar model (its
    one row, along x, is the circle)."""
    return mu if planar else mu / math.sqrt(2)


def _spec(form: pb.Formulation, tg: Targets, imitator: Robot, copts: Contact) -> pb.Spec:
    k, T = form.knot, tg.T
    lift = {s: (liftoff_knots(tg.stance[s], tg.swing[s]) if copts.rule == "all"
                else np.zeros(T, bool)) for s in SIDES}
    return pb.Spec(T=T, stance=tg.stance, swing=tg.swing, liftoff=lift,
                   goal_active={s: tg.stance[s] & np.all(np.isfinite(tg.push[s]), axis=1)
                                for s in SIDES},
                   planar=k.planar, free=imitator.base == "free", cone=k.flags.cone,
                   clearance=copts.clearance, leg_length=imitator.legs["left"].length,
                   n_base=len(k.base_idx), n_act=len(k.act_idx))


def _variable_bounds(form: pb.Formulation, ctx: Context, spec: pb.Spec
                     ) -> tuple[np.ndarray, np.ndarray]:
    """``(lbx, ubx)`` ``(n_x, T)``: joint position and velocity limits, frozen joints, swing
    feet's wrenches at 0, the slacks at 0, and every :class:`~.parts.Bound`'s box (where a
    box and a joint's limits do not meet, the joint is held at the limit nearest the box)."""
    k, lim, tg = form.knot, ctx.lim, ctx.tg
    var, T = k.var, tg.T
    lbx = np.full((var.size, T), -np.inf)
    ubx = np.full((var.size, T), np.inf)
    qs, vs, as_ = var["q"].start, var["v"].start, var["a"].start
    qi, vi = lim.q_index, k.act_idx
    lbx[qs + qi], ubx[qs + qi] = lim.lower[:, None], lim.upper[:, None]
    lbx[vs + vi], ubx[vs + vi] = -lim.velocity[:, None], lim.velocity[:, None]
    for part in form.parts:
        if isinstance(part, Bound):
            idx, lo, hi = part.box(var, ctx, spec)
            lo_, hi_ = np.maximum(lbx[idx], lo.T), np.minimum(ubx[idx], hi.T)
            empty = lo_ > hi_
            lo_[empty] = hi_[empty] = np.where(lbx[idx] > hi.T, lbx[idx], ubx[idx])[empty]
            lbx[idx], ubx[idx] = lo_, hi_
    fz = lim.frozen
    lbx[qs + qi[fz]] = ubx[qs + qi[fz]] = lim.freeze_at[fz, None]
    for blk in (vs, as_):
        lbx[blk + vi[fz]] = ubx[blk + vi[fz]] = 0.0
    for s in SIDES:
        sl = var[f"w_{s}"]
        lbx[sl, ~tg.stance[s]] = ubx[sl, ~tg.stance[s]] = 0.0
    for name in ("s_plus", "s_minus"):
        lbx[var[name]] = ubx[var[name]] = 0.0
    return lbx, ubx


SCREEN = 0.03
"""A row of a screenable part (:attr:`~.parts.Constraint.screenable`) enters a solve at knot
k only when the start (or a result) brings it within this much of its bounds (scaled units:
0.03 leg lengths, Talos 2.1 cm, G1 1.9 cm, iCub 1.3 cm) at a knot within
:data:`SCREEN_KNOTS` of k. Talos, 100 knots: 0.07 kept 20,300 of 31,100 self-collision rows
(79 iterations), 0.02 kept 15,739 of 31,600 (64), neither needing a second solve; iCub at
0.03 needed one (3 rows violated) — measured with one row per sphere pair; the rows are now one
per pair of frames (:class:`~.parts.self_collision.SelfCollision`), 42 per knot on Talos."""
SCREEN_KNOTS = 3


def near_bounds(form: pb.Formulation, spec: pb.Spec, X: np.ndarray, P: np.ndarray,
                lbg: np.ndarray, ubg: np.ndarray) -> np.ndarray:
    """``(ng,)`` bool: False for the rows a screenable part may leave out
    (:attr:`~.parts.Constraint.screenable`, :meth:`~.parts.Constraint.screenable_rows`) at
    knots where ``X`` ``(n_x, T)`` keeps them farther than :data:`SCREEN` from their bounds at
    every knot within :data:`SCREEN_KNOTS`; True for every other row."""
    T, n = spec.T, form.ngk
    out = np.ones(lbg.size, bool)
    parts = [np.arange(sl.start, sl.stop)[c.screenable_rows(form.knot)]
             for c, sl in zip(form.cons, form.slices) if c.screenable]
    if not parts:
        return out
    G = np.asarray(form.fun["kg"].map(T)(X, P))  # (ngk, T)
    lo, hi = lbg[:n * T].reshape(T, n).T, ubg[:n * T].reshape(T, n).T
    with np.errstate(invalid="ignore"):
        slack = np.minimum(G - lo, hi - G)
    near = np.zeros((n, T), bool)
    for rows in parts:  # a part's rows (indices at a knot) that may be left out
        close = slack[rows] / form.scale[rows, None] < SCREEN
        for d in range(-SCREEN_KNOTS, SCREEN_KNOTS + 1):  # within SCREEN_KNOTS knots
            near[rows, max(d, 0):T + min(d, 0)] |= close[:, max(-d, 0):T - max(d, 0)]
        out[:n * T].reshape(T, n)[:, rows] = near[rows].T
    return out


def rescreen(c: pb.Compiled, num: Numbers, z: np.ndarray, tol: float) -> np.ndarray:
    """Rows left out of the solve (``num.screened``) that the solution ``z`` violates by more
    than ``tol`` (scaled units), with every left-out row ``z`` brings within :data:`SCREEN`
    (:func:`near_bounds`); empty when ``z`` meets every left-out row."""
    if not num.screened.size:
        return num.screened
    g = np.asarray(c.g_fun(z, num.P.T.ravel())).ravel()[num.screened]
    i = num.screened
    viol = (np.maximum(num.lbg[i] - g, 0) + np.maximum(g - num.ubg[i], 0)) / num.row_scale[i]
    if not np.any(viol > tol):
        return np.zeros(0, int)
    Z = z.reshape(num.spec.T, -1).T
    near = near_bounds(c.form, num.spec, Z, num.P, num.lbg, num.ubg)
    return i[near[i]]


def _warm_start(form: pb.Formulation, ctx: Context, lbx: np.ndarray, ubx: np.ndarray
                ) -> np.ndarray:
    """``(n_x, T)``: :mod:`.initial`'s configurations inside the variables' bounds ``lbx``,
    ``ubx`` ``(n_x, T)``, integration-consistent velocities and accelerations, wrenches from
    a per-knot QP."""
    k, var, tg, lim = form.knot, form.knot.var, ctx.tg, ctx.lim
    imitator = ctx.imitator
    q0 = initial_q(ctx.demonstrator, imitator, tg, lim.q_index).copy()
    q0 = np.clip(q0, lbx[var["q"]].T, ubx[var["q"]].T)
    q0, v0, a0 = consistent_start(imitator.model, tg.t, q0)
    vi = k.act_idx
    v0[:, vi] = np.clip(v0[:, vi], -lim.velocity, lim.velocity)
    x0 = np.zeros((var.size, tg.T))
    x0[var["q"]], x0[var["v"]], x0[var["a"]] = q0.T, v0.T, a0.T
    start = robot_motion(imitator, tg.t, q0, tg.stance).replace(v=v0, a=a0)
    for s, wv in initial_wrenches(imitator, start, ctx.cs, ctx.contact.f_min, k.nw).items():
        x0[var[f"w_{s}"]] = wv.T / k.mg  # the variables are wrenches over m·g
    return x0


def unmet(c: pb.Compiled, num: Numbers, z: np.ndarray, tol: float) -> tuple[Unmet, ...]:
    """Constraint groups (the parts' row labels) violated by more than ``tol`` (scaled units)
    at ``z``, worst first."""
    g = np.asarray(c.g_fun(z, num.P.T.ravel())).ravel()
    viol = (np.maximum(num.lbg - g, 0) + np.maximum(g - num.ubg, 0)) / num.row_scale
    T, n = num.spec.T, c.ng_knot
    worst: dict[str, tuple[float, int]] = {}
    knot_of = np.r_[np.repeat(np.arange(T), n), np.repeat(np.arange(1, T), c.form.ns),
                    np.full(c.form.nseam, T - 1)]
    for i in np.flatnonzero(viol > tol):
        name = c.labels[i]
        if viol[i] > worst.get(name, (0.0, 0))[0]:
            worst[name] = (float(viol[i]), int(knot_of[i]))
    out = [Unmet(k_, v, kk) for k_, (v, kk) in worst.items()]
    return tuple(sorted(out, key=lambda u: -u.violation))


WARM_START = {"warm_start_init_point": "yes", "mu_init": 1e-6,
              "warm_start_bound_push": 1e-6, "warm_start_bound_frac": 1e-6,
              "warm_start_slack_bound_push": 1e-6, "warm_start_slack_bound_frac": 1e-6,
              "warm_start_mult_bound_push": 1e-6}
"""IPOPT options of a re-solve after screened rows came back (:func:`solve_budgeted`): it
starts from the previous solve's iterate and multipliers (the new rows' at 0) with a small
barrier parameter instead of restarting the barrier from the defaults."""


_HEAP = {-1: 1 << 30, -2: 64 << 20, -3: 1 << 30}
"""glibc ``mallopt`` settings during a solve: M_TRIM_THRESHOLD (−1) 1 GiB, M_TOP_PAD (−2)
64 MiB, M_MMAP_THRESHOLD (−3) 1 GiB; afterwards each goes back to glibc's documented default,
128 KiB, and the heap is trimmed."""


@contextmanager
def kept_heap():
    """Keep freed memory in the process during a solve (glibc only; elsewhere nothing): MUMPS
    allocates its factor arrays afresh at every factorisation, and by default glibc maps those
    large blocks with ``mmap`` and unmaps them on ``free``, so that every factorisation
    page-faults its arrays in again as system time. G1 100 knots, second call (python
    /tmp/h2a_work/prof.py g1 with IPOPT's timing statistics): system time of the solve 1.64 →
    0.06 s, IPOPT's total 12.8 → 12.1 s CPU; Talos's was 3.8 of 28.3 s."""
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt, libc.malloc_trim  # noqa: B018 (glibc's, not another C library's)
    except (OSError, AttributeError):
        yield
        return
    for k, v in _HEAP.items():
        libc.mallopt(ctypes.c_int(k), ctypes.c_int(v))
    try:
        yield
    finally:
        for k in _HEAP:
            libc.mallopt(ctypes.c_int(k), ctypes.c_int(128 << 10))
        libc.malloc_trim(ctypes.c_size_t(0))


def run_solver(c: pb.Compiled, num: Numbers, x0: np.ndarray, elastic: bool, verbose: bool,
               label: str, stop: str = "settled", budget: int = MAX_ITERATIONS,
               lam: tuple[np.ndarray, np.ndarray] | None = None, tol: float = 1e-6,
               ipopt: dict | None = None) -> tuple[np.ndarray, dict]:
    """One IPOPT solve from ``x0`` ``(n_x, T)`` of at most ``budget`` iterations; returns
    ``(z, stats)``; ``stats["lam"]`` = ``(λ_x (n_x·T,), λ_g (ng,))``, the final multipliers,
    λ_g over every row (0 on the rows the solve left out). ``lam``: multipliers of the same
    shapes to start from (a solver compiled with :data:`WARM_START`). ``stop``: one of
    :data:`STOPS`. The hard solve (``elastic`` False: only the :data:`GOAL` rows' slacks
    free) also ends when its constraint violation stalls (:class:`~.stopping.Plateau`),
    returning the least-violating iterate with status :data:`STALLED`; the least-infeasible
    solve (``elastic``: every relaxable row's slacks free where its bound applies) never
    stalls. The free slacks start at the violations of ``x0``'s rows (:func:`_slack_start`).
    An iterate counts as feasible for the stop when every row is within ``tol`` (scaled
    units) and IPOPT's barrier parameter is at most :data:`~.stopping.MU_TOL` against the
    cost (``ipopt``: the caller's IPOPT options, whose ``obj_scaling_factor`` sets IPOPT's
    scale of the cost)."""
    lbx, ubx = num.lbx.copy(), num.ubx.copy()
    free = _free_slacks(c, num, goal_only=not elastic)
    for name, fr in zip(("s_plus", "s_minus"), free):
        ubx[c.knot.var[name]] = fr
    x0 = _slack_start(c, num, x0, free)
    P = num.P.copy()
    if not elastic:  # the goal's L1 price in the hard solve (Weights.elastic in the fallback)
        P[c.knot.par["elastic"]] = GOAL_WEIGHT
    c.progress.reset()
    lbg, ubg = num.lbg[num.keep], num.ubg[num.keep]
    scale = float({**IPOPT_DEFAULTS, **(ipopt or {})}["obj_scaling_factor"])
    stopper = Plateau(lbg, ubg, num.row_scale[num.keep], settle=stop == "settled",
                      budget=max(int(budget), 1), viol_tol=tol, mu_tol=MU_TOL * scale)
    if elastic:
        stopper.stall_after = 10**9
    args = {"x0": x0.T.ravel(), "p": P.T.ravel(), "lbx": lbx.T.ravel(),
            "ubx": ubx.T.ravel(), "lbg": lbg, "ubg": ubg}
    if lam is not None:
        args.update(lam_x0=lam[0], lam_g0=lam[1][num.keep])
    with guard(verbose, lbg, ubg, label, stopper, c.solver), single_thread(), kept_heap():
        try:
            sol = c.solver(**args)
        except RuntimeError as e:
            raise SolverError(f"IPOPT could not run the optimal adaptor's NLP: {e}") from None
    st = dict(c.solver.stats())
    z = np.asarray(sol["x"]).ravel()
    lam_g = np.zeros(num.lbg.size)
    lam_g[num.keep] = np.asarray(sol["lam_g"]).ravel()
    st["lam"] = (np.asarray(sol["lam_x"]).ravel(), lam_g)
    if st.get("return_status") == "User_Requested_Stop" and stopper.reason:
        if stopper.reason == "settled":
            assert stopper.best_x is not None  # it settles on a feasible iterate
            z = stopper.best_x
            st.update(success=True, return_status=PLATEAU)
        elif stopper.reason == "stalled":
            assert stopper.least_x is not None  # it stalls after iterates were recorded
            z = stopper.least_x
            st.update(success=False, return_status=STALLED)
        else:
            if stopper.best_x is not None:
                z = stopper.best_x
            st.update(success=stopper.best_x is not None, return_status=BUDGET)
    return z, st


def trajectory_mode(demo: Motion, demonstrator: Robot, imitator: Robot, force: str, o: dict,
                    cs: dict[str, SoleContact], bmap, options: dict):
    """:func:`gdimitate.retarget.adapt_optimal`'s trajectory mode: ``o`` its options checked
    (:func:`gdimitate.retarget.optimal.check_options`), ``cs`` the soles, ``bmap`` the body map,
    ``options`` as given (``rate``, ``ipopt``). One problem over all knots; returns the
    :class:`~gdimitate.AdaptedMotion` (turned back out of the heading frame, its gait
    measured)."""
    rate, forces, periodic = options.get("rate", DEFAULT_RATE), o["forces"], o["periodic"]
    if periodic:
        from .periodic import periodic_rate, periodic_stride

        demo, forces = periodic_stride(demo, forces)
    own = demo
    psi, demo, forces = heading_frame(demonstrator, imitator, demo, forces, o["gait_scaling"])
    if periodic:  # on the clock the problem runs on (Froude: × √r), a knot on the stride's end
        rate = periodic_rate(demo, DEFAULT_RATE if rate is None else rate)
    demo_k = resample(demonstrator, demo, DEFAULT_RATE if rate is None else rate)
    act_names = limits.resolve(imitator, actuated_v_indices(imitator), o["limits"]).names
    tg = demonstration_targets(demonstrator, demo_k, imitator, bmap, act_names, force, forces,
                               o["contact"].rule)
    t0, compiles = time.perf_counter(), codegen.COMPILE_COUNT
    form = problem_for(imitator, force, o["contact"], bmap, act_names, periodic=periodic)

    def solve(weights: Weights):
        out = _solve_turned(form, tg, demonstrator, imitator, force, o, cs, weights, options,
                            (t0, compiles))
        motion = turn_motion(out.motion, psi) if imitator.base == "free" else out.motion
        gait = compare_gait(demonstrator, own, imitator, motion, o["gait_scaling"])
        return dataclasses.replace(out, motion=motion, gait=gait)

    out = solve(o["weights"])
    if o["stride_retry"] and imitator.base == "free" and stride.short(out):  # once
        if o["verbose"]:
            print(f"  {imitator.name}: travel {out.gait.travel_ratio:.2f} of the scaled "
                  "demonstrator's: solving again with the gait's weights raised …",
                  file=sys.stderr, flush=True)
        out = stride.kept(out, solve(stride.stride_weights(o["weights"])))
    return out


def _solve_turned(form: pb.Formulation, tg: Targets, demonstrator: Robot, imitator: Robot,
                  force: str, o: dict, cs: dict[str, SoleContact], weights: Weights,
                  options: dict, since: tuple[float, int]):
    """One solve of the problem ``form`` on the targets ``tg`` (in the heading frame) at
    ``weights``: the packaged, audited :class:`~gdimitate.AdaptedMotion`, not yet turned
    back. ``since``: the clock and :data:`.codegen.COMPILE_COUNT` before ``form`` was made
    (``build_s`` and ``compiled`` count from there)."""
    t0, compiles = since
    num = setup(form, tg, imitator, demonstrator, weights, o["limits"], o["contact"], cs)
    c, cached = pb.compiled(form, tg.T, num.keep, options.get("ipopt"))
    build_s = 0.0 if cached else time.perf_counter() - t0
    t1 = time.perf_counter()
    c, z, st, bad, iters, elastic = solve_budgeted(
        c, num, o["tol"], o["verbose"], f"{imitator.name} ({tg.T} knots)", o["stop"],
        options.get("ipopt"))
    info = SolverInfo(status=str(st.get("return_status")),
                      success=bool(st.get("success")) and not bad and not elastic,
                      iterations=iters, time_s=time.perf_counter() - t1, build_s=build_s,
                      cached=cached, elastic=elastic, knots=tg.T,
                      variables=int(np.sum(num.lbx != num.ubx)),
                      constraints=int(num.keep.size), unmet=bad,
                      compiled=codegen.COMPILE_COUNT > compiles,
                      derivatives="C" if c.form.compiled else "virtual machine")
    return package(c, num, z, tg, demonstrator, imitator, cs, force, o["contact"], info,
                   o["periodic"])


def heading_frame(demonstrator: Robot, imitator: Robot, demo: Motion,
                  forces: ContactForces | None, scaling: str
                  ) -> tuple[float, Motion, ContactForces | None]:
    """``(ψ, demo, forces)``: the demonstration (and its measured forces, or None) turned by
    −ψ, its heading yaw (:func:`~gdimitate.model.heading.walk_heading`), about the vertical through
    its first base position — the frame the problem is written in (docs/design.md §13) —
    and on the clock of the gait ``scaling`` (Froude: durations × √r)."""
    psi, about = walk_heading(demonstrator, demo), demo.q[0, :2]
    demo = turn_motion(demo, -psi, about)
    forces = None if forces is None else turn_forces(forces, -psi, about)
    ts = time_scale(scaling, leg_ratio(demonstrator, imitator))
    return psi, on_clock(demo, ts), None if forces is None else forces_on_clock(forces, ts)


def solve_budgeted(c: pb.Compiled, num: Numbers, tol: float, verbose: bool, label: str,
                   stop: str, ipopt: dict | None = None
                   ) -> tuple[pb.Compiled, np.ndarray, dict, tuple[Unmet, ...], int, bool]:
    """The hard solve, then — when it fails — the least-infeasible one, in
    :data:`MAX_ITERATIONS` together. A hard solve whose result violates rows the solve left
    out (``num.screened``) is solved again from its result with those rows back
    (:func:`rescreen`; ``num`` is updated) — unless it stalled (:data:`STALLED`): then the
    rows join the least-infeasible solve, which gets the iterations. Returns ``(compiled, z,
    IPOPT's stats, unmet, iterations, elastic)``; a least-infeasible solve that the budget
    cut short with a larger worst violation than the hard solve's result gives way to that
    result (``elastic`` False; the CMU walk → G1 with a 0.1-rad cone: hard solves at 2e-8
    when the budget ran out, 30 elastic iterations left 0.045 of base residual)."""
    T, iters, hard = num.spec.T, 0, MAX_ITERATIONS - MIN_ELASTIC
    x, lam = num.x0, None
    while True:
        z, st = run_solver(c, num, x, False, verbose, label, stop, budget=hard - iters,
                           lam=lam, tol=tol, ipopt=ipopt)
        iters += int(st.get("iter_count", 0))
        back = rescreen(c, num, z, tol)
        if back.size:  # rows the result violates join the problem, warm-started
            num.keep = np.union1d(num.keep, back)
            num.screened = np.setdiff1d(num.screened, back)
            c, _ = pb.compiled(c.form, T, num.keep, {**(ipopt or {}), **WARM_START})
            lam = st["lam"]
        if not back.size or iters >= hard or st.get("return_status") == STALLED:
            break  # a stalled hard solve gains nothing from more rows: relax them instead
        x = z.reshape(T, -1).T
    z = _zero_slacks(c, z, T)  # the goal rows' slacks out: their real values are reported
    bad = unmet(c, num, z, tol)
    if not (back.size or not st.get("success") or _beyond_goal(c, bad)):
        return c, z, st, bad, iters, False
    # the least-infeasible solve, in the same budget (IPOPT's own start: no warm start)
    c, _ = pb.compiled(c.form, T, num.keep, ipopt)
    z2, st2 = run_solver(c, num, z.reshape(T, -1).T, True, verbose, "least-infeasible", stop,
                         budget=max(MAX_ITERATIONS - iters, MIN_ELASTIC), tol=tol, ipopt=ipopt)
    iters += int(st2.get("iter_count", 0))
    z2 = _zero_slacks(c, z2, T)
    bad2 = unmet(c, num, z2, tol)
    if not st2.get("success") and _worst(c, bad2) > _worst(c, bad):
        return c, z, st, bad, iters, False  # the budget cut it short of the hard result
    return c, z2, st2, bad2, iters, True


def _worst(c: pb.Compiled, bad: tuple[Unmet, ...]) -> float:
    """The largest violation (scaled units) in :func:`unmet`'s list of rows other than the
    :data:`GOAL` parts' (the physics; the goal is priced, not imposed); 0 when none."""
    goal = _goal_labels(c)
    return max((u.violation for u in bad if u.name not in goal), default=0.0)


def _goal_labels(c: pb.Compiled) -> set[str]:
    return {lab for part, sl in zip(c.form.cons, c.form.slices) if isinstance(part, GOAL)
            for lab in c.form.labels[sl]}


def problem_for(imitator: Robot, force: str, copts: Contact, bmap, act_names, parts=None,
                periodic: bool = False) -> pb.Formulation:
    """The :class:`~.problem.Formulation` of an imitator under a force model, contact options
    and body map (``parts``: a list of parts instead of :func:`~.parts.default_parts`, the
    robot's :func:`~.parts.body.body_parts` and, for a free-flying imitator, the gait's
    :class:`~.parts.Steps` and, unless ``periodic``, :class:`~.parts.OverFeet`;
    ``periodic``: with the :class:`~.parts.periodic.PeriodicSeam`)."""
    flags = Flags(goal="force" if force in ("measured", "dynamics") else force,
                  cone=copts.cone_half_angle > 0, segments=len(bmap.segments))
    q_index = tuple(int(imitator.idx_q(j)) for j in act_names)
    if parts is None:
        parts = (default_parts(tuple(bmap.segments.values()), q_index)
                 + body_parts(imitator, act_names))
        if imitator.base == "free":  # the gait in 3-D; the planar corner is the paper's
            # a closed cycle starts and ends in double support and its seam shifts the base
            # by one stride, so its steps fix how far it travels; the body-over-feet pull
            # (weights 10, 30, 100) left G1's 45-knots/s cycle audit-infeasible after 149
            # iterations (cop, force direction), where without it the cycle is feasible in
            # 76 (docs/design.md §14); nor did it lengthen Talos's (weight 3: 0.69 of the
            # scaled stride, 10: 0.66; without it 0.70; docs/guide/limits.md)
            parts = parts + ((Steps(),) if periodic else (Steps(), OverFeet()))
    if periodic:
        from ..parts.periodic import PeriodicSeam

        parts = tuple(parts) + (PeriodicSeam(),)
    return pb.formulation(imitator, flags, tuple(parts))


GOAL = (ForceDirection,)
"""Parts whose rows carry their free elastic slack pair in every solve, the hard one too (an
exact L1 penalty, :attr:`~.params.Weights.elastic` per unit of violation: where the rows can
be met and the weight exceeds their multipliers the optimum is the hard one's): the goal, the
one set of rows a demonstration may ask the imitator for beyond its reach (the CMU walk's
toe-off shank lean on G1; HOAP-2's sagittal walk). Without it the hard solve of such a
demonstration crawled with IPOPT's Hessian regularisation at 1e9–1e17 until its stall test
fired (CMU → G1: iterations 50–80 cost 430 s CPU) and the least-infeasible solve followed."""


GOAL_WEIGHT = 30.0
"""L1 price of the :data:`GOAL` rows' violation in the hard solve (per unit of a row — rad of
force direction — and knot, in the knot's cost; the least-infeasible solve keeps
:attr:`~.params.Weights.elastic`, 1e3). High enough that a goal the imitator can meet is met
(its multipliers stay below it: G1, Talos, Case I unchanged), low enough that IPOPT converges
where it cannot: on the CMU walk → G1, 1e3 left the hard solve wandering (82 iterations,
violation 0.01–0.4, stalled), 30 converged in 56 iterations (violation 1e-10)."""


def _free_slacks(c: pb.Compiled, num: Numbers, goal_only: bool
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Upper bounds ``(n_slack, T)`` of ``s⁺``, ``s⁻``: ∞ where the slack relaxes a bound of a
    row the solve keeps (``num.keep``) — of a :data:`GOAL` part only, with ``goal_only`` —
    else 0 (the slack leaves the problem)."""
    out = np.ones(num.lbg.size, bool)
    out[num.keep] = False
    sp, sm = c.form.slack_bounds(np.where(out, -np.inf, num.lbg),
                                 np.where(out, np.inf, num.ubg), c.T)
    if goal_only:
        goal = np.zeros(c.form.ngk, bool)
        for part, sl in zip(c.form.cons, c.form.slices):
            goal[sl] = isinstance(part, GOAL)
        on = goal[c.form.relax_rows][:, None]
        sp, sm = np.where(on, sp, 0.0), np.where(on, sm, 0.0)
    return sp, sm


def _slack_start(c: pb.Compiled, num: Numbers, X: np.ndarray,
                 free: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """``X`` ``(n_x, T)`` with each free slack (``free``: :func:`_free_slacks`) at the
    violation of its row's bound at ``X`` (its row met exactly, the start's violation
    priced by the L1 term, instead of slacks at 0 and the rows' violation in IPOPT's
    infeasibility); fixed slacks at 0."""
    var, T, n = c.knot.var, c.T, c.form.ngk
    X = np.array(X, dtype=float)
    X[var["s_plus"]] = X[var["s_minus"]] = 0.0
    if not (np.any(free[0] > 0) or np.any(free[1] > 0)):
        return X
    g = np.asarray(c.g_fun(X.T.ravel(), num.P.T.ravel())).ravel()[:n * T].reshape(T, n).T
    lo = num.lbg[:n * T].reshape(T, n).T
    hi = num.ubg[:n * T].reshape(T, n).T
    rr = c.form.relax_rows
    with np.errstate(invalid="ignore"):
        below = np.nan_to_num(np.maximum(lo[rr] - g[rr], 0.0))
        above = np.nan_to_num(np.maximum(g[rr] - hi[rr], 0.0))
    X[var["s_plus"]] = np.where(free[0] > 0, below, 0.0)
    X[var["s_minus"]] = np.where(free[1] > 0, above, 0.0)
    return X


def _beyond_goal(c: pb.Compiled, bad: tuple[Unmet, ...]) -> bool:
    """Whether rows other than the :data:`GOAL` parts' are unmet (then the least-infeasible
    solve runs; a goal missed alone is the hard solve's answer, its L1 term's least miss)."""
    goal = _goal_labels(c)
    return any(u.name not in goal for u in bad)


def _zero_slacks(c: pb.Compiled, z: np.ndarray, T: int) -> np.ndarray:
    """``z`` with the elastic slacks set to 0: the motion's real row values then show the
    violations."""
    Z = z.reshape(T, -1).T.copy()
    for name in ("s_plus", "s_minus"):
        Z[c.knot.var[name]] = 0.0
    return Z.T.ravel()


def wrenches_of(c: pb.Compiled, Z: np.ndarray) -> dict[str, np.ndarray]:
    """``{side: (T, 6)}`` sole-frame wrenches of a solution ``Z`` ``(n_x, T)`` (planar models:
    f_y = τ_x = τ_z = 0)."""
    out = {}
    for s in SIDES:
        w = Z[c.knot.var[f"w_{s}"]].T * c.knot.mg
        if c.knot.planar:
            full = np.zeros((len(w), 6))
            full[:, [0, 2, 4]] = w
            w = full
        out[s] = np.ascontiguousarray(w)
    return out


def package(c: pb.Compiled, num: Numbers, z: np.ndarray, tg: Targets, demonstrator: Robot,
            imitator: Robot, cs: dict[str, SoleContact], force: str, copts: Contact,
            info: SolverInfo, periodic: bool = False):
    """The :class:`~gdimitate.AdaptedMotion` of a solution vector ``z`` (``periodic``:
    the seam made exact, :func:`.periodic.close_seam`, and audited)."""
    from ...assess.result import AdaptedMotion, compare

    T = tg.T
    Z = z.reshape(T, -1).T
    var = c.knot.var
    args = (tg.t, Z[var["q"]].T, Z[var["v"]].T, Z[var["a"]].T, wrenches_of(c, Z), tg.stance,
            {s: cs[s].frame for s in SIDES}, c.knot.base_idx)
    target = tg.push if force in ("measured", "dynamics") else None
    ha = float(copts.cone_half_angle)
    if periodic:
        from .periodic import close_seam

        q, v, a, W = close_seam(imitator, demonstrator, tg.demo.q, *args, contacts=dict(cs),
                                targets=target, half_angle=ha)
    else:
        q, v, a, W = make_consistent(imitator, *args, contacts=dict(cs), targets=target,
                                     half_angle=ha)
    base = robot_motion(imitator, tg.t, q, tg.stance)
    motion = base.replace(v=v, a=a)
    push_r = None
    if force in ("measured", "dynamics"):
        from ...assess.metrics import frame_rotations

        push_r = {s: np.where(tg.stance[s][:, None], -np.einsum(
            "tij,tj->ti", frame_rotations(imitator, q, cs[s].frame), W[s][:, :3]), np.nan)
            for s in SIDES}
    report = compare(demonstrator, tg.demo.replace(contact=tg.stance), imitator, motion,
                     "optimal", {s: np.ones(T, bool) for s in SIDES}, force,
                     push_m=tg.push, push_r=push_r)
    from ...assess.audit import audit

    aud = audit(limited_robot(imitator, num.lim), motion, W, cs, target=target,
                cone_half_angle=copts.cone_half_angle)
    if periodic:
        from ...assess.audit.periodic import seam_audit

        aud = seam_audit(aud, imitator, motion, W, demonstrator, tg.demo.q)
    return AdaptedMotion(motion=motion, report=report, robot=imitator, wrenches=W,
                         contacts=dict(cs), audit=aud, solver=audited(info, aud),
                         force_model=force)


def audited(info: SolverInfo, aud) -> SolverInfo:
    """The solver's record with what its rows only approximate folded in: the self-collision
    rows bound sphere covers of the links while the audit measures their collision hulls, so
    the rows can be met while the audit's check fails. Then the solve is no success and each
    such failed check (:data:`APPROXIMATED`) is named in ``unmet`` as ``"audit: <check>"``
    (violation in the check's dimensionless scale). Other failed checks are left to the audit
    (e.g. a stance foot that Eq. (1)'s ``"anchor"`` contact rule does not hold)."""
    if aud is None or aud.feasible:
        return info
    extra = tuple(Unmet(f"audit: {c.name}", float(c.violation), int(c.knot))
                  for c in aud.checks if not c.passed and c.name.startswith(APPROXIMATED))
    if not extra:
        return info
    return dataclasses.replace(info, success=False, unmet=info.unmet + extra)
