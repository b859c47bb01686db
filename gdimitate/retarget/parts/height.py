"""Keypoint cost: per leg, hip-over-ankle height / leg length minus the demonstrator's
(parameter ``height_<side>``; weight ``height``). Eq. (1) keeps it."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from ..knot import Knot
from .base import Cost


@dataclass(frozen=True)
class Height(Cost):
    """Per leg the hip's height over the ankle in leg lengths minus the demonstrator's."""

    name: str = "height"
    weight: str = "height"

    def residual(self, k: Knot) -> ca.SX:
        """``(2, 1)`` dimensionless (over each leg's length)."""
        return ca.vertcat(*[(k.hip[s][2] - k.ankle[s][2]) / k.leg[s].length
                            - k.P(f"height_{s}") for s in SIDES])
