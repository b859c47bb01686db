"""Streaming adaptor: frames per second and audited feasibility (issue 17).

Run: ``python benchmarks/streaming.py [--robots talos,g1,icub,romeo] [--frames 200]
[--force measured] [--baseline-rev ff13e49] [--baseline-frames 200]`` (``--robot talos`` is
``--robots talos``).

The shipped real 3-D walk (with its measured forces) is streamed frame by frame into
``gdimitate.retarget.StreamingAdaptor`` for each of ``--robots``, one process per robot and
revision, one after the other (the machine is shared: nothing runs in parallel). Frames per
second are counted after a warm-up (the first five frames), in wall-clock and in CPU time
(``time.process_time``: the machine is shared); every frame is then judged by
:func:`gdimitate.audit.audit` on the assembled motion (knot by knot, the same verdict
``adapt(..., mode="per_frame").frame_feasible`` reports), and the checks that fail most often
are listed with the number of frames each fails. Where the adaptor's ``step`` takes
``v_demo`` (the demonstrator's velocity at the first frame), it is given, as
``adapt(..., mode="per_frame")`` does.

The same-run baseline is the streaming of ``--baseline-rev`` (a git revision of this
repository, extracted with ``git archive`` into a temporary folder and run in its own process)
for the same robots over ``--baseline-frames`` frames: by default ``ff13e49``, the inverse-
dynamics QP before its references were made robot-relative (G1 19/205, iCub 0/205 frames
feasible); ``edd0e2f`` is the tree before the inverse-dynamics QP (a Gauss–Newton QP of the
two-knot window per frame), ``7b16d65`` the one before issue 17 (an IPOPT solve per frame). The
machine's load average is printed with the table.
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

from revision import checkout

ROOT = Path(__file__).resolve().parents[1]

_CHILD = textwrap.dedent("""
    import inspect, json, sys, time, warnings
    import numpy as np
    warnings.simplefilter("ignore")
    import gdimitate as gd
    from gdimitate.audit import audit
    from gdimitate.kinematics import robot_motion
    name, frames, force, warm = sys.argv[1], int(sys.argv[2]), sys.argv[3], 5
    h, m, f = gd.gait.human_walk_3d()
    robot = gd.Robot.from_library(name)
    kw = {"audit": False} if "audit" in inspect.signature(
        gd.retarget.StreamingAdaptor).parameters else {}
    moving = "v_demo" in inspect.signature(gd.retarget.StreamingAdaptor.step).parameters
    import pinocchio as pin
    v0 = pin.difference(h.model, m.q[0], m.q[1]) / (m.t[1] - m.t[0])
    sa = gd.retarget.StreamingAdaptor(h, robot, force, dt=m.dt, **kw)
    T = min(frames + warm, m.T)
    sides = ("left", "right")
    q, v = np.zeros((T, robot.model.nq)), np.zeros((T, robot.model.nv))
    a, W = np.zeros((T, robot.model.nv)), {s: np.zeros((T, 6)) for s in sides}
    def fk(k):
        if force != "measured":
            return None
        return {s: np.array([np.interp(m.t[k], f.t, f[s].force[:, i]) for i in range(3)])
                for s in sides}
    statuses = []
    for k in range(T):
        if k == warm:
            t0, c0 = time.perf_counter(), time.process_time()
        extra = {"v_demo": v0} if moving and k == 0 else {}
        r = sa.step(m.q[k], {s: bool(m.contact[s][k]) for s in sides}, forces=fk(k), **extra)
        q[k], v[k] = r.q, r.v
        statuses.append(r.status)
        if k:
            a[k - 1] = r.previous_a
            for s in sides:
                W[s][k - 1] = r.previous_wrenches[s]
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
    a[-1], wl, _ = sa.final()
    for s in sides:
        W[s][-1] = wl[s]
    c = {s: np.asarray(m.contact[s][:T], bool) for s in sides}
    motion = robot_motion(robot, m.t[:T], q, c).replace(v=v, a=a)
    rep = audit(sa._audit_robot, motion, W, sa.contacts)
    ok = np.asarray(rep.knot_feasible, bool)
    fails = {c.name: int((~k).sum()) for c, k in zip(rep.checks, rep.knot_checks) if (~k).any()}
    top = sorted(fails.items(), key=lambda x: -x[1])[:4]
    print("RESULT " + json.dumps({
        "frames_per_s": (T - warm) / elapsed, "cpu_frames_per_s": (T - warm) / cpu,
        "frames": T, "feasible": int(ok.sum()),
        "binding": [f"{n} ({c})" for n, c in top],
        "statuses": {s: statuses.count(s) for s in set(statuses)}}))
""")


def run(root: Path, robot: str, frames: int, force: str) -> dict:
    env = {**os.environ, "PYTHONPATH": str(root)}
    p = subprocess.run([sys.executable, "-c", _CHILD, robot, str(frames), force],
                       capture_output=True, text=True, env=env, cwd=tempfile.gettempdir())
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"error": (p.stderr or p.stdout)[-400:]}



def row(label: str, r: dict) -> str:
    if "error" in r:
        return f"| {label} | error: {r['error']!r} | | | |"
    pct = 100 * r["feasible"] / r["frames"]
    cpu = r.get("cpu_frames_per_s", float("nan"))
    return (f"| {label} | {r['frames_per_s']:.1f} ({cpu:.0f} of CPU) | "
            f"{r['feasible']}/{r['frames']} "
            f"({pct:.0f} %) | {', '.join(r['binding'])} | {r['statuses']} |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--robots", default="talos",
                    help="comma-separated library robots, e.g. talos,g1,icub,romeo")
    ap.add_argument("--robot", default=None, help="one robot (the same as --robots NAME)")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--force", default="measured")
    ap.add_argument("--baseline-rev", default="ff13e49",
                    help="git revision streamed as the same-run baseline ('' for none)")
    ap.add_argument("--baseline-frames", type=int, default=200)
    a = ap.parse_args()
    robots = [a.robot] if a.robot else [r.strip() for r in a.robots.split(",") if r.strip()]
    rows = [f"streaming the shipped 3-D walk (force={a.force}); goal ≥ 200 frames/s after "
            "warm-up, ≥ 95 % of frames audited feasible", "",
            "| robot | streaming | frames/s wall (of CPU time) | audited feasible frames "
            "| checks failed most (frames) | frame solves |",
            "|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as tmp:
        base = checkout(a.baseline_rev, tmp) if a.baseline_rev else None
        for robot in robots:
            rows.append(row(f"{robot} | this tree", run(ROOT, robot, a.frames, a.force)))
            if base is not None:
                rows.append(row(f"{robot} | baseline {a.baseline_rev}",
                                run(base, robot, a.baseline_frames, a.force)))
    rows.append("")
    rows.append(f"load average (1, 5, 15 min): {os.getloadavg()}, {os.cpu_count()} CPUs")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
