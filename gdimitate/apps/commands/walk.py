"""``gdimitate walk``: a periodic cycle walked in MuJoCo under a whole-body oscillator network
(:mod:`gdimitate.walker`)."""

from __future__ import annotations

import argparse

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...safety import output_job, prepare_output_dir
from .common import (
    add_demonstration_args,
    add_robot_args,
    load_robot,
    read_demonstration,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate walk``: a periodic cycle walked in MuJoCo under an oscillator network."""
    from ..demo import WALK_IMITATOR

    wk = sub.add_parser("walk", help="a periodic cycle, a whole-body oscillator network and N "
                                     "steps in MuJoCo (walk.json, plots, trajectory, HTML)",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: the robot fell, fewer steps "
                               "than asked, or the cycle is not feasible")
    add_demonstration_args(wk, "demonstration", "the shipped real 3-D walk")
    add_robot_args(wk, "--imitator", WALK_IMITATOR, "imitator robot")
    wk.add_argument("--steps", type=int, default=20, help="steps to walk (default: %(default)s)")
    wk.add_argument("--gain", type=float, default=0.5,
                    help="feedback gain of the ground into the network (0: open loop) "
                         "(default: %(default)s)")
    wk.add_argument("--rate", type=float, default=None,
                    help="knots per second of the cycle's optimal solve (default: "
                         "gdimitate.walker.WALK_RATE)")
    wk.add_argument("--no-html", action="store_true", help="skip walk.html")
    wk.add_argument("--out", default="gdimitate-walk", help="output folder (default: %(default)s)")
    wk.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ...walker.command import walk_command

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)
        return walk_command(out, read_demonstration(a.demonstration, a), load_robot(a.imitator, a),
                            a.steps, a.gain, html=not a.no_html,
                            **({} if a.rate is None else {"rate": a.rate}))
