"""Keypoint cost: per leg, the unit thigh direction (hip → knee, divided by the imitator's thigh
length: :func:`.shank.unit_segment`) minus the demonstrator's (parameter ``thigh_<side>``;
weight ``thigh``). Eq. (1) gives it up."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from ..knot import Knot
from .base import Cost
from .shank import unit_segment


@dataclass(frozen=True)
class Thigh(Cost):
    """Per leg the unit thigh vector minus the demonstrator's."""

    name: str = "thigh"
    weight: str = "thigh"

    def residual(self, k: Knot) -> ca.SX:
        """``(6, 1)`` dimensionless: per leg x, y, z."""
        return ca.vertcat(*[unit_segment(k, s, 0) - k.P(f"thigh_{s}") for s in SIDES])
