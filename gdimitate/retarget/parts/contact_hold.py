"""Contact hold between neighbouring knots: a stance foot neither slides nor turns — per foot
``Δp_x``, ``Δp_y`` of the sole frame's origin and ``sin Δψ`` of its x axis (planar: ``Δp_x``)
between knot k − 1 (stance) and knot k (stance or lift-off; :mod:`.flat_contact` explains the
lift-off knot). Never relaxed."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.robot import SIDES
from ..knot import Knot
from .base import Bounds, PairConstraint, Spec


@dataclass(frozen=True)
class ContactHold(PairConstraint):
    """Between knots: per foot ``Δp_x``, ``Δp_y`` and ``sin Δψ`` of the sole's x axis (planar:
    ``Δp_x``), imposed where the foot is in stance at k − 1 and in stance or lifting off at
    k."""

    name: str = "contact hold (slip)"

    def carry(self, k: Knot) -> ca.SX:
        """``(8, 1)`` per foot the sole origin's ``p_x``, ``p_y`` [m] and its x axis's world
        ``R[0, 0]``, ``R[1, 0]`` (planar ``(2, 1)``: ``p_x`` per foot)."""
        out = []
        for s in SIDES:
            p, R = k.sole_p[s], k.sole_R[s]
            out += [p[0]] if k.planar else [p[0], p[1], R[0, 0], R[1, 0]]
        return ca.vertcat(*out)

    def rows(self, k: Knot, prev: ca.SX, cur: ca.SX) -> ca.SX:
        """``(6, 1)`` per foot ``Δp_x``, ``Δp_y`` [m] and ``sin Δψ`` (planar ``(2, 1)``:
        ``Δp_x`` per foot)."""
        if k.planar:
            return cur - prev
        rows = []
        for i in range(2):
            o = 4 * i
            rows += [cur[o] - prev[o], cur[o + 1] - prev[o + 1],
                     cur[o + 3] * prev[o + 2] - cur[o + 2] * prev[o + 3]]  # sin Δψ
        return ca.vertcat(*rows)

    def bounds(self, spec: Spec, n: int) -> Bounds:
        """0 where the foot is held (stance at k − 1, stance or lift-off at k), free
        elsewhere; each ``(T − 1, n)``."""
        m = n // 2
        lo = np.full((spec.T - 1, n), -np.inf)
        for i, s in enumerate(SIDES):
            h = (spec.stance[s] | spec.liftoff[s])[1:] & spec.stance[s][:-1]
            lo[h, i * m:(i + 1) * m] = 0.0
        return Bounds(lo, np.where(np.isfinite(lo), 0.0, np.inf))
