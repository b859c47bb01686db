"""Keypoint cost: per mapped segment pair (pelvis, torso) the world orientation, as the 9
rotation entries minus the demonstrator's (parameter ``torso``; weight ``torso``); squared,
2·(3 − trace(RᵀR*)) ≈ 2·angle²."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ..knot import Knot
from .base import Cost


@dataclass(frozen=True)
class Segments(Cost):
    """``frames``: the imitator's mapped segment frames (the body map's, in order)."""

    frames: tuple[str, ...] = ()
    name: str = "segments"
    weight: str = "torso"

    def residual(self, k: Knot) -> ca.SX:
        """``(9·n_frames, 1)``: per frame the 9 entries of ``R − R_target`` (column-major)."""
        tgt = k.P("torso")
        out = [ca.vec(k.sym.placement(f)[0]) - tgt[9 * i: 9 * i + 9]
               for i, f in enumerate(self.frames)]
        return ca.vertcat(*out) if out else ca.SX(0, 1)
