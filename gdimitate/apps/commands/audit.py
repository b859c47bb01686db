"""``gdimitate audit``: robot motion files checked for physical feasibility."""

from __future__ import annotations

import argparse
import json

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...safety import atomic_write, output_job, prepare_output_dir
from .common import (
    add_robot_args,
    load_robot,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate audit``: robot motion files checked for physical feasibility."""
    from ...batch.audit import AUDIT_FORMATS

    au = sub.add_parser("audit", help="check robot motion files (gdimitate .npz, CSV, LAFAN1 / "
                        "BeyondMimic CSV, GMR pickle, Isaac Lab AMP or MuJoCo qpos NPZ) for "
                        "physical feasibility: torques, friction, CoP, slip, penetration")
    au.add_argument("files", nargs="+", metavar="FILE_OR_FOLDER",
                    help="motion files, or folders (every motion file directly in them): "
                    + "; ".join(f"{k}: {v}" for k, v in AUDIT_FORMATS.items()))
    add_robot_args(au, "--robot", None, "the robot the motions were made for (optional for "
                   "a gdimitate .npz, which records it)")
    au.add_argument("--out", default="gdimitate-audit",
                    help="output folder for report.json and audit.csv (default: %(default)s)")
    au.add_argument("--fps", type=float, default=30.0,
                    help="frame rate of a LAFAN1 CSV [Hz] (default: %(default)s)")
    au.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ...batch.audit import audit_csv, audit_files, audit_table, find_motion_files

    files = find_motion_files(a.files)
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        audited = audit_files(files, lambda: load_robot(a.robot, a) if a.robot else None, a.fps)
        with atomic_write(out / "report.json") as tmp:
            tmp.write_text(json.dumps([f.to_dict() for f in audited], indent=2, default=str))
        with atomic_write(out / "audit.csv") as tmp:
            tmp.write_text(audit_csv(audited))
    for line in audit_table(audited):
        print(line)
    bad = [f for f in audited if not f.audit.feasible]
    for f in bad:
        print(f"{f.path.name}: NOT feasible; failed checks:")
        for line in f.audit.failed():
            print(f"  {line}")
    print(f"{len(audited) - len(bad)} of {len(audited)} clip(s) feasible; wrote "
          f"{out}/report.json, audit.csv")
    return EXIT_NOT_FEASIBLE if bad else 0
