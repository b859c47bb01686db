"""``gdimitate repair``: a robot motion file made physically consistent on its robot
(:mod:`gdimitate.apps.repair`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...safety import output_job, prepare_output_dir
from .common import (
    EXIT_STATUS,
    add_robot_args,
    load_robot,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate repair``: a robot motion file made physically consistent on its robot."""
    rp = sub.add_parser("repair", help="make a robot motion file (any format audit reads) "
                        "physically consistent on the same robot: the whole-body adaptor from "
                        "the robot to itself, the audits before and after",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: {EXIT_STATUS[3]}")
    rp.add_argument("file", metavar="FILE", help="a motion file gdimitate audit reads")
    add_robot_args(rp, "--robot", None, "the robot the motion was made for (optional for a "
                   "gdimitate .npz, which records it)")
    rp.add_argument("--out", default="gdimitate-repair", help="output folder (default: "
                    "%(default)s)")
    rp.add_argument("--fps", type=float, default=30.0,
                    help="frame rate of a LAFAN1 CSV [Hz] (default: %(default)s)")
    rp.add_argument("--rate", type=float, default=None,
                    help="the adaptor's knots/s (default: the file's frame rate over the "
                         "smallest whole number that brings it to 50 or below)")
    rp.add_argument("--simulate", action="store_true",
                    help="also run the input and the repaired motion in MuJoCo")
    rp.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ...batch.audit import find_motion_files
    from ...errors import InvalidInputError
    from ..repair import repair_file

    if Path(a.file).expanduser().is_dir():
        raise InvalidInputError(f"{a.file} is a folder; repair takes one motion file (audit "
                                "takes folders)")
    (path,) = find_motion_files([a.file])
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        status, lines = repair_file(out, path, load_robot(a.robot, a) if a.robot else None,
                                    fps=a.fps, simulate=a.simulate, rate=a.rate)
    print("\n".join(lines))
    return status
