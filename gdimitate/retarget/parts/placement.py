"""Keypoint cost: per leg, the horizontal ankle − hip offset / leg length minus the
demonstrator's (parameter ``placement_<side>``; weight ``placement``). Eq. (1) gives it up."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from ..knot import Knot
from .base import Cost


@dataclass(frozen=True)
class Placement(Cost):
    """Per leg the horizontal ankle − hip offset in leg lengths minus the demonstrator's."""

    name: str = "placement"
    weight: str = "placement"

    def residual(self, k: Knot) -> ca.SX:
        """``(4, 1)`` dimensionless: per leg x, y."""
        return ca.vertcat(*[(k.ankle[s][:2] - k.hip[s][:2]) / k.leg[s].length
                            - k.P(f"placement_{s}") for s in SIDES])
