"""The ``gdimitate`` command line: ``demo``, ``paper``, ``adapt``, ``view``, ``entrain``.

Ctrl-C (SIGINT) and SIGTERM stop a command cleanly: every meshcat server it started is
stopped, temporary files are removed, output files are written under a temporary name and
renamed when complete (``demo`` removes what it wrote), and the exit status is 130 (SIGINT) or
143 (SIGTERM). Errors exit with status 2 and a message.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path

from .errors import GdimitateError
from .safety import atomic_write, prepare_output_dir, removed_on_failure

__all__ = ["main"]


class _Terminated(BaseException):
    """Raised in the main thread by SIGTERM so that ``finally`` blocks run."""


def _port(text: str) -> int:
    """argparse type of a TCP port 1–65535."""
    try:
        p = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 1 <= p <= 65535:
        raise argparse.ArgumentTypeError(f"port must be in 1-65535, got {p}")
    return p


def _cmd_demo(a: argparse.Namespace) -> None:
    from .demo import run_demo

    with removed_on_failure(a.out):  # interrupted or failed: no half-written folder
        run_demo(prepare_output_dir(a.out), imitator=a.imitator, method=a.method)


def _cmd_paper(a: argparse.Namespace) -> None:
    from .paper import run_paper

    run_paper(a.out)


def _load_demonstration(path: str | None, demonstrator: str | None):
    from .gait import human_walk, read_opensim
    from .motion import Motion
    from .robot import Robot

    if path is None:
        return human_walk()
    p = Path(path)
    if p.suffix == ".mot":
        return read_opensim(p)
    if p.suffix == ".npz":
        if not demonstrator:
            raise GdimitateError("a .npz motion needs --demonstrator ROBOT (its robot's name)")
        return Robot.from_library(demonstrator), Motion.from_npz(p)
    raise GdimitateError(f"unknown demonstration format {p.suffix!r}: use .mot (OpenSim) or "
                         ".npz (gdimitate Motion)")


def _cmd_adapt(a: argparse.Namespace) -> None:
    from .adapt import adapt
    from .robot import Robot

    out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
    robot, motion = _load_demonstration(a.demonstration, a.demonstrator)
    imitator = Robot.from_library(a.imitator)
    print(f"adapting {motion.T} frames of {robot.name} → {imitator.name} "
          f"(method={a.method}, force={a.force}) …", flush=True)
    result = adapt(motion, robot, imitator, a.method, force=a.force)
    with atomic_write(out / "imitator_joints.csv") as tmp:
        result.motion.to_csv(tmp)
    with atomic_write(out / "imitator_motion.npz") as tmp:
        result.motion.to_npz(tmp)
    with atomic_write(out / "report.json") as tmp:
        tmp.write_text(json.dumps(result.report.to_dict(), indent=2))
    r = result.report
    print(f"wrote {out}/imitator_joints.csv, imitator_motion.npz, report.json\n"
          f"  infeasible frames {r.infeasible_frames}, force-direction error max "
          f"{r.force_direction_error_max:.3g} rad, joint-limit violation max "
          f"{r.joint_limit_violation_max:.3g} rad")


def _cmd_view(a: argparse.Namespace) -> None:
    import time

    from .examples import example
    from .metrics import force_direction, sagittal_angles
    from .motion import Motion
    from .robot import Robot
    from .viz import Viewer, compare

    live = a.html is None
    v = None
    try:
        if a.motion is not None:
            if not a.robot:
                raise GdimitateError("a motion file needs --robot NAME (the robot it belongs to)")
            robot, motion = Robot.from_library(a.robot), Motion.from_npz(a.motion)
            v = Viewer.start(a.port, a.open)
            v.show(robot, motion, force_directions=sagittal_angles(
                force_direction(robot, motion)) if motion.contact else None)
            v.animate()
            if a.html:
                v.save_html(a.html)
        else:
            print(f"building example {a.example!r} (method={a.method}) …", flush=True)
            ex = example(a.example, a.method)
            v = compare(ex.demonstrator, ex.demonstration, ex.imitator, ex.adapted,
                        layout=a.layout, html=a.html, port=a.port, open_browser=a.open,
                        demo_force=sagittal_angles(
                            force_direction(ex.demonstrator, ex.demonstration)),
                        imitator_force=sagittal_angles(
                            force_direction(ex.imitator, ex.adapted.motion)))
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


def _cmd_entrain(a: argparse.Namespace) -> None:
    from .adapt import adapt
    from .cpg import entrain
    from .gait import human_walk
    from .motion import Motion
    from .robot import Robot

    if a.motion is not None:
        if not a.robot:
            raise GdimitateError("a motion file needs --robot NAME (the robot it belongs to)")
        robot, motion = Robot.from_library(a.robot), Motion.from_npz(a.motion)
    else:
        print("no motion given: adapting the shipped real walk to hoap2 (Eq. 1) …", flush=True)
        human, walk = human_walk()
        robot = Robot.from_library(a.robot or "hoap2")
        motion = adapt(walk, human, robot).motion
    out = prepare_output_dir(a.out)
    print(f"entraining a Matsuoka network to {robot.name}'s joints and base "
          f"({motion.T} frames) and replaying {a.duration or motion.t[-1]:.2f} s free …",
          flush=True)
    cpg = entrain(robot, motion, duration=a.duration)
    with atomic_write(out / "oscillator_params.json") as tmp:
        tmp.write_text(cpg.result.to_json())
    with atomic_write(out / "replay_joints.csv") as tmp:
        cpg.replay.to_csv(tmp)
    with atomic_write(out / "replay_motion.npz") as tmp:
        cpg.replay.to_npz(tmp)
    with atomic_write(out / "report.json") as tmp:
        tmp.write_text(json.dumps(
            {"robot": robot.name, "learned_frequency_hz": float(cpg.result.frequency),
             "constant_angles_rad": cpg.constant, "per_joint": cpg.report}, indent=2,
            default=float))
    print(f"wrote {out}/oscillator_params.json, replay_joints.csv, replay_motion.npz, "
          f"report.json\n  learned frequency {cpg.result.frequency:.4f} Hz")
    for j, r in cpg.report.items():
        print(f"  {j:<12} nRMSE entrained {r['nrmse_entrained'] * 100:5.2f} %   "
              f"frequency error after stop {r['freq_error_after'] * 100:5.2f} %")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for docs and tests)."""
    from .library import list_robots

    p = argparse.ArgumentParser(
        prog="gdimitate",
        description="Goal-directed imitation of rhythmic motion between robots of different "
                    "bodies (force-direction-preserving retargeting, CPG replay, meshcat).")
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="the main job: real human walk → HOAP-2-sized imitator")
    d.add_argument("--out", default="gdimitate-demo", help="output folder (default: %(default)s)")
    d.add_argument("--imitator", default="hoap2", choices=list_robots(),
                   help="imitator robot (default: %(default)s)")
    d.add_argument("--method", default="optimal", choices=["analytic", "copy", "optimal"],
                   help="adaptor whose motion is entrained and shown (default: %(default)s)")
    d.set_defaults(func=_cmd_demo)
    pp = sub.add_parser("paper", help="the paper's Figs. 4–13 (in spirit) + summary.json")
    pp.add_argument("--out", default="paper-out", help="output folder (default: %(default)s)")
    pp.set_defaults(func=_cmd_paper)
    ad = sub.add_parser("adapt", help="adapt a demonstration file for an imitator")
    ad.add_argument("demonstration", nargs="?", default=None,
                    help="OpenSim .mot or gdimitate .npz (default: the shipped real walk)")
    ad.add_argument("--demonstrator", default=None, help="robot of a .npz motion")
    ad.add_argument("--imitator", default="hoap2", choices=list_robots())
    ad.add_argument("--method", default="analytic", choices=["analytic", "copy", "optimal"])
    ad.add_argument("--force", default="segment", choices=["segment", "com", "grf"])
    ad.add_argument("--out", default="gdimitate-adapt", help="output folder (default: %(default)s)")
    ad.set_defaults(func=_cmd_adapt)
    from .examples import EXAMPLES

    vw = sub.add_parser("view", help="meshcat preview: live in the browser or --html FILE")
    vw.add_argument("motion", nargs="?", default=None, help="a gdimitate .npz motion (optional)")
    vw.add_argument("--robot", default=None, help="robot of the motion file")
    vw.add_argument("--example", default="human-walk", choices=EXAMPLES,
                    help="built-in example when no motion file is given (default: %(default)s)")
    vw.add_argument("--method", default="analytic", choices=["analytic", "copy", "optimal"])
    vw.add_argument("--layout", default="side", choices=["side", "ghost"])
    vw.add_argument("--html", default=None, help="write a self-contained HTML file and exit")
    vw.add_argument("--port", type=_port, default=None,
                    help="web port of the live viewer (1-65535; default: a free one)")
    vw.add_argument("--open", action="store_true", help="open the live viewer in a browser")
    vw.add_argument("--seconds", type=float, default=None,
                    help="stop the live viewer after this many seconds (default: Ctrl-C)")
    vw.set_defaults(func=_cmd_view)
    en = sub.add_parser("entrain", help="tune a Matsuoka network to a motion and replay it")
    en.add_argument("motion", nargs="?", default=None,
                    help="a gdimitate .npz motion (default: the real walk adapted to hoap2)")
    en.add_argument("--robot", default=None, help="robot of the motion file")
    en.add_argument("--duration", type=float, default=None,
                    help="seconds of free-running replay (default: the motion's duration)")
    en.add_argument("--out", default="gdimitate-entrain",
                    help="output folder (default: %(default)s)")
    en.set_defaults(func=_cmd_entrain)
    return p


def _on_signal(signum: int, frame: object) -> None:
    # once: a second Ctrl-C must not interrupt the clean-up (which is bounded: a server is
    # given 5 s to stop, then killed)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    if signum == signal.SIGTERM:
        raise _Terminated
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``gdimitate`` command: 0 on success, 2 on an error (message on
    stderr), 130 after Ctrl-C, 143 after SIGTERM."""
    args = build_parser().parse_args(argv)
    previous = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, _on_signal)
    except ValueError:  # not the main thread: leave signals alone
        pass
    try:
        args.func(args)
    except GdimitateError as e:
        print(f"gdimitate {args.command}: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"gdimitate {args.command}: interrupted", file=sys.stderr)
        return 130
    except _Terminated:
        print(f"gdimitate {args.command}: terminated", file=sys.stderr)
        return 143
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
