"""Whole-body dynamics, two constraint parts sharing one recursion.

``rnea(q, v, a) − Σ_c J_c(q)ᵀ w_c = Sᵀ τ`` (Featherstone's recursive Newton-Euler with the
contact wrenches inside the recursion,
:meth:`gdimitate.symbolic.SymbolicModel.rnea_contact_expr`; :meth:`Knot.torques
<gdimitate.retarget.knot.Knot.torques>` builds it once per knot):

- :class:`BaseDynamics` — the unactuated base rows vanish, in N and N·m (so that the
  optimiser's absolute tolerance is the audit's); equalities, never relaxed;
- :class:`TorqueLimits` — each actuated joint's ``τ_j / τ_max,j`` in [−1, 1]; relaxable. A
  joint the user freezes still has its torque counted here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Constraint


@dataclass(frozen=True)
class BaseDynamics(Constraint):
    name: str = "dynamics: base residual"
    relaxable: bool = False

    def rows(self, k):
        return k.torques()[k.base_idx.tolist()]

    def bounds(self, spec):
        z = np.zeros((spec.T, spec.n_base))
        return z, z

    def scale(self, k) -> float:
        return k.mg


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
