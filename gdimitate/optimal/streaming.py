"""Per-frame (streaming) optimal adaptor: one small IPOPT problem per demonstration frame.

For online imitation the future is unknown, so each frame is solved alone, warm-started from the
previous frame's answer, with the trajectory problem's constraints minus those that need future
frames:

- kept: force direction in stance (``segment`` or ``com``), stance sole on the ground and — once
  it has been down one frame — where it stood the frame before (no slip), swing sole not below
  the ground, joint position limits, joint velocity limits as |q − q_prev| ≤ q̇_max·dt (a backward
  difference);
- dropped: torque limits and the ``grf`` force model (both need the acceleration at the current
  frame, i.e. the next frame).

The cost is the trajectory problem's (:class:`~.problem.Weights`), its smoothness term taken
against the previous frame's residuals, plus a tiny pull towards the previous frame's ``x`` that
keeps the problem well posed.
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np
import pinocchio as pin

from ..adapt import AdaptedMotion, compare
from ..errors import InvalidInputError, UnknownNameError
from ..metrics import angle_down
from ..motion import Motion
from ..planar import eq1
from ..robot import SIDES, Robot
from ..sagittal import compose_q, leg_angles, robot_motion
from .limits import Limits, resolve_limits
from .problem import Weights
from .targets import CONTACT_MODES

__all__ = ["StreamingAdaptor", "adapt_per_frame", "STREAMING_FORCE_MODELS"]

#: Force models the per-frame mode supports (``grf`` needs the next frame).
STREAMING_FORCE_MODELS = ("segment", "com")
_STATES = ("swing", "touch", "hold")  # per foot: in the air, landed now, down since before


class StreamingAdaptor:
    """Adapt a demonstration frame by frame (module docstring).

    ``demonstrator``, ``imitator``: :class:`~gdimitate.robot.Robot`; ``force``: ``"segment"`` or
    ``"com"``; ``limits``: :class:`~.limits.Limits` overrides; ``weights``: cost
    :class:`~.problem.Weights`; ``dt``: default frame period [s]; ``contact``: ``"all"`` or
    ``"anchor"`` (see :data:`.targets.CONTACT_MODES`).

    Use :meth:`step` with each new demonstrator configuration; :meth:`reset` to start over.
    After each step, :attr:`last` holds the frame's solver status, iterations and constraint
    violations.
    """

    def __init__(self, demonstrator: Robot, imitator: Robot, force: str = "segment",
                 limits: Limits | None = None, weights: Weights | None = None,
                 dt: float = 1 / 60, contact: str = "all", ipopt: dict | None = None):
        from .solve import sagittal_model

        if force not in STREAMING_FORCE_MODELS:
            raise UnknownNameError("per-frame force model", force, STREAMING_FORCE_MODELS)
        if contact not in CONTACT_MODES:
            raise UnknownNameError("contact mode", contact, CONTACT_MODES)
        if not (np.isfinite(dt) and dt > 0):
            raise InvalidInputError(f"dt must be a positive period in seconds; got {dt!r}")
        for r in (demonstrator, imitator):
            if set(r.legs) != set(SIDES):
                from ..errors import LegMatchError

                raise LegMatchError(f"{r.name} legs {sorted(r.legs)} cannot be matched to {SIDES}")
        self.demonstrator, self.imitator = demonstrator, imitator
        self.force, self.dt, self.contact_mode = force, float(dt), contact
        self.weights = weights or Weights()
        self.model = sagittal_model(imitator)
        self.limits = resolve_limits(imitator, self.model.driven, limits)
        self._ipopt = ipopt or {}
        self._solvers: dict[tuple[str, str], ca.Function] = {}
        self._nr = 0
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget the previous frame (the next :meth:`step` starts a new motion at x = 0)."""
        self._x: np.ndarray | None = None
        self._xpp: np.ndarray | None = None
        self._r: np.ndarray | None = None
        self._sole_x = {s: 0.0 for s in SIDES}
        self._down = {s: False for s in SIDES}
        self._since = {s: -1 for s in SIDES}
        self._anchor: str | None = None
        self._k = 0
        self.last: dict = {}

    # ------------------------------------------------------------------ targets
    def frame_targets(self, q: np.ndarray, contact: dict[str, bool]) -> np.ndarray:
        """The demonstrator's targets of one frame as the parameter vector of the problem:
        per side (height ratio, shank angle, ankle angle θ3, push angle), then torso."""
        d = self.demonstrator
        m, data = d.model, d.data
        torso, ang = leg_angles(d, q[None, :])
        pin.forwardKinematics(m, data, q)
        com = pin.centerOfMass(m, data, q) if self.force == "com" else None
        out = []
        for s in SIDES:
            leg = d.legs[s]
            hip = data.oMi[m.getJointId(leg.hip)].translation
            knee = data.oMi[m.getJointId(leg.knee)].translation
            sole = pin.updateFramePlacement(m, data, d.frame_id(leg.sole)).translation
            ankle = data.oMi[m.getJointId(leg.ankle)].translation if leg.ankle else sole
            shank = angle_down(ankle - knee)
            push = shank if self.force == "segment" else angle_down(sole - com)
            out += [(hip[2] - ankle[2]) / leg.length, shank, ang[s][0, 2], push]
        out.append(torso[0])
        return np.array(out, dtype=float)

    # ------------------------------------------------------------------ problem
    def _solver(self, key: tuple[str, str]) -> ca.Function:
        if key in self._solvers:
            return self._solvers[key]
        M, w, robot = self.model, self.weights, self.imitator
        x = ca.SX.sym("x", M.nx)
        tg = ca.SX.sym("tg", 9)
        xp = ca.SX.sym("xp", M.nx)
        hold = ca.SX.sym("hold", 2)
        dt = ca.SX.sym("dt")
        P = M.kin(x)
        ang = M.planar_angles(ca.reshape(x, M.nx, 1))
        res, g, lbg, ubg = [], [], [], []
        com = P[24:27]
        for i, s in enumerate(SIDES):
            leg = robot.legs[s]
            hip, knee = P[12 * i: 12 * i + 3], P[12 * i + 3: 12 * i + 6]
            ankle, sole = P[12 * i + 6: 12 * i + 9], P[12 * i + 9: 12 * i + 12]
            h, sh, a3, push = tg[4 * i], tg[4 * i + 1], tg[4 * i + 2], tg[4 * i + 3]
            vs = ankle - knee
            res.append(np.sqrt(w.height) * ((hip[2] - ankle[2]) / leg.length - h))
            res.append(np.sqrt(w.direction) * (vs[0] * ca.cos(sh) + vs[2] * ca.sin(sh))
                       / leg.shank)
            if leg.ankle is not None:
                res.append(np.sqrt(w.ankle) * (ang[s][2] - a3))
            state = key[i]
            if state == "swing":
                g.append(sole[2])
                lbg.append(0.0)
                ubg.append(np.inf)
                continue
            if self.force == "segment":
                e = (vs[0] * ca.cos(push) + vs[2] * ca.sin(push)) / leg.shank
            else:
                p = sole - com
                e = (p[0] * ca.cos(push) + p[2] * ca.sin(push)) / leg.length
            g += [sole[2], e]
            lbg += [0.0, 0.0]
            ubg += [0.0, 0.0]
            if state == "hold":
                g.append(sole[0] - hold[i])
                lbg.append(0.0)
                ubg.append(0.0)
        res.append(np.sqrt(w.torso) * (x[2] - tg[8]))
        R = ca.vertcat(*res)
        rp = ca.SX.sym("rp", R.shape[0])
        first = ca.SX.sym("first")
        cost = ca.sumsqr(R) + (1 - first) * w.smoothness * ca.sumsqr((R - rp) / dt)
        cost += 1e-8 * ca.sumsqr(x - xp)
        p = ca.vertcat(tg, xp, hold, dt, rp, first)
        nlp = {"x": x, "p": p, "f": cost, "g": ca.vertcat(*g)}
        opts = {"print_time": False, "ipopt": {
            "print_level": 0, "sb": "yes", "tol": 1e-9, "max_iter": 100,
            "mu_strategy": "adaptive", "mu_init": 1e-4, **self._ipopt}}
        solver = ca.nlpsol(f"frame_{key[0]}_{key[1]}", "ipopt", nlp, opts)
        self._solvers[key] = (solver, np.array(lbg), np.array(ubg), ca.Function(
            "res", [x, tg, hold], [R, ca.vertcat(*g)]))
        self._nr = R.shape[0]
        return self._solvers[key]

    def _initial_x(self, q: np.ndarray, tg: np.ndarray) -> np.ndarray:
        d, r = self.demonstrator, self.imitator
        torso, ang = leg_angles(d, q[None, :])
        new = {}
        for s in SIDES:
            a = ang[s]
            e = eq1(a[:, 0], a[:, 1], (d.legs[s].thigh, d.legs[s].shank),
                    (r.legs[s].thigh, r.legs[s].shank))
            new[s] = np.column_stack([e.theta1, e.theta2, a[:, 2]])
        x = self.model.x_of_q(compose_q(r, torso, new, template=self.model.template))[0]
        P = np.array(self.model.kin(x)).ravel()
        x[1] -= min(P[11], P[23])  # lower sole on the ground
        return x

    # ------------------------------------------------------------------ step
    def step(self, q_demo: np.ndarray, contact: dict[str, bool], dt: float | None = None
             ) -> np.ndarray:
        """Adapt one demonstrator configuration ``q_demo`` ``(nq_demo,)`` with its contact
        flags ``{"left": bool, "right": bool}``; ``dt`` [s] since the previous frame (default
        the constructor's). Returns the imitator's configuration ``(nq,)``."""
        q_demo = np.asarray(q_demo, dtype=float)
        if q_demo.shape != (self.demonstrator.model.nq,):
            raise InvalidInputError(f"q_demo must have shape ({self.demonstrator.model.nq},) "
                                    f"for {self.demonstrator.name}; got {q_demo.shape}")
        if set(contact) != set(SIDES):
            raise InvalidInputError(f"contact must give 'left' and 'right'; got {list(contact)}")
        dt = self.dt if dt is None else float(dt)
        c = {s: bool(contact[s]) for s in SIDES}
        tg = self.frame_targets(q_demo, c)
        first = self._x is None
        x0 = self._initial_x(q_demo, tg) if first else self._x
        # which stance feet keep their x: all feet down since before, or only the anchor
        for s in SIDES:
            self._since[s] = -1 if not c[s] else (self._since[s] if self._since[s] >= 0
                                                  else self._k)
        if self._anchor is None or not c[self._anchor]:
            cands = [s for s in SIDES if c[s]]
            self._anchor = min(cands, key=lambda s: self._since[s]) if cands else None
        key = []
        for s in SIDES:
            held = c[s] and self._down[s] and not first
            if self.contact_mode == "anchor" and s != self._anchor:
                held = False
            key.append("swing" if not c[s] else "hold" if held else "touch")
        solver, lbg, ubg, resf = self._solver(tuple(key))
        M, lim = self.model, self.limits
        lbx, ubx = np.full(M.nx, -np.inf), np.full(M.nx, np.inf)
        lbx[3:], ubx[3:] = lim.lower, lim.upper
        if not first:
            vmax = lim.velocity * dt
            lbx[3:] = np.maximum(lbx[3:], self._x[3:] - vmax)
            ubx[3:] = np.minimum(ubx[3:], self._x[3:] + vmax)
            if all(k != "hold" for k in key):  # nothing anchors the base: keep its x
                lbx[0] = ubx[0] = 2 * self._x[0] - self._xpp[0] if self._xpp is not None \
                    else self._x[0]
        else:
            lbx[0] = ubx[0] = 0.0
        x0 = np.clip(x0, np.where(np.isfinite(lbx), lbx, -1e10), np.where(np.isfinite(ubx),
                                                                          ubx, 1e10))
        rp = self._r if self._r is not None else np.zeros(self._nr)
        p = np.concatenate([tg, self._x if not first else x0,
                            [self._sole_x["left"], self._sole_x["right"]], [dt], rp,
                            [1.0 if first else 0.0]])
        sol = solver(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        st = solver.stats()
        x = np.array(sol["x"]).ravel()
        R, gv = (np.array(v).ravel() for v in resf(
            x, tg, [self._sole_x['left'], self._sole_x['right']]))
        viol = float(np.max(np.maximum(lbg - gv, 0) + np.maximum(gv - ubg, 0), initial=0.0))
        bx = float(np.max(np.maximum(lbx - x, 0) + np.maximum(x - ubx, 0)))
        P = np.array(M.kin(x)).ravel()
        for i, s in enumerate(SIDES):
            if c[s]:
                self._sole_x[s] = P[12 * i + 9]
            self._down[s] = c[s]
        self._xpp = self._x
        self._x, self._r = x, R
        self._k += 1
        self.last = {"status": st.get("return_status"), "success": bool(st.get("success")),
                     "iterations": int(st.get("iter_count", 0)),
                     "constraint_violation": max(viol, bx), "contact_state": tuple(key)}
        return M.q_numeric(x)[0]


def adapt_per_frame(demo: Motion, demonstrator: Robot, imitator: Robot, force: str = "segment",
                    limits: Limits | None = None, weights: Weights | None = None,
                    tol: float = 1e-6, ipopt: dict | None = None, contact: str = "all"
                    ) -> AdaptedMotion:
    """Batch use of :class:`StreamingAdaptor` over every frame of ``demo`` (what
    ``adapt(..., method="optimal", mode="per_frame")`` calls). The report's ``solver`` gives
    the status counts, total iterations, time and frames per second; ``feasible`` marks frames
    whose per-frame constraints hold within ``tol``."""
    ad = StreamingAdaptor(demonstrator, imitator, force, limits, weights, demo.dt, contact,
                          ipopt)
    T = demo.T
    q = np.empty((T, imitator.model.nq))
    ok = np.zeros(T, bool)
    statuses: dict[str, int] = {}
    iters = 0
    t0 = time.perf_counter()
    for k in range(T):
        dt = demo.t[k] - demo.t[k - 1] if k else demo.dt
        q[k] = ad.step(demo.q[k], {s: bool(demo.contact[s][k]) for s in SIDES}, dt)
        statuses[ad.last["status"]] = statuses.get(ad.last["status"], 0) + 1
        iters += ad.last["iterations"]
        ok[k] = ad.last["success"] and ad.last["constraint_violation"] <= tol
    elapsed = time.perf_counter() - t0
    out = robot_motion(imitator, demo.t, q, demo.contact)
    report = compare(demonstrator, demo, imitator, out, "optimal", {s: ok for s in SIDES}, force)
    fd = np.nan_to_num(np.abs(np.column_stack([report.force_direction_error[s]
                                               for s in SIDES]))).max(axis=1)
    ok &= fd <= tol
    report.feasible = {s: ok.copy() for s in SIDES}
    report.infeasible_frames = {s: int((~ok).sum()) for s in SIDES}
    if not ok.all():
        report.infeasible_constraint = (f"per-frame constraints not met at {(~ok).sum()} "
                                        f"frame(s), first at t = {demo.t[~ok][0]:.3f} s")
    report.solver = {"mode": "per_frame", "status": statuses, "success": bool(ok.all()),
                     "iterations": iters, "time_s": elapsed, "frames_per_s": T / elapsed,
                     "knots": T}
    report.extra.update({"missing_limits": ad.limits.missing, "contact_mode": contact})
    return AdaptedMotion(motion=out, report=report, robot=imitator)
