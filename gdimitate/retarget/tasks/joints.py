"""Joint similarity: each actuated joint's angle minus its target — the mapped demonstrator
joint (``scale · q_demo + offset``, weight ``joints``) or, for joints the body map leaves out,
the imitator's neutral pose (weight ``posture``). Per-joint weights are parameters; frozen
joints have weight 0."""

from __future__ import annotations

import casadi as ca

from ..knot import Knot


def residual(k: Knot, q_index) -> ca.SX:
    q = k.q[list(map(int, q_index))]
    return k.P("joint_weight") * (q - k.P("joint_target"))  # √weight
