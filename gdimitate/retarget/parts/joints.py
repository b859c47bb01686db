"""Joint similarity: each actuated joint's angle minus its target — the mapped demonstrator
joint (``scale · q_demo + offset``, weight ``joints``) or, for joints the body map leaves out,
the imitator's neutral pose (weight ``posture``). The per-joint √weights are the knot's
``joint_weight`` parameter (frozen joints: 0), so the part has no single weight name."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ..knot import Knot
from .base import Cost


@dataclass(frozen=True)
class Joints(Cost):
    """``q_index``: the actuated joints' indices into ``q`` (velocity order)."""

    q_index: tuple[int, ...] = ()
    name: str = "joints"
    weight: str | None = None

    def residual(self, k: Knot) -> ca.SX:
        """``(n_act, 1)``: ``√w_j (q_j − q_j,target)`` [√weight · rad]."""
        q = k.q[list(map(int, self.q_index))]
        return k.P("joint_weight") * (q - k.P("joint_target"))  # carries √weight
