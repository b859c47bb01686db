"""``adapt_optimal``: warm-start from Eq. (1), solve, fall back to the least-infeasible motion,
and report honestly.

The report (:class:`~gdimitate.adapt.AdaptationReport`) of the optimal method fills:

- ``solver``: ``status`` (IPOPT's return status), ``success``, ``iterations``, ``time_s``
  (wall time of the solves), ``elastic`` (True when the hard problem failed and the
  least-infeasible fallback ran), ``knots``, ``variables``, ``constraints``;
- ``feasible``: per leg the per-knot feasibility — every hard constraint met at that knot within
  ``tol`` (m, rad, rad/s, N·m) — the same mask for both legs;
- ``torque_ratio_max``: per driven joint max |τ| / τ_limit (NaN without a limit);
- ``infeasible_constraint``: ``None``, or which constraint group could not be met and by how
  much;
- ``extra["torques"]`` ``(T, n_driven)`` [N·m] and ``extra["wrenches"]`` ``(T, 2·nw)`` (per
  foot, world axes at the sole: fx, fz, my for planar models, the full wrench otherwise) of the
  returned motion, ``extra["driven"]`` the joint order;
- ``extra["analytic"]``: the same limit measures for the Eq. (1) warm start, so that one can see
  what the optimiser fixed; ``extra["violations"]``: max violation per constraint group;
  ``extra["missing_limits"]``: driven joints whose URDF gives no limit of some kind.
"""

from __future__ import annotations

import time
import weakref
from collections import OrderedDict

import numpy as np

from ..adapt import AdaptedMotion, _check_pair, adapt, compare
from ..errors import InvalidInputError, SolverError, UnknownNameError
from ..metrics import FORCE_MODELS
from ..motion import Motion
from ..robot import SIDES, Robot
from ..sagittal import robot_motion
from .limits import Limits, ResolvedLimits, resolve_limits
from .model import SagittalModel, robot_key
from .problem import TrajectoryProblem, Weights
from .targets import CONTACT_MODES, contact_links, demonstration_targets, slice_motion

__all__ = ["adapt_optimal", "sagittal_model", "MODES", "limit_report", "place_base"]

MODES = ("trajectory", "per_frame")
_MODELS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: Models by :func:`.model.robot_key`, shared by equal robots loaded twice (e.g. two
#: ``Robot.from_library("talos")``); least recently used dropped first.
_MODELS_BY_KEY: OrderedDict[str, SagittalModel] = OrderedDict()
MODEL_CACHE_SIZE = 8


def sagittal_model(robot: Robot) -> SagittalModel:
    """The (cached) :class:`SagittalModel` of ``robot``: per robot object, and per
    :func:`~.model.robot_key` so that an equal robot built again reuses it."""
    if robot in _MODELS and _MODELS[robot].key == robot_key(robot):
        return _MODELS[robot]
    key = robot_key(robot)
    model = _MODELS_BY_KEY.get(key)
    if model is None:
        model = SagittalModel(robot)
        _MODELS_BY_KEY[key] = model
        while len(_MODELS_BY_KEY) > MODEL_CACHE_SIZE:
            _MODELS_BY_KEY.popitem(last=False)
    _MODELS_BY_KEY.move_to_end(key)
    _MODELS[robot] = model
    return model


def _knots(motion: Motion, subsample: int, frames) -> Motion:
    if not (isinstance(subsample, (int, np.integer)) and subsample >= 1):
        raise InvalidInputError(f"subsample must be an integer ≥ 1; got {subsample!r}")
    idx = np.arange(motion.T)
    if frames is not None:
        try:
            idx = idx[frames]
        except (IndexError, TypeError) as e:
            raise InvalidInputError(f"frames={frames!r} does not select frames of a "
                                    f"{motion.T}-frame motion ({e})") from None
    idx = np.atleast_1d(idx)[::subsample]
    return slice_motion(motion, idx)


def limit_report(model: SagittalModel, limits: ResolvedLimits, t: np.ndarray, X: np.ndarray,
                 tau: np.ndarray | None) -> dict:
    """Max |q̇|/limit, |τ|/limit and position-limit excess per driven joint of a motion ``X``
    ``(T, nx)`` with torques ``tau`` ``(T, n_driven)``."""
    from .model import difference_matrices

    D1, _ = difference_matrices(t)
    qd = X[:, 3:]
    vel = D1 @ X[:, 3:]
    out: dict = {"torque_ratio_max": {}, "velocity_ratio_max": {}, "position_excess_max": {}}
    for i, j in enumerate(model.driven):
        out["velocity_ratio_max"][j] = float(np.max(np.abs(vel[:, i])) / limits.velocity[i])
        exc = np.maximum(limits.lower[i] - qd[:, i], qd[:, i] - limits.upper[i])
        out["position_excess_max"][j] = float(max(np.max(exc), 0.0))
        if tau is not None:
            out["torque_ratio_max"][j] = float(np.max(np.abs(tau[:, i])) / limits.effort[i])
    if tau is not None:
        out["torque_peak"] = {j: float(np.max(np.abs(tau[:, i])))
                              for i, j in enumerate(model.driven)}
    return out


def _describe(name: str, v: np.ndarray, t: np.ndarray, unit: str) -> str:
    bad = np.flatnonzero(np.nan_to_num(v) > 0)
    return (f"{name}: violated by up to {np.nanmax(v):.3g} {unit} at {bad.size} knot(s), "
            f"t = {t[bad[0]]:.3f}–{t[bad[-1]]:.3f} s")


_UNITS = {"position": "rad", "velocity": "rad/s", "torque": "N·m", "contact": "m", "no": "m",
          "swing": "m", "force": "rad", "base": "N or N·m", "flight": "m"}


def adapt_optimal(motion: Motion, demonstrator: Robot, imitator: Robot, force: str = "segment",
                  *, limits: Limits | None = None, weights: Weights | None = None,
                  contact: str = "all", subsample: int = 1, frames=None,
                  mode: str = "trajectory", tol: float = 1e-6, ipopt: dict | None = None,
                  expand: bool = True) -> AdaptedMotion:
    """The optimal adaptor (DESIGN §6); ``gdimitate.adapt(..., method="optimal", ...)`` calls it.

    ``motion``: the demonstration (of ``demonstrator``), ``force``: ``"segment"``, ``"com"`` or
    ``"grf"``. Options:

    - ``limits``: :class:`Limits` overrides of the URDF limits (e.g. lower efforts);
    - ``weights``: :class:`Weights` of the cost (defaults documented there);
    - ``contact``: ``"all"`` (every stance foot fixed — default) or ``"anchor"`` (only the
      foot down longest fixed, the other touching the ground: Eq. (1)'s own contact model);
    - ``subsample`` (every n-th frame) and ``frames`` (a slice or index array) choose the knots;
      the returned motion lives on those knots;
    - ``mode``: ``"trajectory"`` (one problem over all knots) or ``"per_frame"`` (one small
      problem per frame, causal: see :class:`~gdimitate.optimal.StreamingAdaptor`);
    - ``tol``: feasibility tolerance of the report (m, rad, rad/s, N·m); ``ipopt``: extra IPOPT
      options; ``expand``: expand the NLP to SX (faster for the robots here).

    Never raises on an infeasible problem: the least-infeasible motion comes back with
    ``report.infeasible_constraint`` saying what could not be met. Raises
    :class:`~gdimitate.errors.UnknownNameError` / :class:`~gdimitate.errors.InvalidInputError`
    for bad options, :class:`~gdimitate.errors.SolverError` if IPOPT cannot be set up.
    """
    _check_pair(motion, demonstrator, imitator)
    if force not in FORCE_MODELS:
        raise UnknownNameError("force model", force, FORCE_MODELS)
    if contact not in CONTACT_MODES:
        raise UnknownNameError("contact mode", contact, CONTACT_MODES)
    if mode not in MODES:
        raise UnknownNameError("mode", mode, MODES)
    if weights is None:
        weights = Weights()
    if not isinstance(weights, Weights):
        raise InvalidInputError(f"weights must be a gdimitate.optimal.Weights; got "
                                f"{type(weights).__name__}")
    if not (np.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"tol must be a positive number; got {tol!r}")
    demo = _knots(motion, subsample, frames)
    model = sagittal_model(imitator)
    lim = resolve_limits(imitator, model.driven, limits)
    if mode == "per_frame":
        from .streaming import adapt_per_frame

        return adapt_per_frame(demo, demonstrator, imitator, force=force, limits=limits,
                               weights=weights, tol=tol, ipopt=ipopt, contact=contact)
    targets = demonstration_targets(demonstrator, demo, force)
    analytic = adapt(demo, demonstrator, imitator, method="analytic", force=force)
    X0 = place_base(model, model.x_of_q(analytic.motion.q), demo.contact)
    try:
        problem = TrajectoryProblem(model, targets, lim, weights, contact, ipopt, expand)
    except RuntimeError as e:  # CasADi reports set-up errors as RuntimeError
        raise SolverError(f"could not set up the optimal adaptor's NLP: {e}") from None
    t0 = time.perf_counter()
    z, stats = problem.solve(X0)
    viol = problem.violations(z)
    worst = {k: float(np.nanmax(v)) for k, v in viol.items()}
    hard_ok = bool(stats.get("success")) and all(v <= tol for v in worst.values())
    solver = {"status": stats.get("return_status"), "success": bool(stats.get("success")),
              "iterations": int(stats.get("iter_count", -1)), "elastic": False}
    if not hard_ok:
        # least-infeasible fallback: the elastic solve (limits may give, by as little as
        # possible); the best of {elastic, hard last iterate, Eq. (1)} comes back, ranked by the
        # goal constraints (contact, force direction) first, then by the limits
        z_el, st_el = problem.solve(X0, elastic=True)
        z_el[-problem._nS:] = 0.0  # real violations: limits without their slack
        z_an = problem.start_vector(X0)
        cands = [(z_el, "elastic"), (z, "hard"), (z_an, "analytic")]
        scored = [(_merit(problem.violations(c)), name, c) for c, name in cands]
        scored.sort(key=lambda x: x[0])
        _, best, z = scored[0]
        viol = problem.violations(z)
        solver.update({"elastic": True, "hard_status": solver["status"],
                       "status": st_el.get("return_status"),
                       "iterations": solver["iterations"] + int(st_el.get("iter_count", 0)),
                       "success": False, "returned": best})
    solver["time_s"] = time.perf_counter() - t0
    solver.update(knots=targets.T, variables=int(problem.lbx.size), constraints=int(
        np.sum(np.isfinite(problem.lbg) | np.isfinite(problem.ubg))))  # imposed rows only
    X, _, _ = problem.split(z)
    q = model.q_numeric(X)
    out = robot_motion(imitator, demo.t, q, demo.contact)
    frame_ok = np.ones(targets.T, bool)
    for v in viol.values():
        frame_ok &= ~(np.nan_to_num(v) > tol)
    report = compare(demonstrator, demo, imitator, out, "optimal",
                     {s: frame_ok for s in SIDES}, force)
    fd = np.nan_to_num(np.abs(np.concatenate([report.force_direction_error[s][:, None]
                                              for s in SIDES], axis=1))).max(axis=1)
    frame_ok &= fd <= tol
    report.feasible = {s: frame_ok.copy() for s in SIDES}
    report.infeasible_frames = {s: int((~frame_ok).sum()) for s in SIDES}
    tau = problem.torques(z)
    W = problem.split(z)[1]
    if tau is None:
        tau = _torques_lstsq(problem, X)
        W = problem.initial_wrench(X)
    lr = limit_report(model, lim, targets.t, X, tau)
    report.torque_ratio_max = lr["torque_ratio_max"]
    bad = {k: v for k, v in viol.items() if np.nanmax(v) > tol}
    if bad:
        report.infeasible_constraint = "; ".join(
            _describe(k, v, targets.t, _UNITS.get(k.split()[0], "")) for k, v in bad.items())
    elif not frame_ok.all():
        report.infeasible_constraint = (f"force direction: error up to "
                                        f"{report.force_direction_error_max:.3g} rad")
    report.solver = solver
    tau0 = _torques_lstsq(problem, X0)
    a_lr = limit_report(model, lim, targets.t, X0, tau0)
    report.extra.update({
        "violations": {k: float(np.nanmax(v)) for k, v in viol.items()},
        "limits": lr,
        "analytic": {**a_lr, "infeasible_frames": dict(analytic.report.infeasible_frames),
                     "force_direction_error_max": analytic.report.force_direction_error_max,
                     "joint_limit_violation_max": analytic.report.joint_limit_violation_max},
        "missing_limits": lim.missing,
        "contact_mode": contact,
        "max_change": _max_change(model, X0, X),
        "torques": tau, "wrenches": W, "driven": model.driven,
    })
    return AdaptedMotion(motion=out, report=report, robot=imitator)


def _merit(viol: dict[str, np.ndarray]) -> tuple[float, float]:
    """(goal-constraint violation, limit violation) — lexicographic ranking of candidates."""
    goal = max((np.nanmax(v) for k, v in viol.items() if "limit" not in k), default=0.0)
    lim = max((np.nanmax(v) for k, v in viol.items() if "limit" in k), default=0.0)
    return (round(float(goal), 9), float(lim))


def place_base(model: SagittalModel, X: np.ndarray, contact: dict[str, np.ndarray]
               ) -> np.ndarray:
    """``X`` ``(T, nx)`` with the base's x re-placed so that the anchor foot
    (:func:`.targets.contact_links` ``"anchor"``) does not slip, starting from ``X[0, 0]``;
    constant horizontal velocity through knots where no foot is anchored."""
    X = np.array(X, dtype=float)
    links = contact_links(contact, "anchor")
    Z = X.copy()
    Z[:, 0] = 0.0
    P = np.array(model.kin.map(len(X))(Z.T))
    rel = {s: P[3 * (SIDES.index(s) * 4 + 3), :] for s in SIDES}  # sole x with base x = 0
    for k in range(1, len(X)):
        s = next((s for s in SIDES if links[s][k]), None)
        if s is not None:
            X[k, 0] = X[k - 1, 0] + rel[s][k - 1] - rel[s][k]
        else:
            X[k, 0] = 2 * X[k - 1, 0] - X[k - 2, 0] if k >= 2 else X[k - 1, 0]
    return X


def _torques_lstsq(problem: TrajectoryProblem, X: np.ndarray) -> np.ndarray:
    """Driven torques ``(T, n_driven)`` of ``X`` with least-squares contact wrenches."""
    import casadi as ca

    M = problem.model
    W = problem.initial_wrench(X)
    V, A = problem.D1 @ X, problem.D2 @ X
    nw = M.nw
    f = M.dyn_map(len(X))
    _, tau = f(X.T, V.T, A.T, W[:, :nw].T, W[:, nw:].T)
    return np.array(ca.DM(tau)).T


def _max_change(model: SagittalModel, X0: np.ndarray, X: np.ndarray) -> dict:
    """Where the optimal motion departs most from Eq. (1): per driven joint and the torso, the
    largest |Δ| [rad] and the time index where it happens."""
    names = ("torso", *model.driven)
    d = np.abs(X[:, 2:] - X0[:, 2:])
    i = int(np.argmax(d.max(axis=0)))
    return {"per_joint": {n: float(v) for n, v in zip(names, d.max(axis=0))},
            "joint": names[i], "rad": float(d[:, i].max()), "knot": int(np.argmax(d[:, i]))}
