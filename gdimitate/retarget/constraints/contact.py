"""Flat-foot contact: a stance foot lies flat on the floor and keeps its pose.

At a stance knot the sole frame's origin is at z = 0 and its normal is vertical (rows
``p_z``, ``R[2, 0]``, ``R[2, 1]``; planar models ``p_z``, ``R[2, 0]``). Between two
consecutive stance knots of the same foot it neither slides nor turns (hold rows
``Δp_x``, ``Δp_y`` and ``sin Δψ`` of the sole's x axis; planar ``Δp_x``). Never relaxed.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ...robot import SIDES
from ..knot import Knot

NAME = "contact"
RELAX = False


def rows_per_side(planar: bool) -> int:
    return 2 if planar else 3


def expr(k: Knot) -> ca.SX:
    out = []
    for s in SIDES:
        p, R = k.sole_p[s], k.sole_R[s]
        out += [p[2], R[2, 0]] + ([] if k.planar else [R[2, 1]])
    return ca.vertcat(*out)


def bounds(spec) -> tuple[np.ndarray, np.ndarray]:
    n = rows_per_side(spec.planar)
    lo = np.full((spec.T, 2 * n), -np.inf)
    for i, s in enumerate(SIDES):
        lo[spec.stance[s], i * n:(i + 1) * n] = 0.0
    hi = np.where(np.isfinite(lo), 0.0, np.inf)
    return lo, hi


def hold_quantities(k: Knot) -> ca.SX:
    """Per foot ``(p_x, p_y, R[0, 0], R[1, 0])`` (planar: ``p_x``) — compared between knots."""
    out = []
    for s in SIDES:
        p, R = k.sole_p[s], k.sole_R[s]
        out += [p[0]] if k.planar else [p[0], p[1], R[0, 0], R[1, 0]]
    return ca.vertcat(*out)


def hold_rows(H0: ca.MX, H1: ca.MX, planar: bool) -> ca.MX:
    """Hold rows between knots (columns of ``H0`` = knot k − 1, ``H1`` = knot k)."""
    if planar:
        return H1 - H0
    rows = []
    for i in range(2):
        o = 4 * i
        rows += [H1[o, :] - H0[o, :], H1[o + 1, :] - H0[o + 1, :],
                 H1[o + 3, :] * H0[o + 2, :] - H1[o + 2, :] * H0[o + 3, :]]  # sin Δψ
    return ca.vertcat(*rows)


def hold_bounds(spec) -> tuple[np.ndarray, np.ndarray]:
    """``(T − 1, n)`` bounds of the hold rows (0 where the foot is down at k − 1 and k)."""
    n = 1 if spec.planar else 3
    lo = np.full((spec.T - 1, 2 * n), -np.inf)
    for i, s in enumerate(SIDES):
        h = spec.stance[s][1:] & spec.stance[s][:-1]
        lo[h, i * n:(i + 1) * n] = 0.0
    return lo, np.where(np.isfinite(lo), 0.0, np.inf)
