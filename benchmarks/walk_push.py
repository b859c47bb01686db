"""Push experiment of the walk (docs/design.md §14): what does the ground's feedback into the
oscillator network buy?

For each robot: its periodic cycle from the shipped 3-D walk (cached under --cache, not in
the package: a G1 cycle takes minutes), one tuned network, then walks of --steps steps with a
horizontal push of 0.1 s on the base at mid-stance (forward: +x; sideways: +y, 3-D robots
only — the planar model has no lateral freedom), magnitudes as fractions of m·g, feedback
gain 0 (open loop) and > 0, repeated trials (the push at mid-stance of different steps).
Same-run baseline: the unpushed walk at each gain. Reports, per (robot, direction, gain),
the largest push every trial survived and the steps the body's rhythm needed to come back
(:meth:`gdimitate.walker.WalkResult.steps_to_rhythm`: heel-strike intervals back within 5 %
of the period of the unpushed walk's), as a Markdown table (stdout and --md).

    python benchmarks/walk_push.py                       # HOAP-2, forward, quick
    python benchmarks/walk_push.py --robots hoap2 g1 --md benchmarks/walk_push.md
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from results import add_flag, recording

from gdimitate.model.contact import SoleContact
from gdimitate.model.motion import Motion
from gdimitate.model.robot import SIDES, Robot


def save_cycle(path: Path, cyc, name: str) -> None:
    m = cyc.motion
    np.savez(path, t=m.t, q=m.q, v=m.v, a=m.a, joint_names=np.array(m.joint_names),
             base_nq=m.base_nq, joint_nq=np.array(m.joint_nq),
             **{f"contact_{s}": m.contact[s] for s in SIDES},
             **{f"w_{s}": cyc.wrenches[s] for s in SIDES},
             contacts=json.dumps({s: cyc.contacts[s].__dict__ for s in SIDES}),
             feasible=bool(cyc.feasible), robot=name)


def load_cycle(path: Path):
    d = np.load(path, allow_pickle=False)
    robot = Robot.load(str(d["robot"]))
    m = Motion(t=d["t"], joint_names=tuple(d["joint_names"]), q=d["q"], v=d["v"], a=d["a"],
               contact={s: d[f"contact_{s}"] for s in SIDES}, base_nq=int(d["base_nq"]),
               joint_nq=tuple(int(x) for x in d["joint_nq"]))
    cs = {s: SoleContact(**v) for s, v in json.loads(str(d["contacts"])).items()}
    return SimpleNamespace(robot=robot, motion=m, wrenches={s: d[f"w_{s}"] for s in SIDES},
                           contacts=cs, feasible=bool(d["feasible"]))


def cycle_of(name: str, cache: Path, given: dict[str, Path] | None = None):
    from gdimitate.walker import periodic_cycle

    if given and name in given:  # a cycle saved by save_cycle (e.g. adapted elsewhere)
        return load_cycle(given[name])
    path = cache / f"cycle_{name}.npz"
    if not path.exists():
        t = time.perf_counter()
        cyc, _ = periodic_cycle(imitator=name)
        print(f"{name}: periodic cycle in {time.perf_counter() - t:.0f} s, audit "
              f"{'feasible' if cyc.feasible else 'NOT feasible'}", flush=True)
        save_cycle(path, cyc, name)
    return load_cycle(path)


def run(name: str, args, forces) -> list[dict]:
    from gdimitate.walker import WalkNetwork, WalkPush, walk

    cyc = cycle_of(name, args.cache, dict(args.cycle))
    net = WalkNetwork.tune(cyc.robot, cyc.motion)
    mg = cyc.robot.mass * 9.81
    dirs = {"forward": (1.0, 0.0, 0.0)}
    if cyc.robot.base == "free":
        dirs["sideways"] = (0.0, 1.0, 0.0)
    rows = []
    for gain in args.gains:
        if args.nominal_steps:
            rows.append(nominal(name, cyc, forces, net, gain, args.nominal_steps))
        base = walk(cycle=cyc, forces=forces, steps=args.steps, network=net, feedback_gain=gain)
        rows.append(dict(robot=name, direction="none", gain=gain, push=0.0, trial=0,
                         survived=not base.fell, steps=base.steps_completed, rhythm=None))
        print(f"{name} gain {gain}: unpushed {base.steps_completed} steps, fell {base.fell}",
              flush=True)
        for dname, d in dirs.items():
            for frac in args.magnitudes:
                for trial in range(args.trials):
                    push = WalkPush(step=2 + trial, force=tuple(frac * mg * np.array(d)))
                    r = walk(cycle=cyc, forces=forces, steps=args.steps, network=net,
                             feedback_gain=gain, push=push)
                    rows.append(dict(robot=name, direction=dname, gain=gain, push=frac,
                                     trial=trial, survived=not r.fell,
                                     steps=r.steps_completed, rhythm=r.steps_to_rhythm(base)))
                    print(f"  {dname} {frac:.2f} m·g trial {trial}: "
                          f"{'survived' if not r.fell else 'FELL'}, steps "
                          f"{r.steps_completed}, rhythm back after {r.steps_to_rhythm(base)}",
                          flush=True)
    return rows


def nominal(name: str, cyc, forces, net, gain: float, steps: int) -> dict:
    """The unpushed walk of ``steps`` steps: the issue's criteria (no fall; push RMS vs
    measured per step ≤ 5°; the network's frequency within 1 % of the cycle's)."""
    from gdimitate.walker import walk

    t = time.process_time()
    d = walk(cycle=cyc, forces=forces, steps=steps, network=net, feedback_gain=gain).to_dict()
    rm = [x for x in d["per_step_force_direction_rmse_deg"] if x is not None]
    row = dict(robot=name, direction="nominal", gain=gain, steps=d["steps_completed"],
               requested=steps, fell=d["fell"], rmse_min=min(rm), rmse_max=max(rm),
               over5=sum(x > 5.0 for x in rm), f=d["frequency_hz"],
               f_cycle=d["cycle_frequency_hz"],
               f_step_max=d["frequency_error_max"], rmse=rm, cpu_s=time.process_time() - t)
    print(f"{name} gain {gain:g}, {steps} steps unpushed: {row['steps']} steps, "
          f"fell {row['fell']}; "
          f"push RMS vs measured per step {row['rmse_min']:.2f}–{row['rmse_max']:.2f}° "
          f"({row['over5']} > 5°): {', '.join(f'{x:.2f}' for x in rm)}; frequency "
          f"{row['f']:.4f} Hz vs {row['f_cycle']:.4f} ({row['f'] / row['f_cycle'] - 1:+.2%}), "
          f"each step within {row['f_step_max']:.2%} ({row['cpu_s']:.0f} s CPU)", flush=True)
    return row


def nominal_table(rows: list[dict]) -> str:
    out = ["| robot | feedback gain | steps | fell | push RMS vs measured per step | "
           "frequency vs cycle's | largest per-step frequency error |",
           "|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["direction"] != "nominal":
            continue
        out.append(f"| {r['robot']} | {r['gain']:g} | {r['steps']}/{r['requested']} | "
                   f"{'yes' if r['fell'] else 'no'} | {r['rmse_min']:.1f}–{r['rmse_max']:.1f}° "
                   f"({r['over5']} of {len(r['rmse'])} > 5°) | {r['f']:.4f} Hz vs "
                   f"{r['f_cycle']:.4f} "
                   f"({r['f'] / r['f_cycle'] - 1:+.2%}) | {r['f_step_max']:.2%} |")
    return "\n".join(out)


def table(rows: list[dict]) -> str:
    out = ["| robot | push | feedback gain | largest push survived (all trials) [m·g, 0.1 s] "
           "| steps to rhythm at that push (per trial) | unpushed walk |",
           "|---|---|---|---|---|---|"]
    keys = sorted({(r["robot"], r["direction"], r["gain"]) for r in rows
                   if r["direction"] not in ("none", "nominal")})
    for robot, d, g in keys:
        mine = [r for r in rows if (r["robot"], r["direction"], r["gain"]) == (robot, d, g)]
        ok = sorted({r["push"] for r in mine
                     if all(x["survived"] for x in mine if x["push"] == r["push"])})
        best = ok[-1] if ok else None
        rh = [x["rhythm"] for x in mine if x["push"] == best] if best is not None else []
        base = [r for r in rows if (r["robot"], r["direction"], r["gain"]) == (robot, "none", g)]
        bs = f"{base[0]['steps']} steps, {'no fall' if base[0]['survived'] else 'FELL'}" \
            if base else "–"
        out.append(f"| {robot} | {d} | {g:g} | {best if best is not None else 'none'} | "
                   f"{', '.join('–' if x is None else str(x) for x in rh) or '–'} | {bs} |")
    return "\n".join(out)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robots", nargs="+", default=["hoap2"])
    p.add_argument("--magnitudes", nargs="+", type=float, default=[0.1, 0.2, 0.4])
    p.add_argument("--gains", nargs="+", type=float, default=[0.0, 0.5])
    p.add_argument("--trials", type=int, default=2)
    p.add_argument("--steps", type=int, default=8)
    p.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "gdimitate" / "walk_push")
    p.add_argument("--nominal-steps", type=int, default=0,
                   help="also walk this many steps unpushed at each gain (the issue's criteria)")
    p.add_argument("--md", type=Path, default=None, help="also write the table there")
    p.add_argument("--cycle", nargs="*", default=[], metavar="ROBOT=NPZ",
                   type=lambda x: (x.split("=", 1)[0], Path(x.split("=", 1)[1])),
                   help="use this saved cycle (save_cycle's .npz) for ROBOT")
    add_flag(p)
    args = p.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    warnings.simplefilter("ignore")
    from gdimitate.apps.demo import default_demonstration

    _, _, forces = default_demonstration()
    t0 = time.perf_counter()
    rows = []
    for name in args.robots:
        rows += run(name, args, forces)
    md = nominal_table(rows) + "\n\n" + table(rows)
    print(md)
    print(f"({time.perf_counter() - t0:.0f} s)")
    if args.md:
        args.md.write_text(md + "\n")
    (args.cache / "walk_push_rows.json").write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    with recording("walk_push", "--results" in sys.argv[1:]):
        main()
