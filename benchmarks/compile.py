"""The first run's compilation against the solve's speed (issue 37): each robot's per-knot
derivatives compiled with other C compiler flags than ``codegen.CFLAGS``, in a cache of their
own, against the shipped flags in the same run.

Run: ``python benchmarks/compile.py [--robots g1] [--flags=-O0;-Og] [--repeats 3]
[--results]``.

Each row is one robot and one set of flags (the first set, the shipped ``CFLAGS``' level, is
the baseline), in a fresh Python process with an empty ``$GDIMITATE_CACHE_DIR``: one right
stride of the shipped 3-D walk adapted with measured forces (``gd.adapt``, the demo's case)
once — its wall time includes compiling the derivatives, announced on stderr — then
``--repeats`` more times; the CPU seconds of those later calls (their median) are the solve's
speed with that code. The audit's verdict of the last call is printed: flags change how fast
the same expressions are evaluated, not the result.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

from results import add_flag, recording

ROOT = Path(__file__).resolve().parents[1]

_CHILD = textwrap.dedent("""
    import json, statistics, sys, time, warnings
    warnings.simplefilter("ignore")
    import gdimitate.retarget.trajectory.codegen as cg
    flags, name, repeats = sys.argv[1], sys.argv[2], int(sys.argv[3])
    cg.CFLAGS = tuple(flags.split()) + tuple(f for f in cg.CFLAGS if not f.startswith("-O"))
    import gdimitate as gd
    h, demo, fs = gd.gait.human_walk_3d()
    demo, fs = gd.gait.one_stride(demo, fs)
    robot = gd.Robot.from_library(name)
    t0 = time.perf_counter()
    r = gd.adapt(demo, h, robot, method="optimal", force="measured", forces=fs)
    first = time.perf_counter() - t0
    cpu = []
    for _ in range(repeats):
        c0 = time.process_time()
        r = gd.adapt(demo, h, robot, method="optimal", force="measured", forces=fs)
        cpu.append(time.process_time() - c0)
    print("RESULT " + json.dumps({"first_s": first, "cpu_s": statistics.median(cpu),
                                  "compiled": cg.COMPILE_COUNT, "iterations":
                                  r.solver.iterations, "feasible": bool(r.audit.feasible)}))
""")


def run(flags: str, robot: str, repeats: int) -> dict:
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "GDIMITATE_CACHE_DIR": cache, "OMP_NUM_THREADS": "1",
               "GDIMITATE_COMPILE": "wait"}  # the compilation timed before the solve
        p = subprocess.run([sys.executable, "-c", _CHILD, flags, robot, str(repeats)],
                           cwd=ROOT, env=env, capture_output=True, text=True, timeout=3600)
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"error": (p.stderr.strip().splitlines() or ["no output"])[-1][:100]}


def main() -> None:
    sys.path.insert(0, str(ROOT))
    from gdimitate.retarget.trajectory.codegen import CFLAGS

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robots", default="g1")
    ap.add_argument("--flags", default="-O0", help="';'-separated sets of flags to compare "
                    "with the shipped optimisation level")
    ap.add_argument("--repeats", type=int, default=3)
    add_flag(ap)
    a = ap.parse_args()
    base = " ".join(f for f in CFLAGS if f.startswith("-O"))
    sets = [base] + [f.strip() for f in a.flags.split(";") if f.strip() and f.strip() != base]
    print("| robot | flags | first call [s wall, compiling] | later calls [s CPU, median] | "
          "ratio to the shipped flags | iterations | audit |")
    print("|---|---|---|---|---|---|---|")
    for robot in a.robots.split(","):
        ref = None
        for flags in sets:
            r = run(flags, robot, a.repeats)
            if "error" in r:
                print(f"| {robot} | `{flags}` | error: {r['error']} |||||", flush=True)
                continue
            ref = r["cpu_s"] if ref is None else ref
            print(f"| {robot} | `{flags}`{' (shipped)' if flags == base else ''} | "
                  f"{r['first_s']:.0f} | {r['cpu_s']:.2f} | {r['cpu_s'] / ref:.2f} | "
                  f"{r['iterations']} | {'feasible' if r['feasible'] else 'NOT feasible'} |",
                  flush=True)


if __name__ == "__main__":
    with recording("compile", "--results" in sys.argv[1:]):
        main()
