"""Smoothness: the squared generalised acceleration ``a`` [rad/s², m/s²] of every knot
(weight ``smoothness``). Accelerations are decision variables linked to ``v`` and ``q`` by
integration, so this penalises the motion's real second differences."""

from __future__ import annotations

import casadi as ca

from ..knot import Knot


def residual(k: Knot) -> ca.SX:
    return k.weight(5) * k.a  # √weight
