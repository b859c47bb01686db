"""Changing the walk's frequency (docs/design.md §14): the demonstration re-timed by a factor
k (stride frequency × k: times ÷ k, the same path and measured force directions), its
periodic cycle re-adapted, the network re-tuned, a few steps walked in MuJoCo. Where does it
stop being feasible (the audit) or walkable (no fall)? Prints a Markdown table; the k = 1 row
is the same-run baseline.

    python benchmarks/walk_frequency.py --robot hoap2 --factors 0.8 0.9 1 1.1 1.2 1.3
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings

import numpy as np
from results import add_flag, recording

from gdimitate.model.contact import ContactForces


def retimed(demo, forces, k: float):
    t0 = demo.t[0]
    t = t0 + (demo.t - t0) / k
    f = ContactForces(t0 + (forces.t - t0) / k, forces.feet, forces.source,
                      forces.frame_note + f"; re-timed ×{k:g}")
    return demo.replace(t=t, v=None, a=None), f


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robot", default="hoap2")
    p.add_argument("--factors", nargs="+", type=float, default=[0.8, 0.9, 1.0, 1.1, 1.2, 1.3])
    p.add_argument("--steps", type=int, default=6)
    p.add_argument("--gain", type=float, default=0.5)
    add_flag(p)
    args = p.parse_args()
    warnings.simplefilter("ignore")
    from gdimitate.apps.demo import default_demonstration
    from gdimitate.model.robot import Robot
    from gdimitate.walker import periodic_cycle, walk

    robot, demo, forces = default_demonstration()
    imit = Robot.load(args.robot)
    print("| k | stride frequency [Hz] | cycle audit | solver | adapt [s] | steps walked "
          f"(of {args.steps}) | network frequency / cycle − 1 | largest per-step error | "
          "push RMS vs measured, worst step |")
    print("|---|---|---|---|---|---|---|---|---|")
    for k in args.factors:
        d, f = retimed(demo, forces, k)
        t = time.perf_counter()
        cyc, _ = periodic_cycle(d, robot, imit, f)
        ta = time.perf_counter() - t
        aud = "feasible" if cyc.feasible else "NOT: " + ", ".join(cyc.audit.binding[:2])
        r = walk(cycle=cyc, forces=f, steps=args.steps, feedback_gain=args.gain).to_dict()
        walked = f"{r['steps_completed']}" + (" (fell)" if r["fell"] else "")
        err = r["frequency_hz"] / r["cycle_frequency_hz"] - 1 if r["frequency_hz"] else np.nan
        rm = [x for x in r["per_step_force_direction_rmse_deg"] if x is not None and x == x]
        step_err = r["frequency_error_max"]
        print(f"| {k:g} | {r['cycle_frequency_hz']:.3f} | {aud} | {cyc.solver.status} | "
              f"{ta:.1f} | {walked} | {100 * err:+.2f} % | "
              f"{'–' if step_err is None else f'{100 * step_err:.2f} %'} | "
              f"{f'{max(rm):.1f}°' if rm else '–'} |", flush=True)


if __name__ == "__main__":
    with recording("walk_frequency", "--results" in sys.argv[1:]):
        main()
