"""``gdimitate walk [DEMO] --imitator NAME --steps N --out DIR``: the command's work, kept
out of :mod:`gdimitate.apps.cli` (which only parses)."""

from __future__ import annotations

import math
from pathlib import Path

from ..assess.verdict import EXIT_NOT_FEASIBLE
from ..model.robot import Robot
from . import WALK_RATE

__all__ = ["walk_command"]


def walk_command(out: Path, demo, imitator: Robot, steps: int, gain: float, html: bool = True,
                 log=print, rate: float = WALK_RATE) -> int:
    """Write a walk into ``out`` (``demo``: a loaded demonstration with ``robot``,
    ``motion``, ``forces``, or None for the shipped 3-D walk); exit status 0 when it walked
    every step with a feasible cycle, :data:`~gdimitate.assess.verdict.EXIT_NOT_FEASIBLE` otherwise.
    ``rate`` [knots/s]: the cycle's knot rate (default :data:`~gdimitate.walker.WALK_RATE`)."""
    from . import periodic_cycle, walk

    if demo is None:
        log("no demonstration given: the shipped real 3-D walk (one right stride, measured "
            "forces)")
        args = (None, None)
        forces = None
    else:
        args, forces = (demo.motion, demo.robot), demo.forces
    log(f"[1/3] periodic cycle → {imitator.name} (whole-body optimal adaptor, periodic seam) …")
    cycle, forces = periodic_cycle(args[0], args[1], imitator, forces, rate,
                                   say=lambda line: log(f"      {line}"))
    why = "feasible" if cycle.feasible else "NOT feasible: " + ", ".join(cycle.audit.binding[:4])
    log(f"      audit: {why}")
    from ..assess.verdict import gait_lines

    for line in gait_lines(cycle):  # the cycle's stride against the scaled one; what binds
        log(f"      {line}")
    if not cycle.feasible:
        log("      the walk follows this cycle as it is: MuJoCo shows whether the robot still "
            "walks it, but the cycle itself breaks the limits above")
    log(f"[2/3] network + MuJoCo: {steps} steps, feedback gain {gain:g} …")
    res = walk(cycle=cycle, forces=forces, steps=steps, feedback_gain=gain)
    log("[3/3] writing walk.json, plots, trajectory" + (", walk.html" if html else "") + " …")
    files = res.save(out, html=html)
    d = res.to_dict()
    rmse = [x for x in d["per_step_force_direction_rmse_deg"] if x == x]
    log(f"steps completed {d['steps_completed']}/{steps}"
        + (f"; FELL at {d['fell_at_s']:.2f} s" if d["fell"] else "")
        + f"; stride frequency {d['frequency_hz']:.4f} Hz (cycle {d['cycle_frequency_hz']:.4f})"
        + (f"; push RMS vs measured per step max {max(rmse):.2f}°" if rmse else ""))
    planned = math.hypot(*d["stride_m"][:2])
    log(f"stride {d['simulated_stride_m']:.3f} m per cycle simulated, {planned:.3f} m "
        f"planned, {d['scaled_stride_m']:.3f} m the demonstrator's scaled to the legs: ratio "
        f"{d['simulated_stride_ratio']:.2f} (plan {d['plan_stride_ratio']:.2f})")
    log(f"wrote {out}/" + ", ".join(files))
    ok = cycle.feasible and not d["fell"] and d["steps_completed"] >= steps
    if not ok:
        why = ("the cycle is not feasible" if not cycle.feasible
               else "the robot fell" if d["fell"] else "it walked fewer steps than asked")
        log(f"result written, but {why}: exit status {EXIT_NOT_FEASIBLE}")
    return 0 if ok else EXIT_NOT_FEASIBLE
