"""Rows between the last knot and the first: what makes a cycle periodic.

A :class:`SeamConstraint` is the wrap-around counterpart of a
:class:`~.base.PairConstraint`: :meth:`~SeamConstraint.carry` is what of a knot the rows need
(evaluated at the first knot and at the last), :meth:`~SeamConstraint.rows` combines them
(``k`` gives the parameters, bound to the first knot's) and :meth:`~SeamConstraint.bounds`
gives :class:`~.base.Bounds` each ``(n,)``. Never relaxed; the report labels its rows with its name.
The problem (:mod:`..trajectory.problem`) adds these rows once, after the per-knot and pair rows.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Sequence

import casadi as ca

from ..knot import Knot
from .base import Bounds, Part, Spec

__all__ = ["SeamConstraint", "seam_functions"]


class SeamConstraint(Part):
    """Rows linking the last knot to the first (see module)."""

    @abstractmethod
    def carry(self, k: Knot) -> ca.SX:
        """``(m, 1)`` SX: what of knot ``k`` the rows need (a function of ``k.x`` only)."""

    @abstractmethod
    def rows(self, k: Knot, first: ca.SX, last: ca.SX) -> ca.SX:
        """``(n, 1)`` SX rows from :meth:`carry` at the first knot (``first``) and at the
        last (``last``), both ``(m, 1)``."""

    @abstractmethod
    def bounds(self, spec: Spec, n: int) -> Bounds:
        """:class:`~.base.Bounds` of the ``n`` rows, each ``(n,)``, for a demonstration."""


def seam_functions(k: Knot, seams: Sequence[SeamConstraint]
                   ) -> tuple[dict[str, ca.Function], list[str], list[int]]:
    """``({"sg", "sjac", "sh"}, labels, sizes)`` of the seam parts at knot symbols ``k``:
    ``sg (x_first, x_last, p) -> rows``, ``sjac`` their Jacobian in ``(x_first, x_last)``,
    ``sh (x_first, x_last, p, λ)`` the Hessian of ``λᵀ rows`` (kept as SX functions: they are
    evaluated once per solve, not over the knots)."""
    x0 = ca.SX.sym("x_first", k.var.size)
    rows, labels, sizes = [], [], []
    for sp in seams:
        first = ca.Function("carry", [k.x], [sp.carry(k)])(x0)
        r = sp.rows(k, first, sp.carry(k))
        rows.append(r)
        sizes.append(int(r.shape[0]))
        labels += [sp.name] * int(r.shape[0])
    g = ca.vertcat(*rows)
    xx = ca.vertcat(x0, k.x)
    lam = ca.SX.sym("lam_seam", g.shape[0])
    fun = {"sg": ca.Function("sg", [x0, k.x, k.p], [g]),
           "sjac": ca.Function("sjac", [x0, k.x, k.p], [ca.jacobian(g, xx)]),
           "sh": ca.Function("sh", [x0, k.x, k.p, lam], [ca.hessian(ca.dot(lam, g), xx)[0]])}
    return fun, labels, sizes
