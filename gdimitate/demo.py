"""``gdimitate demo``: the main job on the built-in default.

The shipped real human walk (OpenSim subject01) → planar human demonstrator → HOAP-2-sized
imitator through the optimal adaptor (Eq. (1) and joint copying alongside) → a Matsuoka
oscillator network entrained to the imitator's angles, then replaying free after the teaching
input stops → plots, the imitator's and the
replay's joint trajectories (CSV), tuned oscillator parameters and a summary (JSON),
``demo.html`` (meshcat: demonstrator ghost, imitator, CPG replay; plays offline) and a short
table on stdout.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import plots
from .adapt import adapt
from .cpg import entrain
from .gait import human_walk
from .metrics import force_direction, joint_limit_margins, sagittal_angles
from .paper import step_length
from .robot import Robot

__all__ = ["run_demo"]


def _table(rows: list[tuple[str, str]]) -> str:
    w = max(len(k) for k, _ in rows)
    return "\n".join(f"  {k:<{w}}  {v}" for k, v in rows)


def _write_html(path: Path, demo_robot, demo, imit, adapted, cpg) -> str:
    """Demonstrator (a translucent ghost scaled to the imitator), imitator and CPG replay."""
    from .viz import Viewer

    L = imit.legs["left"].length
    v = Viewer.start(quiet=True)
    try:
        v.show(imit, adapted.motion, name="imitator",
               force_directions=sagittal_angles(force_direction(imit, adapted.motion)))
        v.show(demo_robot, demo, name="demonstrator", scale=L / demo_robot.legs["left"].length,
               color=(0.55, 0.75, 1.0), opacity=0.35, foot_paths=False,
               force_directions=sagittal_angles(force_direction(demo_robot, demo)))
        v.show(imit, cpg.replay, name="cpg_replay", offset=(0.0, 2.5 * L, 0.0))
        v.animate(fps=30)
        v.save_html(path)
    finally:
        v.close()
    return str(path)


def run_demo(out: str | Path = "gdimitate-demo", imitator: str | Robot = "hoap2",
             method: str = "optimal", log=print) -> dict[str, Any]:
    """Run the main job and write its files into ``out``; return the summary dict.

    ``method``: the adaptor whose motion is written, entrained and shown (default: the
    optimal adaptor, which respects the imitator's limits); Eq. (1) and joint copying are
    always computed too and compared in the printed table and ``summary.json``."""
    t0 = time.perf_counter()
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / ".write-test").write_text("")
        (out / ".write-test").unlink()
    except OSError as e:
        from .errors import InvalidInputError

        raise InvalidInputError(f"cannot write to output folder {out}: {e}") from None
    log("[1/6] loading the shipped real walk (OpenSim subject01, 60 Hz) …")
    demo_robot, demo = human_walk()
    imit = imitator if isinstance(imitator, Robot) else Robot.load(imitator)
    log(f"[2/6] adapting {demo_robot.name} (leg {demo_robot.legs['left'].length:.3f} m) → "
        f"{imit.name} (leg {imit.legs['left'].length:.3f} m), method={method} …")
    results = {"copy": adapt(demo, demo_robot, imit, "copy"),
               "analytic": adapt(demo, demo_robot, imit, "analytic")}
    if method not in results:
        results[method] = adapt(demo, demo_robot, imit, method)
    adapted = results[method]
    rep = adapted.report
    log("[3/6] writing trajectories and plots …")
    adapted.motion.to_csv(out / "imitator_joints.csv")
    adapted.motion.to_npz(out / "imitator_motion.npz", robot=imit)
    labels = {"optimal": "optimal adaptor", "analytic": "Eq. (1)", "copy": "joint copy"}
    tracks = [("human demonstrator", demo_robot, demo)] + [
        (f"{imit.name}, {labels[m]}", imit, results[m].motion)
        for m in ("optimal", "analytic", "copy") if m in results]
    title = f"real walk → {imit.name}"
    plots.plot_heights(tracks, title, out / "heights.png")
    plots.plot_angles(tracks, title, out / "angles.png")
    plots.plot_paths(tracks, title, out / "paths.png")
    plots.plot_com(tracks, title, out / "com.png")
    margins = joint_limit_margins(imit, adapted.motion)
    summary: dict[str, Any] = {
        "demonstration": "OpenSim subject01 treadmill walk (shipped)",
        "demonstrator": demo_robot.name,
        "imitator": imit.name,
        "method": method,
        "frames": demo.T,
        "duration_s": float(demo.t[-1]),
        "adaptor": {**rep.to_dict(), **({"torque_ratio_max": {
            j.name: j.torque_ratio for j in adapted.audit.joints}, "feasible_physically":
            bool(adapted.audit.feasible)} if adapted.audit is not None else {})},
        "audit": adapted.audit.to_dict() if adapted.audit is not None else None,
        **{f"{m}_baseline": results[m].report.to_dict() for m in results if m != method},
        "joint_limit_margin_min_rad": {j: float(m.min()) for j, m in margins.items()},
        "step_length_over_leg_length": {
            "demonstrator": step_length(demo_robot, demo) / demo_robot.legs["left"].length,
            **{m: step_length(imit, results[m].motion) / imit.legs["left"].length
               for m in results},
        },
    }
    log("[4/6] entraining the Matsuoka network and replaying it free-running …")
    cpg = entrain(imit, adapted.motion)
    (out / "oscillator_params.json").write_text(cpg.result.to_json())
    cpg.replay.to_csv(out / "cpg_replay_joints.csv")
    rep_cpg = cpg.report
    summary["cpg"] = {
        "learned_frequency_hz": float(cpg.result.frequency),
        "joints": list(cpg.names),
        "nrmse_entrained_max": max(v["nrmse_entrained"] for v in rep_cpg.values()),
        "freq_error_after_max": max(v["freq_error_after"] for v in rep_cpg.values()),
        "per_joint": rep_cpg,
    }
    log("[5/6] writing demo.html (meshcat) …")
    summary["html"] = _write_html(out / "demo.html", demo_robot, demo, imit, adapted, cpg)
    summary["elapsed_s"] = time.perf_counter() - t0
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
    log("[6/6] done.\n")
    cols = [m for m in ("optimal", "analytic", "copy") if m in results]
    reps = {m: results[m].report for m in cols}
    def row(label, fn):
        return (label, "  ".join(f"{fn(m):>16}" for m in cols))

    def torque(m):  # the audit's recomputation (optimal method: it has wrenches)
        aud = results[m].audit
        ratios = [j.torque_ratio for j in aud.joints if np.isfinite(j.torque_ratio)] if aud \
            else []
        return f"{max(ratios):.2f}" if ratios else "—"

    def physical(m):
        aud = results[m].audit
        return "—" if aud is None else ("yes" if aud.feasible else
                                        "no: " + ", ".join(aud.binding[:2]))

    hk = [j for j in rep_cpg if j.split("_")[-1] in ("hip", "knee")]
    rows = [
        ("demonstration", f"{demo.T} frames, {demo.t[-1]:.2f} s, human leg "
                          f"{demo_robot.legs['left'].length:.3f} m"),
        ("imitator", f"{imit.name}, leg {imit.legs['left'].length:.3f} m"),
        row("", lambda m: labels[m]),
        row("infeasible frames (L+R)", lambda m: f"{sum(reps[m].infeasible_frames.values())}"
                                                 f" of {2 * demo.T}"),
        row("push-direction error [deg]",
            lambda m: f"{np.degrees(reps[m].force_direction_error_max):.1e}"),
        row("hip-height ratio error", lambda m: f"{reps[m].hip_height_ratio_error_max:.3f}"),
        row("joint-limit excess [deg]",
            lambda m: f"{np.degrees(reps[m].joint_limit_violation_max):.2f}"),
        row("max |torque| / limit", torque),
        row("physically feasible", physical),
        row("ground penetration [mm]", lambda m: f"{reps[m].ground_penetration_max * 1e3:.1f}"),
        ("CPG learned frequency", f"{cpg.result.frequency:.4f} Hz"),
        ("CPG tracking nRMSE max", f"{max(rep_cpg[j]['nrmse_entrained'] for j in hk) * 100:.1f} %"
                                   " hip/knee, "
                                   f"{summary['cpg']['nrmse_entrained_max'] * 100:.1f} % all"),
        ("CPG freq. error after stop", f"{summary['cpg']['freq_error_after_max'] * 100:.2f} %"),
        ("output", f"{out}/ (demo.html, summary.json, *.csv, *.png)"),
        ("elapsed", f"{summary['elapsed_s']:.1f} s"),
    ]
    log(_table(rows))
    return summary
