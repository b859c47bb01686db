"""Scaled keypoints through the body map: what the demonstration's shape means for a body of
other proportions (lengths divided by each robot's leg length).

Per leg: hip-over-ankle height / leg length (Eq. (1) keeps it), the unit shank direction
(knee → ankle; Eq. (1) keeps it too), the foot's world orientation (its sole frame; Eq. (1)
keeps it with the ankle angle), the unit thigh direction (hip → knee) and the horizontal
ankle − hip offset / leg length (foot placement; Eq. (1) gives both of these up). Per mapped
segment pair (pelvis, torso): the world orientation, as the 9 entries of the rotation matrix
minus the demonstrator's (squared: 2·(3 − trace(RᵀR*)) = 4·(1 − cos angle)·... ≈ angle² ·2).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin

from ...robot import SIDES
from ..knot import Knot


def segment_lengths(k: Knot) -> dict[str, tuple[float, float]]:
    """Per side the imitator's 3-D ``(|knee − hip|, |ankle − knee|)`` [m] (rigid, so
    measured once at the neutral pose)."""
    r = k.robot
    pin.framesForwardKinematics(r.model, r.data, r.neutral)
    out = {}
    for s in SIDES:
        leg = r.legs[s]
        p = {j: r.data.oMf[r.model.getFrameId(j)].translation for j in
             (leg.hip, leg.knee, leg.ankle or leg.sole)}
        out[s] = (float(np.linalg.norm(p[leg.knee] - p[leg.hip])),
                  float(np.linalg.norm(p[leg.ankle or leg.sole] - p[leg.knee])))
    return out


def residual(k: Knot, segment_frames: tuple[str, ...]) -> ca.SX:
    lengths = segment_lengths(k)
    w = [k.weight(i) for i in range(5)]  # square roots of the weights
    out = []
    for s in SIDES:
        L = k.leg[s].length
        hip, knee, ankle = k.hip[s], k.knee[s], k.ankle[s]
        lt, ls = lengths[s]
        out.append(w[0] * ((hip[2] - ankle[2]) / L - k.P(f"height_{s}")))
        out.append(w[1] * ((ankle[:2] - hip[:2]) / L - k.P(f"placement_{s}")))
        out.append(w[2] * ((ankle - knee) / ls - k.P(f"shank_{s}")))
        out.append(w[3] * ((knee - hip) / lt - k.P(f"thigh_{s}")))
        out.append(k.weight(7) * (ca.vec(k.sole_R[s]) - k.P(f"foot_{s}")))
    tgt = k.P("torso")
    for i, f in enumerate(segment_frames):
        R = k.sym.placement(f)[0]
        out.append(w[4] * (ca.vec(R) - tgt[9 * i: 9 * i + 9]))
    return ca.vertcat(*out)
