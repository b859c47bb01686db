"""Unmapped joints held within a range of their neutral pose: ``|q_j − q_j,neutral| ≤
half_range`` for every actuated joint the body map leaves out (an imitator's arms when the
demonstrator has none, its wrists, head, grippers), so that the optimiser cannot swing them as
counterweights (the posture cost alone, weight ``Weights.posture``, let G1's arms sweep
2.5 rad). A :class:`~.base.Bound`: the range is a box on those joints' ``q`` (intersected with
their position limits), not rows — as rows (one per actuated joint, masked by a parameter)
it put 3200 two-sided rows into Talos's 100-knot KKT system, 6 % of them, for what IPOPT
handles as variable bounds. Which joints are held comes from the demonstration
(:meth:`PostureRange.values`), so one compiled problem serves every body map. Never
relaxed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..context import Context
from ..knot import Layout
from .base import Bound, Bounds, Box, Spec

__all__ = ["PostureRange"]


@dataclass(frozen=True)
class PostureRange(Bound):
    """``q_index``: indices into ``q`` of the actuated joints (velocity order, as
    :class:`.Joints`); ``held`` [rad]: their neutral poses; ``half_range`` [rad]."""

    q_index: tuple[int, ...] = ()
    held: tuple[float, ...] = ()
    half_range: float = 0.1
    name: str = "posture range"

    def values(self, ctx: Context) -> dict[str, np.ndarray]:
        """``{"hold": (T, n)}``: 1 for a joint the body map leaves out (and not frozen), else
        0 (the box's mask; not a parameter of the knot)."""
        hold = ~np.asarray(ctx.tg.mapped, bool) & ~np.asarray(ctx.lim.frozen, bool)
        return {"hold": np.tile(hold.astype(float), (ctx.tg.T, 1))}

    def bounds(self, spec: Spec) -> Bounds:
        """``(lo, hi)`` ``(T, n)`` [rad] of ``q_j − q_j,neutral`` where a joint is held."""
        n = len(self.q_index)
        return Bounds(np.full((spec.T, n), -self.half_range),
                      np.full((spec.T, n), self.half_range))

    def box(self, var: Layout, ctx: Context, spec: Spec) -> Box:
        """The held joints' ``q`` within ``held ± half_range`` [rad], ``(T, n)``; free where
        a joint is mapped or frozen."""
        held = self.values(ctx)["hold"] > 0
        lo, hi = self.bounds(spec)
        mid = np.asarray(self.held, float)[None, :]
        idx = var["q"].start + np.asarray(self.q_index, int)
        return Box(idx, np.where(held, mid + lo, -np.inf), np.where(held, mid + hi, np.inf))
