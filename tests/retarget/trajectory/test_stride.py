"""The stride retry's choice (gdimitate/retarget/trajectory/stride.py) on results built by hand:
which motion is kept, why the other is not, and the solver record of both solves. The kept
branch on a real solve: tests/adaptation/test_footsteps.py."""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import pytest

from gdimitate.assess.solver import SolverInfo, Unmet
from gdimitate.retarget.params import Weights
from gdimitate.retarget.trajectory.stride import STRIDE_RETRY, kept, short, stride_weights


@dataclass(frozen=True)
class Result:
    audit: SimpleNamespace
    gait: SimpleNamespace | None
    solver: SolverInfo


def result(feasible: bool, travel: float, miss: float = 0.0, iterations: int = 10,
           time_s: float = 1.0) -> Result:
    unmet = (Unmet("force direction: left", miss, 3),) if miss else ()
    info = SolverInfo("Solve_Succeeded", not miss, iterations, time_s, 0.0, True, False, 50,
                      100, 100, unmet)
    return Result(SimpleNamespace(feasible=feasible), SimpleNamespace(travel_ratio=travel),
                  info)


def test_the_gait_weights_are_raised_and_nothing_else():
    w = Weights(steps=7.0, over_feet=3.0, height=2.0)
    r = stride_weights(w)
    assert (r.steps, r.over_feet) == (7.0 * STRIDE_RETRY, 3.0 * STRIDE_RETRY)
    assert r.height == 2.0 and r.shank == w.shank and r.elastic == w.elastic


@pytest.mark.parametrize("feasible, travel, want", [
    (True, 0.79, True), (True, 0.8, False), (False, 0.5, False), (True, float("nan"), False)])
def test_short_means_feasible_and_under_the_kept_band(feasible, travel, want):
    assert short(result(feasible, travel)) is want


def test_without_a_gait_nothing_is_short():
    r = result(True, 0.5)
    assert not short(Result(r.audit, None, r.solver))


@pytest.mark.parametrize("again, take, why", [
    (result(True, 0.9, iterations=7, time_s=2.0), True, "kept"),
    (result(False, 0.9), False, "not kept (audit-infeasible)"),
    (result(True, 0.9, miss=0.01), False, "not kept (a goal missed by more)"),
    (result(True, 0.6), False, "not kept (no further)"),
])
def test_the_second_motion_is_kept_only_where_it_costs_nothing(again, take, why):
    first = result(True, 0.7, iterations=5, time_s=1.5)
    out = kept(first, again)
    assert out.gait is (again.gait if take else first.gait)
    assert out.solver.unmet == (again if take else first).solver.unmet
    assert out.solver.iterations == 5 + again.solver.iterations
    assert out.solver.time_s == pytest.approx(1.5 + again.solver.time_s)
    assert out.solver.retry == (f"travel 0.70 of the scaled demonstrator's: solved again with "
                                f"the gait's weights × {STRIDE_RETRY:g}: "
                                f"{again.gait.travel_ratio:.2f}, {why}")


def test_a_first_motion_that_misses_a_goal_may_give_way_to_one_that_misses_it_less():
    first = result(True, 0.5, miss=0.2)
    assert kept(first, result(True, 0.6, miss=0.1)).gait.travel_ratio == 0.6
    assert kept(first, result(True, 0.6, miss=0.3)).gait.travel_ratio == 0.5
