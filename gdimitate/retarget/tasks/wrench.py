"""Wrench regularisation: the squared contact wrenches divided by the robot's weight m·g
(weight ``wrench``); it chooses the split between the feet in double support, where the
dynamics leave it open."""

from __future__ import annotations

import casadi as ca

from ...robot import SIDES
from ..knot import Knot


def residual(k: Knot) -> ca.SX:
    w = ca.vertcat(*[k.x[k.var[f"w_{s}"]] for s in SIDES])  # already over m·g
    return k.weight(6) * w  # √weight
