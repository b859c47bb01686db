"""Whole-body dynamics, base rows: ``rnea(q, v, a) − Σ_c J_c(q)ᵀ w_c`` (Featherstone's
recursive Newton-Euler with the contact wrenches inside the recursion,
:meth:`gdimitate.model.symbolic.SymbolicModel.rnea_contact_expr`, built once per knot by
:meth:`Knot.torques <gdimitate.retarget.knot.Knot.torques>`) has vanishing unactuated base
rows, in N and N·m (so that the optimiser's absolute tolerance is the audit's; :meth:`scale`
m·g turns them into scaled units for reports). Equalities, never relaxed."""

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
