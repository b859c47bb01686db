"""``gdimitate export``: a motion written in another file format (:mod:`gdimitate.export`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ...errors import OutputError
from ...safety import atomic_write, output_job
from .common import (
    read_demonstration,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate export``: a motion written in another file format."""
    from ...export.writers import FORMATS

    ex = sub.add_parser("export", help="write a motion as CSV, NPZ, MuJoCo qpos, or what "
                        "motion-tracking pipelines read: the LAFAN1 CSV, a GMR pickle, an Isaac "
                        "Lab AMP NPZ")
    ex.add_argument("motion", help="a motion: gdimitate .npz (e.g. adapt's imitator_motion.npz)"
                    ", or any demonstration file (.mot/.sto/.osim/.bvh)")
    ex.add_argument("--format", default="csv", choices=list(FORMATS),
                    help="; ".join(f"{k}: {v}" for k, v in FORMATS.items())
                    + " (default: %(default)s)")
    ex.add_argument("--out", default=None,
                    help="output file (default: beside the motion, with the format's suffix)")
    ex.add_argument("--fps", type=float, default=30.0,
                    help="frame rate of lafan1_csv, gmr, isaaclab_amp, beyondmimic_npz [Hz] "
                         "(default: %(default)s)")
    ex.add_argument("--body-order", default=None, choices=["depth", "breadth"],
                    help="body order of gmr / isaaclab_amp: depth-first (MuJoCo; gmr's "
                         "default) or breadth-first (PhysX; isaaclab_amp's default)")
    for flag, what in (("--grf", "forces of a .mot/.sto/.osim motion"),
                       ("--coordinates", "joint angles of an .osim motion"),
                       ("--markers", ".trc/.c3d markers of an .osim motion"),
                       ("--osim", "OpenSim model of a full-body .mot/.sto or .trc/.c3d"),
                       ("--demonstrator", "robot of a .npz that records none")):
        ex.add_argument(flag, default=None, help=what)
    ex.set_defaults(func=run, treadmill=False)


def run(a: argparse.Namespace) -> None:
    from ...export.writers import FORMATS, export_motion, read_wrenches

    demo = read_demonstration(a.motion, a)
    wrenches = read_wrenches(a.motion) if Path(a.motion).suffix.lower() == ".npz" else None
    out = Path(a.out) if a.out else Path(a.motion).with_suffix(
        {"csv": ".csv", "npz": ".export.npz", "mujoco": ".mujoco.npz",
         "lafan1_csv": ".lafan1.csv", "gmr": ".gmr.pkl", "isaaclab_amp": ".amp.npz",
         "beyondmimic_npz": ".beyondmimic.npz"}[a.format])
    if out.is_dir():
        raise OutputError(f"cannot write {out}: it is a folder; give a file name")
    with output_job(out.parent), atomic_write(out) as tmp:  # the folder made if needed
        export_motion(demo.robot, demo.motion, tmp, a.format, wrenches=wrenches, fps=a.fps,
                      body_order=a.body_order)
    print(f"wrote {out} ({FORMATS[a.format]}; robot {demo.robot.name}, from {demo.motion.T} "
          "frames)")
