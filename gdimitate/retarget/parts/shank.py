"""Keypoint cost: per leg, the unit shank direction (knee → ankle, divided by the imitator's
shank length) minus the demonstrator's (parameter ``shank_<side>``; weight ``shank``). Eq. (1)
keeps it. :func:`unit_segment`, the imitator's unit thigh or shank vector, is shared with the
thigh cost and the ``segment`` force model."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...model.robot import SIDES
from ..knot import Knot
from .base import Cost


def unit_segment(k: Knot, side: str, segment: int) -> ca.SX:
    """``(3,)`` the imitator's unit vector along a leg segment, world axes: ``segment`` 0 the
    thigh (hip → knee), 1 the shank (knee → ankle, or the sole without an ankle), the joint
    positions' difference divided by the segment's 3-D length ``Leg.segments`` [m] (rigid, so
    a unit vector at every configuration, whatever the leg's joint axes)."""
    top, bottom = ((k.hip, k.knee), (k.knee, k.ankle))[segment]
    return (bottom[side] - top[side]) / k.leg[side].segments[segment]


@dataclass(frozen=True)
class Shank(Cost):
    """Per leg the unit shank vector minus the demonstrator's."""

    name: str = "shank"
    weight: str = "shank"

    def residual(self, k: Knot) -> ca.SX:
        """``(6, 1)`` dimensionless: per leg x, y, z."""
        return ca.vertcat(*[unit_segment(k, s, 1) - k.P(f"shank_{s}") for s in SIDES])
