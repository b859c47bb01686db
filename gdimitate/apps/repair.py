"""``gdimitate repair FILE --robot R --out DIR [--simulate]``: a robot motion file from any
retargeter made physically consistent on its own robot (:func:`gdimitate.repair.repair`).

The file is read by ``gdimitate audit``'s readers (:func:`gdimitate.batch.audit.read_robot_motion`:
gdimitate's ``.npz``, the ``csv`` export, LAFAN1 / BeyondMimic CSV, a GMR pickle, Isaac Lab AMP,
MuJoCo qpos and BeyondMimic NPZ). The folder gets what ``gdimitate adapt`` writes
(:data:`gdimitate.apps.outputs.ADAPT_FILES`: ``imitator_joints.csv``, ``imitator_motion.npz``,
``report.json``, ``gait.png``); report.json's ``verdict`` is the repair's (the audit of the
repaired motion) and its ``repair`` entry holds the audits before and after side by side, the
keypoints and push kept, and — with ``--simulate`` — both motions run in MuJoCo
(:func:`gdimitate.sim.simulate`: the input with its estimated wrenches, the repaired motion
with the adaptor's). Exit status 0 when the repaired motion audits feasible (and, simulated,
does not fall), 3 when not, 2 on an error.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..adaptation.repairer import RepairResult
from ..assess.verdict import EXIT_NOT_FEASIBLE, Verdict
from ..model.motion import Motion
from ..model.robot import Robot

__all__ = ["input_plan", "repair_file", "repair_verdict", "simulate_both"]


def repair_verdict(r: RepairResult) -> Verdict:
    """The repair's :class:`~gdimitate.verdict.Verdict`: the audit of the repaired motion
    (:attr:`RepairResult.after`), with the solver's record."""
    from ..assess.verdict import solver_record

    a = r.after
    return Verdict(bool(a.feasible), "audit (Pinocchio) of the repaired motion",
                   tuple(a.report.binding), (), solver_record(r.adapted.solver),
                   tuple(a.failed()))


def input_plan(robot: Robot, motion: Motion, r: RepairResult):
    """The input as a plan for :func:`gdimitate.sim.simulate`: its q, v and a (differenced
    where absent), the audit's stance schedule and the audit's estimated wrenches
    (``r.before.wrenches``)."""
    from ..assess.audit.dataset import stance_schedule
    from ..model.motion import differentiate
    from ..sim.reference import Plan

    stance, _ = stance_schedule(robot, motion)
    m = motion.replace(contact=stance)
    if m.v is None or m.a is None:
        m = differentiate(robot.model, m)
    return Plan(m, {s: w.copy() for s, w in r.before.wrenches.wrenches.items()},
                dict(robot.require_contacts()))


def simulate_both(robot: Robot, motion: Motion, r: RepairResult) -> dict[str, dict[str, Any]]:
    """The input (:func:`input_plan`) and the repaired motion run in MuJoCo under the
    whole-body tracking controller: ``{"before": ..., "after": ...}``, each ``fell``,
    ``fall_time`` [s from the start], ``slip_max`` [m]."""
    from ..sim import simulate

    out = {}
    for key, plan in (("before", input_plan(robot, motion, r)), ("after", r.adapted)):
        m = simulate(robot, plan).metrics
        t0 = float(plan.motion.t[0])
        out[key] = {"fell": bool(m.fell),
                    "fall_time": None if m.fall_time is None else float(m.fall_time - t0),
                    "slip_max": float(m.slip_max)}
    return out


def repair_file(out: Path, path: Path, robot: Robot | None, *, fps: float = 30.0,
                simulate: bool = False, rate: float | None = None
                ) -> tuple[int, list[str]]:
    """Repair the motion file ``path`` (``robot``: the robot it was made for; None only for
    gdimitate's ``.npz``; ``fps`` [Hz]: a LAFAN1 CSV's frame rate; ``rate`` [knots/s]: the
    adaptor's grid) and write the outputs into the prepared folder ``out``. Returns the exit
    status and the console lines."""
    from ..adaptation.repairer import repair
    from ..batch.audit import read_robot_motion
    from .outputs import write_adapted

    bot, motion, fmt = read_robot_motion(path, robot, fps)
    r = repair(bot, motion, rate=rate)
    v = repair_verdict(r)
    sim = simulate_both(bot, motion, r) if simulate else None
    extra = {"verdict": v.to_dict(),
             "repair": {"file": str(path), "format": fmt, "robot": bot.name, **r.to_dict(),
                        "simulation": sim}}
    write_adapted(out, bot, motion.replace(contact=dict(r.schedule)), r.adapted, extra)
    lines = [f"repaired {path.name} ({fmt}, {bot.name}, {motion.T} frames) in {r.seconds:.1f} s; "
             f"wrote {out}/imitator_joints.csv, imitator_motion.npz, report.json, gait.png"]
    lines += [f"  {x}" for x in r.lines()]
    if sim is not None:
        for key in ("before", "after"):
            s = sim[key]
            lines.append(f"  MuJoCo, {key:<6}          " + (
                f"FELL at {s['fall_time']:.2f} s" if s["fell"] else "walked the whole motion")
                + f"; stance slip max {100 * s['slip_max']:.1f} cm")
    lines += [f"  {x}" for x in v.lines()]
    status = v.exit_status
    if sim is not None and sim["after"]["fell"]:
        status = EXIT_NOT_FEASIBLE
    return status, lines

