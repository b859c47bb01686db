"""A free-flyer's unit quaternion at knot 0 (``|quat|² − 1 = 0``; :mod:`.integration` keeps it
at every later knot). No rows for other bases. Never relaxed."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..knot import Knot
from .base import Bounds, Constraint, Spec


@dataclass(frozen=True)
class QuaternionNorm(Constraint):
    """``|quat|² − 1 = 0`` of a free-flyer base at knot 0 (no rows otherwise)."""

    name: str = "quaternion norm"

    def rows(self, k: Knot) -> ca.SX:
        """``(1, 1)`` ``|quat|² − 1`` for a free-flyer, ``(0, 1)`` otherwise."""
        if k.robot.base != "free":
            return ca.SX(0, 1)
        quat = k.q[3:7]
        return ca.dot(quat, quat) - 1.0

    def bounds(self, spec: Spec) -> Bounds:
        """0 at knot 0, free after; each ``(T, 1)`` (free-flyer) or ``(T, 0)``."""
        n = 1 if spec.free else 0
        lo = np.full((spec.T, n), -np.inf)
        lo[0] = 0.0
        return Bounds(lo, np.where(np.isfinite(lo), 0.0, np.inf))
