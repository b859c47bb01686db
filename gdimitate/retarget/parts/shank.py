"""Keypoint cost: per leg, the unit shank direction (knee → ankle, divided by the imitator's
shank length) minus the demonstrator's (parameter ``shank_<side>``; weight ``shank``). Eq. (1)
keeps it."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...robot import SIDES
from .base import Cost


@dataclass(frozen=True)
class Shank(Cost):
    name: str = "shank"
    weight: str = "shank"

    def residual(self, k):
        L = k.segment_lengths()
        return ca.vertcat(*[(k.ankle[s] - k.knee[s]) / L[s][1] - k.P(f"shank_{s}")
                            for s in SIDES])
