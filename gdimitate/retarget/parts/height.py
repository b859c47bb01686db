"""Keypoint cost: per leg, hip-over-ankle height / leg length minus the demonstrator's
(parameter ``height_<side>``; weight ``height``). Eq. (1) keeps it."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from .base import Cost


@dataclass(frozen=True)
class Height(Cost):
    name: str = "height"
    weight: str = "height"

    def residual(self, k):
        return ca.vertcat(*[(k.hip[s][2] - k.ankle[s][2]) / k.leg[s].length
                            - k.P(f"height_{s}") for s in SIDES])
