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

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import InvalidInputError
from ..metrics import GRAVITY
from ..robot import SIDES
from .limits import ResolvedLimits
from .model import SagittalModel, difference_matrices
from .targets import Targets, contact_links

__all__ = ["Weights", "TrajectoryProblem"]


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


class TrajectoryProblem:
    """The NLP for one demonstration (see the module docstring); :meth:`solve` runs IPOPT.

    ``model``: the imitator's :class:`SagittalModel`; ``targets``: the demonstration's
    :class:`Targets` on the knots; ``limits``: resolved limits of the driven joints;
    ``contact``: a mode of :data:`.targets.CONTACT_MODES`; ``ipopt``: extra IPOPT options.
    """

    def __init__(self, model: SagittalModel, targets: Targets, limits: ResolvedLimits,
                 weights: Weights = Weights(), contact: str = "all",
                 ipopt: dict | None = None, expand: bool = True):
        self.model, self.targets, self.limits, self.weights = model, targets, limits, weights
        self.contact_mode = contact
        self.links = contact_links(targets.contact, contact)
        self.use_dyn = limits.has_effort
        self._build(ipopt or {}, expand)

    # ------------------------------------------------------------------ build
    def _build(self, ipopt_opts: dict, expand: bool) -> None:
        M, tg, lim, w = self.model, self.targets, self.limits, self.weights
        robot = M.robot
        T, nx, nd, nw = tg.T, M.nx, len(M.driven), M.nw
        D1, D2 = difference_matrices(tg.t)
        self.D1, self.D2 = D1, D2
        X = ca.MX.sym("X", nx, T)
        W = ca.MX.sym("W", 2 * nw, T) if self.use_dyn else ca.MX(2 * nw, T)
        S = ca.MX.sym("S", 3 * nd)
        sq, sv, st = S[:nd], S[nd:2 * nd], S[2 * nd:]
        P = M.kin.map(T)(X)
        V = ca.mtimes(X, ca.DM(D1.T))
        A = ca.mtimes(X, ca.DM(D2.T))
        ang = M.planar_angles(X)

        g, lbg, ubg, self.groups = [], [], [], {}

        allk = np.arange(T)

        def add(name: str, expr, lo, hi, knots=allk) -> None:
            expr = ca.vec(expr)
            n = expr.shape[0]
            start = sum(e.shape[0] for e in g)
            knots = np.asarray(knots, int)
            if knots.size != n:
                knots = np.repeat(knots, n // knots.size)
            self.groups.setdefault(name, []).append((start, n, knots))
            g.append(expr)
            lbg.append(np.broadcast_to(np.asarray(lo, float), (n,)).ravel())
            ubg.append(np.broadcast_to(np.asarray(hi, float), (n,)).ravel())

        res = []  # weighted residual rows (1, T)
        mass = robot.mass
        com = M.point(P, "left", "com")
        if tg.model == "grf":
            G = ca.DM(D1 @ D1)
            acc = ca.mtimes(com, G.T)  # (3, T)
        for s in SIDES:
            leg = robot.legs[s]
            hip, knee = M.point(P, s, "hip"), M.point(P, s, "knee")
            ankle, sole = M.point(P, s, "ankle"), M.point(P, s, "sole")
            c = tg.contact[s]
            height = (hip[2, :] - ankle[2, :]) / leg.length - _row(tg.height[s])
            vs = ankle - knee
            phi = tg.shank[s]
            shank_err = (vs[0, :] * _row(np.cos(phi)) + vs[2, :] * _row(np.sin(phi))) / leg.shank
            res += [np.sqrt(w.height) * height, np.sqrt(w.direction) * shank_err]
            if leg.ankle is not None:
                res.append(np.sqrt(w.ankle) * (ang[s][2] - _row(tg.angles[s][:, 2])))
            if w.placement > 0:
                pl = (sole[0, :] - hip[0, :]) / leg.length - _row(tg.placement[s])
                res.append(np.sqrt(w.placement) * pl)
            if w.joints > 0:
                for k in (0, 1):
                    res.append(np.sqrt(w.joints) * (ang[s][k] - _row(tg.angles[s][:, k])))
            # contact and force direction
            kst = np.flatnonzero(c)
            sw = np.flatnonzero(~c)
            if kst.size:
                add(f"contact height ({s} sole)", sole[2, kst], 0.0, 0.0, kst)
                f = np.nan_to_num(tg.force[s][kst])
                cf, sf = _row(np.cos(f)), _row(np.sin(f))
                if tg.model == "segment":
                    e = (vs[0, kst] * cf + vs[2, kst] * sf) / leg.shank
                elif tg.model == "com":
                    p = sole[:, kst] - com[:, kst]
                    e = (p[0, :] * cf + p[2, :] * sf) / leg.length
                else:
                    push = -(acc[:, kst] + ca.DM([0.0, 0.0, GRAVITY]))  # per unit mass
                    e = (push[0, :] * cf + push[2, :] * sf) / GRAVITY
                add(f"force direction ({s})", e, 0.0, 0.0, kst)
            lk = np.flatnonzero(self.links[s])
            if lk.size:
                add(f"no slip ({s} sole)", sole[0, lk] - sole[0, lk - 1], 0.0, 0.0, lk)
            if sw.size:
                add(f"swing clearance ({s} sole)", sole[2, sw], 0.0, np.inf, sw)
        res.append(np.sqrt(w.torso) * (X[2, :] - _row(tg.torso)))
        # frames where no foot is linked: constant horizontal base velocity (flight)
        free = [k for k in range(2, T) if not any(self.links[s][k] for s in SIDES)]
        if free:
            add("flight", X[0, free] - 2 * X[0, [k - 1 for k in free]]
                + X[0, [k - 2 for k in free]], 0.0, 0.0, free)
        # limits
        for i, j in enumerate(M.driven):
            row = X[3 + i, :]
            if np.isfinite(lim.lower[i]):
                add(f"position limit ({j})", row + sq[i], lim.lower[i], np.inf)
            if np.isfinite(lim.upper[i]):
                add(f"position limit ({j})", row - sq[i], -np.inf, lim.upper[i])
            if np.isfinite(lim.velocity[i]):
                add(f"velocity limit ({j})", V[3 + i, :] + sv[i], -lim.velocity[i], np.inf)
                add(f"velocity limit ({j})", V[3 + i, :] - sv[i], -np.inf, lim.velocity[i])
        if self.use_dyn:
            tau_base, tau = M.dyn.map(T)(X, V, A, W[:nw, :], W[nw:, :])
            add("base dynamics", tau_base, 0.0, 0.0)
            for i, j in enumerate(M.driven):
                if np.isfinite(lim.effort[i]):
                    add(f"torque limit ({j})", tau[i, :] + st[i] * lim.effort[i],
                        -lim.effort[i], np.inf)
                    add(f"torque limit ({j})", tau[i, :] - st[i] * lim.effort[i],
                        -np.inf, lim.effort[i])
            self._tau_fun = ca.Function("tau", [X, W], [tau])
        R = ca.vertcat(*res)
        dt = np.diff(tg.t)
        cost = ca.sumsqr(R) / T
        if w.smoothness > 0 and T > 1:
            dR = (R[:, 1:] - R[:, :-1]) / ca.repmat(_row(dt), R.shape[0], 1)
            cost += w.smoothness * ca.sumsqr(dR) / (T - 1)
        if w.acceleration > 0:
            cost += w.acceleration * ca.sumsqr(A) / T
        mean_dt = float(np.mean(dt))
        cost += w.elastic * (ca.sum1(sq) + mean_dt * ca.sum1(sv) + ca.sum1(st))
        if self.use_dyn:
            cost += w.wrench * ca.sumsqr(W / (mass * GRAVITY)) / T
        xs = [ca.vec(X)] + ([ca.vec(W)] if self.use_dyn else []) + [S]
        self._nX = nx * T
        self._nW = 2 * nw * T if self.use_dyn else 0
        nlp = {"x": ca.vertcat(*xs), "f": cost, "g": ca.vertcat(*g)}
        self.lbg, self.ubg = np.concatenate(lbg), np.concatenate(ubg)
        self._residual_fun = ca.Function("res", [X], [R])
        self._g_fun = ca.Function("g", [nlp["x"]], [nlp["g"]])
        opts = {"print_time": False, "expand": expand,
                "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-10,
                          "constr_viol_tol": 1e-10, "acceptable_tol": 1e-7,
                          "acceptable_iter": 5, "max_iter": 300, "mu_strategy": "adaptive",
                          "warm_start_init_point": "yes", "warm_start_bound_push": 1e-9,
                          "warm_start_mult_bound_push": 1e-9, "mu_init": 1e-6,
                          **ipopt_opts}}
        self.solver = ca.nlpsol("optimal_adaptor", "ipopt", nlp, opts)
        # variable bounds: base x at knot 0 (set per solve), wrenches, slacks
        n = nlp["x"].shape[0]
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
        self._nS = 3 * nd

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
        xs = ca.SX.sym("x", M.nx)
        xd, xdd = ca.SX.sym("xd", M.nx), ca.SX.sym("xdd", M.nx)
        wv = ca.SX.sym("w", 2 * nw)
        tb = M.dyn(xs, xd, xdd, wv[:nw], wv[nw:])[0]
        f = ca.Function("lin", [xs, xd, xdd, wv], [tb, ca.jacobian(tb, wv)])
        V, A = self.D1 @ X, self.D2 @ X
        out = np.zeros((T, 2 * nw))
        for k in range(T):
            b0, B = (np.array(v) for v in f(X[k], V[k], A[k], np.zeros(2 * nw)))
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
        sol = self.solver(x0=z0, lbx=lbx, ubx=ubx, lbg=self.lbg, ubg=self.ubg)
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
        gv = np.array(self._g_fun(z)).ravel()
        viol = np.maximum(self.lbg - gv, 0) + np.maximum(gv - self.ubg, 0)
        T = self.targets.T
        out: dict[str, np.ndarray] = {}
        for name, parts in self.groups.items():
            arr = np.full(T, -np.inf)
            for start, n, knots in parts:
                np.maximum.at(arr, knots, viol[start:start + n])
            out[name] = np.where(np.isinf(arr), np.nan, arr)
        return out

    def torques(self, z: np.ndarray) -> np.ndarray | None:
        """Driven-joint torques ``(T, n_driven)`` [N·m] of a solution (None without dynamics)."""
        if not self.use_dyn:
            return None
        X, Wz, _ = self.split(z)
        return np.array(self._tau_fun(X.T, Wz.T)).T

    def residuals(self, X: np.ndarray) -> np.ndarray:
        """Weighted cost residuals ``(n_res, T)`` of a motion ``X`` ``(T, nx)``."""
        return np.array(self._residual_fun(np.asarray(X).T))
