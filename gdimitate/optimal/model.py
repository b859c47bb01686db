"""The imitator as the optimiser sees it: a sagittal parametrisation and its CasADi functions.

Per knot the decision vector is ``x = [base_x, base_z, θ, q_d]`` ``(nx,)`` — the floating base's
forward position and height [m], the torso's planar angle θ [rad] (DESIGN §4's sign: positive
leaning forward) and the *driven* joints ``q_d`` [rad]: hip pitch, knee and ankle pitch of the
left leg, then of the right leg (no ankle for point-footed robots). Every other joint is held at
a neutral template pose (clipped into its position limits). The full Pinocchio configuration is
built symbolically: for a free-flyer the base quaternion is ``q_y(−θ) ⊗ q(base_rotation)``, unit
by construction, so the optimiser never has to keep a quaternion normalised.

Velocities and accelerations come from finite differences of ``x`` over the knots
(:func:`difference_matrices`); :meth:`SagittalModel.pin_va` turns ``(x, ẋ, ẍ)`` into Pinocchio's
``(v, a)`` (for a free-flyer the base's are expressed in the base frame: ``v_lin = Rᵀṗ``,
``a_lin = Rᵀp̈ − ω × v_lin``).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import casadi as ca
import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError, LegMatchError
from ..robot import PLANAR_BASE, SIDES, Robot
from ..symbolic import SymbolicModel

__all__ = ["SagittalModel", "difference_matrices", "KIN_POINTS", "robot_key"]

#: Points the kinematic function returns, per side, then the centre of mass.
KIN_POINTS = ("hip", "knee", "ankle", "sole")


def difference_matrices(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(D1, D2)``, each ``(T, T)``: first and second time derivatives on the grid ``t`` [s].

    ``D1`` is NumPy's ``gradient`` (second-order central differences, one-sided at the ends —
    what :meth:`Motion.velocity` uses); ``D2`` the compact three-point second difference on a
    non-uniform grid, copied from the neighbour at the two ends.
    """
    t = np.asarray(t, dtype=float)
    T = t.size
    D1 = np.gradient(np.eye(T), t, axis=0)
    D2 = np.zeros((T, T))
    for k in range(1, T - 1):
        h0, h1 = t[k] - t[k - 1], t[k + 1] - t[k]
        D2[k, k - 1] = 2.0 / (h0 * (h0 + h1))
        D2[k, k] = -2.0 / (h0 * h1)
        D2[k, k + 1] = 2.0 / (h1 * (h0 + h1))
    if T >= 3:
        D2[0], D2[-1] = D2[1], D2[-2]
    return D1, D2


def _quat_mul(a: ca.SX, b: np.ndarray) -> ca.SX:
    """Hamilton product ``a ⊗ b`` of quaternions stored ``(x, y, z, w)``."""
    av, aw = a[:3], a[3]
    bv, bw = ca.SX(b[:3]), float(b[3])
    v = aw * bv + bw * av + ca.cross(av, bv)
    return ca.vertcat(v, aw * bw - ca.dot(av, bv))


def _rot_y(phi: ca.SX) -> ca.SX:
    c, s = ca.cos(phi), ca.sin(phi)
    return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))


@dataclass(frozen=True)
class _Index:
    base_q: tuple[int, ...]   # q indices of (x, z) for free, (base_x, base_z, base_pitch) planar
    driven_q: tuple[int, ...]
    driven_v: tuple[int, ...]
    base_v: tuple[int, ...]   # v rows of the unactuated base


class SagittalModel:
    """A robot reduced to the sagittal decision vector ``x`` (module docstring).

    Attributes: ``robot``; ``sym`` (:class:`~gdimitate.symbolic.SymbolicModel`); ``driven``
    (joint names in ``x[3:]`` order); ``nx``; ``template`` ``(nq,)`` (held joints' values);
    ``nw`` (contact wrench components per foot: 3 for planar models — fx, fz, my — 6 for a
    free-flyer); ``kin``: ``casadi.Function`` ``x -> (3·(4·2 + 1),)``: world positions of hip,
    knee, ankle (sole when there is no ankle) and sole of the left then right leg, then the
    centre of mass; ``dyn``: ``(x, ẋ, ẍ, w_left, w_right) -> (τ_base, τ_driven)`` (built on
    first use).
    """

    def __init__(self, robot: Robot):
        if robot.base not in ("planar", "free"):
            raise LegMatchError(f"{robot.name} has a {robot.base} base; the optimal adaptor "
                                "needs a floating base (planar or free-flyer)")
        self.robot = robot
        m = robot.model
        self.sym = SymbolicModel(m)
        driven = []
        for s in SIDES:
            leg = robot.legs[s]
            driven += [j for j in (leg.hip, leg.knee, leg.ankle) if j is not None]
        self.driven: tuple[str, ...] = tuple(driven)
        self.nx = 3 + len(driven)
        self.nw = 3 if robot.base == "planar" else 6
        tmpl = robot.neutral.copy()
        for j in robot.joint_names:  # held joints: neutral, clipped into the position limits
            jm = m.joints[m.getJointId(j)]
            if jm.nq != 1 or j in PLANAR_BASE:
                continue
            lo, hi = m.lowerPositionLimit[jm.idx_q], m.upperPositionLimit[jm.idx_q]
            if np.isfinite(lo) and np.isfinite(hi) and lo < hi:
                tmpl[jm.idx_q] = np.clip(tmpl[jm.idx_q], lo, hi)
        self.template = tmpl
        if robot.base == "planar":
            base_q = tuple(robot.idx_q(b) for b in PLANAR_BASE)
            base_v = tuple(robot.idx_v(b) for b in PLANAR_BASE)
        else:
            base_q, base_v = (0, 2), tuple(range(6))
        self.idx = _Index(base_q=base_q, driven_q=tuple(robot.idx_q(j) for j in driven),
                          driven_v=tuple(robot.idx_v(j) for j in driven), base_v=base_v)
        # planar angle = sign*q + offset for driven joints (hip relative to the torso)
        sg, off = [], []
        for s in SIDES:
            leg = robot.legs[s]
            for k, j in enumerate((leg.hip, leg.knee, leg.ankle)):
                if j is not None:
                    sg.append(leg.signs[k])
                    off.append(leg.offsets[k])
        self.signs = np.array(sg)
        self.offsets = np.array(off)
        self._build_kin()
        self._dyn: ca.Function | None = None
        self._base_wrench: ca.Function | None = None
        self._maps: dict[tuple[str, int], ca.Function] = {}
        self.key: str = robot_key(robot)

    # ------------------------------------------------------------------ configuration
    def q_of_x(self, x: ca.SX) -> ca.SX:
        """Full configuration ``(nq,)`` from ``x`` ``(nx,)`` (SX)."""
        q = ca.SX(self.template)
        q = ca.SX(q)
        if self.robot.base == "planar":
            for k, i in enumerate(self.idx.base_q):
                q[i] = x[k]
        else:
            q[0], q[2] = x[0], x[1]
            half = -x[2] / 2  # rotation about +y by φ = −θ
            qy = ca.vertcat(0, ca.sin(half), 0, ca.cos(half))
            q0 = pin.Quaternion(self.robot.base_rotation).coeffs()
            q[3:7] = _quat_mul(qy, np.asarray(q0))
        for k, i in enumerate(self.idx.driven_q):
            q[i] = x[3 + k]
        return q

    def x_of_q(self, q: np.ndarray) -> np.ndarray:
        """Decision vectors ``(T, nx)`` of configurations ``(T, nq)`` (the torso angle read as
        :func:`gdimitate.sagittal.torso_angle` does)."""
        from ..sagittal import torso_angle

        q = np.atleast_2d(np.asarray(q, dtype=float))
        x = np.empty((len(q), self.nx))
        x[:, 0] = q[:, self.idx.base_q[0]]
        x[:, 1] = q[:, self.idx.base_q[1]]
        x[:, 2] = torso_angle(self.robot, q)
        x[:, 3:] = q[:, list(self.idx.driven_q)]
        return x

    def q_numeric(self, x: np.ndarray) -> np.ndarray:
        """Configurations ``(T, nq)`` of decision vectors ``(T, nx)``."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        return np.array(self._q_fun(x.T)).T

    def pin_va(self, x: ca.SX, xd: ca.SX, xdd: ca.SX) -> tuple[ca.SX, ca.SX]:
        """Pinocchio ``(v, a)`` ``(nv,)`` from ``x`` and its time derivatives (SX)."""
        nv = self.robot.model.nv
        v, a = ca.SX.zeros(nv), ca.SX.zeros(nv)
        if self.robot.base == "planar":
            for k, i in enumerate(self.idx.base_v):
                v[i], a[i] = xd[k], xdd[k]
        else:
            R = ca.mtimes(_rot_y(-x[2]), ca.SX(self.robot.base_rotation))
            pd = ca.vertcat(xd[0], 0, xd[1])
            pdd = ca.vertcat(xdd[0], 0, xdd[1])
            w = ca.mtimes(R.T, ca.vertcat(0, -xd[2], 0))
            vl = ca.mtimes(R.T, pd)
            v[0:3], v[3:6] = vl, w
            a[0:3] = ca.mtimes(R.T, pdd) - ca.cross(w, vl)
            a[3:6] = ca.mtimes(R.T, ca.vertcat(0, -xdd[2], 0))
        for k, i in enumerate(self.idx.driven_v):
            v[i], a[i] = xd[3 + k], xdd[3 + k]
        return v, a

    def wrench6(self, w: ca.SX) -> ca.SX:
        """World wrench ``(6,)`` [force; torque] from the ``(nw,)`` variables of one foot."""
        if self.nw == 6:
            return w
        return ca.vertcat(w[0], 0, w[1], 0, w[2], 0)

    # ------------------------------------------------------------------ functions
    def _build_kin(self) -> None:
        x = ca.SX.sym("x", self.nx)
        q = self.q_of_x(x)
        self._q_fun = ca.Function("q_of_x", [x], [q])
        pts = []
        for s in SIDES:
            leg = self.robot.legs[s]
            names = (leg.hip, leg.knee, leg.ankle if leg.ankle else leg.sole, leg.sole)
            for n in names:
                pts.append(self.sym.frame_position(n)(q))
        pts.append(self.sym.com(q))
        self.kin = ca.Function("kin", [x], [ca.vertcat(*pts)], ["x"], ["p"])

    def point(self, p: ca.SX | ca.MX | np.ndarray, side: str, what: str):
        """Slice ``(3,)`` of a ``kin`` output: ``what`` in :data:`KIN_POINTS`, or ``"com"``."""
        if what == "com":
            return p[24:27, :]
        k = SIDES.index(side) * 4 + KIN_POINTS.index(what)
        return p[3 * k: 3 * k + 3, :]

    @property
    def dyn(self) -> ca.Function:
        """``(x, ẋ, ẍ, w_left (nw,), w_right (nw,)) -> (τ_base, τ_driven)``: the inverse
        dynamics of the base (must vanish) and of the driven joints [N, N·m]."""
        if self._dyn is None:
            x, xd, xdd = (ca.SX.sym(n, self.nx) for n in ("x", "xd", "xdd"))
            wl, wr = ca.SX.sym("wl", self.nw), ca.SX.sym("wr", self.nw)
            q = self.q_of_x(x)
            v, a = self.pin_va(x, xd, xdd)
            soles = [self.robot.legs[s].sole for s in SIDES]
            tau = self.sym.rnea_contact(soles)(q, v, a, self.wrench6(wl), self.wrench6(wr))
            base = ca.vertcat(*[tau[i] for i in self.idx.base_v])
            drv = ca.vertcat(*[tau[i] for i in self.idx.driven_v])
            self._dyn = ca.Function("dyn", [x, xd, xdd, wl, wr], [base, drv],
                                    ["x", "xd", "xdd", "wl", "wr"], ["tau_base", "tau"])
        return self._dyn

    @property
    def base_wrench(self) -> ca.Function:
        """``(x, ẋ, ẍ) -> (τ_base at zero wrench, ∂τ_base/∂(w_left, w_right))``: the base rows
        of the inverse dynamics are affine in the contact wrenches (built on first use)."""
        if self._base_wrench is None:
            x, xd, xdd = (ca.SX.sym(n, self.nx) for n in ("x", "xd", "xdd"))
            wv = ca.SX.sym("w", 2 * self.nw)
            tb = self.dyn(x, xd, xdd, wv[:self.nw], wv[self.nw:])[0]
            jac = ca.jacobian(tb, wv)
            tb0, jac0 = (ca.substitute(e, wv, ca.DM.zeros(2 * self.nw)) for e in (tb, jac))
            self._base_wrench = ca.Function("base_wrench", [x, xd, xdd], [tb0, jac0])
        return self._base_wrench

    def base_wrench_map(self, T: int) -> ca.Function:
        """:attr:`base_wrench` mapped over ``T`` knots (cached per ``T``)."""
        key = ("base_wrench", T)
        if key not in self._maps:
            self._maps[key] = self.base_wrench.map(T)
        return self._maps[key]

    def dyn_map(self, T: int) -> ca.Function:
        """:attr:`dyn` mapped over ``T`` knots (cached per ``T``)."""
        key = ("dyn", T)
        if key not in self._maps:
            self._maps[key] = self.dyn.map(T)
        return self._maps[key]

    def planar_angles(self, x) -> dict[str, list]:
        """Per side the planar ``[θ1 absolute, θ2, θ3]`` rows of decision vectors ``x`` of shape
        ``(nx, n)`` (SX, MX or a 2-D NumPy array); θ3 is 0 for legs without an ankle."""
        out, k = {}, 3
        for s in SIDES:
            leg = self.robot.legs[s]
            rows = []
            for j in (leg.hip, leg.knee, leg.ankle):
                if j is None:
                    rows.append(0 * x[2, :])
                    continue
                i = k - 3
                rows.append(self.signs[i] * x[k, :] + self.offsets[i])
                k += 1
            rows[0] = rows[0] + x[2, :]
            out[s] = rows
        return out


def robot_key(robot: Robot) -> str:
    """A fingerprint of everything a :class:`SagittalModel` is built from: the Pinocchio model
    (joint types, placements, inertias, frames, position limits, gravity), the legs, the base
    and its orientation and the neutral pose. Two robots with the same key give the same
    model, so a model (and the NLPs built on it) can be shared between them."""
    m = robot.model
    h = hashlib.sha1()
    h.update(repr((robot.name, robot.base, tuple(m.names), tuple(m.parents), m.nq, m.nv,
                   tuple(j.shortname() for j in m.joints),
                   tuple(sorted((s, repr(leg)) for s, leg in robot.legs.items())))).encode())
    arrs = [np.asarray(robot.base_rotation, float), np.asarray(robot.neutral, float),
            np.asarray(m.lowerPositionLimit, float), np.asarray(m.upperPositionLimit, float),
            np.asarray(m.gravity.linear, float)]
    arrs += [np.asarray(p.homogeneous) for p in m.jointPlacements]
    arrs += [np.asarray(i.toDynamicParameters()) for i in m.inertias]
    for f in m.frames:
        h.update(f"{f.name}:{int(f.parentJoint)};".encode())
        arrs.append(np.asarray(f.placement.homogeneous))
    for a in arrs:
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()


def check_same_legs(demonstrator: Robot, imitator: Robot) -> None:
    """Raise :class:`LegMatchError` when the two robots' legs cannot be paired."""
    for r in (demonstrator, imitator):
        if set(r.legs) != set(SIDES):
            raise LegMatchError(f"{r.name} legs {sorted(r.legs)} cannot be matched to {SIDES}")
    for s in SIDES:
        if demonstrator.legs[s].length <= 0 or imitator.legs[s].length <= 0:
            raise InvalidInputError(f"{s} leg of zero length")
