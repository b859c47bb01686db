"""The trajectory optimisation of DESIGN §6, transcribed over the demonstration's knots.

Decision variables: ``X`` ``(nx, T)`` (the imitator's sagittal vector at every knot, see
:mod:`.model`), the contact wrenches ``W`` ``(2·nw, T)`` of both feet (only when a torque limit is
finite; zero-bounded for a foot in swing) and three elastic slacks per driven joint (position,
velocity, torque; fixed at 0 unless the hard problem is infeasible).

Hard constraints, at every knot k:

- force direction: in stance, the push vector ``p`` (knee→ankle for ``segment``, com→sole for
  ``com``, ``−m(c̈ − g)`` for ``grf``) points along the demonstrator's angle φ:
  ``(p_x cos φ + p_z sin φ)/|p|₀ = 0`` (``|p|₀`` the shank length, leg length or m·g);
- contact: a stance sole at height 0; a linked stance sole (:func:`.targets.contact_links`) at
  the same x as at k − 1; a swing sole not below the ground; the base's x at knot 0 fixed;
- joint position, velocity (``Ẋ = X D1ᵀ``) and torque limits of the driven joints, torques by
  inverse dynamics ``τ = rnea(q, v, a) − Σ Jᵀ w`` with ``a`` from ``X D2ᵀ``, the unactuated base
  rows equal to zero (they determine the wrench in single support; in double support the split
  is chosen by the optimiser with each foot's normal force ≥ 0).

Cost (mean over knots): squared residuals — hip-over-ankle height / leg length, shank direction,
ankle angle, torso angle (and, weight 0 by default, foot placement and thigh/knee angles) —
minus the demonstrator's, plus smoothness: the squared rate of change of those residuals. All
residuals vanish on Eq. (1)'s motion, which is therefore the optimum whenever it meets the
constraints (the paper's planar model, ``segment`` force, no active limit).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import InvalidInputError
from ..metrics import GRAVITY
from ..robot import SIDES
from .limits import ResolvedLimits
from .model import SagittalModel, difference_matrices
from .targets import Targets, contact_links

__all__ = ["Weights", "TrajectoryProblem", "clear_cache", "CACHE_SIZE"]


@dataclass(frozen=True)
class Weights:
    """Cost weights of the optimal adaptor (defaults in brackets).

    - ``height`` [1]: (hip-over-ankle height / leg length − the demonstrator's)², per leg;
    - ``direction`` [1]: (shank direction − the demonstrator's)² [rad²] (a hard constraint in
      stance under ``segment``; the soft version keeps the swing leg's shape);
    - ``ankle`` [1]: (ankle angle relative to the shank − the demonstrator's)² [rad²];
    - ``torso`` [1]: (torso angle − the demonstrator's)² [rad²];
    - ``placement`` [0]: ((sole x − hip x) / leg length − the demonstrator's)²;
    - ``joints`` [0]: (thigh and knee planar angles − the demonstrator's)² [rad²];
      ``placement`` and ``joints`` are 0 by default because Eq. (1) gives them up to keep the
      force direction and the scaled height: raising them moves the optimum off Eq. (1);
    - ``smoothness`` [1e-4 s²]: squared time derivative of the weighted residuals (spreads
      unavoidable deviations over neighbouring knots; zero on Eq. (1) where it is feasible);
    - ``acceleration`` [0 s⁴]: squared joint and base accelerations;
    - ``wrench`` [1e-6]: squared contact wrench / (m·g) (picks the double-support split);
    - ``elastic`` [1e3]: penalty per unit of limit slack in the least-infeasible fallback solve
      (slack in rad, rad/s × mean knot spacing, and torque / limit).
    """

    height: float = 1.0
    direction: float = 1.0
    ankle: float = 1.0
    torso: float = 1.0
    placement: float = 0.0
    joints: float = 0.0
    smoothness: float = 1e-4
    acceleration: float = 0.0
    wrench: float = 1e-6
    elastic: float = 1e3

    def __post_init__(self) -> None:
        for k, v in self.__dict__.items():
            if not (np.isfinite(v) and v >= 0):
                raise InvalidInputError(f"Weights.{k} must be finite and ≥ 0; got {v!r}")


def _row(v) -> ca.DM:
    return ca.DM(np.asarray(v, dtype=float)).T


#: Built solvers kept per process (least recently used dropped first).
CACHE_SIZE = 8
_COMPILED: OrderedDict[tuple, _Compiled] = OrderedDict()
#: How many NLPs (``nlpsol`` + helper functions) have been built in this process; a call that
#: reuses a cached one leaves it unchanged.
BUILD_COUNT = 0


def clear_cache() -> None:
    """Forget every cached NLP (the next :class:`TrajectoryProblem` builds its own)."""
    _COMPILED.clear()


def _pattern(T: int) -> tuple[ca.Sparsity, ca.Sparsity]:
    """Structural sparsity of ``(D1, D2)`` on any ``T``-knot grid (from a generic grid)."""
    t = np.cumsum(1.0 + 0.1 * np.sin(np.arange(T)))
    return tuple(ca.Sparsity.triplet(T, T, *(list(map(int, a)) for a in np.nonzero(D)))
                 for D in difference_matrices(t))


def _nonzeros(D: np.ndarray, sp: ca.Sparsity) -> np.ndarray:
    r, c = sp.get_triplet()
    return D[np.asarray(r, int), np.asarray(c, int)]


@dataclass
class _Compiled:
    """An NLP built once for a problem *shape*; every number of a demonstration is in ``p``.

    ``blocks``: constraint blocks in ``g`` order, ``(kind, index, knots)`` with ``kind`` in
    ``sole_z, force, slip, flight, pos_lo, pos_hi, vel_lo, vel_hi, base, tau_lo, tau_hi``;
    ``rows``: row of each target in the ``tg`` parameter; ``sizes``: sizes of the parameter
    blocks ``(tg, d1, d2, invdt, scalars, effort)``.
    """

    solver: ca.Function
    g_fun: ca.Function
    res_fun: ca.Function
    tau_fun: ca.Function | None
    blocks: list[tuple[str, int, np.ndarray]]
    rows: dict[tuple, int]
    sp: tuple[ca.Sparsity, ca.Sparsity]
    nz: int
    ng: int


_SCALARS = ("height", "direction", "ankle", "torso", "placement", "joints", "smoothness",
            "acceleration", "wrench", "elastic", "mean_dt")


def _compile(M: SagittalModel, T: int, force: str, use_dyn: bool, flags: tuple[bool, ...],
             ipopt_opts: dict, expand: bool) -> _Compiled:
    """Build the parametric NLP of one shape (see :class:`TrajectoryProblem`)."""
    global BUILD_COUNT
    robot = M.robot
    nx, nd, nw = M.nx, len(M.driven), M.nw
    placement, joints, smooth, accel = flags
    # ---- parameters
    rows: dict[tuple, int] = {}
    for s in SIDES:
        keys = ["height", "cos_shank", "sin_shank"]
        keys += ["ankle"] if robot.legs[s].ankle is not None else []
        keys += ["placement"] if placement else []
        keys += ["joint0", "joint1"] if joints else []
        keys += ["cos_force", "sin_force"]
        for k in keys:
            rows[(s, k)] = len(rows)
    rows[("torso",)] = len(rows)
    sp1, sp2 = _pattern(T)
    TG = ca.MX.sym("tg", len(rows), T)
    d1, d2 = ca.MX.sym("d1", sp1.nnz()), ca.MX.sym("d2", sp2.nnz())
    invdt = ca.MX.sym("invdt", 1, max(T - 1, 1))
    sc = ca.MX.sym("scalars", len(_SCALARS))
    eff = ca.MX.sym("effort", nd)
    w = {k: sc[i] for i, k in enumerate(_SCALARS)}
    pvec = ca.vertcat(ca.vec(TG), d1, d2, ca.vec(invdt), sc, eff)

    def tg(*key):
        return TG[rows[key], :]

    D1, D2 = ca.sparsity_cast(d1, sp1), ca.sparsity_cast(d2, sp2)
    X = ca.MX.sym("X", nx, T)
    W = ca.MX.sym("W", 2 * nw, T) if use_dyn else ca.MX(2 * nw, T)
    S = ca.MX.sym("S", 3 * nd)
    sq, sv, st = S[:nd], S[nd:2 * nd], S[2 * nd:]
    P = M.kin.map(T)(X)
    V = ca.densify(ca.mtimes(X, D1.T))
    A = ca.densify(ca.mtimes(X, D2.T))
    ang = M.planar_angles(X)
    g: list = []
    blocks: list[tuple[str, int, np.ndarray]] = []
    allk = np.arange(T)

    def add(kind: str, index: int, expr, knots=allk) -> None:
        expr = ca.vec(expr)
        knots = np.asarray(knots, int)
        if knots.size != expr.shape[0]:
            knots = np.tile(knots, expr.shape[0] // knots.size)
        g.append(expr)
        blocks.append((kind, index, knots))

    res = []
    com = M.point(P, "left", "com")
    for i, s in enumerate(SIDES):
        leg = robot.legs[s]
        hip, knee = M.point(P, s, "hip"), M.point(P, s, "knee")
        ankle, sole = M.point(P, s, "ankle"), M.point(P, s, "sole")
        height = (hip[2, :] - ankle[2, :]) / leg.length - tg(s, "height")
        vs = ankle - knee
        shank_err = (vs[0, :] * tg(s, "cos_shank") + vs[2, :] * tg(s, "sin_shank")) / leg.shank
        res += [w["height"] * height, w["direction"] * shank_err]
        if leg.ankle is not None:
            res.append(w["ankle"] * (ang[s][2] - tg(s, "ankle")))
        if placement:
            pl = (sole[0, :] - hip[0, :]) / leg.length - tg(s, "placement")
            res.append(w["placement"] * pl)
        if joints:
            for k in (0, 1):
                res.append(w["joints"] * (ang[s][k] - tg(s, f"joint{k}")))
        cf, sf = tg(s, "cos_force"), tg(s, "sin_force")
        if force == "segment":
            e = (vs[0, :] * cf + vs[2, :] * sf) / leg.shank
        elif force == "com":
            p = sole - com
            e = (p[0, :] * cf + p[2, :] * sf) / leg.length
        else:
            acc = ca.mtimes(ca.mtimes(com, D1.T), D1.T)
            push = -(acc + ca.repmat(ca.DM([0.0, 0.0, GRAVITY]), 1, T))  # per unit mass
            e = (push[0, :] * cf + push[2, :] * sf) / GRAVITY
        add("sole_z", i, sole[2, :])
        add("force", i, e)
        if T > 1:
            add("slip", i, sole[0, 1:] - sole[0, :-1], allk[1:])
    res.append(w["torso"] * (X[2, :] - tg("torso")))
    if T > 2:
        add("flight", 0, X[0, 2:] - 2 * X[0, 1:-1] + X[0, :-2], allk[2:])
    for i in range(nd):
        add("pos_lo", i, X[3 + i, :] + sq[i])
        add("pos_hi", i, X[3 + i, :] - sq[i])
        add("vel_lo", i, V[3 + i, :] + sv[i])
        add("vel_hi", i, V[3 + i, :] - sv[i])
    tau_fun = None
    if use_dyn:
        tau_base, tau = M.dyn.map(T)(X, V, A, W[:nw, :], W[nw:, :])
        add("base", 0, tau_base)
        for i in range(nd):
            add("tau_lo", i, tau[i, :] + st[i] * eff[i])
            add("tau_hi", i, tau[i, :] - st[i] * eff[i])
        tau_fun = ca.Function("tau", [X, W, pvec], [tau])
    R = ca.vertcat(*res)
    cost = ca.sumsqr(R) / T
    if smooth:
        dR = (R[:, 1:] - R[:, :-1]) * ca.repmat(invdt, R.shape[0], 1)
        cost += w["smoothness"] * ca.sumsqr(dR) / (T - 1)
    if accel:
        cost += w["acceleration"] * ca.sumsqr(A) / T
    cost += w["elastic"] * (ca.sum1(sq) + w["mean_dt"] * ca.sum1(sv) + ca.sum1(st))
    if use_dyn:
        cost += w["wrench"] * ca.sumsqr(W / (robot.mass * GRAVITY)) / T
    z = ca.vertcat(*([ca.vec(X)] + ([ca.vec(W)] if use_dyn else []) + [S]))
    gg = ca.vertcat(*g)
    nlp = {"x": z, "p": pvec, "f": cost, "g": gg}
    opts = {"print_time": False, "expand": expand,
            "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-10,
                      "constr_viol_tol": 1e-10, "acceptable_tol": 1e-7,
                      "acceptable_iter": 5, "max_iter": 300, "mu_strategy": "adaptive",
                      "warm_start_init_point": "yes", "warm_start_bound_push": 1e-9,
                      "warm_start_mult_bound_push": 1e-9, "mu_init": 1e-6,
                      **ipopt_opts}}
    solver = ca.nlpsol("optimal_adaptor", "ipopt", nlp, opts)
    g_fun = ca.Function("g", [z, pvec], [gg])
    res_fun = ca.Function("res", [X, pvec], [R])
    if expand:
        g_fun, res_fun = g_fun.expand(), res_fun.expand()
        tau_fun = tau_fun.expand() if tau_fun is not None else None
    BUILD_COUNT += 1
    return _Compiled(solver=solver, g_fun=g_fun, res_fun=res_fun, tau_fun=tau_fun,
                     blocks=blocks, rows=rows, sp=(sp1, sp2), nz=int(z.shape[0]),
                     ng=int(gg.shape[0]))


def _freeze(d: dict) -> tuple:
    """A hashable, order-independent form of an options dict."""
    return tuple(sorted((k, _freeze(v) if isinstance(v, dict) else repr(v))
                        for k, v in d.items()))


class TrajectoryProblem:
    """The NLP for one demonstration (see the module docstring); :meth:`solve` runs IPOPT.

    ``model``: the imitator's :class:`SagittalModel`; ``targets``: the demonstration's
    :class:`Targets` on the knots; ``limits``: resolved limits of the driven joints;
    ``contact``: a mode of :data:`.targets.CONTACT_MODES`; ``ipopt``: extra IPOPT options.

    The NLP is *parametric*: targets, time grid, weights, limits and the contact schedule enter
    as parameter values and bounds, so a problem of the same shape (imitator, number of knots,
    force model, whether torques are limited, which optional cost terms are on, IPOPT options)
    reuses the solver built before (``cached`` is True then; see :data:`BUILD_COUNT`). Every
    constraint exists at every knot; where the schedule does not impose it its bounds are
    infinite, which IPOPT ignores.
    """

    def __init__(self, model: SagittalModel, targets: Targets, limits: ResolvedLimits,
                 weights: Weights = Weights(), contact: str = "all",
                 ipopt: dict | None = None, expand: bool = True):
        self.model, self.targets, self.limits, self.weights = model, targets, limits, weights
        self.contact_mode = contact
        self.links = contact_links(targets.contact, contact)
        self.use_dyn = limits.has_effort
        T = targets.T
        flags = (weights.placement > 0, weights.joints > 0,
                 bool(weights.smoothness > 0 and T > 1), weights.acceleration > 0)
        key = (model.key, T, targets.model, self.use_dyn, flags, _freeze(ipopt or {}),
               bool(expand))
        self.cached = key in _COMPILED
        if self.cached:
            _COMPILED.move_to_end(key)
        else:
            _COMPILED[key] = _compile(model, T, targets.model, self.use_dyn, flags,
                                      ipopt or {}, expand)
            while len(_COMPILED) > CACHE_SIZE:
                _COMPILED.popitem(last=False)
        self._c = _COMPILED[key]
        self.solver = self._c.solver
        self._numbers()

    # ------------------------------------------------------------------ numbers
    def _numbers(self) -> None:
        """Parameter vector, bounds and constraint groups of this demonstration."""
        M, tg, lim, w, c = self.model, self.targets, self.limits, self.weights, self._c
        T, nd, nw = tg.T, len(M.driven), M.nw
        D1, D2 = difference_matrices(tg.t)
        self.D1, self.D2 = D1, D2
        TG = np.zeros((len(c.rows), T))
        for s in SIDES:
            vals = {"height": tg.height[s], "cos_shank": np.cos(tg.shank[s]),
                    "sin_shank": np.sin(tg.shank[s]), "cos_force": None, "sin_force": None}
            f = np.where(tg.contact[s], np.nan_to_num(tg.force[s]), 0.0)
            vals["cos_force"], vals["sin_force"] = np.cos(f), np.sin(f)
            vals["ankle"] = tg.angles[s][:, 2]
            vals["joint0"], vals["joint1"] = tg.angles[s][:, 0], tg.angles[s][:, 1]
            vals["placement"] = tg.placement.get(s, np.zeros(T))
            for key, r in c.rows.items():
                if key[0] == s:
                    TG[r] = vals[key[1]]
        TG[c.rows[("torso",)]] = tg.torso
        dt = np.diff(tg.t)
        invdt = 1.0 / dt if T > 1 else np.zeros(1)
        scal = {"height": np.sqrt(w.height), "direction": np.sqrt(w.direction),
                "ankle": np.sqrt(w.ankle), "torso": np.sqrt(w.torso),
                "placement": np.sqrt(w.placement), "joints": np.sqrt(w.joints),
                "smoothness": w.smoothness, "acceleration": w.acceleration,
                "wrench": w.wrench, "elastic": w.elastic, "mean_dt": float(np.mean(dt))}
        eff = np.where(np.isfinite(lim.effort), lim.effort, 0.0)
        self.p = np.concatenate([TG.ravel(order="F"), _nonzeros(D1, c.sp[0]),
                                 _nonzeros(D2, c.sp[1]), invdt,
                                 [scal[k] for k in _SCALARS], eff])
        # constraint bounds and groups
        inf = np.inf
        lbg, ubg = np.full(c.ng, -inf), np.full(c.ng, inf)
        parts: dict[tuple, list] = {}
        free = np.array([not any(self.links[s][k] for s in SIDES) for k in range(T)])
        start = 0
        for kind, i, knots in c.blocks:
            n = knots.size
            sl = slice(start, start + n)
            start += n
            s = SIDES[i] if kind in ("sole_z", "force", "slip") else ""
            j = M.driven[i] if kind in ("pos_lo", "pos_hi", "vel_lo", "vel_hi", "tau_lo",
                                        "tau_hi") else None
            if kind == "sole_z":
                st_ = tg.contact[s][knots]
                lbg[sl] = 0.0
                ubg[sl] = np.where(st_, 0.0, inf)
                parts[(0, i, 0, f"contact height ({s} sole)")] = [(sl, st_, knots)]
                parts[(0, i, 3, f"swing clearance ({s} sole)")] = [(sl, ~st_, knots)]
                continue
            if kind == "force":
                on = tg.contact[s][knots]
                order, name = (0, i, 1), f"force direction ({s})"
                lo, hi = 0.0, 0.0
            elif kind == "slip":
                on = self.links[s][knots]
                order, name = (0, i, 2), f"no slip ({s} sole)"
                lo, hi = 0.0, 0.0
            elif kind == "flight":
                on = free[knots]
                order, name = (4, 0, 0), "flight"
                lo, hi = 0.0, 0.0
            elif kind in ("pos_lo", "pos_hi", "vel_lo", "vel_hi"):
                order = (5, i, int(kind.startswith("vel")))
                name = ("position" if kind.startswith("pos") else "velocity") + f" limit ({j})"
                lo, hi = {"pos_lo": (lim.lower[i], inf), "pos_hi": (-inf, lim.upper[i]),
                          "vel_lo": (-lim.velocity[i], inf),
                          "vel_hi": (-inf, lim.velocity[i])}[kind]
                on = np.full(n, bool(np.isfinite(lo) or np.isfinite(hi)))
            elif kind == "base":
                on = np.ones(n, bool)
                order, name = (6, 0, 0), "base dynamics"
                lo, hi = 0.0, 0.0
            else:  # torque limits
                e = lim.effort[i]
                on = np.full(n, bool(np.isfinite(e)))
                order, name = (7, i, 0), f"torque limit ({j})"
                lo, hi = (-e, inf) if kind == "tau_lo" else (-inf, e)
            lbg[sl] = np.where(on, lo, -inf)
            ubg[sl] = np.where(on, hi, inf)
            parts.setdefault((*order, name), []).append((sl, on, knots))
        self.lbg, self.ubg = lbg, ubg
        # groups in the order of the constraint's first appearance: per side contact height,
        # force direction, no slip, swing clearance; flight; limits per joint; dynamics; torques
        self.groups: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
        for key in sorted(parts, key=lambda k: k[:3]):
            name = key[-1]
            for sl, on, knots in parts[key]:
                if on.any():
                    idx = np.arange(sl.start, sl.stop)[on]
                    self.groups.setdefault(name, []).append((idx, knots[on]))
        # variable bounds: base x at knot 0 (set per solve), wrenches, slacks
        self._nX = M.nx * T
        self._nW = 2 * nw * T if self.use_dyn else 0
        self._nS = 3 * nd
        n = c.nz
        self.lbx, self.ubx = np.full(n, -np.inf), np.full(n, np.inf)
        if self.use_dyn:
            lw = np.full((2 * nw, T), -np.inf)
            uw = np.full((2 * nw, T), np.inf)
            iz = 1 if nw == 3 else 2  # index of f_z in one foot's wrench
            both = tg.contact["left"] & tg.contact["right"]
            for k, s in enumerate(SIDES):
                rows = slice(k * nw, (k + 1) * nw)
                lw[rows, ~tg.contact[s]] = 0.0
                uw[rows, ~tg.contact[s]] = 0.0
                lw[k * nw + iz, both] = 0.0
            self.lbx[self._nX:self._nX + self._nW] = lw.ravel(order="F")
            self.ubx[self._nX:self._nX + self._nW] = uw.ravel(order="F")

    # ------------------------------------------------------------------ solve
    def split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """``(X (T, nx), W (T, 2·nw) or None, slacks (3, n_driven))`` of a solution vector."""
        T, nx = self.targets.T, self.model.nx
        z = np.asarray(z, dtype=float).ravel()
        X = z[:self._nX].reshape(T, nx)
        Wz = (z[self._nX:self._nX + self._nW].reshape(T, -1) if self.use_dyn else None)
        return X, Wz, z[self._nX + self._nW:].reshape(3, -1)

    def initial_wrench(self, X: np.ndarray) -> np.ndarray:
        """Contact wrenches ``(T, 2·nw)`` that zero the base rows of the inverse dynamics for
        the motion ``X`` ``(T, nx)`` (least squares over the stance feet)."""
        M, T, nw = self.model, self.targets.T, self.model.nw
        V, A = self.D1 @ X, self.D2 @ X
        b0s, Bs = (np.array(v) for v in M.base_wrench_map(T)(X.T, V.T, A.T))
        nb = b0s.shape[0]
        out = np.zeros((T, 2 * nw))
        for k in range(T):
            b0, B = b0s[:, k], Bs[:, k * 2 * nw:(k + 1) * 2 * nw].reshape(nb, 2 * nw)
            cols = [i for c, s in enumerate(SIDES) if self.targets.contact[s][k]
                    for i in range(c * nw, (c + 1) * nw)]
            if cols:
                out[k, cols] = np.linalg.lstsq(B[:, cols], -b0.ravel(), rcond=None)[0]
        return out

    def solve(self, X0: np.ndarray, elastic: bool = False, W0: np.ndarray | None = None
              ) -> tuple[np.ndarray, dict]:
        """Run IPOPT from ``X0`` ``(T, nx)``; ``elastic``: let the limit slacks be positive
        (started at the warm start's own violations, so the start is feasible for them).
        Returns the solution vector and CasADi's solver stats."""
        X0 = np.asarray(X0, float)
        z0 = self.start_vector(X0, W0)
        lbx, ubx = self.lbx.copy(), self.ubx.copy()
        lbx[0] = ubx[0] = X0[0, 0]
        s0 = len(lbx) - self._nS
        lbx[s0:] = 0.0
        ubx[s0:] = np.inf if elastic else 0.0
        if elastic:
            z0[s0:] = self._initial_slack(z0)
        sol = self.solver(x0=z0, p=self.p, lbx=lbx, ubx=ubx, lbg=self.lbg, ubg=self.ubg)
        return np.array(sol["x"]).ravel(), dict(self.solver.stats())

    def start_vector(self, X: np.ndarray, W: np.ndarray | None = None) -> np.ndarray:
        """Solution-shaped vector of a motion ``X`` ``(T, nx)``: wrenches by least squares (or
        ``W`` ``(T, 2·nw)``), zero slacks."""
        z = [np.asarray(X, float).ravel()]
        if self.use_dyn:
            z.append((self.initial_wrench(X) if W is None else W).ravel())
        z.append(np.zeros(self._nS))
        return np.concatenate(z)

    def _initial_slack(self, z: np.ndarray) -> np.ndarray:
        """Slacks ``(3·n_driven,)`` that make the limit constraints of ``z`` hold (+1 %)."""
        nd = len(self.model.driven)
        viol = self.violations(z)
        out = np.zeros((3, nd))
        for k, kind in enumerate(("position", "velocity", "torque")):
            for i, j in enumerate(self.model.driven):
                v = viol.get(f"{kind} limit ({j})")
                if v is not None:
                    scale = self.limits.effort[i] if kind == "torque" else 1.0
                    out[k, i] = 1.01 * float(np.nanmax(v)) / scale + 1e-6
        return out.ravel()

    # ------------------------------------------------------------------ evaluation
    def violations(self, z: np.ndarray) -> dict[str, np.ndarray]:
        """Per constraint group, the violation ``(T,)`` at every knot (0 where met, NaN where
        the group has no constraint at that knot) — in the group's own units (m, rad, rad/s,
        N·m; force direction ≈ rad)."""
        gv = np.array(self._c.g_fun(z, self.p)).ravel()
        viol = np.maximum(self.lbg - gv, 0) + np.maximum(gv - self.ubg, 0)
        T = self.targets.T
        out: dict[str, np.ndarray] = {}
        for name, parts in self.groups.items():
            arr = np.full(T, -np.inf)
            for idx, knots in parts:
                np.maximum.at(arr, knots, viol[idx])
            out[name] = np.where(np.isinf(arr), np.nan, arr)
        return out

    def torques(self, z: np.ndarray) -> np.ndarray | None:
        """Driven-joint torques ``(T, n_driven)`` [N·m] of a solution (None without dynamics)."""
        if not self.use_dyn:
            return None
        X, Wz, _ = self.split(z)
        return np.array(self._c.tau_fun(X.T, Wz.T, self.p)).T

    def residuals(self, X: np.ndarray) -> np.ndarray:
        """Weighted cost residuals ``(n_res, T)`` of a motion ``X`` ``(T, nx)``."""
        return np.array(self._c.res_fun(np.asarray(X).T, self.p))
