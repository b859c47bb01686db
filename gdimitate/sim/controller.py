"""Whole-body inverse-dynamics tracking controller: one quadratic program per control step.

Decision variables ``x = [a; w_c for each stance foot c]``: the generalised acceleration
``a`` ``(nv,)`` and the 6-D contact wrench of each stance foot (in its sole frame at its
origin, the plan's convention). The joint torques follow from them,
``τ = S (M a + h − Σ_c J_cᵀ w_c)``, so that (Del Prete, Mansard et al., TSID; Herzog et al.,
"Momentum control with hierarchical inverse dynamics on a torque-controlled humanoid", 2016)

    minimise   Σ_tasks  weight · ‖J_task a + J̇_task v − a*_task‖²  +  wrench regularisation
    subject to the unactuated (floating-base) rows of M a + h = Σ_c J_cᵀ w_c,
               A_c w_c ≤ 0 (the sole's 16-row contact wrench cone, Caron et al. 2015), f_z ≥ 0,
               −τ_max ≤ τ ≤ τ_max (every joint with a finite effort limit).

Tasks, each with a PD law on top of the plan's feed-forward acceleration
``a* = a_ref + K_p e + K_d ė``: stance feet held (zero sole acceleration; the pose error is
measured from where the foot was when its stance began), swing feet (sole pose of the plan),
centre of mass, floating-base orientation, and every actuated joint (posture). The plan's
wrenches enter as the wrench regularisation's target (feed-forward of the contact forces).
Model quantities — M, h, Jacobians, J̇v — come from Pinocchio at the simulated state. The QP
is solved by DAQP (Arnström, Bemporad, Axehill 2022; an exact dual active-set solver, PyPI
``daqp``).

Gains are natural frequencies ω of critically damped error dynamics (K_p = ω², K_d = 2ζω),
given in units of the robot's own pendulum frequency ω₀ = √(g/ℓ), ℓ its leg length (hip to
sole): the same defaults then suit a 0.5 m and a 1.7 m robot. Weights are in the tasks' own
units (m/s², rad/s²).
"""

from __future__ import annotations

from ctypes import c_int
from dataclasses import dataclass, replace

import daqp
import numpy as np
import pinocchio as pin

from ..errors import SimulationError
from ..model.mjcf import SimModel
from ..model.robot import SIDES, Robot
from .reference import Sample, base_joint

__all__ = ["ControllerGains", "TrackingController", "pendulum_frequency"]

_LOCAL = pin.ReferenceFrame.LOCAL
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class ControllerGains:
    """Gains and weights of :class:`TrackingController`.

    Natural frequencies (in units of ω₀ = √(g/ℓ), see the module docstring): ``com``,
    ``base`` (orientation), ``swing`` (swing-sole pose), ``posture`` (actuated joints),
    ``stance`` (stance-sole drift); ``damping``: damping ratio ζ of all of them.
    Task weights [1/(m/s²)²]: ``w_stance``, ``w_com``, ``w_base``, ``w_swing``, ``w_posture``;
    ``w_wrench``: weight of the wrench regularisation ‖(w − w_plan)/s‖², s = (m·g for forces,
    m·g·ℓ for moments); ``w_acc``: a small ‖a‖² term that keeps the QP strictly convex.
    ``cop_margin`` [-]: the fraction of the sole's half-length and half-width kept between the
    centre of pressure and the sole's edges in the QP's wrench cones (0: the whole sole).

    The centre of mass outweighs the posture thirtyfold: in single support the contact force
    is m·(c̈ − g), so the centre-of-mass task is what sets the push the simulation is judged
    by, and a posture task of comparable weight (29 joint rows on G1 against 3) let the QP
    trade it away. Measured on the shipped 3-D walk (``benchmarks/peers.py``; simulated push
    vs the measured one, left/right sagittal RMS, and the largest stance slip):
    ``w_com`` = 10: G1 2.7°/3.2°, iCub falls after 2.7 s; 30: G1 1.5°/1.5°, Talos 1.5°/1.2°,
    iCub 3.0°/1.3° over the whole clip, every slip ≤ 0.9 cm; 100: G1 1.1°/1.0°, but the
    stance foot of the demo's 30-knots/s stride creeps 1.3 cm.
    """

    com: float = 2.0
    base: float = 3.0
    swing: float = 5.0
    posture: float = 3.0
    stance: float = 2.0
    damping: float = 1.0
    w_stance: float = 1e3
    w_com: float = 30.0
    w_base: float = 10.0
    w_swing: float = 10.0
    w_posture: float = 1.0
    w_wrench: float = 1e-2
    w_acc: float = 1e-6
    cop_margin: float = 0.0

    def __post_init__(self) -> None:
        for k, v in self.__dict__.items():
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 0):
                raise SimulationError(f"ControllerGains.{k} must be a finite number ≥ 0; got "
                                      f"{v!r}")
        if self.cop_margin >= 1:
            raise SimulationError("ControllerGains.cop_margin is a fraction of the sole's "
                                  f"half-sizes, in [0, 1); got {self.cop_margin!r}")
        if self.w_acc <= 0 or self.w_posture <= 0:
            raise SimulationError("ControllerGains.w_acc and w_posture must be > 0 (they keep "
                                  "the QP strictly convex)")

    def pd(self, name: str, omega0: float) -> tuple[float, float]:
        """``(K_p, K_d)`` [1/s², 1/s] of task ``name`` for pendulum frequency ω₀ [rad/s]."""
        w = getattr(self, name) * omega0
        return w * w, 2.0 * self.damping * w


def pendulum_frequency(robot: Robot) -> float:
    """ω₀ = √(g/ℓ) [rad/s], ℓ the mean hip-to-sole height of the legs at the neutral pose."""
    m, d = robot.model, robot.data
    pin.framesForwardKinematics(m, d, robot.neutral)
    heights = [d.oMi[m.getJointId(robot.legs[s].hip)].translation[2]
               - d.oMf[m.getFrameId(robot.legs[s].sole)].translation[2] for s in SIDES]
    ell = float(np.mean(heights))
    if not ell > 0:
        raise SimulationError(f"{robot.name}: the hips are not above the soles at the neutral "
                              "pose; cannot scale the gains")
    return float(np.sqrt(np.linalg.norm(m.gravity.linear) / ell))


@dataclass(frozen=True)
class ControlOutput:
    """One control step: ``tau`` ``(nu,)`` [N·m] in actuator order, ``a`` ``(nv,)`` the QP's
    acceleration, ``wrench`` {side: (6,)} its contact wrenches (zeros in swing), ``status``
    DAQP's exit flag (1 optimal, 2 soft optimal; < 0 failed: the previous torques are kept)."""

    tau: np.ndarray
    a: np.ndarray
    wrench: dict[str, np.ndarray]
    status: int


@dataclass(frozen=True)
class _Layout:
    H0: np.ndarray
    A: np.ndarray
    up: np.ndarray
    lo: np.ndarray
    sense: np.ndarray


@dataclass(frozen=True)
class _Kinematics:
    """Pinocchio's quantities at one simulated state: base rotation ``Rb``, angular velocity
    ``wb`` and drift (world); base Jacobian ``Jb`` (angular rows, world-aligned); per foot
    (placement, LWA velocity, local velocity, local drift, classical LWA drift, local and LWA
    Jacobians); centre of mass, its velocity, drift and Jacobian; mass matrix ``M`` and
    non-linear effects ``h``."""

    Rb: np.ndarray
    wb: np.ndarray
    base_drift: np.ndarray
    Jb: np.ndarray
    feet: dict
    com: np.ndarray
    vcom: np.ndarray
    com_drift: np.ndarray
    Jcom: np.ndarray
    M: np.ndarray
    h: np.ndarray


class TrackingController:
    """The QP tracking controller of the module docstring for one robot and its MuJoCo model.

    ``contacts``: {side: SoleContact} of the plan (the frames and cones used).
    Call :meth:`reset` at the start of a run and :meth:`step` every control period.
    """

    def __init__(self, sim: SimModel, gains: ControllerGains = ControllerGains()):
        robot = sim.robot
        self.robot, self.sim, self.gains = robot, sim, gains
        self.model = robot.model
        self.data = robot.model.createData()
        self.nv = robot.model.nv
        self.act = sim.idx_v_act
        # base rows; a frozen joint (massless subtree, not simulated) has all-zero rows
        self.unact = np.setdiff1d(np.arange(self.nv), np.r_[self.act, sim.idx_v_frozen])
        self.base_id = base_joint(robot)
        self.contacts = sim.contacts
        self.fid = {s: self.model.getFrameId(sim.contacts[s].frame) for s in SIDES}
        shrink = 1.0 - gains.cop_margin
        self.cone = {s: replace(c, half_length=c.half_length * shrink,
                                half_width=c.half_width * shrink).cone()
                     for s, c in sim.contacts.items()}
        w0 = pendulum_frequency(robot)
        self.pd = {k: gains.pd(k, w0) for k in ("com", "base", "swing", "posture", "stance")}
        mg = robot.mass * float(np.linalg.norm(self.model.gravity.linear))
        ell = float(np.linalg.norm(self.model.gravity.linear)) / w0**2
        self.wrench_scale = np.array([mg] * 3 + [mg * ell] * 3)
        self.limited = np.isfinite(sim.effort)
        self.lim_idx = self.act[self.limited]
        self.lim_effort = sim.effort[self.limited]
        self.wrench_weight = gains.w_wrench / self.wrench_scale**2
        self._layouts: dict[tuple[str, ...], _Layout] = {}
        self.select = np.zeros((self.act.size, self.nv))
        self.select[np.arange(self.act.size), self.act] = 1.0
        self.reset()

    def reset(self) -> None:
        """Forget stance anchors and the last torques."""
        self.anchor: dict[str, pin.SE3 | None] = {s: None for s in SIDES}
        self.tau = np.zeros(self.act.size)

    def _layout(self, stance: tuple[str, ...]) -> _Layout:
        """The constant parts of the QP for one set of stance feet (cached)."""
        lay = self._layouts.get(stance)
        if lay is not None:
            return lay
        nv, ns = self.nv, len(stance)
        n = nv + 6 * ns
        H0 = np.zeros((n, n))
        H0[:nv, :nv] = self.gains.w_acc * np.eye(nv)
        nd = self.unact.size + self.lim_idx.size
        A = np.zeros((nd + 17 * ns, n))
        up = np.zeros(nd + 17 * ns)
        lo = np.full(nd + 17 * ns, -1e30)
        sense = np.zeros(nd + 17 * ns, dtype=c_int)
        sense[:self.unact.size] = 5  # equality
        for i, s in enumerate(stance):
            sl = slice(nv + 6 * i, nv + 6 * i + 6)
            H0[sl, sl] = np.diag(self.wrench_weight)
            r = nd + 17 * i
            A[r:r + 16, sl] = self.cone[s]
            A[r + 16, nv + 6 * i + 2] = -1.0  # f_z >= 0
        lay = _Layout(H0, A, up, lo, sense)
        self._layouts[stance] = lay
        return lay

    # ------------------------------------------------------------------ the QP
    def step(self, q: np.ndarray, v: np.ndarray, ref: Sample) -> ControlOutput:
        """Torques for the simulated state ``(q, v)`` tracking the plan sample ``ref``."""
        k = self._kinematics(q, v)
        stance = [s for s in SIDES if ref.stance[s]]
        rows, rhs, wts = self._tasks(q, v, ref, k)
        return self._solve(stance, rows, rhs, wts, ref, k)

    def _kinematics(self, q: np.ndarray, v: np.ndarray) -> _Kinematics:
        """Pinocchio's quantities at the simulated state (the drifts J̇v from a pass with zero
        acceleration, read before crba/nle overwrite the data)."""
        m, d = self.model, self.data
        nv = self.nv
        pin.forwardKinematics(m, d, q, v, np.zeros(nv))
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        Rb = d.oMi[self.base_id].rotation.copy()
        wb = Rb @ d.v[self.base_id].angular
        base_drift = Rb @ d.a[self.base_id].angular
        Jb = pin.getJointJacobian(m, d, self.base_id, _LWA)[3:]
        feet = {}
        for s in SIDES:
            f = self.fid[s]
            feet[s] = (d.oMf[f].copy(), pin.getFrameVelocity(m, d, f, _LWA).vector.copy(),
                       pin.getFrameVelocity(m, d, f, _LOCAL).vector.copy(),
                       pin.getFrameAcceleration(m, d, f, _LOCAL).vector.copy(),
                       pin.getFrameClassicalAcceleration(m, d, f, _LWA).vector.copy(),
                       pin.getFrameJacobian(m, d, f, _LOCAL).copy(),
                       pin.getFrameJacobian(m, d, f, _LWA).copy())
        pin.centerOfMass(m, d, q, v, np.zeros(nv))
        com, vcom, com_drift = d.com[0].copy(), d.vcom[0].copy(), d.acom[0].copy()
        Jcom = pin.jacobianCenterOfMass(m, d, q, False)
        M = pin.crba(m, d, q)
        M = np.triu(M)
        M = M + np.triu(M, 1).T
        h = pin.nonLinearEffects(m, d, q, v)
        return _Kinematics(Rb, wb, base_drift, Jb, feet, com, vcom, com_drift, Jcom, M, h)

    def _tasks(self, q: np.ndarray, v: np.ndarray, ref: Sample,
               k: _Kinematics) -> tuple[list, list, list]:
        """The task rows ``J``, right-hand sides ``a* − J̇v`` and weights (module docstring);
        updates the stance anchors."""
        m, g = self.model, self.gains
        rows, rhs, wts = [], [], []

        def task(J: np.ndarray, drift: np.ndarray, target: np.ndarray, w: float) -> None:
            rows.append(J)
            rhs.append(target - drift)
            wts.append(np.full(J.shape[0], w))

        kp, kd = self.pd["com"]
        task(k.Jcom, k.com_drift,
             ref.com_acc + kp * (ref.com - k.com) + kd * (ref.com_vel - k.vcom), g.w_com)
        kp, kd = self.pd["base"]
        err = pin.log3(ref.base_rot @ k.Rb.T)
        task(k.Jb, k.base_drift, ref.base_alpha + kp * err + kd * (ref.base_omega - k.wb),
             g.w_base)
        for s in SIDES:
            oMf, v_lwa, v_loc, a_loc, a_cls, J_loc, J_lwa = k.feet[s]
            if ref.stance[s]:
                if self.anchor[s] is None:
                    self.anchor[s] = oMf.copy()
                kp, kd = self.pd["stance"]
                e = pin.log6(oMf.actInv(self.anchor[s])).vector
                task(J_loc, a_loc, kp * e - kd * v_loc, g.w_stance)
            else:
                self.anchor[s] = None
                kp, kd = self.pd["swing"]
                e = np.r_[ref.foot_pos[s] - oMf.translation,
                          pin.log3(ref.foot_rot[s] @ oMf.rotation.T)]
                task(J_lwa, a_cls, ref.foot_acc[s] + kp * e + kd * (ref.foot_vel[s] - v_lwa),
                     g.w_swing)
        kp, kd = self.pd["posture"]
        dq = pin.difference(m, q, ref.q)
        task(self.select, np.zeros(self.act.size),
             ref.a[self.act] + kp * dq[self.act] + kd * (ref.v[self.act] - v[self.act]),
             g.w_posture)
        return rows, rhs, wts

    def _solve(self, stance: list[str], rows: list, rhs: list, wts: list, ref: Sample,
               k: _Kinematics) -> ControlOutput:
        """Assemble the QP (cost of the tasks and the wrench regularisation; the unactuated
        dynamics, torque limits and cones) and solve it with DAQP."""
        nv = self.nv
        ns = len(stance)
        n = nv + 6 * ns
        lay = self._layout(tuple(stance))
        Jt = np.vstack(rows)
        W = np.concatenate(wts)
        H = lay.H0.copy()
        H[:nv, :nv] += Jt.T @ (W[:, None] * Jt)
        f = np.zeros(n)
        f[:nv] = -Jt.T @ (W * np.concatenate(rhs))
        for i, s in enumerate(stance):
            f[nv + 6 * i: nv + 6 * i + 6] = -self.wrench_weight * ref.wrench[s]
        # dynamics: the full generalised force M a + h - Σ Jc^T w = Dyn x + h
        Dyn = np.empty((nv, n))
        Dyn[:, :nv] = k.M
        for i, s in enumerate(stance):
            Dyn[:, nv + 6 * i: nv + 6 * i + 6] = -k.feet[s][5].T
        h = k.h
        A, up, lo = lay.A.copy(), lay.up.copy(), lay.lo.copy()
        nu_, nl = self.unact.size, self.lim_idx.size
        A[:nu_] = Dyn[self.unact]
        up[:nu_] = lo[:nu_] = -h[self.unact]
        A[nu_:nu_ + nl] = Dyn[self.lim_idx]
        up[nu_:nu_ + nl] = self.lim_effort - h[self.lim_idx]
        lo[nu_:nu_ + nl] = -self.lim_effort - h[self.lim_idx]
        x, _, status, _ = daqp.solve(H, f, A, up, lo, lay.sense)
        wrench = {s: np.zeros(6) for s in SIDES}
        if status < 0:
            return ControlOutput(self.tau.copy(), np.full(nv, np.nan), wrench, int(status))
        a = x[:nv]
        tau_full = Dyn @ x + h
        self.tau = np.clip(tau_full[self.act], -self.sim.effort, self.sim.effort)
        for i, s in enumerate(stance):
            wrench[s] = x[nv + 6 * i: nv + 6 * i + 6].copy()
        return ControlOutput(self.tau.copy(), a, wrench, int(status))
