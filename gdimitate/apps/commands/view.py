"""``gdimitate view``: the meshcat preview, live in the browser or as a self-contained HTML file."""

from __future__ import annotations

import argparse

from ...assess.verdict import EXIT_NOT_FEASIBLE
from .common import (
    METHOD_HELP,
    METHODS,
    add_demonstration_args,
    add_robot_args,
    port_number,
    positive_seconds,
    read_demonstration,
    run_adaptation,
)

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate view``: the meshcat preview, live or as a self-contained HTML file."""
    from ..demo import DEFAULT_IMITATOR
    from ..examples import EXAMPLES

    vw = sub.add_parser("view", help="meshcat preview: live in the browser or --html FILE",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: the adaptation shown is not "
                               "feasible or leaves a goal unmet")
    add_demonstration_args(vw, "motion", "one stride of the shipped real 3-D walk adapted to "
                                          "--imitator, as demo")
    add_robot_args(vw, "--imitator", DEFAULT_IMITATOR,
                   "imitator the default walk is adapted to when no motion is given")
    vw.add_argument("--example", default=None, choices=EXAMPLES,
                    help="a built-in example instead of the default walk (human-walk: the "
                         "sagittal walk on HOAP-2; case-I, case-II, humanoid: the paper's)")
    vw.add_argument("--method", default="optimal", choices=METHODS, help=METHOD_HELP)
    vw.add_argument("--layout", default="side", choices=["side", "ghost"],
                    help="example: robots side by side or overlaid (default: %(default)s)")
    vw.add_argument("--html", default=None, help="write a self-contained HTML file and exit")
    vw.add_argument("--port", type=port_number, default=None,
                    help="web port of the live viewer (1-65535; default: a free one)")
    vw.add_argument("--open", action="store_true", help="open the live viewer in a browser")
    vw.add_argument("--seconds", type=positive_seconds, default=None,
                    help="stop the live viewer after this many seconds (default: Ctrl-C)")
    vw.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    import time

    from ...assess.metrics import force_direction
    from ...assess.verdict import verdict
    from ...viz import Viewer, compare
    from ..examples import example

    live = a.html is None
    v = None
    status = 0
    try:
        if a.motion is not None:
            demo = read_demonstration(a.motion, a)
            robot, motion = demo.robot, demo.motion
            v = Viewer.start(a.port, a.open and live, quiet=not live)
            v.show(robot, motion, force_directions=force_direction(robot, motion)
                   if motion.contact else None)
            v.animate()
            if a.html:
                v.save_html(a.html)
        else:
            if a.example is not None:
                print(f"building example {a.example!r} (method={a.method}) …", flush=True)
                ex = example(a.example, a.method)
                demonstrator, demonstration, adapted = ex.demonstrator, ex.demonstration, \
                    ex.adapted
            else:
                demonstrator, demonstration, _, adapted = run_adaptation(a, None)
            verdict_ = verdict(adapted)
            for line in verdict_.lines():
                print(f"  {line}", flush=True)
            status = verdict_.exit_status
            # a file only: the server is gone when the command ends, so no URL is printed
            v = Viewer.start(a.port, a.open and live, quiet=not live)
            compare(demonstrator, demonstration, adapted.robot, adapted,
                    layout=a.layout, html=a.html, viewer=v,
                    demo_force=force_direction(demonstrator, demonstration),
                    imitator_force=force_direction(adapted.robot, adapted.motion))
        if a.html:
            print(f"wrote {a.html} (self-contained; open it in a browser, no network needed)")
        if live:
            print("press Ctrl-C to stop the viewer", flush=True)
            deadline = time.monotonic() + (a.seconds if a.seconds else float("inf"))
            while time.monotonic() < deadline:
                v.check_alive()  # a server that died ends the command with an error
                time.sleep(0.2)
    except KeyboardInterrupt:
        if v is None or not live:
            raise  # interrupted while building: status 130
    finally:
        if v is not None:
            v.close()
    return status
