"""``gdimitate stream``: a live mocap stream adapted frame by frame
(:mod:`gdimitate.apps.stream`)."""

from __future__ import annotations

import argparse

from ...assess.verdict import EXIT_NOT_FEASIBLE
from ...safety import output_job, prepare_output_dir
from .common import (
    add_robot_args,
    load_robot,
    port_number,
    positive_seconds,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate stream``: a live mocap stream adapted frame by frame (docs/guide/
    streaming.md)."""
    from ..demo import DEFAULT_IMITATOR

    st = sub.add_parser("stream", help="adapt a live mocap stream frame by frame (a BVH file "
                        "played at its rate, or Lab Streaming Layer), shown in meshcat; "
                        "writes adapt's outputs when stopped (Ctrl-C)",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: some frame's verdict is not "
                               "feasible (docs/guide/streaming.md)")
    st.add_argument("source", help="a .bvh file (played at its own frame rate), or lsl:NAME "
                    "(the LSL stream called NAME: a BVH skeleton's channels '<Joint>.<Channel>' "
                    "or an OpenSim model's coordinates, and 'contact.left', 'contact.right'; "
                    "with --skeleton or --osim)")
    add_robot_args(st, "--imitator", DEFAULT_IMITATOR, "imitator robot")
    st.add_argument("--skeleton", default=None, metavar="FILE.bvh",
                    help="lsl: the BVH file whose HIERARCHY names the stream's channels (its "
                         "unit, up axis and floor are the file's)")
    st.add_argument("--osim", default=None, metavar="FILE.osim",
                    help="lsl: the OpenSim model whose coordinates name the stream's channels "
                         "(degrees and metres, as a .mot with inDegrees=yes)")
    st.add_argument("--loopback", action="store_true",
                    help="lsl: look for the stream on this machine only (liblsl's "
                         "ResolveScope machine)")
    st.add_argument("--timeout", type=positive_seconds, default=10.0,
                    help="lsl: seconds to find the stream, and of silence that ends it "
                         "(default: %(default)s)")
    st.add_argument("--frames", type=int, default=None,
                    help="stop after this many frames adapted (a .bvh: play its first N)")
    st.add_argument("--seconds", type=positive_seconds, default=None, help="stop after this long")
    st.add_argument("--delay", type=float, default=0.0, metavar="MS",
                    help="wait this long after each frame (a slower machine: frames dropped)")
    st.add_argument("--view", action="store_true",
                    help="show the robot following the stream in meshcat (prints its URL)")
    st.add_argument("--port", type=port_number, default=None,
                    help="web port of the --view page (default: a free one)")
    st.add_argument("--open", action="store_true", help="open the --view page in a browser")
    st.add_argument("--out", default="gdimitate-stream",
                    help="output folder (default: %(default)s)")
    st.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ..stream import stream_command

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        return stream_command(a, out, lambda: load_robot(a.imitator, a))
