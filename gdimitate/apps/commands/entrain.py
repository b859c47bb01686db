"""``gdimitate entrain``: a Matsuoka network tuned to a motion, and its free replay checked."""

from __future__ import annotations

import argparse
import json

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...errors import OscillatorError
from ...safety import atomic_write, output_job, prepare_output_dir
from .common import (
    METHOD_HELP,
    METHODS,
    add_demonstration_args,
    add_robot_args,
    positive_seconds,
    read_demonstration,
    run_adaptation,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate entrain``: a Matsuoka network tuned to a motion, and its replay."""
    from ..demo import DEFAULT_IMITATOR

    en = sub.add_parser("entrain", help="tune a Matsuoka network to a motion and replay it",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: the free-running replay "
                               "misses the stride frequency or amplitude (the replay check)")
    add_demonstration_args(en, "motion", "one stride of the shipped real 3-D walk adapted "
                                          "to --robot, as demo")
    add_robot_args(en, "--robot", DEFAULT_IMITATOR, "robot the shipped walk is adapted to "
                   "when no motion is given")
    en.add_argument("--method", default="optimal", choices=METHODS, help=METHOD_HELP)
    en.add_argument("--duration", type=positive_seconds, default=None,
                    help="seconds of free-running replay (default: the motion's duration)")
    en.add_argument("--out", default="gdimitate-entrain",
                    help="output folder (default: %(default)s)")
    en.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ...oscillator.replay import entrain

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        options = {}
        if a.motion is not None:
            demo = read_demonstration(a.motion, a)
            robot, motion = demo.robot, demo.motion
        else:
            a.imitator = a.robot
            _, stride, _, result = run_adaptation(a, None)
            robot, motion = result.robot, result.motion
            # the clip is one stride (heel strike to heel strike): its span is the period
            options["frequency"] = 1.0 / float(stride.t[-1] - stride.t[0])
        print(f"entraining a Matsuoka network to {robot.name}'s joints and base "
              f"({motion.T} frames) and replaying {a.duration or motion.t[-1]:.2f} s free …",
              flush=True)
        cpg = entrain(robot, motion, duration=a.duration, **options)
        check = cpg.check
        if check is None:  # entrain always checks its replay
            raise OscillatorError("entrain returned no replay check")
        with atomic_write(out / "oscillator_params.json") as tmp:
            tmp.write_text(cpg.result.to_json())
        with atomic_write(out / "replay_joints.csv") as tmp:
            cpg.replay.to_csv(tmp)
        with atomic_write(out / "replay_motion.npz") as tmp:
            cpg.replay.to_npz(tmp, robot=robot)
        with atomic_write(out / "report.json") as tmp:
            tmp.write_text(json.dumps(
                {"robot": robot.name, "learned_frequency_hz": float(cpg.result.frequency),
                 "replay_check": check.to_dict(), "constant_angles_rad": cpg.constant,
                 "per_joint": cpg.report}, indent=2, default=float))
    print(f"wrote {out}/oscillator_params.json, replay_joints.csv, replay_motion.npz, "
          f"report.json\n  learned frequency {cpg.result.frequency:.4f} Hz")
    for j, r in cpg.report.items():
        c = check.signals[j]
        print(f"  {j:<12} nRMSE entrained {r['nrmse_entrained'] * 100:5.2f} %   teacher fit "
              f"{r['teacher_fit_nrmse'] * 100:5.2f} %   free-running frequency "
              f"{c['frequency_hz']:.3f} Hz   amplitude ratio {c['amplitude_ratio']:.2f}")
    print(f"  {check.line()}")
    if not check.passed:
        print(f"  result written, but the replay check failed: exit status {EXIT_NOT_FEASIBLE}")
        return EXIT_NOT_FEASIBLE
    return 0
