"""Streaming adaptor: frames per second and the per-frame verdict (issues 17 and 35).

Run: ``python benchmarks/streaming.py [--robots talos,g1,icub,romeo] [--frames 200]
[--force measured] [--start 0] [--no-v-demo] [--repeats 1] [--baseline-rev ff13e49]
[--baseline-frames 200] [--clip 3d|cmu|sfu]`` (``--robot talos`` is ``--robots talos``;
``--clip cmu``/``sfu``: the shipped CMU BVH walk or the SFU-style file made from it,
streamed with the segment push and kinematic contacts).

The shipped real 3-D walk (with its measured forces) is streamed frame by frame into
``gdimitate.retarget.StreamingAdaptor`` for each of ``--robots``, joining at ``--start``
seconds, twice per repeat: with the default constructor (``StreamingAdaptor(human, robot,
force, dt=...)``: each frame's verdict judged by a worker process while the frames go on) and
with ``audit=False`` (no verdict), one process per case, one after the other (the machine is
shared: nothing runs in parallel but the verdict worker itself). Frames per second are counted
after a warm-up (the first five frames), in wall-clock and in the streaming process's CPU time
(``time.process_time``; the worker's is not in it). With the verdict on: the share of frames
feasible by the stream's own verdicts (``FrameResult.verdicts`` and, after ``final()``,
``sa.verdicts()``), whether they are the audit of the assembled motion frame for frame, the
delay of each verdict (frames between a frame's step and the step that delivered its verdict:
median and largest) and how long ``sa.verdicts()`` waited after the last frame for the ones
still on their way. Every frame is also judged by :func:`gdimitate.assess.audit.audit` on the
assembled motion (knot by knot, the verdict ``adapt(..., mode="per_frame").frame_feasible``
reports), and the checks that fail most often are listed with the number of frames each fails.
Where the adaptor's ``step`` takes ``v_demo`` (the demonstrator's velocity at the first frame),
it is given, as ``adapt(..., mode="per_frame")`` does, unless ``--no-v-demo`` (a live stream
has none: the adaptor then shows its first frame and starts at the second, moving with the
velocity estimated from both; the first frame counts as not feasible, and the assembled
motion is audited from the second, on the imitator's own stance flags). With ``--repeats
N`` each case runs N times (interleaved) and the table shows the medians of frames per second
and of the verdicts' wait.

The same-run baseline is the streaming of ``--baseline-rev`` (a git revision of this
repository, extracted with ``git archive`` into a temporary folder and run in its own process,
``audit=False`` where it has the parameter) for the same robots over ``--baseline-frames``
frames: by default ``ff13e49``, the inverse-dynamics QP before its references were made
robot-relative (G1 19/205, iCub 0/205 frames feasible); ``edd0e2f`` is the tree before the
inverse-dynamics QP (a Gauss–Newton QP of the two-knot window per frame), ``7b16d65`` the one
before issue 17 (an IPOPT solve per frame); ``''`` for none. The machine's load average is
printed with the table.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

from results import add_flag, recording
from revision import checkout

ROOT = Path(__file__).resolve().parents[1]

_CHILD = textwrap.dedent("""
    import inspect, json, sys, time, warnings
    import numpy as np
    warnings.simplefilter("ignore")
    import gdimitate as gd
    try:  # this tree's module paths, then a baseline revision's (before the layers)
        from gdimitate.assess.audit import audit
        from gdimitate.model.kinematics import robot_motion
    except ImportError:
        from gdimitate.audit import audit
        from gdimitate.kinematics import robot_motion
    name, frames, force, mode, start, use_v, clip = sys.argv[1:8]
    frames, start, use_v, warm = int(frames), float(start), use_v == "1", 5
    if clip:  # a BVH file: its skeleton, kinematic contacts, no forces
        demo = gd.load_demonstration(clip)
        h, m, f = demo.robot, demo.motion, None
    else:
        h, m, f = gd.gait.human_walk_3d()
    robot = gd.Robot.from_library(name)
    kw = {"audit": False} if mode == "off" and "audit" in inspect.signature(
        gd.retarget.StreamingAdaptor).parameters else {}
    moving = use_v and "v_demo" in inspect.signature(gd.retarget.StreamingAdaptor.step).parameters
    import pinocchio as pin
    k0 = int(np.searchsorted(m.t, m.t[0] + start - 1e-9))
    v0 = pin.difference(h.model, m.q[k0], m.q[k0 + 1]) / (m.t[k0 + 1] - m.t[k0])
    sa = gd.retarget.StreamingAdaptor(h, robot, force, dt=m.dt, **kw)
    T = min(frames + warm, m.T - k0)
    sides = ("left", "right")
    q, v = np.zeros((T, robot.model.nq)), np.zeros((T, robot.model.nv))
    a, W = np.zeros((T, robot.model.nv)), {s: np.zeros((T, 6)) for s in sides}
    def fk(k):
        if force != "measured":
            return None
        return {s: np.array([np.interp(m.t[k], f.t, f[s].force[:, i]) for i in range(3)])
                for s in sides}
    statuses, lag, stance = [], [], {s: [] for s in sides}
    for i in range(T):
        if i == warm:
            t0, c0 = time.perf_counter(), time.process_time()
        k = k0 + i
        extra = {"v_demo": v0} if moving and i == 0 else {}
        r = sa.step(m.q[k], {s: bool(m.contact[s][k]) for s in sides}, forces=fk(k), **extra)
        q[i], v[i] = r.q, r.v
        statuses.append(r.status)
        for s in sides:
            stance[s].append(r.contact[s] if getattr(r, "contact", None) is not None
                             else bool(m.contact[s][k]))
        lag += [i - j for j, _ in getattr(r, "verdicts", ())]
        if r.previous_a is not None:
            a[i - 1] = r.previous_a
            for s in sides:
                W[s][i - 1] = r.previous_wrenches[s]
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
    a[-1], wl, _ = sa.final()
    for s in sides:
        W[s][-1] = wl[s]
    t1 = time.perf_counter()
    own = sa.verdicts(timeout=600) if mode == "default" else None
    wait = time.perf_counter() - t1
    if hasattr(sa, "close"):
        sa.close()
    sk = getattr(sa, "first_frame", 0)  # a first frame that waited is not in the motion
    c = {s: np.asarray(stance[s][sk:], bool) for s in sides}
    motion = robot_motion(robot, m.t[k0 + sk:k0 + T], q[sk:], c).replace(v=v[sk:], a=a[sk:])
    rep = audit(sa._audit_robot, motion, {s: W[s][sk:] for s in sides}, sa.contacts)
    ok = np.concatenate([np.zeros(sk, bool), np.asarray(rep.knot_feasible, bool)])
    fails = {c.name: int((~k).sum()) for c, k in zip(rep.checks, rep.knot_checks) if (~k).any()}
    top = sorted(fails.items(), key=lambda x: -x[1])[:4]
    out = {"frames_per_s": (T - warm) / elapsed, "cpu_frames_per_s": (T - warm) / cpu,
           "frames": T, "feasible": int(ok.sum()),
           "binding": [f"{n} ({c})" for n, c in top],
           "statuses": {s: statuses.count(s) for s in set(statuses)}}
    if own is not None:
        out.update(own_feasible=int(own.sum()), own_frames=int(own.size),
                   agrees=bool(own.size == T and np.array_equal(own, ok)),
                   lag_median=float(np.median(lag)) if lag else None,
                   lag_max=int(max(lag)) if lag else None, in_stream=len(lag), wait_s=wait)
    print("RESULT " + json.dumps(out))
""")


def run(root: Path, robot: str, frames: int, force: str, mode: str = "off", start: float = 0.0,
        v_demo: bool = True, clip: str = "") -> dict:
    """One case in its own process: ``mode`` "default" (the default constructor: verdict on)
    or "off" (``audit=False``), joining ``start`` [s] into the walk (``clip``: a BVH file's
    path; "": the shipped 3-D walk)."""
    env = {**os.environ, "PYTHONPATH": str(root)}
    args = [robot, str(frames), force, mode, str(start), "1" if v_demo else "0", clip]
    p = subprocess.run([sys.executable, "-c", _CHILD, *args], capture_output=True, text=True,
                       env=env, cwd=tempfile.gettempdir())
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"error": (p.stderr or p.stdout)[-400:]}


def median_of(runs: list[dict]) -> dict:
    """The first run's result with the medians of its timings over ``runs`` (all cases that
    did not fail); ``fps_runs``: each run's frames/s."""
    ok = [r for r in runs if "error" not in r]
    if not ok:
        return runs[0]
    out = dict(ok[0])
    for key in ("frames_per_s", "cpu_frames_per_s", "wait_s"):
        if key in out:
            out[key] = statistics.median(r[key] for r in ok)
    out["fps_runs"] = [round(r["frames_per_s"]) for r in ok]
    return out


def row(label: str, r: dict) -> str:
    if "error" in r:
        return f"| {label} | error: {r['error']!r} | | | | | | |"
    pct = 100 * r["feasible"] / r["frames"]
    cpu = r.get("cpu_frames_per_s", float("nan"))
    runs = f" {r['fps_runs']}" if len(r.get("fps_runs", ())) > 1 else ""
    own = agree = delay = "—"
    if "own_feasible" in r:
        own = (f"{r['own_feasible']}/{r['own_frames']} "
               f"({100 * r['own_feasible'] / max(r['own_frames'], 1):.0f} %)")
        agree = "yes" if r["agrees"] else "**no**"
        delay = (f"{r['lag_median']:g} / {r['lag_max']} ({r['in_stream']} in the stream); "
                 f"{r['wait_s']:.2f} s" if r["in_stream"] else f"—; {r['wait_s']:.2f} s")
    return (f"| {label} | {r['frames_per_s']:.0f} ({cpu:.0f} of CPU){runs} | {own} | {agree} "
            f"| {delay} | {r['feasible']}/{r['frames']} ({pct:.0f} %) | "
            f"{', '.join(r['binding'])} | {r['statuses']} |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--robots", default="talos",
                    help="comma-separated library robots, e.g. talos,g1,icub,romeo")
    ap.add_argument("--robot", default=None, help="one robot (the same as --robots NAME)")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--force", default="measured")
    ap.add_argument("--start", type=float, default=0.0,
                    help="join the walk this many seconds in")
    ap.add_argument("--no-v-demo", action="store_true",
                    help="give no demonstrator velocity at the first frame (a live stream)")
    ap.add_argument("--repeats", type=int, default=1,
                    help="runs of each case (interleaved); the table shows the medians")
    ap.add_argument("--baseline-rev", default="ff13e49",
                    help="git revision streamed as the same-run baseline ('' for none)")
    ap.add_argument("--baseline-frames", type=int, default=200)
    ap.add_argument("--clip", default="3d", choices=("3d", "cmu", "sfu"),
                    help="the shipped 3-D walk (measured forces), the shipped CMU BVH walk, or "
                         "issue 32's SFU-style file made from it (tests/helpers/bvh.py); the "
                         "BVH clips stream with the segment push (no forces)")
    add_flag(ap)
    a = ap.parse_args()
    robots = [a.robot] if a.robot else [r.strip() for r in a.robots.split(",") if r.strip()]
    tmp_clip = tempfile.TemporaryDirectory()
    clip = ""
    if a.clip == "cmu":
        import gdimitate as gd

        clip = str(gd.gait.cmu_walk_path())
    elif a.clip == "sfu":
        sys.path.insert(0, str(ROOT))
        from tests.helpers.bvh import write_sfu_style

        clip = str(write_sfu_style(Path(tmp_clip.name) / "sfu_style.bvh"))
    if clip and a.force == "measured":
        a.force = "segment"
    what = {"3d": "the shipped 3-D walk", "cmu": "the shipped CMU BVH walk",
            "sfu": "the SFU-style BVH walk"}[a.clip]
    rows = [f"streaming {what} (force={a.force}), joining {a.start:g} s in, "
            f"{'without' if a.no_v_demo else 'with'} the demonstrator's velocity; "
            f"{a.repeats} run(s) per case, medians", "",
            "| robot | streaming | frames/s wall (of CPU time) | feasible by its own verdict "
            "| = audit of the assembled motion | verdict delay: median / largest [frames]; "
            "wait after the last frame | audited feasible frames (assembled motion) "
            "| checks failed most (frames) | frame solves |",
            "|---|---|---|---|---|---|---|---|---|"]
    cases = [(robot, mode) for robot in robots for mode in ("default", "off")]
    got: dict = {c: [] for c in cases}
    for _ in range(max(a.repeats, 1)):
        for robot, mode in cases:
            got[robot, mode].append(run(ROOT, robot, a.frames, a.force, mode, a.start,
                                        not a.no_v_demo, clip))
    with tempfile.TemporaryDirectory() as tmp:
        base = checkout(a.baseline_rev, tmp) if a.baseline_rev else None
        for robot in robots:
            rows.append(row(f"{robot} | this tree, default (verdict on)",
                            median_of(got[robot, "default"])))
            rows.append(row(f"{robot} | this tree, audit=False", median_of(got[robot, "off"])))
            if base is not None:
                rows.append(row(f"{robot} | baseline {a.baseline_rev}, audit=False",
                                run(base, robot, a.baseline_frames, a.force, "off", a.start,
                                    not a.no_v_demo, clip)))
    rows.append("")
    rows.append(f"load average (1, 5, 15 min): {os.getloadavg()}, {os.cpu_count()} CPUs")
    tmp_clip.cleanup()
    print("\n".join(rows))


if __name__ == "__main__":
    with recording("streaming", "--results" in sys.argv[1:]):
        main()
