"""A warm start for the whole-body problem: Eq. (1)'s motion (the paper's closed form, with
the base placed so that the anchor foot does not slip) where the robots' legs allow it, else
the imitator's neutral pose carrying the mapped joint targets along the demonstrator's scaled
pelvis path; velocities and accelerations by forward differences on the manifold (consistent
with the integration constraints), stance wrenches sharing the weight."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...errors import GdimitateError
from ...model.robot import SIDES, Robot
from ...planar.analytic import adapt_planar
from ..targets import Targets


def initial_q(demonstrator: Robot, imitator: Robot, tg: Targets, q_index: np.ndarray
              ) -> np.ndarray:
    """Configurations ``(T, nq)`` of the warm start."""
    demo = tg.demo.replace(contact=tg.stance)
    try:
        q = adapt_planar(demo, demonstrator, imitator, "analytic").motion.q.copy()
    except GdimitateError:
        q = np.tile(imitator.neutral, (tg.T, 1))
        if imitator.base == "free" and demonstrator.base == "free":
            ratio = imitator.legs["left"].length / demonstrator.legs["left"].length
            q[:, :2] = (tg.demo.q[:, :2] - tg.demo.q[0, :2]) * ratio
    if imitator.base == "free":
        q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    return q


def consistent_start(model: pin.Model, t: np.ndarray, q: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, v, a)`` with ``q_{k+1} = q_k ⊕ h v_{k+1}`` and ``v_{k+1} = v_k + h a_k``
    exactly."""
    T = len(q)
    h = np.diff(t)
    v = np.zeros((T, model.nv))
    for k in range(T - 1):
        v[k + 1] = pin.difference(model, q[k], q[k + 1]) / h[k]
    if T > 1:
        v[0] = v[1]
    qq = q.copy()
    for k in range(T - 1):  # re-integrate so the start meets the integration rows exactly
        qq[k + 1] = pin.integrate(model, qq[k], h[k] * v[k + 1])
    a = np.zeros_like(v)
    for k in range(T - 1):
        a[k] = (v[k + 1] - v[k]) / h[k]
    return qq, v, a


def initial_wrenches(robot: Robot, motion, contacts, f_min: float, nw: int
                     ) -> dict[str, np.ndarray]:
    """Wrenches ``{side: (T, nw)}`` that explain the start's base dynamics inside the cones
    where they can (:func:`gdimitate.assess.wrenches.estimate_wrenches`, a QP per knot; the least
    residual elsewhere), in the variables' layout (planar: f_x, f_z, τ_y)."""
    from ...assess.wrenches import estimate_wrenches

    est = estimate_wrenches(robot, motion, contacts, method="cone", f_min=f_min)
    cols = [0, 2, 4] if nw == 3 else list(range(6))
    return {s: np.where(np.asarray(motion.contact[s])[:, None], est.wrenches[s][:, cols], 0.0)
            for s in SIDES}
