"""Whole-body dynamics, base rows: ``rnea(q, v, a) − Σ_c J_c(q)ᵀ w_c`` (Featherstone's
recursive Newton-Euler with the contact wrenches inside the recursion,
:meth:`gdimitate.model.symbolic.SymbolicModel.rnea_contact_expr`, built once per knot by
:meth:`Knot.torques <gdimitate.retarget.knot.Knot.torques>`) has vanishing unactuated base
rows, in N and N·m (so that the optimiser's absolute tolerance is the audit's; :meth:`scale`
m·g turns them into scaled units for reports). Equalities, never relaxed."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..knot import Knot
from .base import Bounds, Constraint, Spec


@dataclass(frozen=True)
class BaseDynamics(Constraint):
    """The unactuated base rows of the whole-body dynamics, ``(n_base,)`` [N, N·m] (module
    docstring), equal to 0 at every knot."""

    name: str = "dynamics: base residual"
    relaxable: bool = False

    def rows(self, k: Knot) -> ca.SX:
        """``(n_base, 1)`` base rows of ``rnea − Σ Jᵀw`` [N, N·m]."""
        return k.torques()[k.base_idx.tolist()]

    def bounds(self, spec: Spec) -> Bounds:
        """0 on both sides, ``(T, n_base)``."""
        z = np.zeros((spec.T, spec.n_base))
        return Bounds(z, z)

    def scale(self, k: Knot) -> float:
        """m·g [N]: the rows over it are in scaled units."""
        return k.mg
