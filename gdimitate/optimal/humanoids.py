"""Sagittal retargeting of the real human walk onto example-robot-data humanoids.

The demonstrator is the planar human of :func:`gdimitate.gait.human_walk` (OpenSim subject01,
60 Hz, measured-GRF contact); the imitator drives hip pitch, knee and ankle pitch of each leg
(Bolt: hip and knee — it has point feet), holds every other joint at its neutral pose (clipped
into its limits) and lets the floating base follow (x, z and pitch).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..adapt import AdaptedMotion
from ..gait import human_walk
from ..motion import Motion
from ..robot import Robot
from .limits import Limits
from .solve import adapt_optimal

__all__ = ["HUMANOIDS", "RetargetRow", "retarget_humanoid", "retarget_table"]

#: Robots of issue 4's retargeting study.
HUMANOIDS = ("talos", "romeo", "icub", "g1", "bolt")


class RetargetRow(NamedTuple):
    """One robot's line of :func:`retarget_table`."""

    robot: str
    feasible: bool
    infeasible_knots: int
    force_error_max_rad: float
    torque_ratio_max: float
    torque_ratio_joint: str
    eq1_torque_ratio_max: float
    biggest_change_joint: str
    biggest_change_rad: float
    biggest_change_t: float
    solve_s: float
    status: str


def retarget_humanoid(name: str | Robot, force: str = "segment", *, demo: tuple[Robot, Motion]
                      | None = None, limits: Limits | None = None, **options) -> AdaptedMotion:
    """The real human walk retargeted onto humanoid ``name`` (or a :class:`Robot`) by the
    optimal adaptor; ``demo``: an already loaded ``(demonstrator, motion)``; ``options`` go to
    :func:`~gdimitate.optimal.adapt_optimal` (e.g. ``subsample=2``)."""
    robot = name if isinstance(name, Robot) else Robot.from_library(name)
    demonstrator, motion = demo if demo is not None else human_walk()
    return adapt_optimal(motion, demonstrator, robot, force=force, limits=limits, **options)


def row(result: AdaptedMotion) -> RetargetRow:
    """Summarise one retargeting result."""
    rep = result.report
    ratios = {j: v for j, v in rep.torque_ratio_max.items() if np.isfinite(v)}
    jmax = max(ratios, key=ratios.get) if ratios else "-"
    eq1 = rep.extra["analytic"].get("torque_ratio_max", {})
    eq1_vals = [v for v in eq1.values() if np.isfinite(v)]
    ch = rep.extra["max_change"]
    return RetargetRow(
        robot=result.robot.name, feasible=rep.all_feasible and rep.infeasible_constraint is None,
        infeasible_knots=int(max(rep.infeasible_frames.values())),
        force_error_max_rad=rep.force_direction_error_max,
        torque_ratio_max=float(ratios[jmax]) if ratios else float("nan"),
        torque_ratio_joint=jmax,
        eq1_torque_ratio_max=float(max(eq1_vals)) if eq1_vals else float("nan"),
        biggest_change_joint=ch["joint"], biggest_change_rad=ch["rad"],
        biggest_change_t=float(result.motion.t[ch["knot"]]),
        solve_s=float(rep.solver.get("time_s", np.nan)), status=str(rep.solver.get("status")))


def retarget_table(robots=HUMANOIDS, force: str = "segment", **options) -> list[RetargetRow]:
    """:class:`RetargetRow` per robot (the human walk loaded once)."""
    demo = human_walk()
    return [row(retarget_humanoid(r, force, demo=demo, **options)) for r in robots]


def format_table(rows: list[RetargetRow]) -> str:
    """A markdown table of :func:`retarget_table`'s rows."""
    head = ("| robot | feasible | infeasible knots | force-dir. error max [rad] | "
            "max |τ|/τ_lim (joint) | Eq. (1) max |τ|/τ_lim | biggest change vs Eq. (1) | "
            "solve [s] |")
    lines = [head, "|" + "---|" * 8]
    for r in rows:
        lines.append(
            f"| {r.robot} | {'yes' if r.feasible else 'no'} | {r.infeasible_knots} | "
            f"{r.force_error_max_rad:.1e} | {r.torque_ratio_max:.2f} ({r.torque_ratio_joint}) | "
            f"{r.eq1_torque_ratio_max:.1f} | {r.biggest_change_joint} "
            f"{r.biggest_change_rad:.2f} rad at t = {r.biggest_change_t:.2f} s | "
            f"{r.solve_s:.1f} |")
    return "\n".join(lines)
