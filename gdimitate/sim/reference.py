"""The plan a simulation tracks: validation of the plan contract and its references in time.

A plan (an adaptor's output) has ``motion`` — a :class:`~gdimitate.model.motion.Motion` with ``t``
``(T,)`` [s], ``q`` ``(T, nq)``, ``v``, ``a`` ``(T, nv)`` in Pinocchio's conventions and the
stance schedule ``contact`` ``{"left": (T,) bool, "right": …}`` —, ``wrenches`` ``{"left":
(T, 6), "right": (T, 6)}`` (the wrench [f; τ] the ground applies to each foot, in that foot's
contact frame at its origin, zeros in swing) and ``contacts`` ``{"left": SoleContact,
"right": …}``. :func:`check_plan` validates one; :class:`Reference` evaluates, at any time,
the quantities a tracking controller needs: the configuration, velocity, acceleration and
wrenches (between knots as the adaptor's integration scheme has them: accelerations and
wrenches of the step's first knot, velocities linear, ``pin.interpolate`` for q), the
stance of each foot (the value of the last knot at or before the time), and the task-space
references computed with Pinocchio from the plan's own (q, v, a) at the knots — centre of mass,
base orientation and sole poses with their velocities and accelerations in the world frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import PlanError
from ..model.contact import SoleContact
from ..model.kinematics import base_joint_id
from ..model.motion import Motion
from ..model.robot import SIDES, Robot

__all__ = ["Plan", "Reference", "Sample", "base_joint", "check_plan"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class Plan:
    """A plan in the contract's shape (what an adaptor returns; also built by scenario code):
    ``motion`` (with ``v`` and ``a``), ``wrenches`` ``{side: (T, 6)}`` [N, N·m] in each sole
    frame, ``contacts`` ``{side: SoleContact}``."""

    motion: Motion
    wrenches: dict[str, np.ndarray]
    contacts: dict[str, SoleContact]


def base_joint(robot: Robot) -> int:
    """Pinocchio id of the joint whose body is the floating base: the free flyer, or the last
    of our planar base joints (``base_pitch``). :class:`PlanError` for a fixed base."""
    j = base_joint_id(robot)
    if j is not None:
        return j
    raise PlanError(f"{robot.name} has a fixed base; simulate() needs a floating base "
                    "(free flyer or planar x/z/pitch)")


def check_plan(robot: Robot, plan: Any) -> Plan:
    """Validate ``plan`` (any object with ``motion``, ``wrenches``, ``contacts``) against
    ``robot`` and the plan contract; return it as a :class:`Plan` with float arrays.
    Raises :class:`PlanError` saying what does not fit."""
    for name in ("motion", "wrenches", "contacts"):
        if not hasattr(plan, name):
            raise PlanError(f"the plan has no .{name}; a plan needs .motion (Motion with v, a), "
                            ".wrenches {'left': (T, 6), 'right': (T, 6)} and .contacts "
                            "{'left': SoleContact, 'right': SoleContact}")
    mo = plan.motion
    if not isinstance(mo, Motion):
        raise PlanError(f"plan.motion must be a gdimitate.Motion; got {type(mo).__name__}")
    m = robot.model
    if mo.q.shape[1] != m.nq or tuple(mo.joint_names) != robot.joint_names:
        raise PlanError(f"plan.motion does not fit {robot.name!r}: q has {mo.q.shape[1]} "
                        f"columns (robot nq = {m.nq}), joints {list(mo.joint_names)[:4]}… vs "
                        f"{list(robot.joint_names)[:4]}…")
    if mo.v is None or mo.a is None:
        raise PlanError("plan.motion has no v/a; add them with "
                        "gdimitate.model.motion.differentiate(robot.model, motion)")
    if mo.v.shape != (mo.T, m.nv) or mo.a.shape != (mo.T, m.nv):
        raise PlanError(f"plan.motion.v/a must be ({mo.T}, {m.nv}); got {mo.v.shape}, "
                        f"{mo.a.shape}")
    T = mo.T
    if plan.wrenches is None or plan.contacts is None:
        raise PlanError("the plan has no contact wrenches/contacts (of the adaptors, only "
                        "method='optimal' produces them); a plan needs .wrenches "
                        "{'left': (T, 6), 'right': (T, 6)} and .contacts")
    wrenches, contacts = {}, {}
    for s in SIDES:
        if s not in mo.contact:
            raise PlanError(f"plan.motion.contact has no {s!r} stance schedule")
        try:
            w = np.asarray(plan.wrenches[s], dtype=float)
            c = plan.contacts[s]
        except (KeyError, TypeError):
            raise PlanError(f"plan.wrenches and plan.contacts need a {s!r} entry") from None
        if w.shape != (T, 6) or not np.all(np.isfinite(w)):
            raise PlanError(f"plan.wrenches[{s!r}] must be finite, shape ({T}, 6); got "
                            f"{w.shape}")
        if not isinstance(c, SoleContact):
            raise PlanError(f"plan.contacts[{s!r}] must be a SoleContact; got "
                            f"{type(c).__name__}")
        if not m.existFrame(c.frame):
            raise PlanError(f"plan.contacts[{s!r}].frame {c.frame!r} is not a frame of "
                            f"{robot.name!r}")
        swing = ~mo.contact[s]
        if np.any(np.abs(w[swing]) > 1e-9):
            k = int(np.flatnonzero(swing & np.any(np.abs(w) > 1e-9, axis=1))[0])
            raise PlanError(f"plan.wrenches[{s!r}] is non-zero at knot {k} (t = {mo.t[k]:.3f} "
                            "s) where the foot is in swing; the contract has zeros in swing")
        wrenches[s], contacts[s] = w, c
    base_joint(robot)
    return Plan(mo, wrenches, contacts)


@dataclass(frozen=True)
class Sample:
    """The plan at one time: ``q`` ``(nq,)``, ``v``, ``a`` ``(nv,)``; ``wrench`` {side: (6,)};
    ``stance`` {side: bool}; ``com``, ``com_vel``, ``com_acc`` ``(3,)`` [m, m/s, m/s²];
    ``base_rot`` ``(3, 3)``, ``base_height`` [m] (z of the base joint's origin),
    ``base_omega``, ``base_alpha`` ``(3,)`` world angular velocity [rad/s] and acceleration
    [rad/s²]; ``foot_pos`` {side: (3,)}, ``foot_rot`` {side: (3, 3)}, ``foot_vel``/``foot_acc``
    {side: (6,)} world linear (classical) + angular."""

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    wrench: dict[str, np.ndarray]
    stance: dict[str, bool]
    com: np.ndarray
    com_vel: np.ndarray
    com_acc: np.ndarray
    base_rot: np.ndarray
    base_height: float
    base_omega: np.ndarray
    base_alpha: np.ndarray
    foot_pos: dict[str, np.ndarray]
    foot_rot: dict[str, np.ndarray]
    foot_vel: dict[str, np.ndarray]
    foot_acc: dict[str, np.ndarray]


class Reference:
    """Task references of a validated :class:`Plan` on ``robot``, evaluated by :meth:`at`."""

    def __init__(self, robot: Robot, plan: Plan):
        self.robot, self.plan = robot, plan
        m, d = robot.model, robot.model.createData()
        mo = plan.motion
        self.t = mo.t
        T = mo.T
        self.base_id = base_joint(robot)
        fids = {s: m.getFrameId(plan.contacts[s].frame) for s in SIDES}
        self.com = np.zeros((T, 3, 3))  # pos, vel, acc
        self.base_rot = np.zeros((T, 3, 3))
        self.base_z = np.zeros(T)
        self.base_w = np.zeros((T, 2, 3))  # omega, alpha (world)
        self.foot_pos = {s: np.zeros((T, 3)) for s in SIDES}
        self.foot_rot = {s: np.zeros((T, 3, 3)) for s in SIDES}
        self.foot_va = {s: np.zeros((T, 2, 6)) for s in SIDES}
        mv, ma = mo.derivatives("a plan")  # validated: (T, nv) each
        for k in range(T):
            q, v, a = mo.q[k], mv[k], ma[k]
            pin.forwardKinematics(m, d, q, v, a)
            pin.updateFramePlacements(m, d)
            pin.centerOfMass(m, d, q, v, a)
            self.com[k] = (d.com[0], d.vcom[0], d.acom[0])
            R = d.oMi[self.base_id].rotation
            self.base_rot[k] = R
            self.base_z[k] = d.oMi[self.base_id].translation[2]
            self.base_w[k] = (R @ d.v[self.base_id].angular, R @ d.a[self.base_id].angular)
            for s, f in fids.items():
                self.foot_pos[s][k] = d.oMf[f].translation
                self.foot_rot[s][k] = d.oMf[f].rotation
                vel = pin.getFrameVelocity(m, d, f, _LWA)
                acc = pin.getFrameClassicalAcceleration(m, d, f, _LWA)
                self.foot_va[s][k, 0] = np.r_[vel.linear, vel.angular]
                self.foot_va[s][k, 1] = np.r_[acc.linear, acc.angular]

    @property
    def start(self) -> float:
        """First knot time [s]."""
        return float(self.t[0])

    @property
    def end(self) -> float:
        """Last knot time [s]."""
        return float(self.t[-1])

    def samples(self, times: np.ndarray) -> list[Sample]:
        """The plan at many times ``(N,)`` [s] (held at the end points outside the plan).

        Between knots k and k + 1 the samples follow the adaptor's integration scheme
        (``v_{k+1} = v_k + h a_k``, docs/design.md §6): accelerations and wrenches are those
        of knot k (``a_k`` is the acceleration of the whole step, ``w_k`` the wrench that goes
        with it), velocities are linear between the knots (which is what a constant ``a_k``
        gives), positions and orientations are interpolated on the configuration space
        (``pin.interpolate``, slerp), and a foot's stance is knot k's."""
        times = np.asarray(times, dtype=float)
        k = np.clip(np.searchsorted(self.t, times, side="right") - 1, 0, self.t.size - 2)
        al = np.clip((times - self.t[k]) / (self.t[k + 1] - self.t[k]), 0.0, 1.0)
        kc = np.where((al >= 1.0) | (times >= self.t[-1]), k + 1, k)
        mo, p, m = self.plan.motion, self.plan, self.robot.model

        def lerp(x: np.ndarray) -> np.ndarray:
            sh = (-1,) + (1,) * (x.ndim - 1)
            return (1 - al).reshape(sh) * x[k] + al.reshape(sh) * x[k + 1]

        def slerp(R: np.ndarray) -> np.ndarray:
            rel = np.array([pin.log3(R[i].T @ R[i + 1]) for i in range(R.shape[0] - 1)])
            return np.einsum("nij,njk->nik", R[k], _exp3(al[:, None] * rel[k]))

        q = np.array([pin.interpolate(m, mo.q[i], mo.q[i + 1], a) for i, a in zip(k, al)])
        mv, ma = mo.derivatives("a plan")
        v, com, bw, bz, brot = (lerp(mv), lerp(self.com), lerp(self.base_w),
                                lerp(self.base_z), slerp(self.base_rot))
        a = ma[kc]
        com[:, 2], bw[:, 1] = self.com[kc, 2], self.base_w[kc, 1]
        w = {s: p.wrenches[s][kc] for s in SIDES}
        st = {s: mo.contact[s][kc] for s in SIDES}
        fp = {s: lerp(self.foot_pos[s]) for s in SIDES}
        fr = {s: slerp(self.foot_rot[s]) for s in SIDES}
        fv = {s: lerp(self.foot_va[s][:, 0]) for s in SIDES}
        fa = {s: self.foot_va[s][kc, 1] for s in SIDES}
        return [Sample(q=q[i], v=v[i], a=a[i], wrench={s: w[s][i] for s in SIDES},
                       stance={s: bool(st[s][i]) for s in SIDES},
                       com=com[i, 0], com_vel=com[i, 1], com_acc=com[i, 2],
                       base_rot=brot[i], base_height=float(bz[i]), base_omega=bw[i, 0],
                       base_alpha=bw[i, 1], foot_pos={s: fp[s][i] for s in SIDES},
                       foot_rot={s: fr[s][i] for s in SIDES},
                       foot_vel={s: fv[s][i] for s in SIDES},
                       foot_acc={s: fa[s][i] for s in SIDES})
                for i in range(times.size)]

    def at(self, t: float) -> Sample:
        """The plan at time ``t`` [s]: :meth:`samples` at one time."""
        return self.samples(np.array([float(t)]))[0]


def _exp3(w: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(N, 3, 3)`` of rotation vectors ``(N, 3)`` (Rodrigues)."""
    th = np.linalg.norm(w, axis=1)
    K = np.zeros((w.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    small = th < 1e-8
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th**2 / 6, np.sin(ths) / ths)[:, None, None]
    b = np.where(small, 0.5 - th**2 / 24, (1 - np.cos(ths)) / ths**2)[:, None, None]
    return np.eye(3) + a * K + b * (K @ K)
