"""``gdimitate paper``: the paper's Figs. 4–13 (in spirit) and a numeric summary per case."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..adaptation.adaptor import adapt
from ..assess.metrics import sole_paths
from ..model.motion import Motion
from ..model.robot import SIDES, Robot
from ..model.sagittal import leg_angles
from ..planar import eq1
from . import figures as plots
from .cases import PAPER_CASES, paper_case

__all__ = ["step_length", "case_summary", "run_paper"]


def step_length(robot: Robot, motion: Motion) -> float:
    """Mean distance [m] between successive footholds (sole x at each touch-down, both feet)."""
    soles = sole_paths(robot, motion)
    events = []
    for s in SIDES:
        c = motion.contact[s].astype(int)
        for i in np.flatnonzero(np.diff(c) == 1) + 1:
            events.append((motion.t[i], soles[s][i, 0]))
    events.sort()
    if len(events) < 2:
        return float("nan")
    return float(np.mean(np.diff([x for _, x in events])))


def case_summary(name: str) -> tuple[dict[str, Any], dict]:
    """Numbers of one paper case and the objects behind them."""
    demo, imit, motion = paper_case(name)
    with_a = adapt(motion, demo, imit, "analytic")
    without = adapt(motion, demo, imit, "copy")
    with_com = adapt(motion, demo, imit, "analytic", force="com")
    without_com = adapt(motion, demo, imit, "copy", force="com")
    Lm, Lr = demo.legs["left"].length, imit.legs["left"].length
    n_inf = sum(with_a.report.infeasible_frames.values())
    summary = {
        "demonstrator": {"name": demo.name, "thigh_m": demo.legs["left"].thigh,
                         "shank_m": demo.legs["left"].shank},
        "imitator": {"name": imit.name, "thigh_m": imit.legs["left"].thigh,
                     "shank_m": imit.legs["left"].shank},
        "frames": motion.T,
        "infeasible_fraction": n_inf / (2 * motion.T),
        "infeasible_frames": with_a.report.infeasible_frames,
        "shank_direction_error_max": {
            "with_adaptor": with_a.report.force_direction_error_max,
            "without_adaptor": without.report.force_direction_error_max,
        },
        "com_direction_error_max": {
            "with_adaptor": with_com.report.force_direction_error_max,
            "without_adaptor": without_com.report.force_direction_error_max,
        },
        "hip_height_ratio_error_max": {
            "with_adaptor": with_a.report.hip_height_ratio_error_max,
            "without_adaptor": without.report.hip_height_ratio_error_max,
        },
        "step_length_over_leg_length": {
            "demonstrator": step_length(demo, motion) / Lm,
            "imitator_with_adaptor": step_length(imit, with_a.motion) / Lr,
            "imitator_without_adaptor": step_length(imit, without.motion) / Lr,
        },
    }
    return summary, {"demo": demo, "imit": imit, "motion": motion, "with": with_a,
                     "without": without}


def run_paper(out: str | Path, log=print) -> dict[str, Any]:
    """Write the figures (PNG) and ``summary.json`` for the three cases into ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    summary = {}
    for name in PAPER_CASES:
        log(f"case {name}: adapting and plotting …")
        s, o = case_summary(name)
        summary[name] = s
        tracks = [("demonstrator", o["demo"], o["motion"]),
                  ("imitator, with adaptor (Eq. 1)", o["imit"], o["with"].motion),
                  ("imitator, without adaptor (copy)", o["imit"], o["without"].motion)]
        title = (f"Case {name}: demonstrator {s['demonstrator']['thigh_m'] * 100:g}/"
                 f"{s['demonstrator']['shank_m'] * 100:g} cm → imitator "
                 f"{s['imitator']['thigh_m'] * 100:g}/{s['imitator']['shank_m'] * 100:g} cm")
        plots.plot_heights(tracks, title, out / f"case_{name}_heights.png")
        plots.plot_angles(tracks, title, out / f"case_{name}_angles.png")
        plots.plot_paths(tracks, title, out / f"case_{name}_paths.png")
        plots.plot_com(tracks, title, out / f"case_{name}_com.png")
        _, ang = leg_angles(o["demo"], o["motion"].q)
        dl, il = o["demo"].legs["left"], o["imit"].legs["left"]
        args: dict[str, np.ndarray] = {sd: eq1(ang[sd][:, 0], ang[sd][:, 1], (dl.thigh, dl.shank),
                        (il.thigh, il.shank)).argument for sd in SIDES}
        plots.plot_eq1_argument(o["motion"].t, args, title, out / f"case_{name}_eq1_argument.png")
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    log(f"wrote {out / 'summary.json'} and {len(list(out.glob('*.png')))} figures")
    return summary
