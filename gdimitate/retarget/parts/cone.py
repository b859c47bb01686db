"""Contact wrench cone of each stance foot's sole rectangle.

Caron, Pham, Nakamura, "Stability of surface contacts for humanoid robots: closed-form
formulae of the contact wrench cone for rectangular support areas" (ICRA 2015): with the
wrench ``[f; τ]`` at the sole centre in the sole frame, half-lengths X, Y and friction μ,

    |f_x| ≤ μ f_z, |f_y| ≤ μ f_z, |τ_x| ≤ Y f_z, |τ_y| ≤ X f_z, τ_min ≤ τ_z ≤ τ_max

(16 linear rows, :func:`gdimitate.model.contact.wrench_cone_rows`: the cone is written there once),
plus ``f_z ≥ f_min``. The centre-of-pressure rows use X − margin, Y − margin. X, Y and μ are
parameters. Planar models keep the in-plane rows (friction along x, centre of pressure along
x: :data:`gdimitate.model.contact.PLANAR_CONE_ROWS`; f_z ≥ f_min). Rows are divided by m·g;
relaxable. Swing feet carry no wrench (their variables are bounded to 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.contact import PLANAR_CONE_ROWS, wrench_cone_rows
from ...model.robot import SIDES
from ..knot import Knot
from .base import Bounds, Constraint, Spec, per_side_labels


def rows_per_side(planar: bool) -> int:
    """Rows of one foot: the cone's (16, planar 4) and ``f_z ≥ f_min``."""
    return (len(PLANAR_CONE_ROWS) if planar else 16) + 1


def cone_rows(w: ca.SX, X: ca.SX, Y: ca.SX, mu: ca.SX, Xc: ca.SX, Yc: ca.SX, f_min: ca.SX,
              planar: bool) -> list[ca.SX]:
    """The rows (each ≤ 0 inside the cone) of a sole wrench ``w = [f; τ]`` (6,) [N, N·m]:
    :func:`gdimitate.model.contact.wrench_cone_rows` (the one formula of the cone; planar models
    keep its rows :data:`~gdimitate.contact.PLANAR_CONE_ROWS`), then ``f_min − f_z``; the
    sole's half-length ``X`` and half-width ``Y`` [m], friction ``mu``, the centre-of-pressure
    half-sizes ``Xc``, ``Yc`` [m] and ``f_min`` [N] (scalars or SX), each row in N or N·m."""
    rows = wrench_cone_rows(w, X, Y, mu, cop_length=Xc, cop_width=Yc)
    if planar:
        rows = [rows[i] for i in PLANAR_CONE_ROWS]
    return rows + [f_min - w[2]]


@dataclass(frozen=True)
class WrenchCone(Constraint):
    """Per foot the cone's rows (16, planar 4) and ``f_min − f_z``, over m·g, ≤ 0 in
    stance."""

    name: str = "contact wrench cone"
    relaxable: bool = True

    def rows(self, k: Knot) -> ca.SX:
        """``(2·n_side, 1)``: left foot's rows, then the right's (:func:`rows_per_side`),
        dimensionless (over m·g)."""
        out = []
        for s in SIDES:
            X, Y, mu, Xc, Yc = (k.P(f"sole_{s}")[i] for i in range(5))
            rows = cone_rows(k.wrench_local(s), X, Y, mu, Xc, Yc, k.P("f_min")[0], k.planar)
            out.append(ca.vertcat(*rows) / k.mg)
        return ca.vertcat(*out)

    def labels(self, k: Knot) -> list[str]:
        return per_side_labels(self.name, rows_per_side(k.planar))

    def bounds(self, spec: Spec) -> Bounds:
        """``(−inf, 0)`` at a foot's stance knots, free elsewhere; each ``(T, 2·n_side)``."""
        n = rows_per_side(spec.planar)
        hi = np.full((spec.T, 2 * n), np.inf)
        for i, s in enumerate(SIDES):
            hi[spec.stance[s], i * n:(i + 1) * n] = 0.0
        return Bounds(np.full_like(hi, -np.inf), hi)
