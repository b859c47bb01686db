"""Contact wrenches that explain a motion's whole-body dynamics (Newton–Euler of the base).

The unactuated (base) rows of the inverse dynamics ``rnea(q, v, a)`` are the net external
wrench the body needs; on flat ground only the feet provide it::

    rnea(q, v, a)_base = Σ_c (J_c(q)ᵀ w_c)_base          (J_c in the contact frame's LOCAL axes)

Given a motion and its stance schedule, :func:`estimate_wrenches` finds the ``w_c`` per knot:
inside each foot's contact wrench cone (Caron, Pham, Nakamura, ICRA 2015) with a small QP
(DAQP, Arnström, Bemporad, Axehill 2022), or without cones as a minimum-norm least-squares
solution. In single support of a free-flyer the base rows fix the one wrench completely (six
equations, six unknowns); in double support the QP picks the smallest pair of wrenches (in
units of body weight and body weight × sole half-length) that produce the net wrench.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError, SolverError, UnknownNameError
from ..model.contact import ContactForces, SoleContact, wrench_cone
from ..model.kinematics import PLANAR_BASE, base_joint_id, base_v_indices, frame_placements
from ..model.motion import Motion

__all__ = ["WrenchEstimate", "estimate_wrenches", "base_dofs", "METHODS", "measured_wrenches",
           "cone_rows"]

METHODS = ("cone", "lstsq")
GRAVITY = 9.81
#: Weight of the wrench regularisation against the scaled residual when the cones cannot
#: explain the base rows exactly (both in units of body weight).
REGULARISATION = 1e-6
#: The wrench components a planar (x, z, pitch) base can feel: f_x, f_z, τ_y.
PLANAR_COMPONENTS = (0, 2, 4)


@dataclass(frozen=True)
class WrenchEstimate:
    """Estimated contact wrenches of a motion.

    - ``wrenches`` ``{side: (T, 6)}``: ``[f; τ]`` [N, N·m] the ground applies to each foot, in
      its contact frame at the frame's origin (zeros in swing; planar bases: f_y = τ_x = τ_z
      = 0);
    - ``residual`` ``(T, 6)``: the part of the base rows of the inverse dynamics the wrenches do
      not explain, ``rnea(q, v, a)_base − Σ_c (J_cᵀ w_c)_base``, as a wrench at the base origin
      [N, N·m] — free-flyer: in the base's local frame (Pinocchio's convention); planar
      (x, z, pitch) bases: world-aligned axes, f_y = τ_x = τ_z = 0. Zero (to round-off) where
      the cones can explain the motion;
    - ``net`` ``(T, 6)``: the explained part Σ_c (J_cᵀ w_c)_base, same convention;
    - ``exact`` ``(T,)`` bool: the base rows were met exactly (``cone``: inside the cones;
      ``lstsq``: always, unless no foot is in stance);
    - ``method``; ``solve_time`` [s]: total time of the per-knot solves (QP or least squares,
      without the Pinocchio calls).
    """

    wrenches: Mapping[str, np.ndarray]
    residual: np.ndarray
    net: np.ndarray
    exact: np.ndarray
    method: str
    solve_time: float = 0.0

    def __getitem__(self, side: str) -> np.ndarray:
        return self.wrenches[side]


def base_dofs(robot) -> list[int]:
    """Indices in ``v`` of the unactuated base: free-flyer 0–5, planar ``base_x``, ``base_z``,
    ``base_pitch``; ``[]`` for a fixed base (:func:`gdimitate.model.kinematics.base_v_indices`)."""
    return [int(i) for i in base_v_indices(robot)]


def _base_wrench(robot, data, rows: np.ndarray) -> np.ndarray:
    """Base rows ``(nb,)`` → a 6-D wrench at the base origin (see :class:`WrenchEstimate`)."""
    if robot.base == "free":
        return rows
    S = pin.getJointJacobian(robot.model, data, base_joint_id(robot),
                             pin.LOCAL_WORLD_ALIGNED)[:, base_dofs(robot)]
    return np.linalg.pinv(S.T) @ rows


def _validate(robot, motion, contacts, method, f_min):
    if method not in METHODS:
        raise UnknownNameError("method", method, METHODS)
    if not isinstance(motion, Motion):
        raise InvalidInputError(f"motion must be a gdimitate.Motion; got {type(motion).__name__}")
    model = robot.model
    if robot.base not in ("free", "planar"):
        raise InvalidInputError(f"{robot.name} has a fixed base: no base rows to explain; "
                                "estimate_wrenches needs a free-flyer or planar base")
    if motion.q.shape[1] != model.nq:
        raise InvalidInputError(f"motion.q has {motion.q.shape[1]} columns; {robot.name} has "
                                f"nq = {model.nq}")
    motion.derivatives("estimate_wrenches")
    for name in ("v", "a"):
        if getattr(motion, name).shape != (motion.T, model.nv):
            raise InvalidInputError(f"motion.{name} must be (T, nv) = ({motion.T}, "
                                    f"{model.nv}); got {getattr(motion, name).shape}")
    contacts = dict(robot.require_contacts() if contacts is None else contacts)
    for side, c in contacts.items():
        if not isinstance(c, SoleContact):
            raise InvalidInputError(f"contacts[{side!r}] must be a SoleContact")
        robot.frame_id(c.frame)
        if side not in motion.contact:
            raise InvalidInputError(f"motion.contact has no {side!r} stance flags; it has "
                                    f"{sorted(motion.contact)}")
    if not (np.isfinite(f_min) and f_min >= 0):
        raise InvalidInputError(f"f_min must be a finite force ≥ 0 [N]; got {f_min!r}")
    return contacts


def estimate_wrenches(robot, motion: Motion, contacts: Mapping[str, SoleContact] | None = None,
                      *, method: str = "cone", f_min: float = 0.0) -> WrenchEstimate:
    """Contact wrenches that explain the base rows of the inverse dynamics of ``motion``.

    Per knot, with ``b = rnea(q, v, a)`` restricted to the base rows and ``A_c`` the base rows
    of ``J_cᵀ`` (``J_c``: the LOCAL Jacobian of ``contacts[side].frame``), over the feet in
    stance (``motion.contact``):

    - ``method="cone"``: a small QP (DAQP). First ``min Σ‖w̃_c‖²`` s.t. ``Σ_c A_c w_c = b``,
      each ``w_c`` in its foot's contact wrench cone (16 rows; in 3-D 8 more inscribing the
      friction circle ``‖f_t‖ ≤ μ f_z``, within 8 % of μ) and ``f_z ≥ f_min`` [N]
      (``w̃``: forces over the body weight ``m·g``, moments over ``m·g`` × the sole's
      half-length). Where the cones cannot meet ``b`` exactly, the least residual instead:
      ``min ‖r̃‖² + 1e-6·Σ‖w̃_c‖²`` with ``r = b − Σ A_c w_c`` (forces over ``m·g``, moments over
      ``m·g`` × the leg length), same constraints. The split in double support is the QP's.
    - ``method="lstsq"``: the minimum-norm least-squares solution (same scaling) without any
      cone or ``f_min`` — what a kinematic retargeter implicitly asks of the floor (feet may
      pull, the centre of pressure may leave the sole).

    Feet in swing get zeros. ``motion`` needs ``v``, ``a``
    (:func:`gdimitate.model.motion.differentiate`)
    and ``contact``. Free-flyer and planar (x, z, pitch) bases; a fixed base raises
    :class:`~gdimitate.errors.InvalidInputError` (nothing to explain). Returns a
    :class:`WrenchEstimate` (wrenches, the unexplained residual, the explained net wrench).
    """
    contacts = _validate(robot, motion, contacts, method, f_min)
    assert motion.v is not None and motion.a is not None  # checked by _validate
    model = robot.model
    data = model.createData()
    T = motion.T
    bd = base_dofs(robot)
    comps = list(PLANAR_COMPONENTS) if robot.base == "planar" else list(range(6))
    weight = robot.mass * GRAVITY
    leg = float(np.mean([robot.legs[s].length for s in robot.legs])) if robot.legs else 1.0
    moment_rows = _moment_rows(robot, bd)
    row_scale = np.where(moment_rows, weight * leg, weight)
    sides = list(contacts)
    fids = {s: robot.frame_id(contacts[s].frame) for s in sides}
    scale = {s: np.array([weight] * 3 + [weight * contacts[s].half_length] * 3)[comps]
             for s in sides}
    cones = {s: cone_rows(contacts[s], planar=robot.base == "planar")[:, comps] * scale[s]
             for s in sides}
    out = {s: np.zeros((T, 6)) for s in sides}
    residual = np.zeros((T, 6))
    net = np.zeros((T, 6))
    exact = np.zeros(T, bool)
    spent = 0.0
    structures: dict[tuple[str, ...], tuple] = {}
    for k in range(T):
        b = pin.rnea(model, data, motion.q[k], motion.v[k], motion.a[k])[bd].copy()
        pin.computeJointJacobians(model, data, motion.q[k])
        pin.updateFramePlacements(model, data)
        stance = [s for s in sides if motion.contact[s][k]]
        A = [pin.getFrameJacobian(model, data, fids[s], pin.LOCAL)[:, bd].T[:, comps] * scale[s]
             for s in stance]
        t0 = time.perf_counter()
        if not stance:
            x, ok = np.zeros(0), False
        elif method == "lstsq":
            Am = np.hstack(A)
            x = np.linalg.lstsq(Am, b, rcond=None)[0]
            ok = bool(np.allclose(Am @ x, b, rtol=0, atol=1e-9 * weight))
        else:
            key = tuple(stance)
            if key not in structures:
                structures[key] = _qp_rows([cones[s] for s in stance], comps.index(2),
                                           f_min / weight, len(bd))
            x, ok = _cone_qp(np.hstack(A), b, structures[key], row_scale)
        spent += time.perf_counter() - t0
        explained = np.hstack(A) @ x if stance else np.zeros(len(bd))
        n = len(comps)
        for i, s in enumerate(stance):
            out[s][k, comps] = x[i * n:(i + 1) * n] * scale[s]
        net[k] = _base_wrench(robot, data, explained)
        residual[k] = _base_wrench(robot, data, b - explained)
        exact[k] = ok
    return WrenchEstimate(out, residual, net, exact, method, spent)


def cone_rows(c: SoleContact, planar: bool) -> np.ndarray:
    """``(16, 6)`` contact wrench cone rows (Caron et al.; square friction pyramids), plus, in
    3-D, 8 rows of the regular octagon inscribed in the friction circle ``‖f_t‖ ≤ μ f_z`` (the
    pyramid alone admits ‖f_t‖ up to √2·μ f_z; the audit checks the circle)."""
    A = wrench_cone(c.half_length, c.half_width, c.mu)
    if planar:  # f_y = 0: |f_x| ≤ μ f_z is the circle
        return A
    th = np.arange(8) * np.pi / 4
    octagon = np.zeros((8, 6))
    octagon[:, 0], octagon[:, 1] = np.cos(th), np.sin(th)
    octagon[:, 2] = -c.mu * np.cos(np.pi / 8)
    return np.vstack([A, octagon])


def _moment_rows(robot, bd: list[int]) -> np.ndarray:
    """Which base rows are moments (rotational dofs) rather than forces."""
    if robot.base == "free":
        return np.array([False] * 3 + [True] * 3)
    return np.array([j == "base_pitch" for j in PLANAR_BASE])


def _qp_rows(cones: list[np.ndarray], iz: int, fz_min: float, nb: int):
    """The inequality rows of one stance combination: ``(G, upper, lower, sense)`` with each
    foot's cone ``G_c x_c ≤ 0`` and ``x_c[iz] ≥ fz_min`` (scaled units)."""
    n = cones[0].shape[1]
    p = n * len(cones)
    rows = []
    for i, c in enumerate(cones):
        block = np.zeros((c.shape[0] + 1, p))
        block[:-1, i * n:(i + 1) * n] = c
        block[-1, i * n + iz] = 1.0
        rows.append(block)
    G = np.vstack(rows)
    m = cones[0].shape[0]
    up = np.tile(np.r_[np.zeros(m), 1e30], len(cones))
    lo = np.tile(np.r_[np.full(m, -1e30), fz_min], len(cones))
    sense = np.r_[np.full(nb, 5), np.zeros(G.shape[0])].astype(np.intc)
    return G, up, lo, sense


def _cone_qp(A: np.ndarray, b: np.ndarray, rows, row_scale: np.ndarray
             ) -> tuple[np.ndarray, bool]:
    """Solve for the scaled wrenches ``x`` ``(p,)``; True when ``A x = b`` holds exactly."""
    import daqp

    G, up, lo, sense = rows
    nb, p = A.shape
    upper, lower = np.concatenate([b, up]), np.concatenate([b, lo])
    # stage 1: meet the base rows exactly, smallest wrenches
    x, _, flag, _ = daqp.solve(np.eye(p), np.zeros(p), np.concatenate([A, G]), upper, lower,
                               sense)
    if flag == 1:
        return np.asarray(x), True
    # stage 2: least scaled residual r̃ (A x + diag(s) r̃ = b), lightly regularised wrenches
    H = np.diag(np.r_[np.full(p, REGULARISATION), np.ones(nb)])
    M = np.vstack([np.hstack([A, np.diag(row_scale)]),
                   np.hstack([G, np.zeros((G.shape[0], nb))])])
    x, _, flag, _ = daqp.solve(H, np.zeros(p + nb), M, upper, lower, sense)
    if flag != 1:
        raise SolverError(f"the wrench QP failed (DAQP exit flag {flag}) although it is always "
                          "feasible; check the motion for extreme values")
    return np.asarray(x[:p]), False


def measured_wrenches(robot, motion: Motion, forces: ContactForces,
                      contacts: Mapping[str, SoleContact] | None = None) -> dict[str, np.ndarray]:
    """Measured ground reaction forces as contact wrenches ``{side: (T, 6)}`` [N, N·m] at each
    foot's contact frame, in its axes — the convention of :func:`estimate_wrenches`, the
    adaptor's output and :func:`gdimitate.assess.audit.audit` (whose ``tau`` is then the inverse
    dynamics with the measured forces applied).

    Per knot the world force f acts at the centre of pressure c with the free moment τ_free
    (``forces``, on the motion's own time grid): at the frame's origin p with rotation R the
    wrench is ``[Rᵀ f; Rᵀ ((c − p) × f + τ_free)]``; zeros where the foot is not in contact.
    """
    contacts = dict(contacts or robot.require_contacts())
    if forces.t.shape != motion.t.shape or not np.allclose(forces.t, motion.t, atol=1e-9):
        raise InvalidInputError("forces must be on the motion's time grid (read_grf(..., t="
                                "motion.t) resamples them)")
    P = frame_placements(robot, motion.q, [c.frame for c in contacts.values()])
    out = {s: np.zeros((motion.T, 6)) for s in contacts}
    for s, c in contacts.items():
        f, R, p = forces[s], P[c.frame].rotation, P[c.frame].translation
        tau = np.cross(f.cop - p, f.force) + f.torque
        Rt = R.transpose(0, 2, 1)
        w = np.concatenate([np.einsum("tij,tj->ti", Rt, f.force),
                            np.einsum("tij,tj->ti", Rt, tau)], axis=1)
        out[s] = np.where(np.asarray(f.contact, bool)[:, None], w, 0.0)
    return out
