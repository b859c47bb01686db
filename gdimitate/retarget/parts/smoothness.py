"""Smoothness: the generalised acceleration ``a`` [rad/s², m/s²] of every knot (weight
``smoothness``). Accelerations are linked to ``v`` and ``q`` by integration, so this
penalises the motion's real second differences."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ..knot import Knot
from .base import Cost


@dataclass(frozen=True)
class Smoothness(Cost):
    """The knot's generalised acceleration."""

    name: str = "smoothness"
    weight: str = "smoothness"

    def residual(self, k: Knot) -> ca.SX:
        """``(nv, 1)`` ``a`` [rad/s², m/s²]."""
        return k.a
