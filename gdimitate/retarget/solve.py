"""``adapt_optimal``: the whole-body trajectory mode — targets, warm start, the cached NLP,
IPOPT, the least-infeasible fallback and the honest (recomputed) report."""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from ..contact import ContactForces, SoleContact
from ..errors import InvalidInputError, SolverError, UnknownNameError
from ..kinematics import robot_motion
from ..metrics import FORCE_MODELS
from ..motion import Motion
from ..robot import SIDES, Robot
from . import limits
from . import problem as pb
from .bodymap import body_map
from .initial import consistent_start, initial_q, initial_wrenches
from .interrupt import guard
from .knot import Flags, base_dofs
from .params import DEFAULT_RATE, Contact, Limits, Weights
from .parts import default_parts, liftoff_knots
from .parts.body import body_parts
from .polish import make_consistent
from .stopping import PLATEAU, Plateau
from .targets import Targets, demonstration_targets, direction_frame, resample
from .threads import single_thread

__all__ = ["adapt_optimal", "SolverInfo", "Unmet", "OPTIONS", "MODES", "STOPS", "Numbers",
           "Context", "setup", "problem_for", "run_solver", "unmet", "package", "wrenches_of",
           "limited_robot", "resolve_contacts"]

MODES = ("trajectory", "per_frame")
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

OPTIONS = ("force", "forces", "rate", "mode", "weights", "limits", "contact", "body_map",
           "tol", "ipopt", "verbose", "contacts", "stop", "periodic")
"""Keywords :func:`adapt_optimal` accepts (``adapt(..., method="optimal", **options)``)."""


@dataclass(frozen=True)
class Unmet:
    """A constraint group the returned motion does not meet (optimiser's view; the audit is
    the judge): ``name``, worst ``violation`` (in the row's own scaled units: torque/limit,
    force/(m·g), height/leg length, rad, m) and its ``knot``."""

    name: str
    violation: float
    knot: int


@dataclass(frozen=True)
class SolverInfo:
    """How the optimiser ran: IPOPT's ``status``, ``success``, ``iterations``, ``time_s``
    (solves only), ``build_s`` (0 when the NLP came from the cache), ``cached``, ``elastic``
    (True when the hard problem failed and the least-infeasible solve ran), ``knots``,
    ``variables`` (free ones), ``constraints`` (rows the schedule imposes) and ``unmet``."""

    status: str
    success: bool
    iterations: int
    time_s: float
    build_s: float
    cached: bool
    elastic: bool
    knots: int
    variables: int
    constraints: int
    unmet: tuple[Unmet, ...] = ()


@dataclass(frozen=True)
class Context:
    """What a part's :meth:`~.parts.Part.values` may read: the demonstration's
    :class:`~.targets.Targets` ``tg``, the robots, the :class:`~.params.Weights`, the resolved
    limits ``lim``, the :class:`~.params.Contact` options and the soles ``cs``."""

    tg: Targets
    imitator: Robot
    demonstrator: Robot
    weights: Weights
    lim: limits.Resolved
    contact: Contact
    cs: dict


@dataclass
class Numbers:
    """One demonstration's parameter matrix ``P`` ``(n_p, T)``, variable bounds and start
    ``(n_x, T)``, bounds of every row, the per-row divisor that puts every row in scaled units
    (:func:`~.problem.row_scale`), the resolved limits, the :class:`~.problem.Spec` and
    ``keep``: the rows some bound applies to (the only ones the solver sees)."""

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


def resolve_contacts(imitator: Robot, opts: Contact, given) -> dict[str, SoleContact]:
    cs = dict(imitator.require_contacts())
    if given:
        for s, c in dict(given).items():
            if s not in SIDES:
                raise InvalidInputError(f"contacts= keys must be 'left'/'right'; got {s!r}")
            if not isinstance(c, SoleContact):
                c = cs[s].replace(**dict(c))
            if c.frame != cs[s].frame:
                raise InvalidInputError(f"contacts[{s!r}] must keep the frame {cs[s].frame!r} "
                                        "(pass a different frame through Robot(contacts=))")
            cs[s] = c
    if opts.mu is not None:
        cs = {s: c.replace(mu=opts.mu) for s, c in cs.items()}
    for s, c in cs.items():
        if opts.cop_margin >= min(c.half_length, c.half_width):
            raise InvalidInputError(f"cop_margin {opts.cop_margin} m leaves nothing of the "
                                    f"{s} sole ({c.half_length:.3f} × {c.half_width:.3f} m)")
    return cs


def setup(form: pb.Formulation, tg: Targets, imitator: Robot, demonstrator: Robot,
          w: Weights, lim_opts: Limits, copts: Contact, cs: dict[str, SoleContact],
          x_start: np.ndarray | None = None) -> Numbers:
    """Parameters, bounds and warm start of a demonstration for a formulation
    (``x_start`` ``(n_x, T)``: a given start, e.g. the previous frame's in streaming)."""
    k = form.knot
    T = tg.T
    lay, var = k.par, k.var
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
        X, Y, mu = cs[s].half_length, cs[s].half_width, cs[s].mu
        m = copts.cop_margin
        P[lay[f"sole_{s}"]] = np.array([X, Y, mu, X - m, Y - m])[:, None]
    if k.flags.segments:
        P[lay["torso"]] = np.concatenate([tg.segments[:, i].transpose(0, 2, 1).reshape(T, 9)
                                          for i in range(k.flags.segments)], axis=1).T
    lim = limits.resolve(imitator, k.act_idx, lim_opts)
    P[lay["joint_target"]] = tg.joints.T
    jw = np.where(tg.mapped, w.joints, w.posture) * ~lim.frozen
    P[lay["joint_weight"]] = np.sqrt(jw)[:, None]  # residuals carry √weight
    with np.errstate(divide="ignore"):
        P[lay["inv_effort"]] = np.where(np.isfinite(lim.effort), 1.0 / lim.effort, 0.0)[:, None]
    P[lay["weights"]] = np.sqrt([getattr(w, n) for n in k.weight_names])[:, None]
    P[lay["elastic"]] = w.elastic
    P[lay["tan2"]] = math.tan(copts.cone_half_angle) ** 2
    P[lay["f_min"]] = copts.f_min
    ctx = Context(tg, imitator, demonstrator, w, lim, copts, cs)
    for part in form.parts:
        for name, val in part.values(ctx).items():
            P[lay[name]] = np.asarray(val, float).reshape(T, -1).T
    # ---- variable bounds
    lbx = np.full((var.size, T), -np.inf)
    ubx = np.full((var.size, T), np.inf)
    qs, vs, as_ = var["q"].start, var["v"].start, var["a"].start
    qi, vi = lim.q_index, k.act_idx
    lbx[qs + qi], ubx[qs + qi] = lim.lower[:, None], lim.upper[:, None]
    lbx[vs + vi], ubx[vs + vi] = -lim.velocity[:, None], lim.velocity[:, None]
    fz = lim.frozen
    lbx[qs + qi[fz]] = ubx[qs + qi[fz]] = lim.freeze_at[fz, None]
    for blk in (vs, as_):
        lbx[blk + vi[fz]] = ubx[blk + vi[fz]] = 0.0
    for s in SIDES:
        sl = var[f"w_{s}"]
        lbx[sl, ~tg.stance[s]] = ubx[sl, ~tg.stance[s]] = 0.0
    for name in ("s_plus", "s_minus"):
        lbx[var[name]] = ubx[var[name]] = 0.0
    if x_start is None:
        x0 = _warm_start(form, tg, imitator, demonstrator, lim, copts, cs)
    else:
        x0 = np.array(x_start, dtype=float)
    q0 = x0[var["q"]].T
    # the start's horizontal base position is the motion's origin
    base_xy = [0, 1] if imitator.base == "free" else [imitator.idx_q("base_x")]
    lbx[qs + np.array(base_xy), 0] = ubx[qs + np.array(base_xy), 0] = q0[0, base_xy]
    lift = {s: (liftoff_knots(tg.stance[s], tg.swing[s]) if copts.rule == "all"
                else np.zeros(T, bool)) for s in SIDES}
    spec = pb.Spec(T=T, stance=tg.stance, swing=tg.swing, liftoff=lift,
                   goal_active={s: tg.stance[s] & np.all(np.isfinite(tg.push[s]), axis=1)
                                for s in SIDES},
                   planar=k.planar, free=imitator.base == "free", cone=k.flags.cone,
                   clearance=copts.clearance, leg_length=imitator.legs["left"].length,
                   n_base=len(k.base_idx), n_act=len(k.act_idx))
    lbg, ubg = pb.row_bounds(form, spec)
    keep = np.flatnonzero(np.isfinite(lbg) | np.isfinite(ubg))
    return Numbers(P, lbx, ubx, x0, lbg, ubg, spec, lim, pb.row_scale(form, T), keep)


def _warm_start(form: pb.Formulation, tg: Targets, imitator: Robot, demonstrator: Robot,
                lim: limits.Resolved, copts: Contact, cs: dict[str, SoleContact]) -> np.ndarray:
    """``(n_x, T)``: :mod:`.initial`'s configurations inside the limits, integration-consistent
    velocities and accelerations, wrenches from a per-knot QP."""
    k, var = form.knot, form.knot.var
    qi, vi, fz = lim.q_index, k.act_idx, lim.frozen
    q0 = initial_q(demonstrator, imitator, tg, qi).copy()
    q0[:, qi[fz]] = lim.freeze_at[fz]
    lo = np.where(np.isfinite(lim.lower), lim.lower, -1e9)
    hi = np.where(np.isfinite(lim.upper), lim.upper, 1e9)
    q0[:, qi] = np.clip(q0[:, qi], lo, hi)
    q0, v0, a0 = consistent_start(imitator.model, tg.t, q0)
    v0[:, vi] = np.clip(v0[:, vi], -lim.velocity, lim.velocity)
    x0 = np.zeros((var.size, tg.T))
    x0[var["q"]], x0[var["v"]], x0[var["a"]] = q0.T, v0.T, a0.T
    start = robot_motion(imitator, tg.t, q0, tg.stance).replace(v=v0, a=a0)
    for s, wv in initial_wrenches(imitator, start, cs, copts.f_min, k.nw).items():
        x0[var[f"w_{s}"]] = wv.T / k.mg  # the variables are wrenches over m·g
    return x0


def limited_robot(robot: Robot, lim: limits.Resolved) -> Robot:
    """A copy of ``robot`` whose model carries the limits the motion was adapted to (the
    URDF's with :class:`~.params.Limits` overrides), for the audit."""
    import copy

    import pinocchio as pin

    out = copy.copy(robot)
    m = pin.Model(robot.model)
    vi = np.asarray([robot.idx_v(n) for n in lim.names], int)
    el, vl = np.array(m.effortLimit), np.array(m.velocityLimit)
    lo, hi = np.array(m.lowerPositionLimit), np.array(m.upperPositionLimit)
    el[vi], vl[vi] = lim.effort, lim.velocity
    big = np.finfo(float).max
    lo[lim.q_index] = np.where(np.isfinite(lim.lower), lim.lower, -big)
    hi[lim.q_index] = np.where(np.isfinite(lim.upper), lim.upper, big)
    m.effortLimit, m.velocityLimit = el, vl
    m.lowerPositionLimit, m.upperPositionLimit = lo, hi
    out.model, out.data = m, m.createData()
    return out


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


def run_solver(c: pb.Compiled, num: Numbers, x0: np.ndarray, elastic: bool, verbose: bool,
               label: str, stop: str = "settled", budget: int = MAX_ITERATIONS
               ) -> tuple[np.ndarray, dict]:
    """One IPOPT solve from ``x0`` ``(n_x, T)`` of at most ``budget`` iterations; returns
    ``(z, stats)``. ``stop``: one of :data:`STOPS`. The hard solve (``elastic`` False) also
    ends when its constraint violation stalls (:class:`~.stopping.Plateau`), returning the
    least-violating iterate with status :data:`STALLED`; the least-infeasible solve
    (``elastic``: the relaxable rows' slacks free where their bound applies) never stalls."""
    lbx, ubx = num.lbx.copy(), num.ubx.copy()
    if elastic:
        sp, sm = c.form.slack_bounds(num.lbg, num.ubg, c.T)
        ubx[c.knot.var["s_plus"]], ubx[c.knot.var["s_minus"]] = sp, sm
    c.progress.reset()
    lbg, ubg = num.lbg[num.keep], num.ubg[num.keep]
    stopper = Plateau(lbg, ubg, num.row_scale[num.keep], settle=stop == "settled",
                      budget=max(int(budget), 1))
    if elastic:
        stopper.stall_after = 10**9
    with guard(verbose, lbg, ubg, label, stopper), single_thread():
        try:
            sol = c.solver(x0=x0.T.ravel(), p=num.P.T.ravel(), lbx=lbx.T.ravel(),
                           ubx=ubx.T.ravel(), lbg=lbg, ubg=ubg)
        except RuntimeError as e:
            raise SolverError(f"IPOPT could not run the optimal adaptor's NLP: {e}") from None
    st = dict(c.solver.stats())
    z = np.asarray(sol["x"]).ravel()
    if st.get("return_status") == "User_Requested_Stop" and stopper.reason:
        if stopper.reason == "settled":
            z = stopper.best_x
            st.update(success=True, return_status=PLATEAU)
        elif stopper.reason == "stalled":
            z = stopper.least_x
            st.update(success=False, return_status=STALLED)
        else:
            if stopper.best_x is not None:
                z = stopper.best_x
            st.update(success=stopper.best_x is not None, return_status=BUDGET)
    return z, st


def _check_options(opts: dict) -> None:
    bad = [k for k in opts if k not in OPTIONS]
    if bad:
        raise UnknownNameError("optimal-adaptor option", bad[0], OPTIONS)


def adapt_optimal(demo: Motion, demonstrator: Robot, imitator: Robot, force: str = "segment",
                  **options):
    """The whole-body optimal adaptor (``adapt(..., method="optimal", ...)`` calls it).

    Options (:data:`OPTIONS`):

    - ``forces``: the demonstrator's measured :class:`~gdimitate.contact.ContactForces`
      (needed by ``force="measured"``; they also give the contact schedule);
    - ``rate`` [knots/s]: the knot grid (default :data:`~.params.DEFAULT_RATE`, 50 Hz);
    - ``mode``: ``"trajectory"`` (one problem over all knots) or ``"per_frame"`` (the
      streaming adaptor, :class:`~.streaming.StreamingAdaptor`, over the frames);
    - ``weights`` (:class:`~.params.Weights`), ``limits`` (:class:`~.params.Limits`),
      ``contact`` (:class:`~.params.Contact`: μ, f_min, margins, clearance, cone half-angle,
      contact rule), ``contacts`` (``{side: SoleContact | {half_length, half_width, mu}}``
      overriding the measured sole rectangles), ``body_map`` (a
      :class:`~.bodymap.BodyMap`, dict or JSON path; default: the preset);
    - ``tol``: feasibility tolerance of the optimiser's own row check (scaled units, default
      1e-6); ``stop``: when a solve ends (:data:`STOPS`); ``ipopt``: extra IPOPT options;
      ``verbose`` (default True): progress lines
      (iteration, cost, constraint violation) on stderr;
    - ``periodic`` (default False): a periodic gait cycle (:mod:`.periodic`) — one stride,
      heel strike to heel strike of the right foot, whose last knot is its first shifted by
      one stride (:class:`~.parts.periodic.PeriodicSeam`), the audit with its seam checks.

    Returns an :class:`~gdimitate.adapt.AdaptedMotion` with ``motion`` (``q``, ``v``, ``a``,
    ``contact`` = the schedule used), ``wrenches`` ``{side: (T, 6)}`` in each sole frame,
    ``contacts``, ``audit`` (:func:`gdimitate.audit.audit` recomputed from the output) and
    ``solver`` (:class:`SolverInfo`). Never raises on an infeasible problem: the
    least-infeasible motion comes back with ``solver.unmet`` and the audit's ``binding``.
    """
    _check_options(options)
    if force not in FORCE_MODELS:
        raise UnknownNameError("force model", force, FORCE_MODELS)
    mode = options.get("mode", "trajectory")
    if mode not in MODES:
        raise UnknownNameError("mode", mode, MODES)
    w = options.get("weights") or Weights()
    lim_opts = options.get("limits") or Limits()
    copts = options.get("contact") or Contact()
    for name, v, typ in (("weights", w, Weights), ("limits", lim_opts, Limits),
                         ("contact", copts, Contact)):
        if not isinstance(v, typ):
            raise InvalidInputError(f"{name}= must be a gdimitate.retarget.{typ.__name__}; "
                                    f"got {type(v).__name__}")
    tol = float(options.get("tol", 1e-6))
    if not (np.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"tol must be a positive number; got {tol!r}")
    forces: ContactForces | None = options.get("forces")
    if force == "measured" and forces is None:
        raise InvalidInputError("force='measured' needs forces= (the demonstrator's measured "
                                "ContactForces)")
    verbose = bool(options.get("verbose", True))
    stop = options.get("stop", "settled")
    if stop not in STOPS:
        raise UnknownNameError("stop rule", stop, STOPS)
    cs = resolve_contacts(imitator, copts, options.get("contacts"))
    bmap = body_map(demonstrator, imitator, options.get("body_map"))
    if mode == "per_frame" and options.get("periodic"):
        raise InvalidInputError("periodic=True needs mode='trajectory' (the seam links the "
                                "cycle's last knot to its first)")
    if mode == "per_frame":
        from .streaming import adapt_per_frame

        return adapt_per_frame(demo, demonstrator, imitator, force=force, forces=forces,
                               weights=w, limits=lim_opts, contact=copts, contacts=cs,
                               body_map=bmap, tol=tol, ipopt=options.get("ipopt"))
    rate = options.get("rate", DEFAULT_RATE)
    periodic = bool(options.get("periodic", False))
    if periodic:
        from .periodic import periodic_rate, periodic_stride

        demo, forces = periodic_stride(demo, forces)
        rate = periodic_rate(demo, DEFAULT_RATE if rate is None else rate)
    demo_k = resample(demonstrator, demo, DEFAULT_RATE if rate is None else rate)
    _, act = base_dofs(imitator)
    act_names = limits.resolve(imitator, act, lim_opts).names
    tg = demonstration_targets(demonstrator, demo_k, imitator, bmap, act_names, force, forces,
                               copts.rule)
    t0 = time.perf_counter()
    form = problem_for(imitator, force, copts, bmap, act_names, periodic=periodic)
    num = setup(form, tg, imitator, demonstrator, w, lim_opts, copts, cs)
    c, cached = pb.compiled(form, tg.T, num.keep, options.get("ipopt"))
    build_s = 0.0 if cached else time.perf_counter() - t0
    t1 = time.perf_counter()
    z, st = run_solver(c, num, num.x0, False, verbose, f"{imitator.name} ({tg.T} knots)",
                       stop, budget=MAX_ITERATIONS - MIN_ELASTIC)
    bad = unmet(c, num, z, tol)
    elastic = False
    iters = int(st.get("iter_count", 0))
    if bad or not st.get("success"):  # the least-infeasible solve, in the same budget
        elastic = True
        x_start = z.reshape(tg.T, -1).T
        z2, st2 = run_solver(c, num, x_start, True, verbose, "least-infeasible", stop,
                             budget=max(MAX_ITERATIONS - iters, MIN_ELASTIC))
        iters += int(st2.get("iter_count", 0))
        bad2 = unmet(c, num, _zero_slacks(c, z2, tg.T), tol)
        z, st, bad = _zero_slacks(c, z2, tg.T), st2, bad2
    info = SolverInfo(status=str(st.get("return_status")),
                      success=bool(st.get("success")) and not bad and not elastic,
                      iterations=iters, time_s=time.perf_counter() - t1, build_s=build_s,
                      cached=cached, elastic=elastic, knots=tg.T,
                      variables=int(np.sum(num.lbx != num.ubx)),
                      constraints=int(num.keep.size),
                      unmet=bad)
    return package(c, num, z, tg, demonstrator, imitator, cs, force, copts, info, periodic)


def problem_for(imitator: Robot, force: str, copts: Contact, bmap, act_names, parts=None,
                periodic: bool = False) -> pb.Formulation:
    """The :class:`~.problem.Formulation` of an imitator under a force model, contact options
    and body map (``parts``: a list of parts instead of :func:`~.parts.default_parts`;
    ``periodic``: with the :class:`~.parts.periodic.PeriodicSeam`)."""
    flags = Flags(goal="force" if force in ("measured", "dynamics") else force,
                  cone=copts.cone_half_angle > 0, segments=len(bmap.segments))
    q_index = tuple(int(imitator.idx_q(j)) for j in act_names)
    if parts is None:
        parts = (default_parts(tuple(bmap.segments.values()), q_index)
                 + body_parts(imitator, act_names))
    if periodic:
        from .parts.periodic import PeriodicSeam

        parts = tuple(parts) + (PeriodicSeam(),)
    return pb.formulation(imitator, flags, tuple(parts))


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
    """The :class:`~gdimitate.adapt.AdaptedMotion` of a solution vector ``z`` (``periodic``:
    the seam made exact, :func:`.periodic.close_seam`, and audited)."""
    from ..result import AdaptedMotion, compare

    T = tg.T
    Z = z.reshape(T, -1).T
    var = c.knot.var
    args = (tg.t, Z[var["q"]].T, Z[var["v"]].T, Z[var["a"]].T, wrenches_of(c, Z), tg.stance,
            {s: cs[s].frame for s in SIDES}, c.knot.base_idx)
    if periodic:
        from .periodic import close_seam

        q, v, a, W = close_seam(imitator, demonstrator, tg.demo.q, *args)
    else:
        q, v, a, W = make_consistent(imitator, *args)
    base = robot_motion(imitator, tg.t, q, tg.stance)
    motion = base.replace(v=v, a=a)
    push_r = None
    if force in ("measured", "dynamics"):
        from ..metrics import frame_rotations

        push_r = {s: np.where(tg.stance[s][:, None], -np.einsum(
            "tij,tj->ti", frame_rotations(imitator, q, cs[s].frame), W[s][:, :3]), np.nan)
            for s in SIDES}
    report = compare(demonstrator, tg.demo.replace(contact=tg.stance), imitator, motion,
                     "optimal", {s: np.ones(T, bool) for s in SIDES}, force,
                     push_m=tg.push, push_r=push_r)
    from ..audit import audit

    target = tg.push if force in ("measured", "dynamics") else None
    aud = audit(limited_robot(imitator, num.lim), motion, W, cs, target=target,
                cone_half_angle=copts.cone_half_angle)
    if periodic:
        from ..audit.periodic import seam_audit

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
