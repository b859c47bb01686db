"""The periodic seam of a gait cycle (docs/design.md §14): the last knot's state equals the
first's shifted by one stride — the base advanced along the walking direction by a length
the optimiser chooses, everything else equal (base height and orientation, every joint
angle, every velocity). Free-flyer rows: the base displacement across the walking direction
``n⊥·Δp_xy``, ``Δz``, the quaternion's 4 components, the joints, all of ``Δv``; planar: every
``q`` but ``base_x``, all of ``Δv``. The walking direction ``d`` (unit, horizontal) is the
demonstrator's pelvis displacement over the stride (a parameter). Never relaxed."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.footsteps import walking_direction
from ..context import Context
from ..knot import Knot
from .base import Bounds, Spec
from .seam import SeamConstraint

__all__ = ["PeriodicSeam"]


@dataclass(frozen=True)
class PeriodicSeam(SeamConstraint):
    """``x_last = x_first`` shifted along the walking direction (module docstring)."""

    name: str = "periodic seam"

    def params(self, k: Knot) -> dict[str, int]:
        return {"seam_dir": 2}

    def values(self, ctx: Context) -> dict[str, np.ndarray]:
        """``seam_dir`` ``(T, 2)``: the walking direction (unit, horizontal) at every knot."""
        d = walking_direction(ctx.demonstrator, ctx.tg.demo.q)
        return {"seam_dir": np.tile(d, (ctx.tg.T, 1))}

    def carry(self, k: Knot) -> ca.SX:
        """``(nq + nv, 1)``: ``q``, ``v``."""
        return ca.vertcat(k.q, k.v)

    def rows(self, k: Knot, first: ca.SX, last: ca.SX) -> ca.SX:
        """``(nq − 1 + nv, 1)``. Free-flyer: ``n⊥·Δp_xy``, ``Δz`` [m], ``Δquat``, the joints'
        ``Δq`` [rad, m], ``Δv``; planar: every ``Δq`` but ``base_x``'s, ``Δv``."""
        nq = k.sym.nq
        dq, dv = last[:nq] - first[:nq], last[nq:] - first[nq:]
        if k.planar:
            ix = k.robot.idx_q("base_x")
            keep = [i for i in range(nq) if i != ix]
            return ca.vertcat(dq[keep], dv)
        d = k.P("seam_dir")
        across = d[0] * dq[1] - d[1] * dq[0]
        return ca.vertcat(across, dq[2:], dv)

    def bounds(self, spec: Spec, n: int) -> Bounds:
        """0 on both sides, ``(n,)``."""
        z = np.zeros(n)
        return Bounds(z, z)
