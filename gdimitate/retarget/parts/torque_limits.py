"""Torque limits: each actuated joint's ``τ_j / τ_max,j`` in [−1, 1], with ``τ`` the actuated
rows of the same recursion as :mod:`.base_dynamics` (:meth:`Knot.torques
<gdimitate.retarget.knot.Knot.torques>`; ``inv_effort`` is 0 for a joint without a limit).
Relaxable. A joint the user freezes still has its torque counted here."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Constraint


@dataclass(frozen=True)
class TorqueLimits(Constraint):
    name: str = "torque limit"
    relaxable: bool = True

    def rows(self, k):
        return k.torques()[k.act_idx.tolist()] * k.P("inv_effort")

    def bounds(self, spec):
        one = np.ones((spec.T, spec.n_act))
        return -one, one

    def labels(self, k) -> list[str]:
        return [f"torque limit: {n}" for n in k.act_names]
