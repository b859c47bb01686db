"""The audit's computations: Pinocchio recomputation of dynamics, limits, contacts and floor.

Friction is checked against Coulomb's circular cone ``‖f_t‖ ≤ μ f_z`` (the 16-row contact
wrench cone's square pyramids admit up to √2·μ); centre of pressure and yaw moment against
Caron et al.'s closed forms (:func:`gdimitate.model.contact.cone_margin`).

Every check turns a per-knot quantity into a :class:`~.report.Check` (its worst value and knot,
pass/fail against the bound with tolerance, and a dimensionless violation that orders the
binding list). The violation scales: body weight ``m·g`` for forces and base residuals, the
sole's smaller half-size for lengths on a foot (centre of pressure, penetration, slip),
``μ(X+Y)·m·g`` for yaw moments, μ for friction ratios, the limit itself for torque and velocity
ratios, the joint's range for position limits, 1 rad for angles, 1 m/s (1 rad/s) for a stance
foot's velocity.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...errors import InvalidInputError
from ...model.contact import SoleContact, cone_margin
from ...model.motion import Motion
from ..wrenches import base_dofs
from .report import (
    AuditReport,
    AuditTolerances,
    Check,
    FootAudit,
    ForceDirectionAudit,
    JointAudit,
    Penetration,
    SelfCollisionAudit,
    Worst,
)

GRAVITY = 9.81
#: Limits at or above this are Pinocchio's "no limit" (it stores DBL_MAX).
_NO_LIMIT = 1e30


# ---------------------------------------------------------------------- input validation
def _validate(robot, motion, wrenches, contacts, target, cone_half_angle):
    model = robot.model
    if not isinstance(motion, Motion):
        raise InvalidInputError(f"motion must be a gdimitate.Motion; got {type(motion).__name__}")
    T = motion.T
    if motion.q.shape[1] != model.nq:
        raise InvalidInputError(f"motion.q has {motion.q.shape[1]} columns; {robot.name} has "
                                f"nq = {model.nq}")
    motion.derivatives("audit")
    for name in ("v", "a"):
        x = getattr(motion, name)
        if x.shape != (T, model.nv):
            raise InvalidInputError(f"motion.{name} must be (T, nv) = ({T}, {model.nv}); got "
                                    f"{x.shape}")
    contacts = dict(robot.require_contacts() if contacts is None else contacts)
    for side, c in contacts.items():
        if not isinstance(c, SoleContact):
            raise InvalidInputError(f"contacts[{side!r}] must be a SoleContact; got "
                                    f"{type(c).__name__}")
        robot.frame_id(c.frame)
        if side not in motion.contact:
            raise InvalidInputError(f"motion.contact has no {side!r} stance flags; it has "
                                    f"{sorted(motion.contact)}")
    extra = sorted(set(wrenches) - set(contacts))
    missing = sorted(set(contacts) - set(wrenches))
    if extra or missing:
        raise InvalidInputError(f"wrenches must have exactly the feet {sorted(contacts)}; "
                                f"missing {missing}, unknown {extra}")
    W = {}
    for side in contacts:
        w = np.asarray(wrenches[side], dtype=float)
        if w.shape != (T, 6):
            raise InvalidInputError(f"wrenches[{side!r}] must be (T, 6) = ({T}, 6) [N, N·m]; "
                                    f"got {w.shape}")
        if not np.all(np.isfinite(w)):
            r = int(np.argwhere(~np.isfinite(w))[0, 0])
            raise InvalidInputError(f"wrenches[{side!r}] has NaN/inf at knot {r}")
        W[side] = w
    targets = {}
    for side, d in dict(target or {}).items():
        if side not in contacts:
            raise InvalidInputError(f"target has an unknown foot {side!r}; feet: "
                                    f"{sorted(contacts)}")
        d = np.asarray(d, dtype=float)
        if d.shape != (T, 3):
            raise InvalidInputError(f"target[{side!r}] must be (T, 3); got {d.shape}")
        nan = np.isnan(d)
        if np.any(nan.any(axis=1) != nan.all(axis=1)) or np.any(np.isinf(d)):
            raise InvalidInputError(f"target[{side!r}]: each row is a unit vector or all NaN")
        n = np.linalg.norm(d[~nan.any(axis=1)], axis=1)
        if n.size and np.max(np.abs(n - 1)) > 1e-6:
            raise InvalidInputError(
                f"target[{side!r}] rows must be unit vectors (norms from {n.min():.6g} to "
                f"{n.max():.6g}); normalise them")
        targets[side] = d
    if not (np.isfinite(cone_half_angle) and 0 <= cone_half_angle < np.pi):
        raise InvalidInputError(f"cone_half_angle must be in [0, π) rad; got {cone_half_angle!r}")
    return contacts, W, targets


# ---------------------------------------------------------------------- check helper
def _make(name: str, x: np.ndarray, bound: float, sense: str, unit: str, scale: float
          ) -> tuple[Check, np.ndarray]:
    """A check of the per-knot values ``x`` ``(T,)`` (NaN: not applicable at that knot)."""
    valid = ~np.isnan(x)
    if not valid.any():
        return Check(name, float("nan"), bound, -1, True, 0.0, unit, sense), np.ones(x.size, bool)
    if sense == "max":
        k = int(np.nanargmax(x))
        ok = ~valid | (np.where(valid, x, -np.inf) <= bound)
        excess = x[k] - bound
    else:
        k = int(np.nanargmin(x))
        ok = ~valid | (np.where(valid, x, np.inf) >= bound)
        excess = bound - x[k]
    passed = bool(ok.all())
    viol = 0.0 if passed else float(max(excess, 0.0) / scale)
    return (Check(name, float(x[k]), float(bound), k, passed, viol, unit, sense,
                  int((~ok).sum())), ok)


def _worst(x: np.ndarray, sense: str = "max") -> Worst:
    if not np.any(~np.isnan(x)):
        return Worst(float("nan"), -1)
    k = int(np.nanargmax(x) if sense == "max" else np.nanargmin(x))
    return Worst(float(x[k]), k)


def _limit(values: np.ndarray) -> float:
    """A joint's limit from its dofs' model limits: inf where any dof has none (0, inf, DBL_MAX)."""
    v = np.asarray(values, dtype=float)
    if v.size == 0 or np.any(~np.isfinite(v)) or np.any(v <= 0) or np.any(v >= _NO_LIMIT):
        return float("inf")
    return float(v.min())


# ---------------------------------------------------------------------- recomputation
def _kinematics_dynamics(robot, motion, contacts, W):
    """Per knot: ``tau`` ``(T, nv)`` = rnea − Σ Jᵀw, and each contact frame's placement."""
    model = robot.model
    data = model.createData()
    T = motion.T
    tau = np.empty((T, model.nv))
    fids = {s: robot.frame_id(c.frame) for s, c in contacts.items()}
    pos = {s: np.empty((T, 3)) for s in contacts}
    rot = {s: np.empty((T, 3, 3)) for s in contacts}
    for k in range(T):
        q, v, a = motion.q[k], motion.v[k], motion.a[k]
        tk = pin.rnea(model, data, q, v, a).copy()
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        for s, fid in fids.items():
            J = pin.getFrameJacobian(model, data, fid, pin.LOCAL)
            tk -= J.T @ W[s][k]
            pos[s][k] = data.oMf[fid].translation
            rot[s][k] = data.oMf[fid].rotation
        tau[k] = tk
    return tau, pos, rot


def joint_torques(robot, motion: Motion, wrenches: dict[str, np.ndarray]) -> np.ndarray:
    """The audit's own inverse dynamics of ``motion`` (with ``v``, ``a``) and its sole-frame
    contact wrenches ``{side: (T, 6)}`` [N, N·m]: ``tau`` ``(T, nv)`` [N·m, N] =
    ``rnea(q, v, a) − Σ_c J_cᵀ w_c`` (Pinocchio; the base rows are the residual the audit
    bounds, the rest the actuated joints' torques, in Pinocchio's velocity order)."""
    if motion.v is None or motion.a is None:
        raise InvalidInputError("joint torques need the motion's v and a")
    contacts = {s: c for s, c in robot.require_contacts().items() if s in wrenches}
    return _kinematics_dynamics(robot, motion, contacts, wrenches)[0]


def _sole_velocities(robot, motion, contacts) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per foot ``(V, dV)``, each ``(T, 2)``: the norms ``(‖v‖ [m/s], ‖ω‖ [rad/s])`` of the sole
    frame's spatial velocity ``J_c(q_k) v_k`` (Pinocchio's ``forwardKinematics(q, v)``, then
    ``getFrameVelocity`` in ``LOCAL_WORLD_ALIGNED``: the frame origin's velocity and the angular
    velocity, world axes), and those of its change ``(J_c(q_k) − J_c(q_k ⊖ h_k v_k)) v_k`` along
    the step ``v_k`` spans (``h_k = t_k − t_{k−1}``, ``h_0 = t_1 − t_0``; zeros if T = 1)."""
    model = robot.model
    data = model.createData()
    fids = {s: robot.frame_id(c.frame) for s, c in contacts.items()}
    vel = {s: np.zeros((motion.T, 6)) for s in contacts}
    dv = {s: np.zeros((motion.T, 6)) for s in contacts}
    h = np.diff(motion.t)
    h = np.r_[h[:1], h]
    for k in range(motion.T):
        v = motion.v[k]
        pin.forwardKinematics(model, data, motion.q[k], v)
        for s, fid in fids.items():
            vel[s][k] = pin.getFrameVelocity(model, data, fid, pin.LOCAL_WORLD_ALIGNED).vector
        if motion.T < 2:
            continue
        pin.forwardKinematics(model, data, pin.integrate(model, motion.q[k], -h[k] * v), v)
        for s, fid in fids.items():
            dv[s][k] = vel[s][k] - pin.getFrameVelocity(model, data, fid,
                                                        pin.LOCAL_WORLD_ALIGNED).vector

    def norms(x: np.ndarray) -> np.ndarray:
        return np.c_[np.linalg.norm(x[:, :3], axis=1), np.linalg.norm(x[:, 3:], axis=1)]

    return {s: (norms(vel[s]), norms(dv[s])) for s in contacts}


def _forward_differences(model, motion) -> np.ndarray:
    """``(T−1, nv)``: ``pin.difference(q_k, q_{k+1}) / h_k``."""
    h = np.diff(motion.t)
    return np.array([pin.difference(model, motion.q[k], motion.q[k + 1]) / h[k]
                     for k in range(motion.T - 1)])


def _actuated_joints(robot) -> list[int]:
    model = robot.model
    base = set(base_dofs(robot))
    out = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        dofs = set(range(jm.idx_v, jm.idx_v + jm.nv))
        if jm.nv and not dofs & base:
            out.append(j)
    return out


def _stance_intervals(c: np.ndarray) -> list[tuple[int, int]]:
    """``[(start, stop), ...]`` of the runs of True in ``c`` (stop exclusive)."""
    d = np.diff(np.r_[0, c.astype(int), 0])
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def _wrap(x: np.ndarray) -> np.ndarray:
    return (x + np.pi) % (2 * np.pi) - np.pi


# ---------------------------------------------------------------------- the audit
def run_audit(robot, motion, wrenches, contacts, target, cone_half_angle, tol,
              collision_margin: float = 0.0):
    """See :func:`gdimitate.assess.audit.audit`."""
    if not isinstance(tol, AuditTolerances):
        raise InvalidInputError(f"tolerances must be an AuditTolerances; got {type(tol).__name__}")
    contacts, W, targets = _validate(robot, motion, wrenches, contacts, target, cone_half_angle)
    model = robot.model
    T = motion.T
    weight = robot.mass * GRAVITY
    tau, pos, rot = _kinematics_dynamics(robot, motion, contacts, W)
    fd = _forward_differences(model, motion)
    svel = _sole_velocities(robot, motion, contacts)
    checks: list[Check] = []
    masks: list[np.ndarray] = []

    def add(check_and_mask):
        checks.append(check_and_mask[0])
        masks.append(check_and_mask[1])
        return check_and_mask[0]

    # base rows
    bd = base_dofs(robot)
    res = np.max(np.abs(tau[:, bd]), axis=1) if bd else np.full(T, np.nan)
    base_check = add(_make("base_residual", res, tol.base_residual, "max", "N", weight))

    # joints
    joints, unlimited, use = _joint_checks(robot, motion, motion.v, tau, fd, tol, add)
    vc = add(_velocity_consistency(motion.t, motion.v, motion.a, fd, tol))

    # feet
    feet, pen_all = {}, []
    for side, c in contacts.items():
        foot, foot_checks = _foot(side, c, motion.contact[side], W[side], pos[side], rot[side],
                                  svel[side], targets.get(side), cone_half_angle, tol, weight)
        for cm in foot_checks:
            add(cm)
        feet[side] = foot
        pen_all.append(foot.penetration)
    add(_penetration_check(contacts, pos, rot, T, tol))
    pen = max(pen_all, key=lambda p: p.depth)
    collision = _self_collision(robot, motion, collision_margin, tol, add)

    failed = sorted((c for c in checks if not c.passed), key=lambda c: -c.violation)
    return AuditReport(
        feasible=not failed, binding=tuple(c.name for c in failed), checks=tuple(checks),
        feet=feet, joints=tuple(joints), unlimited=tuple(unlimited),
        base_residual=Worst(base_check.value, base_check.knot), penetration=pen,
        velocity_consistency=Worst(vc.value, vc.knot),
        knot_feasible=np.logical_and.reduce(masks), tau=tau, knot_checks=np.array(masks),
        tolerances=tol,
        cone_half_angle=float(cone_half_angle), self_collision=collision, joint_use=use)


def _joint_checks(robot, motion: Motion, v: np.ndarray, tau: np.ndarray, fd: np.ndarray,
                  tol: AuditTolerances, add
                  ) -> tuple[list[JointAudit], list[tuple[str, str]], np.ndarray]:
    """Per actuated joint: torque and velocity against their limits (the velocity at a knot is
    the larger of ``v`` ``(T, nv)`` and the forward difference of ``q``, ``fd`` ``(T-1, nv)``)
    and the position range; each check is passed to ``add``. Returns the :class:`JointAudit`
    list, the ``(joint, "effort" | "velocity")`` pairs without a limit and
    :attr:`AuditReport.joint_use` ``(T, n_joints, 3)``."""
    model = robot.model
    vmag = np.abs(v)
    vmag[:-1] = np.maximum(vmag[:-1], np.abs(fd))
    joints, unlimited = [], []
    act = _actuated_joints(robot)
    use = np.full((motion.T, len(act), 3), np.nan)
    for i, j in enumerate(act):
        jm, name = model.joints[j], model.names[j]
        dofs = slice(jm.idx_v, jm.idx_v + jm.nv)
        tq = np.max(np.abs(tau[:, dofs]), axis=1)
        eff = _limit(model.effortLimit[dofs])
        if np.isfinite(eff):
            use[:, i, 0] = tq / eff
            c = add(_make(f"torque:{name}", use[:, i, 0], 1 + tol.torque, "max", "-", 1.0))
            t_ratio = c.value
        else:
            unlimited.append((name, "effort"))
            t_ratio = float("nan")
        tw = _worst(tq)
        vj = np.max(vmag[:, dofs], axis=1)
        vlim = _limit(model.velocityLimit[dofs])
        vw = _worst(vj)
        if np.isfinite(vlim):
            use[:, i, 1] = vj / vlim
            c = add(_make(f"velocity:{name}", use[:, i, 1], 1 + tol.velocity, "max", "-",
                          1.0))
            v_ratio, v_knot = c.value, c.knot
        else:
            unlimited.append((name, "velocity"))
            v_ratio, v_knot = float("nan"), vw.knot
        pm = Worst(float("inf"), -1)
        if jm.nq == 1 and jm.nv == 1:
            lo, hi = model.lowerPositionLimit[jm.idx_q], model.upperPositionLimit[jm.idx_q]
            if abs(lo) < _NO_LIMIT and abs(hi) < _NO_LIMIT and lo < hi:
                qj = motion.q[:, jm.idx_q]
                use[:, i, 2] = np.minimum(qj - lo, hi - qj)
                c = add(_make(f"position:{name}", use[:, i, 2], -tol.position,
                              "min", "rad" if jm.shortname().startswith("JointModelR") else "m",
                              float(hi - lo)))
                pm = Worst(c.value, c.knot)
        joints.append(JointAudit(name, tw.value, tw.knot, eff, t_ratio, float(np.max(vj)),
                                 v_knot, vlim, v_ratio, pm.value, pm.knot))

    return joints, unlimited, use


def _velocity_consistency(t: np.ndarray, v: np.ndarray, a: np.ndarray, fd: np.ndarray,
                          tol: AuditTolerances):
    """``velocity_consistency``: ``fd`` ``(T-1, nv)``, the forward difference of ``q``, against
    the velocities ``v`` ``(T, nv)`` at the two knots of each step (``a`` ``(T, nv)``, knot times
    ``t`` ``(T,)`` [s])."""
    # the forward difference of a one-step scheme (explicit, implicit or semi-implicit Euler,
    # trapezoid) lies between the velocities at its two knots; central differences leave a
    # third-order term, of the size h·|a_k+1 − a_k| / 2, allowed for.
    T = t.size
    cons = np.zeros(T)
    if T > 1:
        h = np.diff(t)[:, None]
        slack = 0.5 * h * np.abs(a[1:] - a[:-1])
        lo = np.minimum(v[:-1], v[1:]) - slack
        hi = np.maximum(v[:-1], v[1:]) + slack
        cons[:-1] = np.max(np.maximum(np.maximum(lo - fd, fd - hi), 0.0), axis=1)
    vscale = max(1.0, float(np.max(np.abs(v))))
    return _make("velocity_consistency", cons, tol.velocity_consistency, "max", "rad/s",
                 vscale)


def _penetration_check(contacts: dict[str, SoleContact], pos: dict, rot: dict, T: int,
                       tol: AuditTolerances):
    """``penetration``: the deepest sole corner below the floor at each knot (both feet)."""
    depth = np.full(T, -np.inf)
    for side, c in contacts.items():
        corners = pos[side][:, None, :] + np.einsum("tij,cj->tci", rot[side], c.corners())
        depth = np.maximum(depth, np.max(-corners[:, :, 2], axis=1))
    half = min(min(c.half_length, c.half_width) for c in contacts.values())
    return _make("penetration", depth, tol.penetration, "max", "m", half)


def _self_collision(robot, motion, margin, tol, add) -> SelfCollisionAudit | None:
    """The ``self_collision`` check (every knot's closest pair against ``margin``) and its
    summary; ``None`` (no check) for a robot without collision geometry."""
    from ...model.selfcollision import self_collision

    if not (np.isfinite(margin) and margin >= 0):
        raise InvalidInputError(f"collision_margin must be a finite distance ≥ 0 [m]; got "
                                f"{margin!r}")
    sc = self_collision(robot)
    if sc is None or not sc.pairs:
        return None
    closest, pair = sc.closest(motion.q)
    c = add(_make("self_collision", closest, margin - tol.self_collision, "min", "m", 0.05))
    return SelfCollisionAudit(c.value, c.knot, sc.pairs[int(pair[c.knot])],
                              float(margin), len(sc.pairs), sc.excluded)


def _force_direction(side: str, stance: np.ndarray, w: np.ndarray, rot: np.ndarray,
                     target: np.ndarray, half_angle: float, tol: AuditTolerances):
    """``force_direction:<side>``: the angle [rad] between the foot's push on the ground (its
    wrench ``w`` ``(T, 6)`` reversed, turned by the sole rotations ``rot`` ``(T, 3, 3)`` into
    the world) and the unit ``target`` ``(T, 3)`` at stance knots with a normal force; its
    sagittal and frontal parts. Returns the check and its :class:`ForceDirectionAudit`."""
    push = -np.einsum("tij,tj->ti", rot, w[:, :3])  # the foot's push on the ground, world
    norm = np.linalg.norm(push, axis=1)
    use = stance & ~np.isnan(target[:, 0]) & (norm > max(tol.normal, 1e-9))
    u = push / np.where(norm > 0, norm, 1.0)[:, None]
    err = np.where(use, np.arccos(np.clip(np.sum(u * np.nan_to_num(target), axis=1),
                                          -1, 1)), np.nan)
    tg = np.nan_to_num(target)
    sag = np.where(use, np.abs(_wrap(np.arctan2(u[:, 0], -u[:, 2])
                                     - np.arctan2(tg[:, 0], -tg[:, 2]))), np.nan)
    fro = np.where(use, np.abs(_wrap(np.arctan2(u[:, 1], -u[:, 2])
                                     - np.arctan2(tg[:, 1], -tg[:, 2]))), np.nan)
    chk = _make(f"force_direction:{side}", err, half_angle + tol.force_direction, "max",
                "rad", 1.0)
    sw, fw = _worst(sag), _worst(fro)
    rms = float(np.sqrt(np.nanmean(err**2))) if use.any() else float("nan")
    fda = ForceDirectionAudit(side, chk[0].value, chk[0].knot, rms, sw.value, sw.knot,
                              fw.value, fw.knot, int(use.sum()))
    return chk, fda


def _foot(side, c: SoleContact, stance, w, pos, rot, svel, target, half_angle, tol, weight):
    """One foot's checks and its :class:`FootAudit`."""
    T = stance.size
    half = min(c.half_length, c.half_width)
    nan = np.full(T, np.nan)
    out = []
    # cone: a pulling foot (f_z < −tol) is reported by the normal-force check alone (friction
    # ratio and centre of pressure mean nothing there); elsewhere friction, CoP and yaw are
    # evaluated with f_z floored at a tiny positive value, so that a tangential force or a
    # moment without normal force fails them while a zero wrench passes.
    wf = w.copy()
    wf[:, 2] = np.maximum(wf[:, 2], max(tol.normal, 1e-9))
    m = cone_margin(c, wf)
    normal = np.where(stance, w[:, 2], nan)
    pushing = stance & (w[:, 2] >= -tol.normal)
    ratio = np.where(pushing, c.mu - m["friction"], nan)
    cop = np.where(pushing, m["cop"], nan)
    yaw = np.where(pushing, m["yaw"], nan)
    out.append(_make(f"normal:{side}", normal, -tol.normal, "min", "N", weight))
    out.append(_make(f"friction:{side}", ratio, c.mu + tol.friction, "max", "-", c.mu))
    out.append(_make(f"cop:{side}", cop, -tol.cop, "min", "m", half))
    out.append(_make(f"yaw:{side}", yaw, -tol.yaw, "min", "N·m",
                     c.mu * (c.half_length + c.half_width) * weight))
    swing = np.where(~stance, np.max(np.abs(w), axis=1), nan)
    out.append(_make(f"swing_wrench:{side}", swing, tol.swing_wrench, "max", "N", weight))
    # slip: drift of the sole frame since its stance began
    drift, turn = nan.copy(), nan.copy()
    for a, b in _stance_intervals(stance):
        drift[a:b] = np.linalg.norm(pos[a:b] - pos[a], axis=1)
        turn[a:b] = [np.linalg.norm(pin.log3(rot[a].T @ rot[k])) for k in range(a, b)]
    out.append(_make(f"slip:{side}", drift, tol.slip, "max", "m", half))
    out.append(_make(f"slip_rotation:{side}", turn, tol.slip_rotation, "max", "rad", 1.0))
    # a stance foot is still: its sole frame's velocity J_c(q_k) v_k at every stance knot.
    # A one-step scheme's v_k is the velocity of the whole step (q_k ⊖ h_k v_k, q_k): a foot
    # whose pose is the same at both ends of it (zero mean velocity) still has J_c(q) v_k
    # change along it, by dV, and ends the step at about dV/2 (second order in h). That half
    # is allowed for, as velocity_consistency allows the h·|Δa|/2 of central differences; it
    # is O(h·|v|²·ℓ), far below the speed of a foot that moves.
    V, dV = svel
    beyond = np.max(V - 0.5 * dV, axis=1).clip(min=0.0)
    out.append(_make(f"stance_velocity:{side}", np.where(stance, beyond, nan),
                     tol.stance_velocity, "max", "m/s", 1.0))
    raw = _worst(np.where(stance, V.max(axis=1), nan))
    # floor: every corner, every knot
    corners = pos[:, None, :] + np.einsum("tij,cj->tci", rot, c.corners())
    depth = -corners[:, :, 2]
    k, corner = np.unravel_index(int(np.argmax(depth)), depth.shape)
    pen = Penetration(float(depth[k, corner]), int(k), side, int(corner))
    # a flat contact needs the whole sole on the floor: the highest corner of a stance foot
    gap = np.where(stance, np.max(corners[:, :, 2], axis=1), nan)
    out.append(_make(f"contact_gap:{side}", gap, tol.contact_gap, "max", "m", half))
    # force direction
    fda = None
    if target is not None:
        chk, fda = _force_direction(side, stance, w, rot, target, half_angle, tol)
        out.append(chk)
    get = {ch.name.split(":")[0]: ch for ch, _ in out}
    foot = FootAudit(
        side=side, stance_knots=int(stance.sum()), mu=c.mu,
        normal=Worst(get["normal"].value, get["normal"].knot),
        friction=Worst(get["friction"].value, get["friction"].knot),
        cop=Worst(get["cop"].value, get["cop"].knot),
        yaw=Worst(get["yaw"].value, get["yaw"].knot),
        slip=Worst(get["slip"].value, get["slip"].knot),
        slip_rotation=Worst(get["slip_rotation"].value, get["slip_rotation"].knot),
        swing_wrench=Worst(get["swing_wrench"].value, get["swing_wrench"].knot),
        contact_gap=Worst(get["contact_gap"].value, get["contact_gap"].knot),
        stance_velocity=raw,
        penetration=pen, force_direction=fda)
    return foot, out
