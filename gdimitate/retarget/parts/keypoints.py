"""Scaled keypoints through the body map: what the demonstration's shape means for a body of
other proportions (lengths divided by each robot's leg length). One cost part per quantity:

- :class:`Height` — per leg, hip-over-ankle height / leg length (Eq. (1) keeps it);
- :class:`Shank` — the unit shank direction, knee → ankle (Eq. (1) keeps it);
- :class:`Foot` — the foot's world orientation, its sole frame's 9 rotation entries (Eq. (1)
  keeps it with the ankle angle);
- :class:`Thigh` — the unit thigh direction, hip → knee (Eq. (1) gives it up);
- :class:`Placement` — the horizontal ankle − hip offset / leg length (Eq. (1) gives it up);
- :class:`Segments` — per mapped segment pair (pelvis, torso) the world orientation, as the 9
  rotation entries minus the demonstrator's (squared: 2·(3 − trace(RᵀR*)) ≈ 2·angle²).

Targets are the knot's parameter blocks ``height_<side>``, ``shank_<side>``, … (filled from
:class:`~gdimitate.retarget.targets.Targets`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import pinocchio as pin

from ...robot import SIDES
from .base import Cost


def segment_lengths(k) -> dict[str, tuple[float, float]]:
    """Per side the imitator's 3-D ``(|knee − hip|, |ankle − knee|)`` [m] (rigid, so measured
    once at the neutral pose)."""
    if "segment_lengths" not in k.memo:
        r = k.robot
        pin.framesForwardKinematics(r.model, r.data, r.neutral)
        out = {}
        for s in SIDES:
            leg = r.legs[s]
            p = {j: r.data.oMf[r.model.getFrameId(j)].translation for j in
                 (leg.hip, leg.knee, leg.ankle or leg.sole)}
            out[s] = (float(np.linalg.norm(p[leg.knee] - p[leg.hip])),
                      float(np.linalg.norm(p[leg.ankle or leg.sole] - p[leg.knee])))
        k.memo["segment_lengths"] = out
    return k.memo["segment_lengths"]


@dataclass(frozen=True)
class Height(Cost):
    name: str = "height"
    weight: str = "height"

    def residual(self, k):
        return ca.vertcat(*[(k.hip[s][2] - k.ankle[s][2]) / k.leg[s].length
                            - k.P(f"height_{s}") for s in SIDES])


@dataclass(frozen=True)
class Placement(Cost):
    name: str = "placement"
    weight: str = "placement"

    def residual(self, k):
        return ca.vertcat(*[(k.ankle[s][:2] - k.hip[s][:2]) / k.leg[s].length
                            - k.P(f"placement_{s}") for s in SIDES])


@dataclass(frozen=True)
class Shank(Cost):
    name: str = "shank"
    weight: str = "shank"

    def residual(self, k):
        L = segment_lengths(k)
        return ca.vertcat(*[(k.ankle[s] - k.knee[s]) / L[s][1] - k.P(f"shank_{s}")
                            for s in SIDES])


@dataclass(frozen=True)
class Thigh(Cost):
    name: str = "thigh"
    weight: str = "thigh"

    def residual(self, k):
        L = segment_lengths(k)
        return ca.vertcat(*[(k.knee[s] - k.hip[s]) / L[s][0] - k.P(f"thigh_{s}")
                            for s in SIDES])


@dataclass(frozen=True)
class Foot(Cost):
    name: str = "foot"
    weight: str = "foot"

    def residual(self, k):
        return ca.vertcat(*[ca.vec(k.sole_R[s]) - k.P(f"foot_{s}") for s in SIDES])


@dataclass(frozen=True)
class Segments(Cost):
    """``frames``: the imitator's mapped segment frames (the body map's, in order)."""

    frames: tuple[str, ...] = ()
    name: str = "segments"
    weight: str = "torso"

    def residual(self, k):
        tgt = k.P("torso")
        out = [ca.vec(k.sym.placement(f)[0]) - tgt[9 * i: 9 * i + 9]
               for i, f in enumerate(self.frames)]
        return ca.vertcat(*out) if out else ca.SX(0, 1)
