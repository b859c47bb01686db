"""The gait kept: a feasible motion that travels short of the scaled demonstrator is solved
again with the gait's own weights raised (docs/design.md §13, docs/guide/limits.md).

The steps cost (:mod:`..parts.steps`) and the body-over-feet cost (:mod:`..parts.over_feet`) ask
for the demonstrator's distance, scaled to the imitator's legs; the push direction is priced
by an exact L1 term (:data:`.solve.GOAL_WEIGHT`). Where the first optimum strides short — a
local optimum with bent knees, or a clip cut mid-stride — the same problem solved with both
gait weights × :data:`STRIDE_RETRY` often finds the longer one (Talos's cycle 0.70 → 0.93; the
stride cut 0.3 s at each end, Talos 0.79 → 0.88, iCub 0.77 → 0.87). The second motion is
kept only where it costs nothing the first had: audit-feasible, no goal missed by more, and
further. Otherwise the first stays, with what binds said (:func:`gdimitate.assess.verdict.
gait_lines`)."""

from __future__ import annotations

import dataclasses
from typing import Any

from ...model.footsteps import KEPT
from ..params import Weights

__all__ = ["STRIDE_RETRY", "stride_weights", "short", "kept"]

STRIDE_RETRY = 2.0
"""The factor on the ``steps`` and ``over_feet`` weights of the second solve: the largest
whose pull on a step (≤ 1.1·w·δ = 22 with w = 200, δ = 0.1) stays under the push's price
(30 per rad and knot), so the push is not traded for distance."""


def stride_weights(w: Weights) -> Weights:
    """``w`` with its gait weights (``steps``, ``over_feet``) × :data:`STRIDE_RETRY`."""
    return dataclasses.replace(w, steps=w.steps * STRIDE_RETRY,
                               over_feet=w.over_feet * STRIDE_RETRY)


def short(result: Any) -> bool:
    """Whether an adapted motion is audit-feasible but travels less than
    :data:`~gdimitate.model.footsteps.KEPT`'s lower end of the scaled demonstrator (NaN —
    no distance to compare — is not short)."""
    g = result.gait
    return bool(result.audit is not None and result.audit.feasible and g is not None
                and g.travel_ratio < KEPT[0])


def _goal_miss(result: Any) -> float:
    """The largest violation of the solver's unmet rows (0 when none)."""
    return max((u.violation for u in result.solver.unmet), default=0.0)


def kept(first: Any, again: Any) -> Any:
    """``again`` where it is audit-feasible, misses no goal by more than
    ``first`` and travels further, else ``first``; the solver record of the result counts
    both solves' iterations and time and says in ``retry`` what happened."""
    r1, r2 = first.gait.travel_ratio, again.gait.travel_ratio
    why = ("audit-infeasible" if not again.audit.feasible else
           "a goal missed by more" if _goal_miss(again) > _goal_miss(first) else
           "no further" if not r2 > r1 else "")
    note = (f"travel {r1:.2f} of the scaled demonstrator's: solved again with the gait's "
            f"weights × {STRIDE_RETRY:g}: {r2:.2f}, " + (f"not kept ({why})" if why else "kept"))
    out = first if why else again
    s1, s2 = first.solver, again.solver
    solver = dataclasses.replace(out.solver, iterations=s1.iterations + s2.iterations,
                                 time_s=s1.time_s + s2.time_s, retry=note)
    return dataclasses.replace(out, solver=solver)
