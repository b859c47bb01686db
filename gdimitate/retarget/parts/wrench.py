"""Wrench regularisation: the contact wrenches divided by m·g (weight ``wrench``); it chooses
the split between the feet in double support, where the dynamics leave it open."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from ..knot import Knot
from .base import Cost


@dataclass(frozen=True)
class WrenchRegularisation(Cost):
    """The contact wrenches over m·g."""

    name: str = "wrench"
    weight: str = "wrench"

    def residual(self, k: Knot) -> ca.SX:
        """``(2·nw, 1)`` both feet's wrench variables (already over m·g; ``nw`` 6, planar
        3)."""
        return ca.vertcat(*[k.w[s] for s in SIDES])  # already over m·g
