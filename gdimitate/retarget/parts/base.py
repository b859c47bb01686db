"""What a part of the whole-body problem is: a cost (a residual with a named weight) or a
constraint (rows with bounds, labels and whether they may relax), written at one knot
(:class:`~gdimitate.retarget.knot.Knot`) or between two neighbouring knots.

The problem (:mod:`gdimitate.retarget.trajectory.problem`) is the sum of a list of parts
(:func:`gdimitate.retarget.parts.default_parts`): the cost is ``Σ_parts Σ_knots
|√w · residual|² / T``; the constraint rows are the parts' rows stacked in list order; the
weight layout (one ``√w`` parameter per distinct :attr:`Cost.weight`, read from
:class:`~gdimitate.retarget.params.Weights`), the elastic slacks (one pair per row of every
relaxable per-knot constraint) and the report's row labels are all derived from that list.

:class:`Part` is an abstract base: each kind declares what it must say as abstract methods
with typed arguments — the knot ``k`` (:class:`~gdimitate.retarget.knot.Knot`: the symbols
and expressions of one knot), the demonstration's :class:`Spec` (the numbers that decide the
bounds) and its :class:`~gdimitate.retarget.context.Context` (what parameter values are read
from). What a constraint states comes back as value objects: :class:`Rows` at a knot
(expressions, labels, scale, which rows may be screened: :meth:`Constraint.at`) and
:class:`Bounds` for a demonstration (lower and upper, one row each), as mink's limits return
their ``Constraint(G, h)``.

A part is a frozen dataclass (it is hashable and its ``repr`` is part of the cache key of
the compiled problem: two lists that compare equal build the same problem).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import NamedTuple

import casadi as ca
import numpy as np

from ...model.robot import SIDES
from ..context import Context
from ..knot import Knot, Layout

__all__ = ["Spec", "Part", "Cost", "Constraint", "PairConstraint", "Bound", "Rows", "Bounds",
           "Box", "per_side_labels"]


@dataclass(frozen=True)
class Spec:
    """The numbers of one demonstration that decide the constraint bounds: ``T`` knots, per
    side ``stance``/``swing``/``liftoff``/``goal_active`` ``{side: (T,) bool}``, whether the
    imitator is ``planar``/``free``-flying, whether the goal is a ``cone``, the swing
    ``clearance`` [m], the ``leg_length`` [m], the numbers of base and actuated velocity
    rows."""

    T: int
    stance: dict[str, np.ndarray]
    swing: dict[str, np.ndarray]
    liftoff: dict[str, np.ndarray]
    goal_active: dict[str, np.ndarray]
    planar: bool
    free: bool
    cone: bool
    clearance: float
    leg_length: float
    n_base: int
    n_act: int


class Bounds(NamedTuple):
    """Bounds of a constraint's rows for one demonstration: ``lower`` and ``upper``, each
    ``(T, n)`` for the rows at each of ``T`` knots, ``(T − 1, n)`` for rows between
    neighbouring knots, ``(n,)`` for the seam's rows (in the rows' own units; ``±inf`` where
    the schedule imposes nothing). A tuple: ``lo, hi = part.bounds(spec)``."""

    lower: np.ndarray
    upper: np.ndarray


class Box(NamedTuple):
    """A :class:`Bound`'s box for one demonstration: ``index`` ``(n,)`` into a knot's
    variables, ``lower`` and ``upper`` ``(T, n)`` (``±inf`` where it imposes nothing)."""

    indices: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


@dataclass(frozen=True, eq=False)
class Rows:
    """What a per-knot :class:`Constraint` states at one knot (:meth:`Constraint.at`):

    - ``expr`` ``(n, 1)`` SX: the rows, in the part's units;
    - ``labels``: one name per row (the report groups violations by label);
    - ``scale``: the divisor that turns a row into scaled units (1: already scaled);
    - ``screenable`` ``(n,)`` bool: the rows a solve may leave out where the start keeps them
      far from their bounds.

    Checked on construction: one label and one screenable flag per row."""

    expr: ca.SX
    labels: tuple[str, ...]
    scale: float
    screenable: np.ndarray

    def __post_init__(self) -> None:
        n = self.n
        if len(self.labels) != n:
            raise RuntimeError(f"{len(self.labels)} labels for {n} rows")
        if np.shape(self.screenable) != (n,):
            raise RuntimeError(f"{np.shape(self.screenable)} screenable flags for {n} rows")

    @property
    def n(self) -> int:
        """The number of rows."""
        return int(self.expr.shape[0])


class Part(ABC):  # noqa: B024 - abstract through its kinds (Cost, Constraint, …)
    """Common to costs and constraints: ``name`` (what reports call it) and the extra
    parameter blocks the part needs (:meth:`params`, filled by :meth:`values`). Not
    instantiated itself: a part is one of its kinds — :class:`Cost`, :class:`Constraint`,
    :class:`PairConstraint`, :class:`Bound` or a seam
    (:class:`~gdimitate.retarget.parts.seam.SeamConstraint`) —, each with its abstract
    methods."""

    name: str = "part"

    def params(self, k: Knot) -> dict[str, int]:
        """Extra per-knot parameter blocks ``{name: size}`` this part reads with ``k.P(name)``
        (default: none; the knot's standard blocks are listed in :mod:`..knot`)."""
        return {}

    def values(self, ctx: Context) -> dict[str, np.ndarray]:
        """``{name: (T, size)}`` values of :meth:`params` for a demonstration (``ctx``: what
        the part may read of it)."""
        return {}


class Cost(Part):
    """A least-squares cost: :meth:`residual` at one knot, unweighted; the problem multiplies
    it by ``√w`` with ``w = getattr(Weights, weight)`` (``weight = None``: the residual carries
    its own per-row weights, e.g. as a parameter)."""

    weight: str | None = None

    @abstractmethod
    def residual(self, k: Knot) -> ca.SX:
        """``(n, 1)`` SX residual at knot ``k`` (dimensionless: scaled by a leg length, m·g,
        …, so that the weights compare)."""


class Constraint(Part):
    """Rows at one knot with per-knot bounds.

    - :meth:`rows` ``(n, 1)`` SX, each row in scaled units (divide forces by m·g, lengths by a
      leg length, …) so that one tolerance fits all — :meth:`scale` is the divisor that turns
      a row back into those units when its own are physical (1 by default);
    - :meth:`bounds` :class:`Bounds`, each ``(T, n)``, for a demonstration (infinite where the
      schedule does not impose a row: the problem leaves such rows out of the solve);
    - :meth:`labels` one name per row (the report groups violations by label);
    - ``relaxable``: whether the least-infeasible solve may relax it (an L1 slack pair per row,
      weight ``Weights.elastic``);
    - ``screenable``: rows that are far from their bounds almost everywhere (self-collision):
      a solve leaves such a row out at the knots where the start keeps it farther than
      :data:`gdimitate.retarget.trajectory.solve.SCREEN` (scaled units) from its bounds,
      re-checks every left-out row on the result and solves again with those it does not
      meet. :meth:`screenable_rows` says which of its rows may be left out (all by default).

    :meth:`at` gathers what the part states at a knot into one :class:`Rows`."""

    relaxable: bool = False
    screenable: bool = False

    @abstractmethod
    def rows(self, k: Knot) -> ca.SX:
        """``(n, 1)`` SX rows at knot ``k`` (see the class docstring for their units)."""

    @abstractmethod
    def bounds(self, spec: Spec) -> Bounds:
        """:class:`Bounds` of the rows, each ``(T, n)``, for a demonstration ``spec``."""

    def size(self, k: Knot) -> int:
        """``n``, the number of rows at knot ``k``."""
        return int(self.rows(k).shape[0])

    def labels(self, k: Knot) -> list[str]:
        """One label per row (default: the part's name for each)."""
        return [self.name] * self.size(k)

    def scale(self, k: Knot) -> float:
        """The divisor that puts the rows in scaled units (default 1: they already are)."""
        return 1.0

    def screenable_rows(self, k: Knot) -> np.ndarray:
        """``(n,)`` bool: the rows a solve may leave out where the start keeps them far from
        their bounds — every row of a :attr:`screenable` part, none of another's."""
        return np.full(self.size(k), self.screenable)

    def at(self, k: Knot) -> Rows:
        """What the part states at knot ``k``: its :meth:`rows`, :meth:`labels`,
        :meth:`scale` and :meth:`screenable_rows` as one :class:`Rows` (checked: one label
        per row)."""
        expr = self.rows(k)
        labels = self.labels(k)
        n = int(expr.shape[0])
        if len(labels) != n:
            raise RuntimeError(f"part {self.name!r}: {len(labels)} labels for {n} rows")
        return Rows(expr, tuple(labels), float(self.scale(k)),
                    np.asarray(self.screenable_rows(k), bool))


class PairConstraint(Part):
    """Rows linking knot k − 1 to knot k (k = 1…T − 1), never relaxed: :meth:`carry` is what
    of a knot the rows need (evaluated at both knots), :meth:`rows` combines them
    (``prev``, ``cur``: the two evaluations; ``k`` gives knot k's parameters and symbols),
    :meth:`bounds` :class:`Bounds` each ``(T − 1, n)`` (``n``: the rows' count); all rows of
    one pair part share one label, its name."""

    @abstractmethod
    def carry(self, k: Knot) -> ca.SX:
        """``(m, 1)`` SX: what of knot ``k`` the rows need (a function of ``k.x`` only)."""

    @abstractmethod
    def rows(self, k: Knot, prev: ca.SX, cur: ca.SX) -> ca.SX:
        """``(n, 1)`` SX rows from :meth:`carry` at knot k − 1 (``prev``) and at knot k
        (``cur``), both ``(m, 1)``."""

    @abstractmethod
    def bounds(self, spec: Spec, n: int) -> Bounds:
        """:class:`Bounds` of the ``n`` rows, each ``(T − 1, n)``, for a demonstration."""


class Bound(Part):
    """A box on some of a knot's variables, stated as variable bounds rather than rows: IPOPT
    keeps a variable bound out of the constraint Jacobian and the KKT system's constraint
    rows. :meth:`box` gives, for a demonstration, the variables it bounds and their bounds;
    the problem intersects them with the variables' other bounds (joint limits). A bound is
    never relaxed (the least-infeasible solve keeps it)."""

    @abstractmethod
    def box(self, var: Layout, ctx: Context, spec: Spec) -> Box:
        """The :class:`Box` for a demonstration: indices ``(n,)`` into the knot's variables
        (layout ``var``), lower and upper bounds ``(T, n)`` (``±inf`` where the box imposes
        nothing)."""


def per_side_labels(label: str, n_per_side: int) -> list[str]:
    """``["label: left"] * n + ["label: right"] * n``."""
    return [f"{label}: {s}" for s in SIDES for _ in range(n_per_side)]
