"""Gait cost: the steps of the demonstrator scaled to the imitator's legs (docs/design.md
§13). At every knot where both feet are in stance, the horizontal place of the left sole
relative to the right, over the imitator's leg length, minus the demonstrator's footprints'
(:func:`gdimitate.model.footsteps.footprints`: the mean place of each stance phase) over its leg
length (parameters ``steps`` ``(2,)`` and ``steps_on`` ``(1,)``, 1 in double support, else
0; weight ``steps``). A flat stance sole keeps its place, so the cost asks every step's length
and width, and with them the distance walked, of the imitator scaled by the legs' ratio;
nothing else in the problem asks for the distance (the shipped walk → G1 travelled 0.37 of
the scaled distance without it). Written in world axes, so it turns with the walk.

The push direction comes first: each residual component ``e`` enters as
``e / (1 + (e/δ)²)^¼`` (:data:`DELTA`), quadratic near 0 and growing like ``√(δ|e|)`` beyond
δ, so that the cost's pull on a step, ``w·d(ρ²)/de``, stays below ``1.1·w·δ`` (11 at the
default weight 100) however short the step — below the force direction's L1 price
(:data:`~gdimitate.retarget.trajectory.solve.GOAL_WEIGHT`, 30 per rad and knot). With a plain
square,
Romeo (whose steps the velocity and torque limits keep 0.4 of a leg short) gave up 0.3–0.65
rad of its push to lengthen them."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.footsteps import footprints
from ...model.robot import SIDES
from ..context import Context
from ..knot import Knot
from .base import Cost

DELTA = 0.1
"""[leg lengths] Where the steps residual turns from quadratic to square-root growth."""


@dataclass(frozen=True)
class Steps(Cost):
    """In double support the left sole's place relative to the right's, in leg lengths,
    minus the demonstrator's footprints' (module docstring)."""

    name: str = "steps"
    weight: str = "steps"

    def params(self, k: Knot) -> dict[str, int]:
        return {"steps": 2, "steps_on": 1}

    def values(self, ctx: Context) -> dict[str, np.ndarray]:
        """``steps`` ``(T, 2)`` [leg lengths] (0 outside double support), ``steps_on``
        ``(T,)`` 1 in double support, else 0."""
        L, place = footprint_places(ctx)
        rel = (place["left"] - place["right"]) / L
        on = np.all(np.isfinite(rel), axis=1)
        return {"steps": np.where(on[:, None], rel, 0.0), "steps_on": on.astype(float)}

    def residual(self, k: Knot) -> ca.SX:
        """``(2, 1)`` dimensionless, bounded (:func:`bounded`), 0 outside double support."""
        L = float(np.mean([k.leg[s].length for s in SIDES]))
        e = (k.sole_p["left"][:2] - k.sole_p["right"][:2]) / L - k.P("steps")
        return k.P("steps_on")[0] * bounded(e)


def footprint_places(ctx: Context) -> tuple[float, dict[str, np.ndarray]]:
    """``(L, {side: (T, 2)})``: the demonstrator's mean leg length [m] and, per knot, the
    horizontal place [m] of each foot's current footprint (NaN where the foot is not in the
    imitator's stance) — what the gait parts compare the imitator's soles with."""
    tg, d = ctx.tg, ctx.demonstrator
    L = float(np.mean([d.legs[s].length for s in SIDES]))
    place = {s: np.full((tg.T, 2), np.nan) for s in SIDES}
    for f in footprints(d, tg.demo, tg.stance):
        place[f.side][f.start:f.stop] = f.xy
    return L, place


def bounded(e: ca.SX) -> ca.SX:
    """``e / (1 + (e/δ)²)^¼`` (δ = :data:`DELTA`): ``e`` for ``|e| ≪ δ``, its square grows
    like ``δ·|e|`` beyond δ, so that a weight's pull on ``e`` stays below ``1.1·w·δ``."""
    return e / (1 + (e / DELTA) ** 2) ** 0.25
