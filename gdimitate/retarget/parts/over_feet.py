"""Gait cost: the body carried over its feet as the demonstrator carries it (docs/design.md
§13). At every knot with a stance foot, the horizontal place of the hips' midpoint relative to
the stance soles (their mean in double support), along the demonstrator's facing there (the
horizontal normal of the line from its right hip to its left), over
the imitator's leg length, minus the same of the demonstrator relative to its footprints
(:func:`gdimitate.model.footsteps.footprints`) over its leg length (parameters ``over_feet``
``(1,)``
the target, ``over_feet_dir`` ``(2,)`` the facing, ``over_feet_w`` ``(2,)`` the left and
right soles' shares, ``over_feet_on`` ``(1,)``; weight ``over_feet``).

:class:`~.steps.Steps` asks where the feet land relative to each other; this part asks where
the body is over them, so that a clip that begins or ends in single support travels the
scaled distance too (a stride trimmed 0.3 s at each end — one double support — travelled 0.36
of it on G1 with the steps cost alone: the body started slow and ended 0.2 m behind its
stance foot). Along the facing only: across it the imitator's own hip width decides. The
residual enters bounded like the steps' (:func:`~.steps.bounded`), so that the push direction
stays first."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.kinematics import frame_paths
from ...model.robot import SIDES
from ..context import Context
from ..knot import Knot
from .base import Cost
from .steps import bounded, footprint_places


@dataclass(frozen=True)
class OverFeet(Cost):
    """The hips' midpoint along the demonstrator's facing relative to the stance soles, in
    leg lengths, minus the demonstrator's (module docstring)."""

    name: str = "over_feet"
    weight: str = "over_feet"

    def params(self, k: Knot) -> dict[str, int]:
        return {"over_feet": 1, "over_feet_dir": 2, "over_feet_w": 2, "over_feet_on": 1}

    def values(self, ctx: Context) -> dict[str, np.ndarray]:
        """``over_feet`` ``(T, 1)`` [leg lengths], ``over_feet_dir`` ``(T, 2)`` unit,
        ``over_feet_w`` ``(T, 2)`` the soles' shares, ``over_feet_on`` ``(T, 1)`` 0 or 1."""
        tg, d = ctx.tg, ctx.demonstrator
        L, place = footprint_places(ctx)
        w = np.column_stack([np.isfinite(place[s][:, 0]) for s in SIDES]).astype(float)
        n = w.sum(axis=1)
        on = n > 0
        w[on] /= n[on, None]
        feet = sum(np.nan_to_num(place[s]) * w[:, [i]] for i, s in enumerate(SIDES))
        hips = frame_paths(d, tg.demo.q, [d.legs[s].hip for s in SIDES])
        left, right = (hips[d.legs[s].hip][:, :2] for s in SIDES)
        mid, across = (left + right) / 2, left - right
        e = np.column_stack([across[:, 1], -across[:, 0]])  # across turned by −90°: forward
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        target = np.einsum("ij,ij->i", mid - feet, e) / L
        return {"over_feet": np.where(on, target, 0.0)[:, None], "over_feet_dir": e,
                "over_feet_w": w, "over_feet_on": on.astype(float)[:, None]}

    def residual(self, k: Knot) -> ca.SX:
        """``(1, 1)`` dimensionless, bounded (:func:`~.steps.bounded`), 0 without a stance
        foot."""
        L = float(np.mean([k.leg[s].length for s in SIDES]))
        w = k.P("over_feet_w")
        mid = (k.hip["left"][:2] + k.hip["right"][:2]) / 2
        feet = w[0] * k.sole_p["left"][:2] + w[1] * k.sole_p["right"][:2]
        e = (k.P("over_feet_dir").T @ (mid - feet)) / L - k.P("over_feet")
        return k.P("over_feet_on")[0] * bounded(e)
