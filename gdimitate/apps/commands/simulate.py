"""``gdimitate simulate``: an adapted plan executed in MuJoCo and measured
(:mod:`gdimitate.sim`)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...errors import GdimitateError
from ...safety import atomic_write, output_job, prepare_output_dir
from .common import (
    read_demonstration,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate simulate``: a plan executed in MuJoCo and measured."""
    si = sub.add_parser("simulate", help="execute an adapted plan in MuJoCo under the whole-body "
                        "tracking controller and measure it (falls, slip, push directions, CoP)")
    si.add_argument("motion", help="a plan: a gdimitate .npz with v, a and wrenches (written by "
                    "`gdimitate adapt` with the optimal method or AdaptedMotion.save)")
    si.add_argument("--out", default="gdimitate-sim", help="output folder (default: %(default)s)")
    si.add_argument("--reference", default=None,
                    help="the demonstration with measured forces to compare push directions "
                         "with (e.g. an .osim with --coordinates and --grf)")
    si.add_argument("--html", action="store_true",
                    help="also write simulation.html (plan and simulation side by side)")
    for flag, what in (("--grf", "measured forces of --reference"),
                       ("--coordinates", "joint angles of an .osim --reference"),
                       ("--osim", "OpenSim model of a full-body .mot/.sto --reference"),
                       ("--demonstrator", "robot of a .npz that records none")):
        si.add_argument(flag, default=None, help=what)
    si.set_defaults(func=run, treadmill=False, markers=None)


def run(a: argparse.Namespace) -> int:
    from ...export.writers import read_wrenches

    # the plan is a gdimitate .npz that records its robot: --grf, --coordinates and --osim
    # belong to the --reference (they were applied to the plan, which then always failed)
    plan_args = argparse.Namespace(**{**vars(a), "grf": None, "coordinates": None,
                                      "osim": None, "markers": None})
    demo = read_demonstration(a.motion, plan_args)
    wrenches = read_wrenches(a.motion) if Path(a.motion).suffix.lower() == ".npz" else None
    if wrenches is None or demo.motion.v is None:
        raise GdimitateError(f"{a.motion} holds no contact wrenches or velocities: simulate a "
                             "plan written by `gdimitate adapt` (the optimal method) or "
                             "AdaptedMotion.save(..., format='npz')")
    forces = read_demonstration(a.reference, a).forces if a.reference else None
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        return _simulate(a, demo, wrenches, forces)


def _simulate(a: argparse.Namespace, demo, wrenches, forces) -> int:
    from ...sim import plots as sim_plots
    from ...sim import simulate
    from ...sim.animation import show_simulation
    from ...sim.reference import Plan

    robot = demo.robot
    out = prepare_output_dir(a.out)
    print(f"simulating {robot.name}'s plan ({demo.motion.T} knots, "
          f"{demo.motion.t[-1] - demo.motion.t[0]:.2f} s) in MuJoCo at 1 kHz …", flush=True)
    res = simulate(robot, Plan(demo.motion, wrenches, dict(robot.require_contacts())),
                   demo_forces=forces)
    summary = res.metrics.to_dict()
    with atomic_write(out / "sim.json") as tmp:
        tmp.write_text(json.dumps(summary, indent=2, default=str))
    sim_plots.plot_summary(res, out / "simulation.png")
    if a.html:
        from ...viz import Viewer

        v = Viewer.start(quiet=True)
        try:
            show_simulation(robot, res, html=out / "simulation.html", viewer=v)
        finally:
            v.close()
    m = res.metrics
    print(f"FELL at {m.fall_time:.2f} s ({m.fall_reason})" if m.fell else
          "walked the whole plan", f"; stance slip max {100 * m.slip_max:.2f} cm; "
          f"torque saturation {100 * m.torque_saturation:.1f} %; wrote {out}/sim.json, "
          "simulation.png" + (", simulation.html" if a.html else ""))
    if m.fell:
        print(f"result written, but the robot fell: exit status {EXIT_NOT_FEASIBLE}")
        return EXIT_NOT_FEASIBLE
    return 0
