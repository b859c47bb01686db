"""Consistency of the knots by integration (semi-implicit Euler on the configuration
manifold), not by finite-difference matrices:

    v_k = v_{k−1} + h_k a_{k−1},        q_k = q_{k−1} ⊕ h_k v_k     (h_k = t_k − t_{k−1})

with ⊕ Pinocchio's ``integrate`` written symbolically
(:attr:`gdimitate.model.symbolic.SymbolicModel.integrate`: the SE(3) exponential map for a
free-flyer). So the forward difference ``pin.difference(q_k, q_{k+1}) / h`` *is*
``v_{k+1}`` and the forward difference of ``v`` is ``a_k``: velocity limits on ``v`` bound the
velocities the motion really has, the dynamics at knot k use exactly these
``(q_k, v_k, a_k)``, and a new acceleration moves the very next configuration (what the
streaming mode needs). The free-flyer's quaternion has unit norm at knot 0
(:class:`QuaternionNorm`, imposed there only); integration keeps it. Never relaxed.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..knot import Knot
from .base import Bounds, PairConstraint, Spec


@dataclass(frozen=True)
class Integration(PairConstraint):
    """``q_k = q_{k−1} ⊕ h_k v_k`` and ``v_k = v_{k−1} + h_k a_{k−1}`` (module docstring)."""

    name: str = "integration"

    def carry(self, k: Knot) -> ca.SX:
        """``(nq + 2·nv, 1)``: ``q``, ``v``, ``a``."""
        return ca.vertcat(k.q, k.v, k.a)

    def rows(self, k: Knot, prev: ca.SX, cur: ca.SX) -> ca.SX:
        """``(nq + nv, 1)``: ``q_k − q_{k−1} ⊕ h v_k`` [rad, m], ``v_k − v_{k−1} − h a_{k−1}``
        [rad/s, m/s] (``h``: knot k's step [s])."""
        nq, nv = k.sym.nq, k.sym.nv
        q0, v0, a0 = prev[:nq], prev[nq:nq + nv], prev[nq + nv:]
        q1, v1 = cur[:nq], cur[nq:nq + nv]
        h = k.P("h")[0]
        return ca.vertcat(q1 - k.sym.integrate(q0, h * v1), v1 - v0 - h * a0)

    def bounds(self, spec: Spec, n: int) -> Bounds:
        """0 on both sides, ``(T − 1, n)``."""
        z = np.zeros((spec.T - 1, n))
        return Bounds(z, z)
