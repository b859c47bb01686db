"""Whole-body optimal adaptor: speed and memory (issue 9).

Run: ``python benchmarks/adaptor.py [--knots 100] [--robots talos,g1,icub,romeo] [--frames 30]
[--baseline talos]``.
Each humanoid row runs in its own Python process (so that "first call" includes building the
NLP and peak memory is that process's): one gait cycle of the shipped real 3-D walk (left heel
strike to the next), resampled to ``--knots`` knots, whole body, ``force="measured"``; then
the same call again (the cached NLP). The baseline, measured in the same run: the same
problem solved to IPOPT's own convergence test (``stop="converged"``, how the adaptor ended
its solves before the ``"settled"`` rule) on ``--baseline`` robots. Also: the planar
HOAP-2-sized Case II (100 knots, cached) and the streaming mode's frames per second on Talos.
The removed sagittal optimiser's figures are quoted beside them.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import textwrap
import time

QUOTED = {"talos": "removed sagittal optimiser: cached 1.1 s, first 8.6 s, audited infeasible",
          "icub": "removed sagittal optimiser: 4.8 GB peak, audited infeasible"}
"""The removed sagittal optimiser's figures (quoted: its code is gone)."""

_CHILD = textwrap.dedent("""
    import json, resource, sys, time, warnings
    import numpy as np
    warnings.simplefilter("ignore")
    import gdimitate as gd
    from gdimitate.contact import ContactForces, FootForces
    name, N, stop = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    h, m, f = gd.gait.human_walk_3d()
    demo, fs = gd.gait.one_stride(m, f, "left")
    rate = (N - 1) / (demo.t[-1] - demo.t[0]) * (1 + 1e-9)
    robot = gd.Robot.from_library(name)
    out = {}
    for label in ("first", "cached") if stop == "settled" else ("first",):
        t0 = time.perf_counter()
        r = gd.adapt(demo, h, robot, method="optimal", force="measured", forces=fs, rate=rate,
                     verbose=False, stop=stop)
        out[label] = time.perf_counter() - t0
        out[label + "_iterations"] = r.solver.iterations
        out[label + "_status"] = r.solver.status
        out[label + "_solve"] = r.solver.time_s
    out["knots"] = r.solver.knots
    out["feasible"] = bool(r.audit.feasible)
    out["binding"] = list(r.audit.binding[:3])
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print("RESULT " + json.dumps(out))
""")


def humanoid(name: str, knots: int, stop: str = "settled") -> dict:
    p = subprocess.run([sys.executable, "-c", _CHILD, name, str(knots), stop],
                       capture_output=True, text=True)
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"error": (p.stderr or p.stdout)[-400:]}


def planar_case2() -> dict:
    from gdimitate.adapt import adapt
    from gdimitate.cases import paper_case

    d, i, m = paper_case("II")
    rate = 99 / (m.t[-1] - m.t[0]) * (1 + 1e-9)
    out = {}
    for label in ("first", "cached"):
        t0 = time.perf_counter()
        r = adapt(m, d, i, method="optimal", rate=rate, verbose=False)
        out[label] = time.perf_counter() - t0
    out["feasible"] = bool(r.audit.feasible)
    out["knots"] = r.solver.knots
    return out


def streaming(frames: int) -> dict:
    import numpy as np

    import gdimitate as gd

    h, m, f = gd.gait.human_walk_3d()
    robot = gd.Robot.from_library("talos")
    sa = gd.retarget.StreamingAdaptor(h, robot, "segment", dt=m.dt)
    sa.step(m.q[0], {s: bool(m.contact[s][0]) for s in ("left", "right")})  # builds
    t0 = time.perf_counter()
    ok = []
    for k in range(1, frames + 1):
        r = sa.step(m.q[k], {s: bool(m.contact[s][k]) for s in ("left", "right")})
        ok.append(r.previous_feasible)
    dt = time.perf_counter() - t0
    return {"frames_per_s": frames / dt, "feasible_frames": int(np.sum(ok)), "frames": frames}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--knots", type=int, default=100)
    ap.add_argument("--robots", default="talos,g1,icub,romeo")
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--baseline", default="talos",
                    help="robots also solved with stop='converged' (comma-separated, or '')")
    a = ap.parse_args()
    rows = ["| case | goal | first call | cached call | peak memory | audit | "
            "baseline, same run: stop='converged' (solve only) | quoted |",
            "|---|---|---|---|---|---|---|---|"]
    for name in a.robots.split(","):
        r = humanoid(name, a.knots)
        if "error" in r:
            rows.append(f"| {name} | | error: {r['error']!r} | | | | | |")
            continue
        base = ""
        if name in a.baseline.split(","):
            b = humanoid(name, a.knots, "converged")
            base = (f"error: {b['error']!r}" if "error" in b else
                    f"{b['first_solve']:.1f} s ({b['first_iterations']} it., "
                    f"{'feasible' if b['feasible'] else 'infeasible'}); settled/converged "
                    f"{r['cached_solve'] / b['first_solve']:.2f}")
        aud = "feasible" if r["feasible"] else "infeasible: " + ", ".join(r["binding"])
        rows.append(f"| 3-D walk → {name}, {r['knots']} knots | ≤ 60 s / ≤ 10 s / ≤ 2 GB | "
                    f"{r['first']:.1f} s ({r['first_iterations']} it.) | {r['cached']:.1f} s "
                    f"({r['cached_iterations']} it.) | {r['peak_mb']:.0f} MB | {aud} | "
                    f"{base} | {QUOTED.get(name, '')} |")
    p = planar_case2()
    rows.append(f"| Case II → HOAP-2-sized, {p['knots']} knots | ≤ 1 s cached | "
                f"{p['first']:.2f} s | {p['cached']:.2f} s | | "
                f"{'feasible' if p['feasible'] else 'infeasible'} | | |")
    s = streaming(a.frames)
    rows.append(f"| streaming, 3-D walk → Talos | ≥ 200 frames/s | | "
                f"{s['frames_per_s']:.1f} frames/s | | {s['feasible_frames']}/{s['frames']} "
                "frames feasible | | |")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
