"""Scenario code (not part of the core API): small plans for tests and demos of the physics check.

- :func:`standing_plan` — stand still at ``robot.neutral`` with the static split of m·g;
- :func:`sway_plan` — shift the centre of mass sideways (forward-back for planar models) and
  back, feet fixed, by a few damped Gauss-Newton inverse-kinematics steps per knot;
- :func:`kinematic_walk_plan` — a joint-angle walk (:func:`gdimitate.walking_motion`: hip at
  constant height and speed, no balance) with the wrenches its dynamics would need — a
  negative control: its centre of mass leaves the support.

Wrenches come from :func:`split_wrenches`: the minimum-norm contact wrenches that explain the
floating-base rows of Pinocchio's inverse dynamics, *without* cone constraints — so a plan
that is not physically feasible keeps wrenches that pull on the floor or put the centre of
pressure outside the sole, which the simulation must then expose.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import SimulationError
from ..model.mjcf import _effort, _is_base
from ..model.motion import Motion, differentiate
from ..model.robot import SIDES, Robot
from ..sim.reference import Plan, base_joint

__all__ = ["kinematic_walk_plan", "split_wrenches", "standing_plan", "sway_plan"]

_LOCAL = pin.ReferenceFrame.LOCAL


def _unactuated(robot: Robot) -> np.ndarray:
    m = robot.model
    act = [m.joints[j].idx_v for j in range(1, m.njoints)
           if not _is_base(m, j) and m.joints[j].nv == 1 and _effort(m, j) > 0]
    return np.setdiff1d(np.arange(m.nv), act)


def split_wrenches(robot: Robot, motion: Motion) -> dict[str, np.ndarray]:
    """Per knot, the minimum-norm stance-foot wrenches ``{side: (T, 6)}`` (sole frame, at its
    origin; zeros in swing) with Σ_c J_cᵀ w_c equal to the unactuated rows of
    ``rnea(q, v, a)``. The norm is Σ ‖f‖² + ‖τ‖²/r², r = 10 % of the narrowest sole
    half-width: moments are dear, so a centre of mass over one foot shifts the normal forces
    onto that foot rather than loading the soles' edges. ``motion`` needs ``v`` and ``a``."""
    if motion.v is None or motion.a is None:
        raise SimulationError("split_wrenches needs the motion's v and a "
                              "(gdimitate.model.motion.differentiate)")
    V, A = motion.v, motion.a
    m, d = robot.model, robot.model.createData()
    contacts = robot.require_contacts()
    fids = {s: m.getFrameId(contacts[s].frame) for s in SIDES}
    un = _unactuated(robot)
    out: dict[str, np.ndarray] = {s: np.zeros((motion.T, 6)) for s in SIDES}
    lever = 0.1 * min(c.half_width for c in contacts.values())
    for k in range(motion.T):
        q, v, a = motion.q[k], V[k], A[k]
        tau = pin.rnea(m, d, q, v, a)
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        stance = [s for s in SIDES if motion.contact[s][k]]
        if not stance:
            continue
        J = np.hstack([pin.getFrameJacobian(m, d, fids[s], _LOCAL).T for s in stance])
        scale = np.tile(np.r_[np.ones(3), np.full(3, lever)], len(stance))
        w = scale * np.linalg.lstsq(J[un] * scale, tau[un], rcond=None)[0]
        for i, s in enumerate(stance):
            out[s][k] = w[6 * i: 6 * i + 6]
    return out


def _motion(robot: Robot, t: np.ndarray, q: np.ndarray, contact: dict) -> Motion:
    m = robot.model
    nq = tuple(m.joints[j].nq for j in range(1, m.njoints))
    base_nq = 7 if robot.base == "free" else 0
    return Motion(t=t, joint_names=robot.joint_names, q=q, contact=contact, base_nq=base_nq,
                  joint_nq=nq)


def standing_plan(robot: Robot, duration: float, rate: float = 100.0) -> Plan:
    """Stand still for ``duration`` [s] at ``robot.neutral`` (v = a = 0, both feet in stance)
    with the static split of the weight, knots at ``rate`` [Hz]."""
    if not duration > 0:
        raise SimulationError(f"duration must be > 0 s; got {duration!r}")
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    T, m = t.size, robot.model
    mo = _motion(robot, t, np.tile(robot.neutral, (T, 1)),
                 {s: np.ones(T, bool) for s in SIDES})
    mo = mo.replace(v=np.zeros((T, m.nv)), a=np.zeros((T, m.nv)))
    return Plan(mo, split_wrenches(robot, mo), dict(robot.require_contacts()))


def _ik(robot: Robot, q: np.ndarray, com: np.ndarray, feet: dict, base_rot: np.ndarray,
        iters: int = 8) -> np.ndarray:
    m, d = robot.model, robot.model.createData()
    bid = base_joint(robot)
    fids = {s: m.getFrameId(robot.contacts[s].frame) for s in SIDES}
    for _ in range(iters):
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        c = pin.centerOfMass(m, d, q)
        Jc = pin.jacobianCenterOfMass(m, d, q, False)
        rows, errs = [Jc[:2]], [(com - c)[:2]]  # horizontal only: height is free
        for s in SIDES:
            rows.append(pin.getFrameJacobian(m, d, fids[s], _LOCAL))
            errs.append(pin.log6(d.oMf[fids[s]].actInv(feet[s])).vector)
        rows.append(pin.getJointJacobian(m, d, bid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[3:])
        errs.append(pin.log3(base_rot @ d.oMi[bid].rotation.T))
        J, e = np.vstack(rows), np.concatenate(errs)
        dq = J.T @ np.linalg.solve(J @ J.T + 1e-6 * np.eye(J.shape[0]), e)
        q = pin.integrate(m, q, dq)
    return q


def sway_plan(robot: Robot, duration: float, amplitude: float, period: float,
              rate: float = 100.0, axis: int | None = None) -> Plan:
    """Sway the centre of mass along world ``axis`` (0 or 1; default: y, or x for planar
    models) as ``c = c₀ + amplitude · (1 − cos(2πt/period))/2`` [m] (out to ``amplitude`` and
    back each period, starting at rest), feet and base orientation fixed, the CoM height left
    free (straight knees make it singular), both feet in stance."""
    if not (duration > 0 and period > 0):
        raise SimulationError("duration and period must be > 0 s")
    ax = (0 if robot.base == "planar" else 1) if axis is None else int(axis)
    if ax not in (0, 1):
        raise SimulationError(f"axis must be 0 (x) or 1 (y); got {axis!r}")
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    m, d = robot.model, robot.model.createData()
    q0 = robot.neutral.copy()
    pin.framesForwardKinematics(m, d, q0)
    feet = {s: d.oMf[m.getFrameId(robot.contacts[s].frame)].copy() for s in SIDES}
    base_rot = d.oMi[base_joint(robot)].rotation.copy()
    c0 = pin.centerOfMass(m, d, q0).copy()
    qs, q = [], q0
    for tk in t:
        c = c0.copy()
        c[ax] += amplitude * (1 - np.cos(2 * np.pi * tk / period)) / 2
        q = _ik(robot, q, c, feet, base_rot)
        qs.append(q)
    T = t.size
    mo = differentiate(m, _motion(robot, t, np.array(qs), {s: np.ones(T, bool) for s in SIDES}))
    return Plan(mo, split_wrenches(robot, mo), dict(robot.require_contacts()))


def kinematic_walk_plan(robot: Robot, spec=None) -> Plan:
    """A joint-angle walk from :func:`gdimitate.walking_motion` (``spec`` a
    :class:`~gdimitate.planar.walking.GaitSpec`, default ``ROBOT_GAIT``) with finite-difference
    v, a and :func:`split_wrenches` — a negative control (module docstring)."""
    from ..planar.walking import ROBOT_GAIT, walking_motion

    mo = walking_motion(robot, spec or ROBOT_GAIT)
    mo = differentiate(robot.model, mo)
    return Plan(mo, split_wrenches(robot, mo), dict(robot.require_contacts()))
