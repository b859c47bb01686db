"""Exact consistency of a solution before it is reported (docs/design.md §6, §12).

IPOPT stops once its iterate is feasible to its constraint tolerance and the cost has stopped
moving (:data:`~.params.IPOPT_DEFAULTS`), so the equality rows hold to ~1e-6 in their scaled
units rather than to round-off. Before the motion is reported, the equalities are made exact
on the output's own numbers — nothing is clipped and no inequality is touched:

- a free-flyer's quaternion is normalised at every knot;
- ``v`` is rebuilt from ``q`` by the integration rule (``v_k = (q_{k−1} ⊖ q_k) / h_k`` for
  k ≥ 1, Pinocchio's ``difference``) and ``a`` from ``v`` (``a_{k−1} = (v_k − v_{k−1}) /
  h_k``), so that forward differences of ``q`` *are* ``v``;
- the stance wrenches get the least-norm correction that zeroes the unactuated (base) rows of
  ``rnea(q, v, a) − Σ J_cᵀ w_c`` (Pinocchio, not the NLP's expressions). Given the soles'
  ``contacts``, the correction is the least-norm one that also leaves every row of each
  sole's wrench cone (:func:`gdimitate.assess.wrenches.cone_rows`: friction, centre of pressure, yaw
  moment) no worse than ``max(0, its value before)`` — a QP (DAQP) where the plain
  least-norm correction would push a wrench out of its cone. In double support the base rows
  leave it the freedom; where they do not (one foot, or the QP infeasible) the plain
  correction stands and the audit judges it. Given ``targets`` (the push directions the
  solve kept), the push of each stance foot also stays within half the audit's tolerance of
  its target's cone — or no further off than it was — through 8 rows of the regular octagon
  inscribed in that cone. (A periodic cycle's first knot gets a new acceleration when its
  seam is closed, :func:`~.periodic.close_seam`: G1's, at 45 knots/s, then put both soles'
  centres of pressure 7-8 µm past their edges with the plain correction, and Talos's turned
  the push of its right foot, just struck and lightly loaded, 4.1 mrad off its target.)

Each correction is of the size of IPOPT's final constraint violation; the audit
(:func:`gdimitate.assess.audit.audit`) then judges every inequality on the corrected numbers.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...model.contact import SoleContact
from ...model.robot import SIDES, Robot

__all__ = ["make_consistent"]


def _rebuild_derivatives(model: pin.Model, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                         a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    v, a = v.copy(), a.copy()
    h = np.diff(t)
    for k in range(1, len(t)):
        v[k] = pin.difference(model, q[k - 1], q[k]) / h[k - 1]
    for k in range(1, len(t)):
        a[k - 1] = (v[k] - v[k - 1]) / h[k - 1]
    return v, a


def _direction_rows(R: np.ndarray, target: np.ndarray, half_angle: float,
                    comp: list[int]) -> np.ndarray:
    """``(8, len(comp))`` rows ``G`` with ``G w ≤ 0`` when the push ``−R f`` of a sole wrench
    ``w`` (sole frame, ``R`` the sole's rotation) lies in the regular octagonal pyramid
    inscribed in the cone of half-angle ``half_angle`` [rad] about ``target`` ``(3,)``
    (world, unit)."""
    u = -R.T @ target  # the direction of the force on the foot, sole frame
    e1 = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    r = np.tan(half_angle) * np.cos(np.pi / 8)
    G = np.zeros((8, 6))
    for i, phi in enumerate(np.arange(8) * np.pi / 4):
        G[i, :3] = np.cos(phi) * e1 + np.sin(phi) * e2 - r * u
    return G[:, comp]


def _correct_wrenches(robot: Robot, q: np.ndarray, v: np.ndarray, a: np.ndarray,
                      W: dict[str, np.ndarray], stance: dict[str, np.ndarray],
                      frames: dict[str, str], base_idx: np.ndarray,
                      contacts: dict[str, SoleContact] | None = None,
                      targets: dict[str, np.ndarray] | None = None, half_angle: float = 0.0
                      ) -> dict[str, np.ndarray]:
    from ...assess.audit.report import AuditTolerances
    from ...assess.wrenches import cone_rows

    angle = half_angle + 0.5 * AuditTolerances().force_direction

    m, d = robot.model, robot.data
    planar = robot.base == "planar"
    comp = [0, 2, 4] if planar else list(range(6))
    W = {s: w.copy() for s, w in W.items()}
    fids = {s: m.getFrameId(frames[s]) for s in SIDES}
    cones = ({s: cone_rows(c, planar)[:, comp] for s, c in contacts.items()}
             if contacts else None)
    for k in range(len(q)):
        sides = [s for s in SIDES if stance[s][k]]
        if not sides:
            continue
        tau = pin.rnea(m, d, q[k], v[k], a[k]).copy()
        pin.computeJointJacobians(m, d, q[k])
        pin.updateFramePlacements(m, d)
        cols = []
        for s in sides:
            J = pin.getFrameJacobian(m, d, fids[s], pin.LOCAL)[comp]
            tau -= J.T @ W[s][k, comp]
            cols.append(J.T[base_idx])
        A = np.hstack(cols)
        dw = np.linalg.lstsq(A, tau[base_idx], rcond=None)[0]
        if cones is not None:
            w0 = [W[s][k, comp] for s in sides]
            rows = [cones[s] if targets is None or not np.all(np.isfinite(targets[s][k]))
                    else np.vstack([cones[s], _direction_rows(
                        d.oMf[fids[s]].rotation, targets[s][k], angle, comp)])
                    for s in sides]
            dw = _within_cones(A, tau[base_idx], dw, rows, w0)
        for i, s in enumerate(sides):
            W[s][k, comp] += dw[i * len(comp):(i + 1) * len(comp)]
    return W


def _within_cones(A: np.ndarray, b: np.ndarray, dw: np.ndarray, cones: list[np.ndarray],
                  w0: list[np.ndarray]) -> np.ndarray:
    """The least-norm ``dw`` with ``A dw = b`` and every cone row ``G_c (w0_c + dw_c)`` at most
    ``max(0, G_c w0_c)``; ``dw`` (the plain least-norm correction) itself where it already
    keeps them, or where the QP has no solution."""
    import daqp

    n = w0[0].size
    G = np.zeros((sum(c.shape[0] for c in cones), n * len(cones)))
    before, r = [], 0
    for i, (c, w) in enumerate(zip(cones, w0, strict=True)):
        G[r:r + c.shape[0], i * n:(i + 1) * n] = c
        before.append(c @ w)
        r += c.shape[0]
    g0 = np.concatenate(before)
    room = np.maximum(g0, 0.0) - g0  # G dw ≤ room
    if np.all(G @ dw <= room):
        return dw
    nb, p = A.shape
    sense = np.r_[np.full(nb, 5), np.zeros(G.shape[0])].astype(np.intc)
    x, _, flag, _ = daqp.solve(np.eye(p), np.zeros(p), np.vstack([A, G]),
                               np.r_[b, room], np.r_[b, np.full(G.shape[0], -1e30)], sense)
    return np.asarray(x) if flag in (1, 2) else dw


def make_consistent(robot: Robot, t: np.ndarray, q: np.ndarray, v: np.ndarray, a: np.ndarray,
                    W: dict[str, np.ndarray], stance: dict[str, np.ndarray],
                    frames: dict[str, str], base_idx: np.ndarray,
                    contacts: dict[str, SoleContact] | None = None,
                    targets: dict[str, np.ndarray] | None = None, half_angle: float = 0.0
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """The solution with its equality rows exact (see the module docstring).

    Args:
        robot: the imitator.
        t: knot times ``(T,)`` [s]; q ``(T, nq)``, v ``(T, nv)``, a ``(T, nv)``.
        W: sole-frame wrenches ``{side: (T, 6)}`` [N, N·m]; stance ``{side: (T,) bool}``.
        frames: each side's contact frame name; base_idx: the unactuated rows of ``v``.
        contacts: the soles (:class:`~gdimitate.contact.SoleContact`): the wrench correction
            keeps their cones (module docstring); ``None``: the plain least-norm one.
        targets: with ``contacts``, the push directions kept ``{side: (T, 3)}`` (world, unit;
            NaN rows: none) and ``half_angle`` [rad] the cone around them the audit allows.

    Returns:
        ``(q, v, a, W)``, new arrays.
    """
    q = np.array(q, dtype=float)
    if robot.base == "free":
        q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    v, a = _rebuild_derivatives(robot.model, np.asarray(t, float), q, np.asarray(v, float),
                                np.asarray(a, float))
    W = _correct_wrenches(robot, q, v, a, W, stance, frames, np.asarray(base_idx), contacts,
                          targets, half_angle)
    return q, v, a, W
