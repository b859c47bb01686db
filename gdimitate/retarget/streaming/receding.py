"""The streaming mode's per-frame solve: one inverse-dynamics QP at the committed state.

Frame k's step starts from the committed state ``(q_j, v_j)`` of knot ``j = k − 1`` and
chooses knot j's acceleration ``a_j`` ``(nv,)`` and the wrench ``w_c`` ``(6,)`` of each foot in
stance at j (sole frame, at its centre); the next state follows by exact integration on the
configuration's Lie group, ``v_k = v_j + h a_j``, ``q_k = q_j ⊕ h v_k`` (``pin.integrate``,
the trajectory mode's rule, :class:`~.parts.integration.Integration`). At fixed ``(q_j, v_j)``
the whole-body dynamics ``M a + h = Sᵀτ + Σ J_cᵀ w_c`` is linear in ``(a, w)``, and so is every
row the audit (:mod:`gdimitate.audit`) checks at knot j or, one step ahead, at knot k:

- hard: the base rows of the dynamics (equalities; made exact afterwards by the base
  acceleration), every actuated torque within its effort limit, each stance wrench in its
  contact wrench cone (Caron et al. 2015; friction μ/√2 so that the square pyramid lies inside
  the audit's circular cone; ``f_z ≥ f_min``; the centre of pressure ``cop_margin`` inside),
  knot k's joint velocities and positions within their limits (``v_k``, ``q_j + h v_k``),
  the sole velocity ``J_c(q̂_k) v_k`` of each foot in stance at k (a small feedback back to the
  pose its stance began with), every sole corner of a foot in swing at k above the floor;
- soft (a weighted least-squares cost in the tasks' own units, m/s², rad/s²): centre of mass,
  base orientation, swing-foot pose, posture (PD laws on the frame's reference,
  :mod:`.frameref`), the contact force along the demonstrator's direction, small
  regularisations.

Rows one step ahead are linearised at ``q̂_k = q_j ⊕ h (v_j + h a_prev)`` (the previous
frame's acceleration): the error is second order in ``h (a − a_prev)``. DAQP (dual active
set, exact) solves it. When the hard rows cannot all hold, first the limits and the swing
rows become soft, then everything but the base rows: the QP always answers, and the audit
says which frames it could not make feasible.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import daqp
import numpy as np
import pinocchio as pin

from ...model.kinematics import cross
from ...model.robot import SIDES
from ...model.selfcollision import Proximity, self_collision

__all__ = ["FrameQP", "Tasks", "SOLVED"]

SOLVED = (1, 2)
"""DAQP's exit flags of a solved QP (2: optimal with some soft rows relaxed); :meth:`FrameQP.solve`
returns 1 (every hard row met), 2 (solved with hard rows relaxed) or DAQP's negative flag."""
_EQ, _SOFT = 5, 8
_LIMITS = ("torque", "velocity", "position", "collision")
_LOCAL = pin.ReferenceFrame.LOCAL
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
#: margins inside the hard bounds (fractions of the limit; metres for the floor)
TORQUE_MARGIN, VELOCITY_MARGIN, FLOOR_MARGIN = 1e-3, 1e-3, 5e-4
#: pairs of the robot's own collision geometries closer than COLLISION_WATCH [m] at knot j
#: get a row keeping them COLLISION_MARGIN [m] apart at the next knot
COLLISION_WATCH, COLLISION_MARGIN = 0.03, 1e-3
#: every COLLISION_EVERY-th frame all pairs are measured; in between, those that were closer
#: than COLLISION_NEAR [m] (Talos: 77 of 999 pairs at its neutral pose; 0.07 ms, not 0.75).
#: (Proximity.tracked). Measuring instead only the pairs whose bound (Proximity.bounds) was
#: within COLLISION_WATCH, every frame, changed the motions through coal's cached GJK
#: guesses (Talos on the SFU-style walk: 248 of 265 frames feasible, not 253)
COLLISION_EVERY, COLLISION_NEAR = 5, 0.1
#: re-linearise the next knot's sole rows when the step moves a held foot faster than this [m/s]
AHEAD_TOL, PASSES = 2e-5, 6
#: from the second pass on, a proximal term PROXIMAL/2 |a − a_lin|² [rad/s²]⁻² keeps each pass
#: near the linearisation it is taken at (zero at the fixed point: the solution is the same);
#: without it a flat direction of the cost let the passes jump by 100 rad/s² and oscillate,
#: closing the sole rows' error by half per pass at best, and the soles slipped (iCub 186 →
#: 203, G1 201 → 205 of 205 frames)
PROXIMAL = 0.1


@dataclass
class Tasks:
    """What one frame asks (world axes): centre of mass ``com``, ``com_vel``, ``com_acc``
    ``(3,)``; base rotation ``base_rot`` ``(3, 3)``; swing-foot references ``feet`` {side:
    (position (3,), rotation (3, 3), velocity (6,), acceleration (6,), resting: bool)}; ``joints``,
    ``joints_vel`` ``(n_act,)``; ``push`` {side: unit (3,) direction of the ground force on
    the robot, or None}; ``anchor`` {side: pin.SE3 of a stance foot's sole}; ``land`` {side:
    fraction of a resting swing foot's pose error removed per step, instead of
    :attr:`Gains.rest`} (a late touch-down)."""

    com: np.ndarray
    com_vel: np.ndarray
    com_acc: np.ndarray
    base_rot: np.ndarray
    feet: dict
    joints: np.ndarray
    joints_vel: np.ndarray
    push: dict
    anchor: dict
    land: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Gains:
    """Natural frequencies [rad/s] of the PD laws (critically damped) and task weights."""

    com: float = 8.0
    com_xy: float = 2.0
    w_com_xy: float = 30.0
    w_com_xy_single: float = 300.0
    w_cop: float = 5.0
    base: float = 10.0
    swing: float = 18.0
    posture: float = 10.0
    w_com: float = 30.0
    w_base: float = 10.0
    w_swing: float = 30.0
    w_posture: float = 0.3
    w_legs: float = 0.02
    w_push: float = 10.0
    w_wrench: float = 1e-3
    w_acc: float = 1e-5
    hold: float = 0.01  # fraction of a stance foot's pose error removed per step
    rest: float = 0.2  # the same for a swing foot resting on the floor (a hard row: 0.5 per
    # frame asked G1's legs for 400 rad/s² when a sole landed 2 cm off its rest pose)


def _pd(w: float) -> tuple[float, float]:
    return w * w, 2.0 * w


class FrameQP:
    """The QP of the module docstring for one robot.

    ``robot``: the imitator (its model's limits are the ones enforced: pass the limited copy
    the audit judges); ``contacts`` {side: SoleContact}; ``base_idx``, ``act_idx``: velocity
    indices of the base and of the actuated joints; ``f_min`` [N], ``cop_margin`` [m]."""

    def __init__(self, robot, contacts: dict, base_idx: np.ndarray, act_idx: np.ndarray,
                 f_min: float, cop_margin: float, gains: Gains = Gains()):
        from ...model.kinematics import base_joint_id

        m = robot.model
        self.robot, self.m, self.g = robot, m, gains
        self.d, self.d1 = m.createData(), m.createData()
        self.planar = robot.base == "planar"
        self.comp = np.array([0, 2, 4] if self.planar else range(6))
        self.lin = np.array([0, 2] if self.planar else range(3))
        self.ang = np.array([1] if self.planar else range(3))
        self.base_idx, self.act_idx = np.asarray(base_idx, int), np.asarray(act_idx, int)
        self.root = base_joint_id(robot)
        self.fid = {s: m.getFrameId(contacts[s].frame) for s in SIDES}
        self.corners = {s: contacts[s].corners() for s in SIDES}
        self.cone = {s: _cone(contacts[s], cop_margin)[:, self.comp] for s in SIDES}
        self.f_min = float(f_min)
        self.mg = robot.mass * 9.81
        eff = np.asarray(m.effortLimit)[self.act_idx]
        self.lim_t = np.flatnonzero(np.isfinite(eff) & (eff < 1e30))
        self.effort = eff[self.lim_t]
        vel = np.asarray(m.velocityLimit)[self.act_idx]
        self.lim_v = np.flatnonzero(np.isfinite(vel) & (vel < 1e30) & (vel > 0))
        self.vel = vel[self.lim_v]
        self.pos = _position_rows(m, self.act_idx)
        self.sc = self_collision(robot)  # the audit's pairs (None: no collision geometry)
        if self.sc is not None:
            self.proximity, self.dc, self._count = Proximity(self.sc), m.createData(), 0
        self.q_act = q_of_v(m, self.act_idx)
        legs = {jm for x in SIDES for jm in m.supports[m.frames[self.fid[x]].parentJoint]}
        leg_v = {m.joints[j].idx_v for j in legs if j > 0}
        #: the legs follow the feet, centre of mass and base: their posture only regularises
        self.posture_w = np.array([gains.w_legs if i in leg_v else 1.0 for i in self.act_idx])
        self.nw = len(self.comp)
        self.wscale = np.where(np.arange(6)[self.comp] < 3, 1.0, 0.3) * self.mg
        # the centre of pressure drawn to the sole's centre: the moments τ_x, τ_y [N·m] in
        # units of m·g·(10 cm)
        self.cop_w = np.where(np.isin(np.arange(6)[self.comp], (3, 4)),
                              gains.w_cop / (0.1 * self.mg) ** 2, 0.0)
        # the cost's constant parts, made once: the regularisations, the posture rows
        nv, na = m.nv, self.act_idx.size
        self._acc_reg = gains.w_acc * np.eye(nv)
        self._wrench_reg = np.diag(gains.w_wrench / self.wscale**2 + self.cop_w)
        self._posture_J = np.zeros((na, nv))
        self._posture_J[np.arange(na), self.act_idx] = 1.0
        self._com_w = {n: np.where(self.lin == 2, gains.w_com, w) for n, w in
                       ((1, gains.w_com_xy_single), (2, gains.w_com_xy))}
        self._lower = np.tril_indices(nv, -1)  # M's lower triangle, from its upper

    # ------------------------------------------------------------------ model terms
    def _terms(self, q: np.ndarray, v: np.ndarray) -> dict:
        m, d, nv = self.m, self.d, self.m.nv
        pin.forwardKinematics(m, d, q, v, np.zeros(nv))
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        t: dict[str, Any] = {"feet": {}}
        for s in SIDES:
            f = self.fid[s]
            t["feet"][s] = (d.oMf[f].copy(), pin.getFrameVelocity(m, d, f, _LWA).vector.copy(),
                            pin.getFrameClassicalAcceleration(m, d, f, _LWA).vector.copy(),
                            pin.getFrameJacobian(m, d, f, _LOCAL).copy(),
                            pin.getFrameJacobian(m, d, f, _LWA).copy())
        Rb = d.oMi[self.root].rotation.copy()
        t["base"] = (Rb, Rb @ d.v[self.root].angular, Rb @ d.a[self.root].angular,
                     pin.getJointJacobian(m, d, self.root, _LWA)[3:].copy())
        pin.centerOfMass(m, d, q, v, np.zeros(nv))
        t["com"] = (d.com[0].copy(), d.vcom[0].copy(), d.acom[0].copy(),
                    pin.jacobianCenterOfMass(m, d, q, False).copy())
        M = pin.crba(m, d, q).copy()
        M[self._lower] = M.T[self._lower]
        t["M"] = M
        t["h"] = pin.nonLinearEffects(m, d, q, v).copy()
        return t

    def _ahead(self, q_hat: np.ndarray, v_hat: np.ndarray, held: dict) -> dict:
        """At the predicted next state, per sole: for a foot in ``held`` (:meth:`_held`) its
        LOCAL velocity ``J(q̂) v̂`` ``(6,)`` and that velocity's derivatives with respect to
        ``q`` (tangent) and ``v`` (= the LOCAL Jacobian); for the others, its placement and
        LOCAL_WORLD_ALIGNED Jacobian."""
        m, d = self.m, self.d1
        pin.computeForwardKinematicsDerivatives(m, d, q_hat, v_hat, np.zeros(m.nv))
        out: dict[str, tuple] = {}
        for s, f in self.fid.items():
            if s in held:
                dq, dv = pin.getFrameVelocityDerivatives(m, d, f, _LOCAL)
                out[s] = (pin.getFrameVelocity(m, d, f, _LOCAL).vector.copy(), dq, dv)
            else:
                out[s] = (pin.updateFramePlacement(m, d, f),
                          pin.getFrameJacobian(m, d, f, _LWA))
        return out

    # ------------------------------------------------------------------ the QP
    def solve(self, q, v, h: float, now: dict, nxt: dict, tk: Tasks, a_prev: np.ndarray
              ) -> tuple[np.ndarray, dict, int]:
        """``(a (nv,), wrenches {side: (6,)}, DAQP flag)`` at state ``(q, v)`` with step ``h``
        [s], stance flags ``now`` (knot j) and ``nxt`` (knot k) and the frame's tasks."""
        t = self._terms(q, v)
        stance = [s for s in SIDES if now[s]]
        nv, nw = self.m.nv, self.nw
        n = nv + nw * len(stance)
        self._qa = q[self.q_act]
        H, f = self._cost(t, v, tk, stance, nxt, n)
        S = np.ones(n)  # the wrenches in units of m·g: a well-scaled QP
        S[nv:] = self.mg
        H, f = H * S[:, None] * S[None], f * S
        fixed = _Rows(n)  # the rows at knot j: built once
        self._dynamics(fixed, t, stance)
        self._limits(fixed, q, v, h)
        self._collisions(fixed, q, v, h)
        A0, up0, lo0, sense0, kind0 = fixed.stack()
        A0 = A0 * S[None]
        a_lin = a_prev.copy()  # the previous frame's acceleration: a first guess of q_k
        held = self._held(t, h, nxt, tk)
        best: tuple[float, np.ndarray, int] | None = None
        x, flag = np.zeros(n), 1  # set by the first pass
        for i in range(PASSES + 1):  # rows one step ahead, linearised again at each pass's q_k
            v_hat = v + h * a_lin
            q_hat = pin.integrate(self.m, q, h * v_hat)
            if i:  # how well the last pass's soles hold: the pass whose hold best is kept
                err = self._sole_error(t, v, h, held, q_hat, v_hat, a_lin)
                if best is None or err < best[0]:
                    best = (err, x, flag)
                if err < AHEAD_TOL or flag != 1 or i == PASSES:  # (hard rows relaxed: the
                    break  # frame fails anyway; no refinement)
            rows = _Rows(n)
            self._feet_ahead(rows, t, v, h, held, self._ahead(q_hat, v_hat, held), a_lin)
            A, up, lo, sense, kind = rows.stack()
            Hp, fp = H, f
            if i and PROXIMAL > 0:  # a proximal term ρ/2 |a − a_lin|²: zero at the fixed point
                Hp, fp = H.copy(), f.copy()
                Hp[np.arange(nv), np.arange(nv)] += PROXIMAL
                fp[:nv] -= PROXIMAL * a_lin
            x, flag = _solve(Hp, fp, np.vstack([A0, A * S[None]]), np.concatenate([up0, up]),
                             np.concatenate([lo0, lo]), np.concatenate([sense0, sense]),
                             np.concatenate([kind0, kind]))
            x = x * S
            a_lin = x[:nv].copy()
        assert best is not None
        _, x, flag = best
        a = x[:nv].copy()
        W = {s: np.zeros(6) for s in SIDES}
        for i, s in enumerate(stance):
            W[s][self.comp] = x[nv + nw * i: nv + nw * (i + 1)]
        self._exact_base(a, t, W, stance)
        return a, W, flag

    def _cost(self, t, v, tk: Tasks, stance, nxt, n) -> tuple[np.ndarray, np.ndarray]:
        g, nv, nw = self.g, self.m.nv, self.nw
        J, r, w = [], [], []

        def task(Jt, target, weight):
            J.append(Jt)
            r.append(target)
            w.append(np.full(len(target), weight))

        c, vc, dc, Jc = t["com"]
        kp, kd = _pd(g.com)
        kp_com = np.array([g.com_xy**2, kp, kp])  # along the walk (x): mostly the velocity
        acc = tk.com_acc + kp_com * (tk.com - c) + kd * (tk.com_vel - vc) - dc
        J.append(Jc[self.lin])
        r.append(acc[self.lin])
        # horizontally in single support the centre of mass is left to its pendulum dynamics
        # (the steps, placed at the capture point, govern it); in double support it follows
        # the demonstrator's velocity
        w.append(self._com_w[2 if len(stance) > 1 else 1])
        Rb, wb, db, Jb = t["base"]
        kp, kd = _pd(g.base)
        acc = kp * pin.log3(tk.base_rot @ Rb.T) - kd * wb - db
        task(Jb[self.ang], acc[self.ang], g.w_base)
        kp, kd = _pd(g.swing)
        for s in SIDES:
            if nxt[s] or s not in tk.feet or tk.feet[s][4]:
                continue
            oMf, vel, drift, _, Jw = t["feet"][s]
            p, R, vr, ar, _ = tk.feet[s]
            e = np.concatenate([p - oMf.translation, pin.log3(R @ oMf.rotation.T)])
            acc = ar + kp * e + kd * (vr - vel) - drift
            task(Jw[self.comp], acc[self.comp], g.w_swing)
        kp, kd = _pd(g.posture)
        qa = self._qa
        acc = kp * (tk.joints - qa) + kd * (tk.joints_vel - v[self.act_idx])
        J.append(self._posture_J)
        r.append(acc)
        w.append(g.w_posture * self.posture_w)
        Jt = np.zeros((sum(len(x) for x in r), n))
        Jt[:, :nv] = np.vstack(J)
        wt, rt = np.concatenate(w), np.concatenate(r)
        H = Jt.T @ (wt[:, None] * Jt)
        f = -Jt.T @ (wt * rt)
        H[:nv, :nv] += self._acc_reg
        for i, s in enumerate(stance):
            sl = slice(nv + nw * i, nv + nw * (i + 1))
            H[sl, sl] += self._wrench_reg
            d = tk.push.get(s)
            if d is not None:  # the force along d: its components across d vanish
                R = t["feet"][s][0].rotation
                E = _across(d) @ R  # (2, 3): e_i · (R f)
                B = np.zeros((E.shape[0], nw))
                B[:, :self.lin.size] = E[:, self.lin]
                H[sl, sl] += g.w_push / self.mg**2 * B.T @ B
        return H, f

    def _dynamics(self, rows, t, stance) -> None:
        nv, nw = self.m.nv, self.nw
        M, hh = t["M"], t["h"]
        D = np.zeros((nv, rows.n))
        D[:, :nv] = M
        for i, s in enumerate(stance):
            D[:, nv + nw * i: nv + nw * (i + 1)] = -t["feet"][s][3][self.comp].T
            C = np.zeros((self.cone[s].shape[0] + 1, rows.n))
            C[:-1, nv + nw * i: nv + nw * (i + 1)] = self.cone[s]
            C[-1, nv + nw * i + (1 if self.planar else 2)] = -1.0
            ub = np.zeros(C.shape[0])
            ub[-1] = -self.f_min
            ub[:-1] = -1e-7 * self.mg
            rows.add(C, ub, np.full(C.shape[0], -1e30), 0, "hard")
        rows.add(D[self.base_idx], -hh[self.base_idx], -hh[self.base_idx], _EQ, "base")
        if self.lim_t.size:
            Dt = D[self.act_idx[self.lim_t]]
            ht, e = hh[self.act_idx[self.lim_t]], self.effort * (1 - TORQUE_MARGIN)
            rows.add(Dt / self.effort[:, None], (e - ht) / self.effort,
                     (-e - ht) / self.effort, 0, "torque")

    def _limits(self, rows, q, v, h) -> None:
        if self.lim_v.size:
            i = self.act_idx[self.lim_v]
            A = np.zeros((i.size, rows.n))
            A[np.arange(i.size), i] = h / self.vel
            vl = self.vel * (1 - VELOCITY_MARGIN)
            rows.add(A, (vl - v[i]) / self.vel, (-vl - v[i]) / self.vel, 0, "velocity")
        vi, qi, lo, hi = self.pos
        if vi.size:
            A = np.zeros((vi.size, rows.n))
            A[np.arange(vi.size), vi] = h * h
            now = q[qi] + h * v[vi]
            rows.add(A, hi - now, lo - now, 0, "position")

    def _collisions(self, rows, q, v, h) -> None:
        """Each pair of the robot's own collision geometries (the audit's,
        :mod:`gdimitate.model.selfcollision`) closer than :data:`COLLISION_WATCH` at knot j stays
        :data:`COLLISION_MARGIN` apart at knot k, to first order: ``d + h ḋ(v_k) ≥ margin``
        with ``ḋ = nᵀ (ṗ_b − ṗ_a)`` at the nearest points (``n`` from a to b), ``v_k = v + h a``.
        iCub's chest came down onto its swinging thigh (8 cm deep) when it leaned as the
        demonstrator does."""
        if self.sc is None:
            return
        m, d = self.m, self.dc
        pin.computeJointJacobians(m, d, q)
        _, dist, Jd = self.proximity.tracked(d, q, self._count % COLLISION_EVERY == 0,
                                             COLLISION_NEAR, COLLISION_WATCH)
        self._count += 1
        if dist.size:
            M = np.zeros((dist.size, rows.n))
            M[:, :m.nv] = h * h * Jd
            rows.add(M, np.full(dist.size, 1e30), COLLISION_MARGIN - dist - h * Jd @ v, 0,
                     "collision")

    def _held(self, t, h: float, nxt: dict, tk: Tasks) -> dict:
        """``{side: u (6,)}``: the LOCAL sole velocity [m/s, rad/s] asked of each foot held
        at the next knot — in stance (back towards the pose its stance began with) or
        resting in swing (towards its rest pose) — over the step ``h`` [s]; read at knot j's
        pose (fixed: taken at q_k it would move with a, and the passes would close only half
        the rest gain's share per pass)."""
        out = {}
        for s in SIDES:
            rest = not nxt[s] and s in tk.feet and tk.feet[s][4]
            if not (nxt[s] or rest):
                continue
            now = t["feet"][s][0]
            if rest:
                p, R = tk.feet[s][0], tk.feet[s][1]
                out[s] = (tk.land.get(s, self.g.rest)
                          * pin.log6(now.actInv(pin.SE3(R, p))).vector / h)
            elif s in tk.anchor:
                out[s] = self.g.hold * pin.log6(now.actInv(tk.anchor[s])).vector / h
            else:  # touch-down: still
                out[s] = np.zeros(6)
        return out

    def _sole_error(self, t, v, h: float, held: dict, q_hat, v_hat, a_lin) -> float:
        """How far the held feet (:meth:`_held`) would move, at ``a_lin``, from what their
        rows ask [m/s]: the midpoint velocity ``½ (J(q_j) v_k + J(q̂_k) v̂_k)`` less ``u``
        (``q̂_k``, ``v̂_k``: the state ``a_lin`` leads to)."""
        if not held:
            return 0.0
        m, d = self.m, self.d1
        pin.forwardKinematics(m, d, q_hat, v_hat)
        err = 0.0
        for s, u in held.items():
            vel = pin.getFrameVelocity(m, d, self.fid[s], _LOCAL).vector
            mid = 0.5 * (t["feet"][s][3] @ (v + h * a_lin) + vel)
            err = max(err, float(np.max(np.abs(mid - u))))
        return err

    def _feet_ahead(self, rows, t, v, h, held: dict, ahead, a_lin) -> None:
        """Rows of the next knot's soles: a held foot's (:meth:`_held`) velocity, a swinging
        foot's corners above the floor."""
        nv = self.m.nv
        for s in SIDES:
            if s in held:
                vel, dq, Jl = ahead[s]
                # J(q_k) v_k = u: a Newton row in a, q_k = q ⊕ h v_k, v_k = v + h a
                # (both through a); the midpoint rule ½ (J(q_j) + J(q_k)) v_k = u: the sole
                # moves by h·u over the step (not only ends it still), so that it does not
                # drift knot by knot
                Jj = t["feet"][s][3]
                D = 0.5 * (h * Jj + h * Jl + h * h * dq)[self.comp]
                mid = 0.5 * (Jj @ (v + h * a_lin) + vel)
                A = np.zeros((self.nw, rows.n))
                A[:, :nv] = D
                b = (held[s] - mid)[self.comp] + D @ a_lin
                rows.add(A, b, b, _EQ, "stance")
                continue
            oMf, Jw = ahead[s]
            R, p = oMf.rotation, oMf.translation
            rc = self.corners[s] @ R.T  # corner offsets, world axes (4, 3)
            z = p[2] + rc[:, 2]
            Jz = Jw[2][None] + Jw[3][None] * rc[:, [1]] - Jw[4][None] * rc[:, [0]]
            A = np.zeros((4, rows.n))
            A[:, :nv] = h * h * Jz
            lb = -FLOOR_MARGIN - z + h * h * Jz @ a_lin
            rows.add(A, np.full(4, 1e30), lb, 0, "swing")

    def _exact_base(self, a, t, W, stance) -> None:
        """The base rows exact: ``a``'s base components absorb the QP's round-off."""
        M, hh = t["M"], t["h"]
        r = M @ a + hh
        for s in stance:
            r -= t["feet"][s][3].T @ W[s]
        b = self.base_idx
        a[b] -= np.linalg.solve(M[b][:, b], r[b])


class _Rows:
    """Constraint rows ``lo ≤ A x ≤ up`` of ``n`` variables added block by block, each block
    with its DAQP sense and its kind (which relaxation softens it, :func:`_solve`)."""

    def __init__(self, n: int):
        self.n = n
        self.A: list[np.ndarray] = []
        self.up: list[np.ndarray] = []
        self.lo: list[np.ndarray] = []
        self.tags: list[tuple[int, str]] = []
        self.count: list[int] = []

    def add(self, A, up, lo, sense, kind) -> None:
        self.A.append(A)
        self.up.append(np.asarray(up, float))
        self.lo.append(np.asarray(lo, float))
        self.tags.append((sense, kind))
        self.count.append(A.shape[0])

    def stack(self):
        sense, kind = zip(*self.tags)
        return (np.vstack(self.A), np.concatenate(self.up), np.concatenate(self.lo),
                np.repeat(np.array(sense, np.intc), self.count),
                np.repeat(np.array(kind), self.count))


def _solve(H, f, A, up, lo, sense, kind) -> tuple[np.ndarray, int]:
    """DAQP with every hard row (flag 1); failing that, the limits and swing rows soft, then
    every row but the base rows (flag 2: solved with hard rows relaxed); else a negative
    flag and the unconstrained minimiser."""
    up, lo = np.minimum(up, 1e30), np.maximum(lo, -1e30)
    x, _, flag, _ = daqp.solve(H, f, A, up, lo, sense)
    if flag in SOLVED:
        return np.asarray(x), 1
    for soft in (_LIMITS + ("swing",), _LIMITS + ("swing", "hard", "stance")):
        s = sense.copy()
        s[np.isin(kind, soft)] = _SOFT
        x, _, flag, _ = daqp.solve(H, f, A, up, lo, s)
        if flag in SOLVED:
            return np.asarray(x), 2
    return np.linalg.lstsq(H + 1e-9 * np.eye(H.shape[0]), -f, rcond=None)[0], int(flag)


def _cone(c, margin: float) -> np.ndarray:
    """``(16, 6)`` wrench cone rows ``A w ≤ 0`` of sole ``c`` with friction μ/√2 (the square
    pyramid inside the circular cone) and the centre-of-pressure rows ``margin`` inside."""
    from ...model.contact import wrench_cone

    return wrench_cone(c.half_length, c.half_width, c.mu / np.sqrt(2),
                       cop_length=c.half_length - margin, cop_width=c.half_width - margin)


def _across(d: np.ndarray) -> np.ndarray:
    """``(2, 3)``: two unit vectors orthogonal to the unit vector ``d``."""
    ref = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = ref - (ref @ d) * d
    e1 /= np.linalg.norm(e1)
    return np.array([e1, cross(d, e1)])


def q_of_v(m, vi: np.ndarray) -> np.ndarray:
    """``q`` index of each 1-dof velocity index in ``vi`` (joints with nq = nv = 1)."""
    q_of = {}
    for j in range(1, m.njoints):
        jm = m.joints[j]
        for k in range(jm.nv):
            q_of[jm.idx_v + k] = jm.idx_q + k if jm.nq == jm.nv else jm.idx_q
    return np.array([q_of.get(int(k), 0) for k in vi], int)


def _position_rows(m, act_idx: np.ndarray):
    """``(v index, q index, lower, upper)`` of the 1-dof actuated joints with finite limits."""
    vi, qi, lo, hi = [], [], [], []
    for j in range(1, m.njoints):
        jm = m.joints[j]
        if jm.nq == 1 and jm.nv == 1 and jm.idx_v in set(act_idx.tolist()):
            a, b = m.lowerPositionLimit[jm.idx_q], m.upperPositionLimit[jm.idx_q]
            if abs(a) < 1e30 and abs(b) < 1e30 and a < b:
                vi.append(jm.idx_v)
                qi.append(jm.idx_q)
                lo.append(a)
                hi.append(b)
    return np.array(vi, int), np.array(qi, int), np.array(lo), np.array(hi)
