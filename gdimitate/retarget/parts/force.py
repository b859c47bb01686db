"""The goal: each stance foot's force direction parallel to the demonstrator's.

``d`` is the unit direction of the ground's force on the demonstrator's foot (its push on the
ground reversed), ``e1``, ``e2`` complete it to an orthonormal frame (parameters per knot).
The imitator's vector ``c`` is, by force model:

- ``measured``, ``dynamics`` — its own contact force in world axes (divided by m·g);
- ``segment`` — the reverse of its unit shank vector (ankle → knee, divided by the shank's
  3-D length ``Leg.segments[1]``: :func:`.shank.unit_segment`, a unit vector whatever the
  leg's joint axes): the paper's model, under which Eq. (1) is the optimum;
- ``com`` — from its contact point to its centre of mass (divided by the leg length).

Equality: ``e1·c = e2·c = 0``, ``d·c ≥ 0``. Cone of half-angle α:
``(e1·c)² + (e2·c)² ≤ tan²α (d·c)²``, ``d·c ≥ 0``. Rows are imposed where the demonstrator's
direction exists and the imitator's foot is in stance; relaxable. Planar models: ``e2`` is
unused (its row is never imposed).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.robot import SIDES
from ..knot import Knot
from .base import Bounds, Constraint, Spec, per_side_labels
from .shank import unit_segment


def rows_per_side(cone: bool) -> int:
    """Rows of one foot: 2 for a cone, 3 for the equality."""
    return 2 if cone else 3


def vector(k: Knot, side: str) -> ca.SX:
    """``(3, 1)`` the imitator's ``c`` at foot ``side`` (see the module docstring;
    dimensionless)."""
    goal = k.flags.goal
    if goal == "force":
        return k.wrench_world(side)[:3] / k.mg
    if goal == "segment":
        return -unit_segment(k, side, 1)
    return (k.com - k.sole_p[side]) / k.leg[side].length


@dataclass(frozen=True)
class ForceDirection(Constraint):
    """Per foot the imitator's vector ``c`` along the demonstrator's direction ``d``
    (module docstring)."""

    name: str = "force direction"
    relaxable: bool = True

    def rows(self, k: Knot) -> ca.SX:
        """``(6, 1)`` per foot ``e1·c``, ``e2·c``, ``d·c``; a cone ``(4, 1)`` per foot
        ``(e1·c)² + (e2·c)² − tan²α (d·c)²``, ``d·c`` (dimensionless)."""
        out = []
        for s in SIDES:
            c = vector(k, s)
            d, e1, e2 = k.P(f"d_{s}"), k.P(f"e1_{s}"), k.P(f"e2_{s}")
            dc, a, b = ca.dot(d, c), ca.dot(e1, c), ca.dot(e2, c)
            out += [a * a + b * b - k.P("tan2")[0] * dc * dc, dc] if k.flags.cone else \
                [a, b, dc]
        return ca.vertcat(*out)

    def labels(self, k: Knot) -> list[str]:
        return per_side_labels(self.name, rows_per_side(k.flags.cone))

    def bounds(self, spec: Spec) -> Bounds:
        """Where the goal is active (``Spec.goal_active``): ``e1·c = e2·c = 0`` (planar:
        ``e2`` free), ``d·c ≥ 0``; a cone's first row ≤ 0, ``d·c ≥ 0``. Each ``(T, n)``."""
        n = rows_per_side(spec.cone)
        lo = np.full((spec.T, 2 * n), -np.inf)
        hi = np.full((spec.T, 2 * n), np.inf)
        for i, s in enumerate(SIDES):
            on = spec.goal_active[s]
            o = i * n
            if spec.cone:
                hi[on, o] = 0.0
                lo[on, o + 1] = 0.0
            else:
                lo[on, o] = hi[on, o] = 0.0
                if not spec.planar:
                    lo[on, o + 1] = hi[on, o + 1] = 0.0
                lo[on, o + 2] = 0.0
        return Bounds(lo, hi)
