"""Costs on the motion itself: the joint angles, smoothness and the contact wrenches.

- :class:`Joints` — each actuated joint's angle minus its target: the mapped demonstrator
  joint (``scale · q_demo + offset``, weight ``joints``) or, for joints the body map leaves
  out, the imitator's neutral pose (weight ``posture``). The per-joint √weights are the knot's
  ``joint_weight`` parameter (frozen joints: 0), so the part has no single weight name.
- :class:`Smoothness` — the generalised acceleration ``a`` [rad/s², m/s²] of every knot
  (weight ``smoothness``): accelerations are linked to ``v`` and ``q`` by integration, so this
  penalises the motion's real second differences.
- :class:`WrenchRegularisation` — the contact wrenches divided by m·g (weight ``wrench``); it
  chooses the split between the feet in double support, where the dynamics leave it open.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ...robot import SIDES
from .base import Cost


@dataclass(frozen=True)
class Joints(Cost):
    """``q_index``: the actuated joints' indices into ``q`` (velocity order)."""

    q_index: tuple[int, ...] = ()
    name: str = "joints"
    weight: str | None = None

    def residual(self, k):
        q = k.q[list(map(int, self.q_index))]
        return k.P("joint_weight") * (q - k.P("joint_target"))  # carries √weight


@dataclass(frozen=True)
class Smoothness(Cost):
    name: str = "smoothness"
    weight: str = "smoothness"

    def residual(self, k):
        return k.a


@dataclass(frozen=True)
class WrenchRegularisation(Cost):
    name: str = "wrench"
    weight: str = "wrench"

    def residual(self, k):
        return ca.vertcat(*[k.w[s] for s in SIDES])  # already over m·g
