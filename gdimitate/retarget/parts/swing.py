"""Swing clearance: every corner of a swing foot's sole rectangle at least ``clearance``
above the floor z = 0 (swing: not in the demonstration's stance; under Eq. (1)'s ``"anchor"``
rule a second stance foot is neither a contact nor held above the floor), except at a
lift-off knot, where :mod:`.contact` holds the foot flat on the floor for one more knot.
Rows: corner heights / leg length (planar models: the front and back edge). Relaxable."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.robot import SIDES
from ..knot import Knot
from .base import Bounds, Constraint, Spec, per_side_labels


def rows_per_side(planar: bool) -> int:
    """Rows of one foot: its 4 corners (planar: 2 edges)."""
    return 2 if planar else 4


def corners(k: Knot, side: str) -> list[ca.SX]:
    """World heights [m] of the sole corners (front-left, front-right, back-right, back-left;
    planar: front, back)."""
    X, Y = k.P(f"sole_{side}")[0], k.P(f"sole_{side}")[1]
    p, R = k.sole_p[side], k.sole_R[side]
    pts = [(X, 0), (-X, 0)] if k.planar else [(X, Y), (X, -Y), (-X, -Y), (-X, Y)]
    return [p[2] + R[2, 0] * cx + R[2, 1] * cy for cx, cy in pts]


@dataclass(frozen=True)
class SwingClearance(Constraint):
    """Every sole corner of a swing foot at least ``clearance`` above the floor."""

    name: str = "swing clearance"
    relaxable: bool = True

    def rows(self, k: Knot) -> ca.SX:
        """``(8, 1)`` per foot its corners' heights over the leg length (planar ``(4, 1)``)."""
        L = k.leg["left"].length
        return ca.vertcat(*[ca.vertcat(*corners(k, s)) / L for s in SIDES])

    def labels(self, k: Knot) -> list[str]:
        return per_side_labels(self.name, rows_per_side(k.planar))

    def bounds(self, spec: Spec) -> Bounds:
        """Below: ``clearance / leg_length`` at a foot's swing knots but its lift-off knot,
        free elsewhere; above: free. Each ``(T, n)``."""
        n = rows_per_side(spec.planar)
        lo = np.full((spec.T, 2 * n), -np.inf)
        for i, s in enumerate(SIDES):
            up = spec.swing[s] & ~spec.liftoff[s]
            lo[up, i * n:(i + 1) * n] = spec.clearance / spec.leg_length
        return Bounds(lo, np.full_like(lo, np.inf))
