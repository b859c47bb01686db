"""The ``gdimitate`` command line: ``demo``, ``paper``, ``adapt``, ``view``, ``entrain``,
``walk``, ``export``, ``simulate``, ``batch``, ``audit``, ``repair``, ``stream``.

Without a demonstration file, ``adapt``, ``entrain`` and ``view`` use the default story of
``demo``: one stride of the shipped real 3-D walk (with its measured forces) and the G1
imitator (:func:`gdimitate.apps.demo.default_demonstration`).

Ctrl-C (SIGINT) and SIGTERM stop a command cleanly, during a solve too: every meshcat server it
started is stopped, temporary files are removed, output files are written under a temporary
name and renamed when complete. A command holds its output folder for the run
(:func:`gdimitate.safety.output_job`): a second run on the same folder is refused, and a failed
or interrupted command undoes exactly what it wrote there (the files it created removed, the
ones it replaced put back, the folders it made removed when empty) — never a file that was
there before or that another program wrote meanwhile.

Exit status (:data:`EXIT_STATUS`): 0 done; 1 ``batch`` finished with failed files; 2 an
error (message on stderr); 3 the result was written but is not feasible (the audit's verdict;
Eq. (1)'s reachability and the position limits for the kinematic methods), a goal is unmet
(the optimiser's least-infeasible fallback), the CPG replay check failed, or the simulated
robot fell; 130 after Ctrl-C, 143 after SIGTERM.
"""

from __future__ import annotations

import argparse
import re
import signal
import sys

from ..errors import GdimitateError, LegDetectionError
from .commands import (
    adapt,
    audit,
    batch,
    demo,
    entrain,
    export,
    paper,
    repair,
    simulate,
    stream,
    view,
    walk,
)
from .commands.common import EXIT_STATUS
from .signals import handling_signals

__all__ = ["EXIT_STATUS", "build_parser", "main"]


class _Terminated(BaseException):
    """Raised in the main thread by SIGTERM so that ``finally`` blocks run."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for docs and tests)."""
    p = argparse.ArgumentParser(
        prog="gdimitate",
        description="Goal-directed imitation of rhythmic motion between robots of different "
                    "bodies (force-direction-preserving retargeting, CPG replay, meshcat). "
                    "Without a demonstration file, adapt, entrain and view use demo's story: "
                    "one stride of the shipped real 3-D walk, imitated by G1.",
        epilog="exit status: " + "; ".join(f"{k} {v}" for k, v in EXIT_STATUS.items()),
        formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    for command in (demo, paper, adapt, walk, view, entrain, export, simulate, batch, audit,
                    repair, stream):
        command.add(sub)
    return p


def _on_signal(signum: int, frame: object) -> None:
    # once: a second Ctrl-C must not interrupt the clean-up (which is bounded: a server is
    # given 5 s to stop, then killed)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    if signum == signal.SIGTERM:
        raise _Terminated
    raise KeyboardInterrupt


def _for_the_command_line(e: GdimitateError) -> str:
    """The error's message, with Python-only advice turned into the command's options (a
    ``legs={...}`` dict is ``--legs FILE.json`` here)."""
    text = str(e)
    if isinstance(e, LegDetectionError):
        i = text.lower().find("pass legs=")
        if i >= 0:
            text = (text[:i] + "Pass --legs FILE.json (for the robot given by --imitator or "
                    '--robot) holding {"left": {"hip": JOINT, "knee": JOINT, "ankle": JOINT, '
                    '"sole": FRAME}, "right": {...}} with the names above; a BVH '
                    "demonstration's legs are named in Python: gdimitate.bvh.read_bvh(path, "
                    "legs=...)")
    # massless_joints=('A', 'B') in Python is --massless-joints A,B here
    return re.sub(r"or pass massless_joints=\((.*?),?\) if that is intended",
                  lambda m: "or pass --massless-joints " + ",".join(
                      re.findall(r"'([^']*)'", m.group(1))) + " (with the robot's option) if "
                  "that is intended", text)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``gdimitate`` command; the exit statuses are :data:`EXIT_STATUS`
    (0 done, 1 ``batch`` with failed files, 2 an error, 3 written but not feasible or a goal
    unmet, 130 Ctrl-C, 143 SIGTERM)."""
    args = build_parser().parse_args(argv)
    try:
        with handling_signals(_on_signal):
            status = args.func(args)  # batch: 1 when some files failed; 3: not feasible
    except GdimitateError as e:
        print(f"gdimitate {args.command}: error: {_for_the_command_line(e)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"gdimitate {args.command}: interrupted", file=sys.stderr)
        return 130
    except _Terminated:
        print(f"gdimitate {args.command}: terminated", file=sys.stderr)
        return 143
    return int(status or 0)


if __name__ == "__main__":
    raise SystemExit(main())
