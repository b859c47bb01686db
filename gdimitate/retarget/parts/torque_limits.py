"""Torque limits: each actuated joint's ``τ_j / τ_max,j`` in [−1, 1], with ``τ`` the actuated
rows of the same recursion as :mod:`.base_dynamics` (:meth:`Knot.torques
<gdimitate.retarget.knot.Knot.torques>`; ``inv_effort`` is 0 for a joint without a limit).
Relaxable. A joint the user freezes still has its torque counted here."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..knot import Knot
from .base import Bounds, Constraint, Spec


@dataclass(frozen=True)
class TorqueLimits(Constraint):
    """Each actuated joint's torque over its effort limit, within [−1, 1]."""

    name: str = "torque limit"
    relaxable: bool = True

    def rows(self, k: Knot) -> ca.SX:
        """``(n_act, 1)`` ``τ_j / τ_max,j`` (dimensionless; 0 without a limit)."""
        return k.torques()[k.act_idx.tolist()] * k.P("inv_effort")

    def bounds(self, spec: Spec) -> Bounds:
        """−1 and 1, each ``(T, n_act)``."""
        one = np.ones((spec.T, spec.n_act))
        return Bounds(-one, one)

    def labels(self, k: Knot) -> list[str]:
        return [f"torque limit: {n}" for n in k.act_names]
