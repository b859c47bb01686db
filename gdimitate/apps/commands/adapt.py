"""``gdimitate adapt``: a demonstration file adapted for an imitator, the result written with its
verdict."""

from __future__ import annotations

import argparse
import json
import math

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...safety import output_job, prepare_output_dir
from .common import (
    EXIT_STATUS,
    METHOD_HELP,
    METHODS,
    add_demonstration_args,
    add_robot_args,
    run_adaptation,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate adapt``: adapt a demonstration file, write the result and its verdict."""
    from ..demo import DEFAULT_IMITATOR

    ad = sub.add_parser("adapt", help="adapt a demonstration file for an imitator",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: {EXIT_STATUS[3]}")
    add_demonstration_args(ad, "demonstration",
                           "one stride of the shipped real 3-D walk, as demo")
    add_robot_args(ad, "--imitator", DEFAULT_IMITATOR, "imitator robot")
    ad.add_argument("--method", default="optimal", choices=METHODS, help=METHOD_HELP)
    ad.add_argument("--force", default=None, choices=["segment", "com", "dynamics",
                                                       "measured"],
                    help="force-direction model of the goal: segment (hip→sole), com "
                         "(CoM→sole), dynamics (from the motion), measured (the "
                         "demonstration's measured forces: --grf, a C3D's plates, the default "
                         "story's) (default: measured where the demonstration has forces and "
                         "the method is optimal, else segment)")
    ad.add_argument("--periodic", action="store_true",
                    help="adapt one stride (heel strike to heel strike of the right foot) as a "
                         "periodic cycle: its end state is its start shifted by one stride "
                         "(method optimal)")
    ad.add_argument("--out", default="gdimitate-adapt", help="output folder (default: %(default)s)")
    ad.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ...assess.verdict import report_lines, verdict
    from ..outputs import write_adapted

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        demonstrator, demo, _, result = run_adaptation(a, a.demonstration)
        v = verdict(result)
        text = write_adapted(out, demonstrator, demo, result)
    print(f"wrote {out}/imitator_joints.csv, imitator_motion.npz, report.json, gait.png")
    written = json.loads(text)  # the console prints the file's numbers
    for line in report_lines(written) + _error_lines(written):
        print(f"  {line}")
    return v.exit_status


def _error_lines(report: dict) -> list[str]:
    """adapt's last line, from report.json's numbers: the largest push-direction error
    (:func:`gdimitate.assess.verdict.push_errors`: the audit's angle where it measured the push,
    else
    the report's sagittal one) with its side and knot, and the largest position-limit
    excursion."""
    push = report["push_direction_error"]
    worst = max(push, key=lambda s: push[s]["rad"], default=None)
    said = "push-direction error: none measured" if worst is None else (
        f"push-direction error max {push[worst]['rad']:.3g} rad "
        f"({math.degrees(push[worst]['rad']):.1f}°, {worst}, knot {push[worst]['knot']}, "
        f"{push[worst]['measure']})")
    return [f"{said}; joint-limit violation max {report['joint_limit_violation_max_rad']:.3g} "
            "rad"]
