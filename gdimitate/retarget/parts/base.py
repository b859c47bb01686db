"""What a part of the whole-body problem is: a cost (a residual with a named weight) or a
constraint (rows with bounds, labels and whether they may relax), written at one knot
(:class:`~gdimitate.retarget.knot.Knot`) or between two neighbouring knots.

The problem (:mod:`gdimitate.retarget.trajectory.problem`) is the sum of a list of parts
(:func:`gdimitate.retarget.parts.default_parts`): the cost is ``Σ_parts Σ_knots
|√w · residual|² / T``; the constraint rows are the parts' rows stacked in list order; the
weight layout (one ``√w`` parameter per distinct :attr:`Cost.weight`, read from
:class:`~gdimitate.retarget.params.Weights`), the elastic slacks (one pair per row of every
relaxable per-knot constraint) and the report's row labels are all derived from that list.

A part is a frozen dataclass (it is hashable and its ``repr`` is part of the cache key of
the compiled problem: two lists that compare equal build the same problem).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.robot import SIDES

__all__ = ["Spec", "Part", "Cost", "Constraint", "PairConstraint", "Bound", "per_side_labels"]


@dataclass(frozen=True)
class Spec:
    """The numbers of one demonstration that decide the constraint bounds: ``T`` knots, per
    side ``stance``/``swing``/``liftoff``/``goal_active`` ``(T,)`` bool, whether the imitator
    is ``planar``/``free``-flying, whether the goal is a ``cone``, the swing ``clearance``
    [m], the ``leg_length`` [m], the numbers of base and actuated velocity rows."""

    T: int
    stance: dict
    swing: dict
    liftoff: dict
    goal_active: dict
    planar: bool
    free: bool
    cone: bool
    clearance: float
    leg_length: float
    n_base: int
    n_act: int


class Part:
    """Common to costs and constraints: ``name`` (what reports call it) and the extra
    parameter blocks the part needs (:meth:`params`, filled by :meth:`values`)."""

    name: str = "part"

    def params(self, k) -> dict[str, int]:
        """Extra per-knot parameter blocks ``{name: size}`` this part reads with ``k.P(name)``
        (default: none; the knot's standard blocks are listed in :mod:`..knot`)."""
        return {}

    def values(self, ctx) -> dict[str, np.ndarray]:
        """``{name: (T, size)}`` values of :meth:`params` for a demonstration (``ctx``: a
        :class:`gdimitate.retarget.trajectory.solve.Context`)."""
        return {}


class Cost(Part):
    """A least-squares cost: :meth:`residual` at one knot, unweighted; the problem multiplies
    it by ``√w`` with ``w = getattr(Weights, weight)`` (``weight = None``: the residual carries
    its own per-row weights, e.g. as a parameter)."""

    weight: str | None = None

    def residual(self, k) -> ca.SX:  # pragma: no cover - interface
        """``(n,)`` SX residual at knot ``k``."""
        raise NotImplementedError


class Constraint(Part):
    """Rows at one knot with per-knot bounds.

    - :meth:`rows` ``(n,)`` SX, each row in scaled units (divide forces by m·g, lengths by a
      leg length, …) so that one tolerance fits all — :meth:`scale` is the divisor that turns
      a row back into those units when its own are physical (1 by default);
    - :meth:`bounds` ``(lo, hi)`` each ``(T, n)`` for a demonstration (infinite where the
      schedule does not impose a row: the problem leaves such rows out of the solve);
    - :meth:`labels` one name per row (the report groups violations by label);
    - ``relaxable``: whether the least-infeasible solve may relax it (an L1 slack pair per row,
      weight ``Weights.elastic``);
    - ``screenable``: rows that are far from their bounds almost everywhere (self-collision):
      a solve leaves such a row out at the knots where the start keeps it farther than
      :data:`gdimitate.retarget.trajectory.solve.SCREEN` (scaled units) from its bounds, re-checks
      every
      left-out row on the result and solves again with those it does not meet.
      :meth:`screenable_rows` says which of its rows may be left out (all by default)."""

    relaxable: bool = False
    screenable: bool = False

    def size(self, k) -> int:
        return int(self.rows(k).shape[0])

    def rows(self, k) -> ca.SX:  # pragma: no cover - interface
        raise NotImplementedError

    def bounds(self, spec: Spec) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
        raise NotImplementedError

    def labels(self, k) -> list[str]:
        return [self.name] * self.size(k)

    def scale(self, k) -> float:
        return 1.0

    def screenable_rows(self, k) -> np.ndarray:
        """``(n,)`` bool: the rows a solve may leave out where the start keeps them far from
        their bounds — every row of a :attr:`screenable` part, none of another's."""
        return np.full(self.size(k), self.screenable)


class PairConstraint(Part):
    """Rows linking knot k − 1 to knot k (k = 1…T − 1), never relaxed: :meth:`carry` is what
    of a knot the rows need (evaluated at both knots), :meth:`rows` combines them
    (``prev``, ``cur``: the two evaluations; ``k`` gives knot k's parameters and symbols),
    :meth:`bounds` ``(lo, hi)`` each ``(T − 1, n)`` (``n``: the rows' count); all rows of
    one pair part share one label."""

    def carry(self, k) -> ca.SX:  # pragma: no cover - interface
        raise NotImplementedError

    def rows(self, k, prev: ca.SX, cur: ca.SX) -> ca.SX:  # pragma: no cover - interface
        raise NotImplementedError

    def bounds(self, spec: Spec, n: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
        raise NotImplementedError


class Bound(Part):
    """A box on some of a knot's variables, stated as variable bounds rather than rows: IPOPT
    keeps a variable bound out of the constraint Jacobian and the KKT system's constraint
    rows. :meth:`box` gives, for a demonstration, the variables it bounds and their bounds;
    the problem intersects them with the variables' other bounds (joint limits). A bound is
    never relaxed (the least-infeasible solve keeps it)."""

    def box(self, var, ctx, spec: Spec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(index (n,) into the knot's variables (layout ``var``), lo (T, n), hi (T, n))``
        (``±inf`` where the box imposes nothing; ``ctx``: a
        :class:`gdimitate.retarget.trajectory.solve.Context`)."""
        raise NotImplementedError  # pragma: no cover - interface


def per_side_labels(label: str, n_per_side: int) -> list[str]:
    """``["label: left"] * n + ["label: right"] * n``."""
    return [f"{label}: {s}" for s in SIDES for _ in range(n_per_side)]
