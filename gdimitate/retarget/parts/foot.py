"""Keypoint cost: each foot's world orientation, its sole frame's 9 rotation entries minus the
demonstrator's (parameter ``foot_<side>``; weight ``foot``). Eq. (1) keeps it with the ankle
angle."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from .base import Cost


@dataclass(frozen=True)
class Foot(Cost):
    name: str = "foot"
    weight: str = "foot"

    def residual(self, k):
        return ca.vertcat(*[ca.vec(k.sole_R[s]) - k.P(f"foot_{s}") for s in SIDES])
