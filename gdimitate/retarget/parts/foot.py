"""Keypoint cost: each foot's world orientation, its sole frame's 9 rotation entries minus the
demonstrator's (parameter ``foot_<side>``; weight ``foot``). Eq. (1) keeps it with the ankle
angle."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from ..knot import Knot
from .base import Cost


@dataclass(frozen=True)
class Foot(Cost):
    """Each sole frame's world rotation minus the demonstrator's (module docstring)."""

    name: str = "foot"
    weight: str = "foot"

    def residual(self, k: Knot) -> ca.SX:
        """``(18, 1)``: per foot the 9 entries of ``R_sole − R_demo`` (column-major)."""
        return ca.vertcat(*[ca.vec(k.sole_R[s]) - k.P(f"foot_{s}") for s in SIDES])
