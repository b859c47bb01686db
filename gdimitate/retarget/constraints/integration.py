"""Consistency of the knots by integration (semi-implicit Euler on the configuration
manifold), not by finite-difference matrices:

    v_k = v_{k−1} + h_k a_{k−1},        q_k = q_{k−1} ⊕ h_k v_k     (h_k = t_k − t_{k−1})

with ⊕ Pinocchio's ``integrate`` written symbolically
(:attr:`gdimitate.symbolic.SymbolicModel.integrate`: the SE(3) exponential map for a
free-flyer). So the forward difference ``pin.difference(q_k, q_{k+1}) / h`` *is*
``v_{k+1}`` and the forward difference of ``v`` is ``a_k``: velocity limits on ``v`` bound the
velocities the motion really has, the dynamics at knot k use exactly these
``(q_k, v_k, a_k)``, and a new acceleration moves the very next configuration (what the
streaming mode needs). The
free-flyer's quaternion has unit norm at knot 0 (a per-knot row imposed there only);
integration keeps it. Never relaxed.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..knot import Knot

NAME = "integration"
RELAX = False


def step_function(k: Knot) -> ca.Function:
    """``(x_{k−1}, x_k, p_k) -> rows (nq + nv,)``."""
    x0 = ca.SX.sym("x0", k.var.size)
    q0, v0, a0 = x0[k.var["q"]], x0[k.var["v"]], x0[k.var["a"]]
    h = k.P("h")[0]
    rows = ca.vertcat(k.q - k.sym.integrate(q0, h * k.v), k.v - v0 - h * a0)
    return ca.Function("step", [x0, k.x, k.p], [rows])


def quaternion_row(k: Knot) -> ca.SX:
    """``|quat|² − 1`` for a free-flyer base (an empty row otherwise)."""
    if k.robot.base != "free":
        return ca.SX(0, 1)
    quat = k.q[3:7]
    return ca.dot(quat, quat) - 1.0


def quaternion_bounds(spec) -> tuple[np.ndarray, np.ndarray]:
    n = 1 if spec.free else 0
    lo = np.full((spec.T, n), -np.inf)
    lo[0] = 0.0
    return lo, np.where(np.isfinite(lo), 0.0, np.inf)
