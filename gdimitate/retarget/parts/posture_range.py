"""Unmapped joints held within a range of their neutral pose: ``|q_j − q_j,neutral| ≤
half_range`` for every actuated joint the body map leaves out (an imitator's arms when the
demonstrator has none, its wrists, head, grippers), so that the optimiser cannot swing them as
counterweights (the posture cost alone, weight ``Weights.posture``, let G1's arms sweep
2.5 rad). Rows: ``hold_j · (q_j − q_j,neutral)`` [rad] for every actuated joint, ``hold_j`` a
parameter — 1 for a joint the body map leaves out (and not frozen), 0 otherwise — so one
compiled problem serves every body map; bounds ± ``half_range``. Not relaxable."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .base import Constraint

__all__ = ["PostureRange"]


@dataclass(frozen=True)
class PostureRange(Constraint):
    """``q_index``: indices into ``q`` of the actuated joints (velocity order, as
    :class:`.Joints`); ``held`` [rad]: their neutral poses; ``half_range`` [rad]."""

    q_index: tuple[int, ...] = ()
    held: tuple[float, ...] = ()
    half_range: float = 0.1
    name: str = "posture range"
    relaxable: bool = False

    def params(self, k):
        return {"hold": len(self.q_index)}

    def values(self, ctx):
        hold = ~np.asarray(ctx.tg.mapped, bool) & ~np.asarray(ctx.lim.frozen, bool)
        return {"hold": np.tile(hold.astype(float), (ctx.tg.T, 1))}

    def rows(self, k):
        q = k.q[list(map(int, self.q_index))]
        return k.P("hold") * (q - ca.DM(self.held))

    def bounds(self, spec):
        n = len(self.q_index)
        return np.full((spec.T, n), -self.half_range), np.full((spec.T, n), self.half_range)

    def labels(self, k):
        return [f"{self.name}: q[{i}]" for i in self.q_index]
