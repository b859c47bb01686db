"""Smoothness: the generalised acceleration ``a`` [rad/s², m/s²] of every knot (weight
``smoothness``). Accelerations are linked to ``v`` and ``q`` by integration, so this
penalises the motion's real second differences."""

from __future__ import annotations

from dataclasses import dataclass

from .base import Cost


@dataclass(frozen=True)
class Smoothness(Cost):
    name: str = "smoothness"
    weight: str = "smoothness"

    def residual(self, k):
        return k.a
