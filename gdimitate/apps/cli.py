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
import json
import math
import re
import signal
import sys
from pathlib import Path
from typing import TYPE_CHECKING, cast

from ..assess.verdict import EXIT_NOT_FEASIBLE
from ..errors import GdimitateError, LegDetectionError, OscillatorError, OutputError
from ..safety import atomic_write, output_job, prepare_output_dir

if TYPE_CHECKING:
    from ..types import ForceModel

__all__ = ["EXIT_STATUS", "main"]

#: The command's exit statuses and what each means (also in ``gdimitate --help``).
EXIT_STATUS = {
    0: "done",
    1: "batch: some files failed (listed in its summary)",
    2: "error (the message on stderr says what to fix)",
    EXIT_NOT_FEASIBLE: "written, but not feasible, a goal unmet, the CPG replay check failed "
                       "or the simulated robot fell",
    130: "interrupted (Ctrl-C)",
    143: "terminated (SIGTERM)",
}


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


def _seconds(text: str) -> float:
    """argparse type of a finite duration > 0 [s]."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds > 0, got {text}")
    return v


def _json_file(path: str | None, what: str):
    """The JSON object in ``path`` (``--legs``/``--contacts``), or None."""
    if path is None:
        return None
    from ..errors import InvalidInputError
    from ..model.inputs import read_json

    value = read_json(path, what)  # bounded: size, nesting, digits, no NaN
    if not isinstance(value, dict):
        raise InvalidInputError(f"{what} {path}: expected a JSON object "
                                '{"left": {...}, "right": {...}}')
    return value


def _robot(spec: str, a: argparse.Namespace):
    """``Robot.load`` of a library name or a .urdf/.osim path with the command's
    ``--package-dir``/``--contacts``/``--legs``/``--massless-joints``."""
    from ..model.robot import Robot

    massless = [j for j in (a.massless_joints or "").split(",") if j.strip()]
    return Robot.load(spec, package_dir=a.package_dir,
                      contacts=_json_file(a.contacts, "--contacts"),
                      legs=_json_file(a.legs, "--legs"),
                      massless_joints=[j.strip() for j in massless])


def _add_robot_args(p: argparse.ArgumentParser, flag: str, default: str | None,
                    what: str) -> None:
    from ..model.library import list_robots

    p.add_argument(flag, default=default,
                   help=f"{what}: a library name ({', '.join(list_robots())}) or a .urdf/.osim "
                        "path" + (" (default: %(default)s)" if default else ""))
    p.add_argument("--package-dir", default=None,
                   help=f"folder resolving the {flag[2:]} URDF's package:// meshes (default: "
                        "the URDF's folder)")
    p.add_argument("--legs", default=None, metavar="FILE.json",
                   help=f"the {flag[2:]}'s legs where names don't tell them: "
                        '{"left": {"hip": J, "knee": J, "ankle": J, "sole": FRAME}, "right": …}')
    p.add_argument("--contacts", default=None, metavar="FILE.json",
                   help=f"the {flag[2:]}'s sole rectangles: "
                        '{"left": {"half_length": m, "half_width": m, "frame"?: F, "mu"?: x}, …}')
    p.add_argument("--massless-joints", default=None, metavar="J[,J…]",
                   help=f"moving joints of the {flag[2:]} URDF allowed to carry no mass (e.g. "
                        "a hand's finger joints); a library robot's presets are kept")


def _add_demonstration_args(p: argparse.ArgumentParser, positional: str, default_note: str
                            ) -> None:
    p.add_argument(positional, nargs="?", default=None,
                   help="demonstration: OpenSim .mot/.sto, .osim (with --coordinates or "
                        "--markers), markers .trc/.c3d (with --osim), .bvh or a gdimitate .npz "
                        f"(default: {default_note})")
    p.add_argument("--grf", default=None,
                   help="OpenSim ground-reaction-force .mot/.sto of a .mot/.sto/.osim "
                        "demonstration (its ExternalLoads .xml is used when it lies beside it)")
    p.add_argument("--coordinates", default=None,
                   help="the .mot/.sto joint angles of an .osim demonstration")
    p.add_argument("--markers", default=None,
                   help="the .trc/.c3d markers of an .osim demonstration (marker-based IK)")
    p.add_argument("--osim", default=None,
                   help="the OpenSim model of a full-body .mot/.sto or a .trc/.c3d "
                        "demonstration")
    p.add_argument("--demonstrator", default=None,
                   help="robot of a .npz that records none (library name or .urdf path)")
    p.add_argument("--treadmill", action="store_true",
                   help="keep a treadmill trial's kinematics (default: turned overground "
                        "when forces are given)")


def _demonstration(path: str | None, a: argparse.Namespace):
    """The command's demonstration (:func:`gdimitate.io.demonstration.load_demonstration`);
    ``None`` → ``None``."""
    if path is None:
        return None
    from ..io.demonstration import load_demonstration
    from ..model.robot import Robot

    robot = None
    if a.osim is not None:
        robot = Robot.from_osim(a.osim)
    elif a.demonstrator is not None:
        robot = Robot.load(a.demonstrator)
    return load_demonstration(path, grf=a.grf, coordinates=a.coordinates, robot=robot,
                              overground=not a.treadmill, markers=a.markers)


def _cmd_demo(a: argparse.Namespace) -> int:
    from .demo import run_demo

    imitator = _robot(a.imitator, a)
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        s = run_demo(prepare_output_dir(a.out), imitator=imitator, method=a.method)
    fell = s["simulation"]["fell"]
    if s["verdict"]["ok"] and not fell:
        return 0
    why = "the simulated robot fell" if fell else "it is not feasible or a goal is unmet"
    print(f"result written, but {why}: exit status {EXIT_NOT_FEASIBLE}")
    return EXIT_NOT_FEASIBLE


def _cmd_paper(a: argparse.Namespace) -> None:
    from .paper import run_paper

    run_paper(a.out)


def _default_story(imitator: str | None, a: argparse.Namespace):
    """The default demonstration and imitator
    (:func:`gdimitate.apps.demo.default_demonstration`,
    G1 unless ``imitator`` names another), announced."""
    from .demo import DEFAULT_IMITATOR, default_demonstration

    robot, motion, forces = default_demonstration()
    print(f"no demonstration given: one stride of the shipped real 3-D walk ({motion.T} frames, "
          f"{motion.t[-1] - motion.t[0]:.2f} s, measured forces)", flush=True)
    return robot, motion, forces, _robot(imitator or DEFAULT_IMITATOR, a)


def _adapted(a: argparse.Namespace, demonstration: str | None):
    """``(demonstrator, demonstration, forces, result)`` of the command's adaptation."""
    from ..adaptation.adaptor import adapt

    demo = _demonstration(demonstration, a)
    if demo is None:
        robot, motion, forces, imitator = _default_story(a.imitator, a)
    else:
        robot, motion, forces = demo.robot, demo.motion, demo.forces
        print(f"read {demo.source}: {demo.note}", flush=True)
        imitator = _robot(a.imitator, a)
    force = cast("ForceModel", _force_goal(getattr(a, "force", None), a.method, forces))
    print(f"adapting {motion.T} frames of {robot.name} → {imitator.name} "
          f"(method={a.method}, force={force}) …", flush=True)
    options = {"forces": forces} if a.method == "optimal" and forces is not None else {}
    if getattr(a, "periodic", False):  # one stride as a periodic cycle (optimal only)
        options["periodic"] = True
    return robot, motion, forces, adapt(motion, robot, imitator, a.method, force=force,
                                        **options)


def _force_goal(given: str | None, method: str, forces) -> str:
    """The force-direction goal: the one given, else the measured push where the
    demonstration has forces and the method keeps them (optimal), else ``segment``."""
    if given is not None:
        return given
    return "measured" if forces is not None and method == "optimal" else "segment"


def _cmd_adapt(a: argparse.Namespace) -> int:
    from ..assess.verdict import report_lines, verdict
    from .outputs import write_adapted

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        demonstrator, demo, _, result = _adapted(a, a.demonstration)
        v = verdict(result)
        text = write_adapted(out, demonstrator, demo, result)
    print(f"wrote {out}/imitator_joints.csv, imitator_motion.npz, report.json, gait.png")
    written = json.loads(text)  # the console prints the file's numbers
    for line in report_lines(written) + _error_lines(written):
        print(f"  {line}")
    return v.exit_status


def _error_lines(report: dict) -> list[str]:
    """adapt's last line, from report.json's numbers: the largest push-direction error
    (:func:`gdimitate.assess.verdict.push_errors`: the audit's angle where it measured the push,
    else
    the report's sagittal one) with its side and knot, and the largest position-limit
    excursion."""
    push = report["push_direction_error"]
    worst = max(push, key=lambda s: push[s]["rad"], default=None)
    said = "push-direction error: none measured" if worst is None else (
        f"push-direction error max {push[worst]['rad']:.3g} rad "
        f"({math.degrees(push[worst]['rad']):.1f}°, {worst}, knot {push[worst]['knot']}, "
        f"{push[worst]['measure']})")
    return [f"{said}; joint-limit violation max {report['joint_limit_violation_max_rad']:.3g} "
            "rad"]


def _cmd_walk(a: argparse.Namespace) -> int:
    from ..walker.command import walk_command

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)
        return walk_command(out, _demonstration(a.demonstration, a), _robot(a.imitator, a),
                            a.steps, a.gain, html=not a.no_html,
                            **({} if a.rate is None else {"rate": a.rate}))


def _cmd_view(a: argparse.Namespace) -> int:
    import time

    from ..assess.metrics import force_direction
    from ..assess.verdict import verdict
    from ..viz import Viewer, compare
    from .examples import example

    live = a.html is None
    v = None
    status = 0
    try:
        if a.motion is not None:
            demo = _demonstration(a.motion, a)
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
                demonstrator, demonstration, _, adapted = _adapted(a, None)
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


def _cmd_entrain(a: argparse.Namespace) -> int:
    from ..oscillator.replay import entrain

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        options = {}
        if a.motion is not None:
            demo = _demonstration(a.motion, a)
            robot, motion = demo.robot, demo.motion
        else:
            a.imitator = a.robot
            _, stride, _, result = _adapted(a, None)
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


def _cmd_batch(a: argparse.Namespace) -> int:
    from ..batch import BatchOptions, run_batch

    options = BatchOptions(a.imitator, method=a.method, force=a.force, simulate=a.simulate,
                           demonstrator=a.demonstrator)
    where = (f"the workers of Dask scheduler {a.address}" if a.address else
             f"a local Dask cluster of {a.workers} worker process(es)" if a.executor == "dask"
             else f"{a.workers} local worker process(es)")
    print(f"batch: {a.input_dir} → {a.out} ({options.method}, imitator {options.imitator}; "
          f"{where}) …", flush=True)
    res = run_batch(a.input_dir, a.out, options, workers=a.workers, executor=a.executor,
                    address=a.address, pattern=a.pattern, progress=not a.quiet)
    from ..batch.table import console_table

    print(console_table(res.rows))
    counts = ", ".join(f"{len(res.by_status(s))} {s}" for s in ("done", "skipped", "failed"))
    bad = [r.file for r in res.rows if r.status != "failed" and not r.ok]
    print(f"{counts}; {len(bad)} not feasible, with a goal unmet or fallen; {res.wall_s:.1f} s "
          f"on {res.workers} worker(s), {res.files_per_second:.2f} files/s\nwrote "
          f"{res.summary_csv}, {res.summary_json}")
    if res.by_status("failed"):
        return 1
    return EXIT_NOT_FEASIBLE if bad else 0


def _cmd_repair(a: argparse.Namespace) -> int:
    from ..batch.audit import find_motion_files
    from ..errors import InvalidInputError
    from .repair import repair_file

    if Path(a.file).expanduser().is_dir():
        raise InvalidInputError(f"{a.file} is a folder; repair takes one motion file (audit "
                                "takes folders)")
    (path,) = find_motion_files([a.file])
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        status, lines = repair_file(out, path, _robot(a.robot, a) if a.robot else None,
                                    fps=a.fps, simulate=a.simulate, rate=a.rate)
    print("\n".join(lines))
    return status


def _cmd_audit(a: argparse.Namespace) -> int:
    from ..batch.audit import audit_csv, audit_files, audit_table, find_motion_files

    files = find_motion_files(a.files)
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        audited = audit_files(files, lambda: _robot(a.robot, a) if a.robot else None, a.fps)
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


def _cmd_stream(a: argparse.Namespace) -> int:
    from .stream import stream_command

    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        out = prepare_output_dir(a.out)  # before the work: a bad --out fails at once
        return stream_command(a, out, lambda: _robot(a.imitator, a))


def _cmd_export(a: argparse.Namespace) -> None:
    from ..export.writers import FORMATS, export_motion, read_wrenches

    demo = _demonstration(a.motion, a)
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


def _cmd_simulate(a: argparse.Namespace) -> int:
    from ..export.writers import read_wrenches

    # the plan is a gdimitate .npz that records its robot: --grf, --coordinates and --osim
    # belong to the --reference (they were applied to the plan, which then always failed)
    plan_args = argparse.Namespace(**{**vars(a), "grf": None, "coordinates": None,
                                      "osim": None, "markers": None})
    demo = _demonstration(a.motion, plan_args)
    wrenches = read_wrenches(a.motion) if Path(a.motion).suffix.lower() == ".npz" else None
    if wrenches is None or demo.motion.v is None:
        raise GdimitateError(f"{a.motion} holds no contact wrenches or velocities: simulate a "
                             "plan written by `gdimitate adapt` (the optimal method) or "
                             "AdaptedMotion.save(..., format='npz')")
    forces = _demonstration(a.reference, a).forces if a.reference else None
    with output_job(a.out):  # one run per folder; failed: what it wrote is undone
        return _simulate(a, demo, wrenches, forces)


def _simulate(a: argparse.Namespace, demo, wrenches, forces) -> int:
    from ..sim import plots as sim_plots
    from ..sim import simulate
    from ..sim.animation import show_simulation
    from ..sim.reference import Plan

    robot = demo.robot
    out = prepare_output_dir(a.out)
    print(f"simulating {robot.name}'s plan ({demo.motion.T} knots, "
          f"{demo.motion.t[-1] - demo.motion.t[0]:.2f} s) in MuJoCo at 1 kHz …", flush=True)
    res = simulate(robot, Plan(demo.motion, wrenches, dict(robot.require_contacts())),
                   demo_forces=forces)
    summary = res.metrics.to_dict()
    with atomic_write(out / "sim.json") as tmp:
        tmp.write_text(json.dumps(summary, indent=2, default=str))
    sim_plots.plot_summary(res, out / "simulation.png")
    if a.html:
        from ..viz import Viewer

        v = Viewer.start(quiet=True)
        try:
            show_simulation(robot, res, html=out / "simulation.html", viewer=v)
        finally:
            v.close()
    m = res.metrics
    print(f"FELL at {m.fall_time:.2f} s ({m.fall_reason})" if m.fell else
          "walked the whole plan", f"; stance slip max {100 * m.slip_max:.2f} cm; "
          f"torque saturation {100 * m.torque_saturation:.1f} %; wrote {out}/sim.json, "
          "simulation.png" + (", simulation.html" if a.html else ""))
    if m.fell:
        print(f"result written, but the robot fell: exit status {EXIT_NOT_FEASIBLE}")
        return EXIT_NOT_FEASIBLE
    return 0


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
    for add in (_add_demo, _add_paper, _add_adapt, _add_walk, _add_view, _add_entrain,
                _add_export, _add_simulate, _add_batch, _add_audit, _add_repair,
                _add_stream):
        add(sub)
    return p


#: the adaptor methods of demo, adapt, view and entrain, and their help
_METHODS = ["optimal", "analytic", "copy"]
_METHOD_HELP = ("adaptor: optimal (whole-body, contact-consistent, within the imitator's "
                "limits), analytic (the paper's Eq. 1, sagittal), copy (joint angles; the "
                "baseline) (default: %(default)s)")


def _add_demo(sub) -> None:
    """``gdimitate demo``: the main job (:mod:`gdimitate.apps.demo`)."""
    from .demo import DEFAULT_IMITATOR

    d = sub.add_parser("demo", help="the main job: the real 3-D walk → G1 (whole-body adaptor, "
                                    "MuJoCo physics check, oscillator replay)")
    d.add_argument("--out", default="gdimitate-demo", help="output folder (default: %(default)s)")
    _add_robot_args(d, "--imitator", DEFAULT_IMITATOR, "imitator robot (e.g. hoap2, talos)")
    d.add_argument("--method", default="optimal", choices=_METHODS, help=_METHOD_HELP)
    d.set_defaults(func=_cmd_demo)


def _add_paper(sub) -> None:
    """``gdimitate paper``: the paper's figures (:mod:`gdimitate.apps.paper`)."""
    pp = sub.add_parser("paper", help="the paper's Figs. 4–13 (in spirit) + summary.json")
    pp.add_argument("--out", default="paper-out", help="output folder (default: %(default)s)")
    pp.set_defaults(func=_cmd_paper)


def _add_adapt(sub) -> None:
    """``gdimitate adapt``: adapt a demonstration file, write the result and its verdict."""
    from .demo import DEFAULT_IMITATOR

    ad = sub.add_parser("adapt", help="adapt a demonstration file for an imitator",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: {EXIT_STATUS[3]}")
    _add_demonstration_args(ad, "demonstration",
                            "one stride of the shipped real 3-D walk, as demo")
    _add_robot_args(ad, "--imitator", DEFAULT_IMITATOR, "imitator robot")
    ad.add_argument("--method", default="optimal", choices=_METHODS, help=_METHOD_HELP)
    ad.add_argument("--force", default=None, choices=["segment", "com", "dynamics",
                                                       "measured"],
                    help="force-direction model of the goal: segment (hip→sole), com "
                         "(CoM→sole), dynamics (from the motion), measured (the "
                         "demonstration's measured forces: --grf, a C3D's plates, the default "
                         "story's) (default: measured where the demonstration has forces and "
                         "the method is optimal, else segment)")
    ad.add_argument("--periodic", action="store_true",
                    help="adapt one stride (heel strike to heel strike of the right foot) as a "
                         "periodic cycle: its end state is its start shifted by one stride "
                         "(method optimal)")
    ad.add_argument("--out", default="gdimitate-adapt", help="output folder (default: %(default)s)")
    ad.set_defaults(func=_cmd_adapt)


def _add_walk(sub) -> None:
    """``gdimitate walk``: a periodic cycle walked in MuJoCo under an oscillator network."""
    from .demo import WALK_IMITATOR

    wk = sub.add_parser("walk", help="a periodic cycle, a whole-body oscillator network and N "
                                     "steps in MuJoCo (walk.json, plots, trajectory, HTML)",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: the robot fell, fewer steps "
                               "than asked, or the cycle is not feasible")
    _add_demonstration_args(wk, "demonstration", "the shipped real 3-D walk")
    _add_robot_args(wk, "--imitator", WALK_IMITATOR, "imitator robot")
    wk.add_argument("--steps", type=int, default=20, help="steps to walk (default: %(default)s)")
    wk.add_argument("--gain", type=float, default=0.5,
                    help="feedback gain of the ground into the network (0: open loop) "
                         "(default: %(default)s)")
    wk.add_argument("--rate", type=float, default=None,
                    help="knots per second of the cycle's optimal solve (default: "
                         "gdimitate.walker.WALK_RATE)")
    wk.add_argument("--no-html", action="store_true", help="skip walk.html")
    wk.add_argument("--out", default="gdimitate-walk", help="output folder (default: %(default)s)")
    wk.set_defaults(func=_cmd_walk)


def _add_view(sub) -> None:
    """``gdimitate view``: the meshcat preview, live or as a self-contained HTML file."""
    from .demo import DEFAULT_IMITATOR
    from .examples import EXAMPLES

    vw = sub.add_parser("view", help="meshcat preview: live in the browser or --html FILE",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: the adaptation shown is not "
                               "feasible or leaves a goal unmet")
    _add_demonstration_args(vw, "motion", "one stride of the shipped real 3-D walk adapted to "
                                          "--imitator, as demo")
    _add_robot_args(vw, "--imitator", DEFAULT_IMITATOR,
                    "imitator the default walk is adapted to when no motion is given")
    vw.add_argument("--example", default=None, choices=EXAMPLES,
                    help="a built-in example instead of the default walk (human-walk: the "
                         "sagittal walk on HOAP-2; case-I, case-II, humanoid: the paper's)")
    vw.add_argument("--method", default="optimal", choices=_METHODS, help=_METHOD_HELP)
    vw.add_argument("--layout", default="side", choices=["side", "ghost"],
                    help="example: robots side by side or overlaid (default: %(default)s)")
    vw.add_argument("--html", default=None, help="write a self-contained HTML file and exit")
    vw.add_argument("--port", type=_port, default=None,
                    help="web port of the live viewer (1-65535; default: a free one)")
    vw.add_argument("--open", action="store_true", help="open the live viewer in a browser")
    vw.add_argument("--seconds", type=_seconds, default=None,
                    help="stop the live viewer after this many seconds (default: Ctrl-C)")
    vw.set_defaults(func=_cmd_view)


def _add_entrain(sub) -> None:
    """``gdimitate entrain``: a Matsuoka network tuned to a motion, and its replay."""
    from .demo import DEFAULT_IMITATOR

    en = sub.add_parser("entrain", help="tune a Matsuoka network to a motion and replay it",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: the free-running replay "
                               "misses the stride frequency or amplitude (the replay check)")
    _add_demonstration_args(en, "motion", "one stride of the shipped real 3-D walk adapted "
                                          "to --robot, as demo")
    _add_robot_args(en, "--robot", DEFAULT_IMITATOR, "robot the shipped walk is adapted to "
                    "when no motion is given")
    en.add_argument("--method", default="optimal", choices=_METHODS, help=_METHOD_HELP)
    en.add_argument("--duration", type=_seconds, default=None,
                    help="seconds of free-running replay (default: the motion's duration)")
    en.add_argument("--out", default="gdimitate-entrain",
                    help="output folder (default: %(default)s)")
    en.set_defaults(func=_cmd_entrain)


def _add_export(sub) -> None:
    """``gdimitate export``: a motion written in another file format."""
    from ..export.writers import FORMATS

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
    ex.set_defaults(func=_cmd_export, treadmill=False)


def _add_simulate(sub) -> None:
    """``gdimitate simulate``: a plan executed in MuJoCo and measured."""
    si = sub.add_parser("simulate", help="execute an adapted plan in MuJoCo under the whole-body "
                        "tracking controller and measure it (falls, slip, push directions, CoP)")
    si.add_argument("motion", help="a plan: a gdimitate .npz with v, a and wrenches (written by "
                    "`gdimitate adapt` with the optimal method or AdaptedMotion.save)")
    si.add_argument("--out", default="gdimitate-sim", help="output folder (default: %(default)s)")
    si.add_argument("--reference", default=None,
                    help="the demonstration with measured forces to compare push directions "
                         "with (e.g. an .osim with --coordinates and --grf)")
    si.add_argument("--html", action="store_true",
                    help="also write simulation.html (plan and simulation side by side)")
    for flag, what in (("--grf", "measured forces of --reference"),
                       ("--coordinates", "joint angles of an .osim --reference"),
                       ("--osim", "OpenSim model of a full-body .mot/.sto --reference"),
                       ("--demonstrator", "robot of a .npz that records none")):
        si.add_argument(flag, default=None, help=what)
    si.set_defaults(func=_cmd_simulate, treadmill=False, markers=None)


def _add_batch(sub) -> None:
    """``gdimitate batch``: every demonstration file of a folder adapted, in parallel."""
    ba = sub.add_parser("batch", help="adapt every demonstration file in a folder, in parallel "
                        "(process pool or a Dask cluster), resumable, with a summary table")
    ba.add_argument("input_dir", help="folder of demonstration files (.mot, .sto, .bvh, .npz)")
    ba.add_argument("--imitator", required=True,
                    help="imitator robot: a library name or a .urdf/.osim path")
    ba.add_argument("--out", required=True, help="output folder (results + summary.csv/json)")
    ba.add_argument("--method", default="optimal", choices=["analytic", "copy", "optimal"],
                    help="adaptor (default: %(default)s; analytic: planar sagittal inputs)")
    ba.add_argument("--force", default="segment",
                    choices=["segment", "com", "dynamics", "measured"])
    ba.add_argument("--simulate", action="store_true",
                    help="also replay each result in MuJoCo (optimal method)")
    ba.add_argument("--demonstrator", default=None,
                    help="demonstrator model for inputs that need one (full-body .mot: the .osim)")
    ba.add_argument("--workers", type=int, default=1,
                    help="worker processes (process pool, local Dask cluster; default: 1)")
    ba.add_argument("--executor", default="process", choices=["process", "dask"],
                    help="process: a pool on this machine; dask: a Dask cluster")
    ba.add_argument("--address", default=None,
                    help="Dask scheduler to join (tcp://host:8786; default: a local cluster)")
    ba.add_argument("--pattern", default="*", help="file-name glob in INPUT_DIR (default: *)")
    ba.add_argument("--quiet", action="store_true", help="no progress bar")
    ba.set_defaults(func=_cmd_batch)


def _add_audit(sub) -> None:
    """``gdimitate audit``: robot motion files checked for physical feasibility."""
    from ..batch.audit import AUDIT_FORMATS

    au = sub.add_parser("audit", help="check robot motion files (gdimitate .npz, CSV, LAFAN1 / "
                        "BeyondMimic CSV, GMR pickle, Isaac Lab AMP or MuJoCo qpos NPZ) for "
                        "physical feasibility: torques, friction, CoP, slip, penetration")
    au.add_argument("files", nargs="+", metavar="FILE_OR_FOLDER",
                    help="motion files, or folders (every motion file directly in them): "
                    + "; ".join(f"{k}: {v}" for k, v in AUDIT_FORMATS.items()))
    _add_robot_args(au, "--robot", None, "the robot the motions were made for (optional for "
                    "a gdimitate .npz, which records it)")
    au.add_argument("--out", default="gdimitate-audit",
                    help="output folder for report.json and audit.csv (default: %(default)s)")
    au.add_argument("--fps", type=float, default=30.0,
                    help="frame rate of a LAFAN1 CSV [Hz] (default: %(default)s)")
    au.set_defaults(func=_cmd_audit)


def _add_repair(sub) -> None:
    """``gdimitate repair``: a robot motion file made physically consistent on its robot."""
    rp = sub.add_parser("repair", help="make a robot motion file (any format audit reads) "
                        "physically consistent on the same robot: the whole-body adaptor from "
                        "the robot to itself, the audits before and after",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: {EXIT_STATUS[3]}")
    rp.add_argument("file", metavar="FILE", help="a motion file gdimitate audit reads")
    _add_robot_args(rp, "--robot", None, "the robot the motion was made for (optional for a "
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
    rp.set_defaults(func=_cmd_repair)


def _add_stream(sub) -> None:
    """``gdimitate stream``: a live mocap stream adapted frame by frame (docs/guide/
    streaming.md)."""
    from .demo import DEFAULT_IMITATOR

    st = sub.add_parser("stream", help="adapt a live mocap stream frame by frame (a BVH file "
                        "played at its rate, or Lab Streaming Layer), shown in meshcat; "
                        "writes adapt's outputs when stopped (Ctrl-C)",
                        epilog=f"exit status {EXIT_NOT_FEASIBLE}: some frame's verdict is not "
                               "feasible (docs/guide/streaming.md)")
    st.add_argument("source", help="a .bvh file (played at its own frame rate), or lsl:NAME "
                    "(the LSL stream called NAME: a BVH skeleton's channels '<Joint>.<Channel>' "
                    "or an OpenSim model's coordinates, and 'contact.left', 'contact.right'; "
                    "with --skeleton or --osim)")
    _add_robot_args(st, "--imitator", DEFAULT_IMITATOR, "imitator robot")
    st.add_argument("--skeleton", default=None, metavar="FILE.bvh",
                    help="lsl: the BVH file whose HIERARCHY names the stream's channels (its "
                         "unit, up axis and floor are the file's)")
    st.add_argument("--osim", default=None, metavar="FILE.osim",
                    help="lsl: the OpenSim model whose coordinates name the stream's channels "
                         "(degrees and metres, as a .mot with inDegrees=yes)")
    st.add_argument("--loopback", action="store_true",
                    help="lsl: look for the stream on this machine only (liblsl's "
                         "ResolveScope machine)")
    st.add_argument("--timeout", type=_seconds, default=10.0,
                    help="lsl: seconds to find the stream, and of silence that ends it "
                         "(default: %(default)s)")
    st.add_argument("--frames", type=int, default=None,
                    help="stop after this many frames adapted (a .bvh: play its first N)")
    st.add_argument("--seconds", type=_seconds, default=None, help="stop after this long")
    st.add_argument("--delay", type=float, default=0.0, metavar="MS",
                    help="wait this long after each frame (a slower machine: frames dropped)")
    st.add_argument("--view", action="store_true",
                    help="show the robot following the stream in meshcat (prints its URL)")
    st.add_argument("--port", type=_port, default=None,
                    help="web port of the --view page (default: a free one)")
    st.add_argument("--open", action="store_true", help="open the --view page in a browser")
    st.add_argument("--out", default="gdimitate-stream",
                    help="output folder (default: %(default)s)")
    st.set_defaults(func=_cmd_stream)


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
    previous = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, _on_signal)
    except ValueError:  # not the main thread: leave signals alone
        pass
    try:
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
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return int(status or 0)


if __name__ == "__main__":
    raise SystemExit(main())
