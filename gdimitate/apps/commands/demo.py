"""``gdimitate demo``: the main job, the real 3-D walk adapted to G1 and checked in MuJoCo
(:mod:`gdimitate.apps.demo`)."""

from __future__ import annotations

import argparse

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...safety import output_job, prepare_output_dir
from .common import (
    METHOD_HELP,
    METHODS,
    add_robot_args,
    load_robot,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate demo``: the main job (:mod:`gdimitate.apps.demo`)."""
    from ..demo import DEFAULT_IMITATOR

    d = sub.add_parser("demo", help="the main job: the real 3-D walk → G1 (whole-body adaptor, "
                                    "MuJoCo physics check, oscillator replay)")
    d.add_argument("--out", default="gdimitate-demo", help="output folder (default: %(default)s)")
    add_robot_args(d, "--imitator", DEFAULT_IMITATOR, "imitator robot (e.g. hoap2, talos)")
    d.add_argument("--method", default="optimal", choices=METHODS, help=METHOD_HELP)
    d.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ..demo import run_demo

    imitator = load_robot(a.imitator, a)
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        s = run_demo(prepare_output_dir(a.out), imitator=imitator, method=a.method)
    fell = s["simulation"]["fell"]
    if s["verdict"]["ok"] and not fell:
        return 0
    why = "the simulated robot fell" if fell else "it is not feasible or a goal is unmet"
    print(f"result written, but {why}: exit status {EXIT_NOT_FEASIBLE}")
    return EXIT_NOT_FEASIBLE
