"""``gdimitate demo``: the main job on the built-in default (scenario code, not core API).

The shipped real 3-D walk (OpenSim subject01: its own model, IK angles and measured ground
reaction forces) → one stride (heel strike to heel strike of the right foot) → a 3-D humanoid
(G1 by default) through the whole-body optimal adaptor, keeping each stance foot's measured
push direction → the independent audit (docs/design.md §12) → the physics check in MuJoCo
(docs/design.md §11), with the 3-D joint-angle copy simulated alongside as the negative
control → a Matsuoka network entrained to the adapted motion, replaying it free-running →
``demo.html`` (demonstrator, plan and simulation), plots, the adapted motion (NPZ, CSV), the
oscillator parameters and ``summary.json``, and a table on stdout.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # the command line reads DEFAULT_IMITATOR without loading Pinocchio
    from ..model.motion import Motion
    from ..model.robot import Robot
    from ..types import AdaptMethod

__all__ = ["DEFAULT_IMITATOR", "WALK_IMITATOR", "default_demonstration", "run_demo",
           "summary_table"]

#: Knots per second of the demo's optimal solve (the library default is 50 Hz; 30 Hz keeps
#: the demo under two minutes on two cores).
DEMO_RATE = 30.0
#: The imitator of the default story (``demo``, and ``adapt``/``entrain``/``view`` without a
#: demonstration).
DEFAULT_IMITATOR = "g1"
#: ``gdimitate walk``'s default robot: the default story's, whose periodic cycle of the
#: shipped 3-D walk is audit-feasible at :data:`gdimitate.walker.WALK_RATE` and walks in
#: MuJoCo (20/20 steps, push within 4.9° of the measured one on every step).
WALK_IMITATOR = DEFAULT_IMITATOR


def default_demonstration():
    """The default story's demonstration → ``(robot, motion, forces)``: one stride (heel
    strike to heel strike of the right foot) of the shipped real 3-D walk (OpenSim subject01:
    its own model, IK angles, measured ground reaction forces, turned overground); what
    ``gdimitate demo`` adapts, and ``adapt``/``entrain``/``view`` when given no file."""
    from ..io import gait

    robot, walk, forces = gait.human_walk_3d()
    motion, forces = gait.one_stride(walk, forces)
    return robot, motion, forces


def _table(rows: list[tuple[str, str]]) -> str:
    w = max(len(k) for k, _ in rows)
    return "\n".join(f"  {k:<{w}}  {v}" for k, v in rows)


def _write_html(path: Path, demo_robot: Robot, demo: Motion, imit: Robot, sim, L: float) -> str:
    """Demonstrator (a translucent ghost scaled to the imitator), plan and simulation."""
    from ..sim.animation import show_simulation
    from ..viz import Viewer

    v = Viewer.start(quiet=True)
    try:
        show_simulation(imit, sim, viewer=v, gap=1.5 * L)
        v.show(demo_robot, demo, name="demonstrator", scale=L / demo_robot.legs["left"].length,
               offset=(0.0, -3.0 * L, 0.0), color=(0.85, 0.65, 0.45), opacity=0.4,
               foot_paths=False, label=f"demonstrator ({demo_robot.name}, scaled to "
                                       f"{imit.name}'s legs, translucent)")
        v.animate(fps=30)
        v.save_html(path, title=f"gdimitate demo: {demo_robot.name} → {imit.name}")
    finally:
        v.close()
    return str(path)


def run_demo(out: str | Path = "gdimitate-demo", imitator: str | Robot = DEFAULT_IMITATOR,
             method: AdaptMethod = "optimal", log=print, rate: float = DEMO_RATE
             ) -> dict[str, Any]:
    """Run the main job and write its files into ``out``; return the summary dict.

    ``imitator``: a library name or a :class:`Robot` (``"hoap2"`` for the planar HOAP-2-sized
    model); ``method``: the adaptor whose result is simulated, entrained and shown (default
    the whole-body optimal adaptor); ``rate`` [knots/s] of the optimal solve."""
    from .. import sim
    from ..adaptation.adaptor import adapt
    from ..assess.verdict import solver_record, verdict
    from ..model.robot import Robot
    from ..oscillator.replay import entrain
    from ..safety import atomic_write, prepare_output_dir
    from .baselines import joint_copy, kinematic_plan

    t0 = time.perf_counter()
    out = prepare_output_dir(out)
    log("[1/7] loading the shipped 3-D walk (OpenSim subject01: model, IK angles, measured "
        "forces) …")
    demo_robot, demo, forces = default_demonstration()
    imit = imitator if isinstance(imitator, Robot) else Robot.load(imitator)
    L = imit.legs["left"].length
    log(f"[2/7] adapting one stride ({demo.t[0]:.2f}–{demo.t[-1]:.2f} s) → {imit.name} "
        f"(leg {L:.3f} m), method={method}, keeping the measured push directions …")
    opts = dict(force="measured", forces=forces, rate=rate, verbose=False) \
        if method == "optimal" else {}
    adapted = adapt(demo, demo_robot, imit, method, **opts)
    log("[3/7] physics check: MuJoCo + whole-body QP tracking controller …")
    # a kinematic method's motion has no wrenches: simulate it with those it asks of the floor
    plan = adapted if adapted.wrenches is not None else kinematic_plan(
        imit, adapted.motion, method, 0.0)
    plan_sim = sim.simulate(imit, plan, demo_forces=forces)
    copy_sim = None
    if imit.base == "free":
        log("       … and the 3-D joint-angle copy as the negative control …")
        copy_sim = sim.simulate(imit, joint_copy(demo, demo_robot, imit), demo_forces=forces)
    log("[4/7] entraining a Matsuoka network to the adapted motion, replaying it …")
    # the clip is one stride (heel strike to heel strike): its span is the period to learn
    stride = float(adapted.motion.t[-1] - adapted.motion.t[0])
    cpg = entrain(imit, adapted.motion, duration=3 * stride, frequency=1.0 / stride)
    log("[5/7] writing motions and plots …")
    _write_files(out, demo_robot, demo, forces, imit, adapted, plan_sim, cpg)
    log("[6/7] writing demo.html (meshcat: demonstrator, plan, simulation) …")
    html = _write_html(out / "demo.html", demo_robot, demo, imit, plan_sim, L)
    aud = adapted.audit
    summary: dict[str, Any] = {
        "demonstration": "OpenSim subject01 walk (shipped), one right stride",
        "demonstrator": demo_robot.name, "imitator": imit.name, "method": method,
        "frames": demo.T, "duration_s": float(demo.t[-1] - demo.t[0]),
        "knots": adapted.motion.T,
        "audit": aud.to_dict() if aud is not None else None,
        "feasible": bool(adapted.feasible),
        "verdict": verdict(adapted).to_dict(),
        "solver": solver_record(adapted.solver),
        "gait": adapted.gait.to_dict() if adapted.gait is not None else None,
        "simulation": plan_sim.metrics.to_dict(),
        "joint_copy_simulation": copy_sim.metrics.to_dict() if copy_sim else None,
        "cpg": {"learned_frequency_hz": float(cpg.result.frequency),
                "signals": list(cpg.names),
                "nrmse_entrained_max": max(v["nrmse_entrained"] for v in cpg.report.values()),
                "freq_error_after_max": max(v["freq_error_after"] for v in cpg.report.values())},
        "html": html,
    }
    summary["elapsed_s"] = time.perf_counter() - t0
    text = json.dumps(summary, indent=2, default=_json)
    with atomic_write(out / "summary.json") as tmp:
        tmp.write_text(text)
    log("[7/7] done.\n")
    log(summary_table(json.loads(text), out))  # the console prints the file's numbers
    return summary


def _write_files(out: Path, demo_robot: Robot, demo: Motion, forces, imit: Robot, adapted,
                 plan_sim, cpg) -> None:
    """The adapted motion (NPZ, CSV), the oscillator parameters and replay, the push
    directions (demonstrator measured vs plan), the gait (demonstrator scaled vs imitator) and
    the simulation's summary plot."""
    from ..assess.metrics import force_direction
    from ..safety import atomic_write
    from ..sim import plots as sim_plots
    from .figures import plot_force_directions, plot_gait

    with atomic_write(out / "imitator_motion.npz") as tmp:
        adapted.save(tmp)
    with atomic_write(out / "imitator_motion.csv") as tmp:
        adapted.save(tmp, format="csv")
    with atomic_write(out / "oscillator_params.json") as tmp:
        tmp.write_text(cpg.result.to_json())
    with atomic_write(out / "cpg_replay_joints.csv") as tmp:
        cpg.replay.to_csv(tmp)
    dirs = {"demonstrator (measured)": force_direction(demo_robot, demo, "measured",
                                                      forces=forces)}
    if adapted.wrenches is not None:
        dirs[f"{imit.name} plan"] = _plan_directions(imit, adapted)
    plot_force_directions(demo.t, dirs, demo.contact, f"push on the ground → {imit.name}",
                          out / "force_directions.png",
                          times={f"{imit.name} plan": adapted.motion.t})
    plot_gait(demo_robot, demo, adapted, out / "gait.png")
    sim_plots.plot_summary(plan_sim, out / "simulation.png")


def _plan_directions(robot: Robot, adapted):
    """The plan's push directions (its contact forces, reversed, in the world frame)."""
    from ..assess.metrics import ForceDirection, frame_rotations

    out = {}
    for s, c in adapted.contacts.items():
        R = frame_rotations(robot, adapted.motion.q, c.frame)
        f = np.einsum("tij,tj->ti", R, adapted.wrenches[s][:, :3])
        out[s] = ForceDirection.from_vectors(-f, adapted.motion.contact[s], "plan")
    return out


def _json(x: object) -> object:
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


def summary_table(summary: dict[str, Any], out: str | Path) -> str:
    """The table ``gdimitate demo`` prints, rendered from its ``summary.json`` alone
    (``summary``: the file's content, ``out`` the output folder as named to the user): every
    number on the console is the file's, formatted here once (issue 34: one number, one
    definition); ``docs/make_readme_output.py`` renders the README's copy with it."""
    return _table(summary_rows(summary, out))


def _num(x: Any) -> float:
    """A number of summary.json (``None``: NaN or infinite in the run) as a float."""
    return float("nan") if x is None else float(x)


def _simline(m: dict[str, Any]) -> str:
    """A simulation's line from its metrics (:meth:`gdimitate.sim.SimMetrics.to_dict`)."""
    fd = m.get("force_vs_demo") or {}
    rm = "/".join(f"{_num(fd[k]['rmse_sagittal_deg']):.1f}" for k in ("left", "right")
                  if k in fd)
    fell = f"FELL at {_num(m['fall_time_s']):.2f} s" if m["fell"] else "walked the stride"
    return f"{fell}; slip {100 * _num(m['slip_max_m']):.1f} cm; push RMSE L/R {rm} deg"


def summary_rows(summary: dict[str, Any], out: str | Path) -> list[tuple[str, str]]:
    """``(label, value)`` rows of :func:`summary_table`."""
    from ..assess.verdict import Verdict, written_gait_lines

    aud = summary.get("audit")
    rows = [("demonstration", f"{summary['frames']} frames, {_num(summary['duration_s']):.2f} s "
                              "(one stride of the 3-D walk)"),
            ("imitator", f"{summary['imitator']} ({summary['knots']} knots, "
                         f"{summary['method']})")]
    lines = Verdict.from_dict(summary["verdict"], summary["solver"]).lines()
    rows.append(("verdict", lines[0]))
    rows += [("", line) for line in lines[1:]]
    if aud is not None:
        ratios = [_num(j["torque_ratio"]) for j in aud["joints"]]
        worst_tau = max((r for r in ratios if np.isfinite(r)), default=float("nan"))
        rows += [("  worst |torque|/limit", f"{worst_tau:.2f}"),
                 ("  min normal force [N]", ", ".join(
                     f"{s} {_num(f['normal']['value']):.0f}" for s, f in aud["feet"].items()))]
    g = written_gait_lines(summary)
    if g:
        rows += [("gait", g[0].removeprefix("gait "))] + [("", line) for line in g[1:]]
    rows.append(("simulation, plan", _simline(summary["simulation"])))
    if summary.get("joint_copy_simulation") is not None:
        rows.append(("simulation, joint copy", _simline(summary["joint_copy_simulation"])))
    cpg = summary["cpg"]
    rows += [("CPG frequency", f"{_num(cpg['learned_frequency_hz']):.3f} Hz, tracking nRMSE "
                               f"max {100 * _num(cpg['nrmse_entrained_max']):.1f} %"),
             ("output", f"{out}/ (demo.html, summary.json, imitator_motion.npz/.csv, *.png)"),
             ("elapsed", f"{_num(summary['elapsed_s']):.1f} s")]
    return rows
