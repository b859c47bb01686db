"""Whole-body optimal adaptor: speed, iterations, memory and the audit (issues 9, 17).

Run: ``python benchmarks/adaptor.py [--knots 100] [--robots talos,g1,icub,romeo]
[--baseline-rev 7b16d65] [--baseline talos] [--cases hoap2,cmu,clip] [--structured]``.

Each row runs in its own Python process (so that "fresh process" includes loading the compiled
derivatives and peak memory is that process's). Humanoid rows: one gait cycle of the shipped
real 3-D walk (left heel strike to the next), resampled to ``--knots`` knots, whole body,
``force="measured"``, called twice (fresh process: from the process's start to the first
call's answer; then the second call in that process).
Talos also runs twice with an empty cache folder (``GDIMITATE_CACHE_DIR`` set to a temporary
folder): the very first time on a fresh install, by default (``GDIMITATE_COMPILE=background``:
uncompiled while the compiler works in the background) and compiling first (``wait``); every
other row compiles first where its cache misses. The
same-run baseline is the adaptor of ``--baseline-rev`` (a git revision of this repository —
by default the one before issue 17 — extracted with ``git archive`` into a temporary folder and
run the same way) on the ``--baseline`` robots. Further cases: the sagittal walk → HOAP-2 (the
CLI's ``gdimitate adapt`` of the shipped sagittal walk), the CMU BVH clip → G1 (``gdimitate
adapt gdimitate/data/gait/cmu_02_01/cmu_02_01.bvh --imitator g1``: ``force="segment"``, the
default rate), the whole 3.5-s clip → G1 (the README's API snippet), the planar Case II.

``--structured`` adds a table: for each robot row, IPOPT's hard solve and CasADi's fatrop
(:mod:`gdimitate.retarget.trajectory.structured`, the same problem stage by stage) in one
process — CPU time, iterations, time per iteration and where it goes, the cost, the audit of
each result (docs/design.md §6, "what was tried for speed").
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from results import add_flag, recording
from revision import checkout

ROOT = Path(__file__).resolve().parents[1]

_CHILD = textwrap.dedent("""
    import json, resource, sys, time, warnings
    import numpy as np
    warnings.simplefilter("ignore")
    t_import = time.perf_counter()
    import gdimitate as gd
    case, N = sys.argv[1], int(sys.argv[2])
    if case == "hoap2":
        from gdimitate.io.gait import human_walk
        h, demo = human_walk(); fs = None; robot = gd.Robot.from_library("hoap2")
        kw = dict(force="segment")
    elif case == "cmu":
        from gdimitate.io.demonstration import load_demonstration
        d = load_demonstration("gdimitate/data/gait/cmu_02_01/cmu_02_01.bvh")
        h, demo, fs = d.robot, d.motion, d.forces
        robot = gd.Robot.from_library("g1")
        kw = dict(force="segment", **({"forces": fs} if fs is not None else {}))
    elif case == "clip":
        h, demo, fs = gd.gait.human_walk_3d(); robot = gd.Robot.from_library("g1")
        kw = dict(force="measured", forces=fs)
    else:
        h, m, f = gd.gait.human_walk_3d()
        demo, fs = gd.gait.one_stride(m, f, "left")
        rate = (N - 1) / (demo.t[-1] - demo.t[0]) * (1 + 1e-9)
        robot = gd.Robot.from_library(case)
        kw = dict(force="measured", forces=fs, rate=rate)
    out = {}
    calls = ("fresh", "second") if sys.argv[3] == "2" else ("fresh",)
    for label in calls:
        t0, c0 = time.perf_counter(), time.process_time()
        r = gd.adapt(demo, h, robot, method="optimal", verbose=False, **kw)
        out[label] = time.perf_counter() - t0
        out[label + "_cpu"] = time.process_time() - c0
        out[label + "_iterations"] = r.solver.iterations
        out[label + "_status"] = r.solver.status
        out.setdefault("first_done", time.time())  # the fresh process: spawn to first answer
    out["import_s"] = t0 - t_import if len(calls) == 1 else None
    out["knots"] = r.solver.knots
    out["derivatives"] = getattr(r.solver, "derivatives", "C")  # a baseline tree: none
    out["feasible"] = bool(r.audit.feasible)
    out["binding"] = list(r.audit.binding[:3])
    out["unmet"] = [u.name for u in r.solver.unmet[:3]]
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print("RESULT " + json.dumps(out))
""")


_STRUCTURED = textwrap.dedent("""
    import copy, json, sys, time, warnings
    import numpy as np
    warnings.simplefilter("ignore")
    import gdimitate as gd
    from gdimitate.retarget.trajectory import solve as S, structured as SS
    case, N = sys.argv[1], int(sys.argv[2])
    got = {}
    budgeted, package = S.solve_budgeted, S.package
    def spy(c, num, *a, **k):  # the hard solve's problem, as IPOPT gets it
        got["c"], got["num"] = c, copy.deepcopy(num)
        out = budgeted(c, num, *a, **k)
        got["z"] = out[1]
        return out
    def spy_package(*a, **k):
        got["package"] = a
        return package(*a, **k)
    S.solve_budgeted, S.package = spy, spy_package
    h, m, f = gd.gait.human_walk_3d()
    demo, fs = gd.gait.one_stride(m, f, "left")
    rate = (N - 1) / (demo.t[-1] - demo.t[0]) * (1 + 1e-9)
    robot = gd.Robot.from_library(case)
    for _ in range(2):  # the second call: IPOPT's problem built and its derivatives loaded
        c0 = time.process_time()
        r = gd.adapt(demo, h, robot, method="optimal", verbose=False, force="measured",
                     forces=fs, rate=rate)
        ipopt_cpu = time.process_time() - c0
    c, num = got["c"], got["num"]
    SS.stage_functions(c.form)  # compiled once per robot (kept on disk), not timed
    opts = {"max_iter": S.MAX_ITERATIONS}
    c0 = time.process_time()
    SS.stages(c.form, c.T, np.not_equal(*SS.hard_problem(c, num)[2:]), num.keep, opts)
    build = time.process_time() - c0
    c0 = time.process_time()
    z, st, stages = SS.hard_solve(c, num, opts)  # the solver just built
    fatrop_cpu = time.process_time() - c0
    T, P = c.T, num.P.copy()
    P[c.knot.par["elastic"]] = S.GOAL_WEIGHT
    kf = c.form.fun["kf"].map(T)
    cost = lambda zz: float(np.sum(kf(zz.reshape(T, -1).T, P))) / T
    out = S.package(c, num, z, *got["package"][3:9], r.solver)
    fs_ = st["fatrop"]
    print("RESULT " + json.dumps({
        "knots": T, "ipopt_cpu": ipopt_cpu, "ipopt_it": r.solver.iterations,
        "ipopt_feasible": bool(r.audit.feasible), "ipopt_cost": cost(got["z"]),
        "fatrop_cpu": fatrop_cpu, "fatrop_build": build,
        "fatrop_it": int(st["iter_count"]), "fatrop_status": int(st["return_status"]),
        "linear_algebra": fs_["compute_sd_time"],
        "derivatives": fs_["eval_hess_time"] + fs_["eval_jac_time"],
        "stage": [int(np.mean(stages.nx)), int(np.mean(stages.nu)), int(np.mean(stages.ng))],
        "fatrop_cost": cost(z), "fatrop_feasible": bool(out.audit.feasible),
        "fatrop_binding": list(out.audit.binding[:3]),
        "fatrop_unmet": [u.name for u in S.unmet(c, num, z, 1e-6)[:3]]}))
""")


def structured_row(name: str, knots: int) -> str:
    """One row of the ``--structured`` table (IPOPT and fatrop on one problem)."""
    p = subprocess.run([sys.executable, "-c", _STRUCTURED, name, str(knots)],
                       capture_output=True, text=True, cwd=str(ROOT),
                       env={**os.environ, "PYTHONPATH": str(ROOT), "GDIMITATE_COMPILE": "wait"})
    r = next((json.loads(ln[7:]) for ln in p.stdout.splitlines() if ln.startswith("RESULT ")),
             None)
    if r is None:
        return f"| {name} | error: {(p.stderr or p.stdout)[-300:]!r} | |"
    ok = {True: "feasible", False: "infeasible"}
    fat = (f"{r['fatrop_cpu']:.1f} s, {r['fatrop_it']} it. (status {r['fatrop_status']}), "
           f"{r['fatrop_cpu'] / max(r['fatrop_it'], 1):.2f} s/it. (linear algebra "
           f"{r['linear_algebra'] / max(r['fatrop_it'], 1):.3f}, derivatives "
           f"{r['derivatives'] / max(r['fatrop_it'], 1):.3f}); stages nx/nu/ng ≈ "
           f"{'/'.join(map(str, r['stage']))}; built in {r['fatrop_build']:.0f} s; cost "
           f"{r['fatrop_cost'] / r['ipopt_cost']:.4f}× IPOPT's; audit "
           f"{ok[r['fatrop_feasible']]}"
           + (f"; unmet rows: {', '.join(r['fatrop_unmet'])}" if r["fatrop_unmet"] else ""))
    return (f"| 3-D walk → {name}, {r['knots']} knots | {r['ipopt_cpu']:.1f} s, "
            f"{r['ipopt_it']} it., {r['ipopt_cpu'] / r['ipopt_it']:.3f} s/it.; audit "
            f"{ok[r['ipopt_feasible']]} | {fat} |")


def child(root: Path, case: str, knots: int, calls: int = 2, cache: str | None = None,
          mode: str = "wait") -> dict:
    """One case in a process of its own; ``cache``: its compile cache folder (else the
    user's); ``mode``: ``GDIMITATE_COMPILE`` (``wait`` unless the first run's default is
    measured: a row times the compiled derivatives)."""
    env = {**os.environ, "PYTHONPATH": str(root), "GDIMITATE_COMPILE": mode}
    if cache:
        env["GDIMITATE_CACHE_DIR"] = cache
    t0, spawn = time.perf_counter(), time.time()
    p = subprocess.run([sys.executable, "-c", _CHILD, case, str(knots), str(calls)],
                       capture_output=True, text=True, env=env, cwd=str(root))
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            out = json.loads(line[7:])
            out["process_s"] = time.perf_counter() - t0
            out["fresh_process_s"] = out.get("first_done", spawn) - spawn
            return out
    return {"error": (p.stderr or p.stdout)[-400:]}



def _first_time(name: str, knots: int, mode: str) -> str:
    """The first call on an empty cache, ``mode`` ``background`` (the default: uncompiled
    while the compiler works in the background) or ``wait`` (compiled first): the process's
    seconds and what evaluated the derivatives. The background build is let finish before
    its folder goes (it would otherwise compile beside the next rows)."""
    import fcntl

    with tempfile.TemporaryDirectory() as cache:
        f = child(ROOT, name, knots, 1, cache, mode)
        for lock in Path(cache).glob("*.lock"):
            with open(lock, "a") as fh:
                fcntl.flock(fh, fcntl.LOCK_EX)
    if "error" in f:
        return f"error {f['error']!r}"
    return f"{f['process_s']:.0f} s ({mode}: {f['derivatives']})"


def _audit(r: dict) -> str:
    s = "feasible" if r["feasible"] else "infeasible: " + ", ".join(r["binding"])
    if r.get("unmet"):
        s += "; unmet: " + ", ".join(r["unmet"])
    return s


def planar_case2() -> dict:
    from gdimitate.adaptation.adaptor import adapt
    from gdimitate.apps.cases import paper_case

    d, i, m = paper_case("II")
    rate = 99 / (m.t[-1] - m.t[0]) * (1 + 1e-9)
    out = {}
    for label in ("first", "cached"):
        t0 = time.perf_counter()
        r = adapt(m, d, i, method="optimal", rate=rate, verbose=False)
        out[label] = time.perf_counter() - t0
    out["feasible"] = bool(r.audit.feasible)
    out["knots"] = r.solver.knots
    out["derivatives"] = getattr(r.solver, "derivatives", "C")  # a baseline tree: none
    return out


class _Rows(list):
    """The table, each row printed as soon as it is measured."""

    def __init__(self, head: list[str]):
        super().__init__(head)
        print("\n".join(head), flush=True)

    def append(self, row: str) -> None:
        super().append(row)
        print(row, flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--knots", type=int, default=100)
    ap.add_argument("--robots", default="talos,g1,icub,romeo")
    ap.add_argument("--baseline-rev", default="7b16d65")
    ap.add_argument("--baseline", default="talos",
                    help="robots and cases also adapted by --baseline-rev (comma-separated, "
                         "or '')")
    ap.add_argument("--cases", default="hoap2,cmu,clip")
    ap.add_argument("--no-first", action="store_true",
                    help="skip Talos's first-time-ever run (an empty cache: its compilation)")
    ap.add_argument("--structured", action="store_true",
                    help="also solve each robot row's problem with CasADi's fatrop, stage by "
                         "stage, beside IPOPT in one process (a table of its own)")
    add_flag(ap)
    a = ap.parse_args()
    rows = _Rows(["| case | goal | first time ever | fresh process | second call | iterations "
                  "| peak memory | audit | same-run baseline (second call, CPU, iterations) |",
                  "|---|---|---|---|---|---|---|---|---|"])
    base_tree = None
    tmp = tempfile.TemporaryDirectory()
    if a.baseline_rev and a.baseline:
        base_tree = checkout(a.baseline_rev, tmp.name)
    for name in [n for n in a.robots.split(",") if n]:
        first = ""
        if name == "talos" and not a.no_first:
            first = " / ".join(_first_time(name, a.knots, m) for m in ("background", "wait"))
        r = child(ROOT, name, a.knots)
        if "error" in r:
            rows.append(f"| {name} | | error: {r['error']!r} | | | | | | |")
            continue
        base = ""
        if base_tree is not None and name in a.baseline.split(","):
            b = child(base_tree, name, a.knots)
            base = (f"error: {b['error']!r}" if "error" in b else
                    f"{b['second']:.1f} s, CPU {b['second_cpu']:.1f} s "
                    f"({b['second_iterations']} it., {b['peak_mb']:.0f} MB, {_audit(b)}); "
                    f"CPU ratio {r['second_cpu'] / b['second_cpu']:.2f}")
        goal = "≤ 3 min / ≤ 30 s / ≤ 10 s" if name == "talos" else "≤ 15 s second call"
        rows.append(f"| 3-D walk → {name}, {r['knots']} knots | {goal}, ≤ 150 it., ≤ 2 GB | "
                    f"{first} | {r['fresh_process_s']:.1f} s (adapt CPU {r['fresh_cpu']:.1f} s) | "
                    f"{r['second']:.1f} s "
                    f"(CPU {r['second_cpu']:.1f} s) | "
                    f"{r['second_iterations']} | {r['peak_mb']:.0f} MB | {_audit(r)} | {base} |")
    labels = {"hoap2": ("sagittal walk → HOAP-2 (CLI)", "≤ 10 s"),
              "cmu": ("CMU BVH → G1 (CLI)", "≤ 60 s"),
              "clip": ("whole 3.5-s clip → G1 (API snippet)", "≤ 30 s")}
    for case in [c for c in a.cases.split(",") if c]:
        r = child(ROOT, case, 0, 1)
        if "error" in r:
            rows.append(f"| {labels[case][0]} | | error: {r['error']!r} | | | | | | |")
            continue
        base = ""
        if base_tree is not None and case in a.baseline.split(","):
            b = child(base_tree, case, 0, 1)
            base = (f"error: {b['error']!r}" if "error" in b else
                    f"adapt {b['fresh']:.1f} s, CPU {b['fresh_cpu']:.1f} s "
                    f"({b['fresh_iterations']} it., {_audit(b)}); "
                    f"CPU ratio {r['fresh_cpu'] / b['fresh_cpu']:.2f}")
        rows.append(f"| {labels[case][0]}, {r['knots']} knots | {labels[case][1]}, ≤ 150 it. | "
                    f"| {r['process_s']:.1f} s (adapt {r['fresh']:.1f} s, CPU "
                    f"{r['fresh_cpu']:.1f} s) | | "
                    f"{r['fresh_iterations']} | {r['peak_mb']:.0f} MB | {_audit(r)} | {base} |")
    p = planar_case2()
    rows.append(f"| Case II → HOAP-2-sized, {p['knots']} knots | ≤ 1 s second call | "
                f"| {p['first']:.2f} s | {p['cached']:.2f} s | | | "
                f"{'feasible' if p['feasible'] else 'infeasible'} | |")
    tmp.cleanup()
    if a.structured:
        print("\n| case | IPOPT (second call: CPU, iterations, per iteration; audit) | fatrop, "
              "same problem (CPU, iterations, per iteration; result) |\n|---|---|---|",
              flush=True)
        for name in [n for n in a.robots.split(",") if n]:
            print(structured_row(name, a.knots), flush=True)
    print("\nstreaming: python benchmarks/streaming.py")


if __name__ == "__main__":
    with recording("adaptor", "--results" in sys.argv[1:]):
        main()
