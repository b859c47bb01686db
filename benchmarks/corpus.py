"""The gait kept on a corpus (issue 32, docs/design.md §13): every shipped walk and synthetic
variants of it, onto several robots, judged by the audit and the gait's travel ratio.

Run: ``python benchmarks/corpus.py [--robots g1,talos,icub,romeo] [--clips stride,whole,cmu,sfu]
[--variants asis,turn90,turn180,turn-137,rate30,rate60,rate240,trim,mirror,noise]
[--scaling geometric|froude] [--lift position,velocity,effort] [--simulate] [--baseline-rev REV]
[--baseline-robots g1]``.

Clips: ``stride`` — one right stride of the shipped 3-D OpenSim walk (measured forces, the
push goal ``measured``); ``whole`` — the whole 3.5-s clip; ``cmu`` — the shipped CMU BVH walk
(kinematic contacts, ``force="segment"``, the command line's default); ``sfu`` — issue 32's
unseen walk's conventions without SFU's data: the CMU walk rewritten as a file with every
rotation channel in XYZ order, in inches, turned to walk along −y, the 2.2 s around its
middle at its own 120 Hz, 6 decimals (``tests.helpers.bvh.write_sfu_style``: each joint's
rotation re-expressed, its joints where the CMU walk's are), adapted by the command line as
a new user runs it, ``gdimitate adapt FILE --imitator ROBOT`` with its defaults (geometric
scaling only). The ``stride``, ``whole`` and ``cmu`` cases call ``gd.adapt`` in their
process; the ``sfu`` case runs the command in a process of its own and reads what it wrote:
the audit's verdict and the iterations from ``report.json``, the travel ratio computed from
``imitator_motion.npz`` by the rule below, and the CPU seconds of the whole command
(start-up, reading, adaptation, audit, files and figure: a few seconds more than the
adaptation alone; a command that compiled the robot's derivatives is run again and the
second run reported).

``--lift KINDS`` adapts with the robot's own limits of those kinds lifted (``Limits``: every
1-dof joint's position to ±3 rad, velocity and effort to infinity): which limits shorten a
gait that is not kept (docs/design.md §13). The audit then judges against the lifted limits.

Variants, made from the clip's motion (and forces) before the adaptor sees it (for ``sfu``,
by rewriting its file: ``asis``, ``turnD`` and ``trim`` only): ``asis``; ``turnD`` — turned
by D degrees about the vertical through its first base position; ``rateR`` — resampled to R
Hz (linear interpolation, quaternions renormalised, contacts of the nearest frame); ``trim``
— 0.3 s cut from each end (it starts and ends mid-stride); ``mirror`` — mirrored left to
right (``gdimitate.model.mirror``: the walk led by the other foot); ``noise`` — 5 mm on the
base position and 0.01 rad on every joint angle, white, seed 0 (mocap noise; the contacts as
recorded). Each case runs in its own Python process with its own timer (CPU seconds of the
adaptation, derivatives already compiled). The travel ratio is computed here from the output
alone, by docs/design.md §13's definition (the imitator's base travel over the clip over the
demonstrator's × the legs' ratio), so the baseline revision — extracted with ``git archive``
and run the same way — is measured by the same rule.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

from results import add_flag, recording
from revision import checkout

ROOT = Path(__file__).resolve().parents[1]

_CHILD = textwrap.dedent("""
    import json, sys, time, warnings
    import numpy as np
    import pinocchio as pin
    warnings.simplefilter("ignore")
    import gdimitate as gd
    from gdimitate.model.contact import ContactForces, FootForces
    clip, variant, name, scaling, simulate, lift = sys.argv[1:7]
    if clip == "cmu":
        from gdimitate.io.demonstration import load_demonstration
        d = load_demonstration("gdimitate/data/gait/cmu_02_01/cmu_02_01.bvh")
        h, demo, fs, force = d.robot, d.motion, d.forces, "segment"
    else:
        h, demo, fs = gd.gait.human_walk_3d()
        if clip == "stride":
            demo, fs = gd.gait.one_stride(demo, fs)
        force = "measured"

    def turn(m, f, yaw):
        c, s = np.cos(yaw), np.sin(yaw)
        R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
        p0 = np.r_[m.q[0, :2], 0.0]
        q = m.q.copy()
        q[:, :3] = (q[:, :3] - p0) @ R.T + p0
        Q = pin.Quaternion(R)
        for i in range(len(q)):
            q[i, 3:7] = (Q * pin.Quaternion(q[i, 3:7])).coeffs()
        if f is not None:
            f = ContactForces(f.t, {k: FootForces(v.force @ R.T, (v.cop - p0) @ R.T + p0,
                                                  v.torque @ R.T, v.contact)
                                    for k, v in f.feet.items()}, f.source, f.frame_note)
        return m.replace(q=q, v=None, a=None), f

    def resample(m, f, rate):
        t = np.arange(m.t[0], m.t[-1] + 1e-9, 1.0 / rate)
        q = np.column_stack([np.interp(t, m.t, m.q[:, j]) for j in range(m.q.shape[1])])
        q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
        near = np.abs(m.t[None, :] - t[:, None]).argmin(axis=1)
        m2 = m.replace(t=t, q=q, v=None, a=None,
                       contact={k: np.asarray(v)[near] for k, v in m.contact.items()})
        if f is not None:
            lerp = lambda a: np.column_stack([np.interp(t, f.t, a[:, j]) for j in range(3)])
            f = ContactForces(t, {k: FootForces(lerp(v.force), v.cop[near], lerp(v.torque),
                                                v.contact[near]) for k, v in f.feet.items()},
                              f.source, f.frame_note)
        return m2, f

    def cut(m, f, k0, k1):
        sl = slice(k0, k1)
        m2 = m.replace(t=m.t[sl], q=m.q[sl], v=None, a=None,
                       contact={k: np.asarray(v)[sl] for k, v in m.contact.items()})
        if f is not None:
            f = ContactForces(f.t[sl], {k: FootForces(v.force[sl], v.cop[sl], v.torque[sl],
                                                      v.contact[sl])
                                        for k, v in f.feet.items()}, f.source, f.frame_note)
        return m2, f

    if variant.startswith("turn"):
        demo, fs = turn(demo, fs, np.radians(float(variant[4:])))
    elif variant.startswith("rate"):
        demo, fs = resample(demo, fs, float(variant[4:]))
    elif variant == "trim":
        n = int(round(0.3 / np.median(np.diff(demo.t))))
        demo, fs = cut(demo, fs, n, demo.T - n)
    elif variant == "mirror":
        from gdimitate.model.mirror import mirror_forces, mirror_motion
        demo = mirror_motion(h, demo)
        fs = None if fs is None else mirror_forces(fs)
    elif variant == "noise":
        rng = np.random.default_rng(0)
        q = demo.q.copy()
        q[:, :3] += rng.normal(0, 0.005, (demo.T, 3))
        q[:, 7:] += rng.normal(0, 0.01, (demo.T, q.shape[1] - 7))
        demo = demo.replace(q=q, v=None, a=None)
    robot = gd.Robot.from_library(name)
    kw = dict(force=force, verbose=False, **({"forces": fs} if fs is not None else {}))
    if scaling != "geometric":
        kw["gait_scaling"] = scaling
    if lift:  # the robot's own limits lifted, kind by kind (every 1-dof joint)
        import math
        from gdimitate.retarget import Limits
        kinds, m = lift.split(","), robot.model
        one = [n for n in m.names[1:] if m.joints[m.getJointId(n)].nq == 1]
        kw["limits"] = Limits(
            position={n: (-3.0, 3.0) for n in one} if "position" in kinds else None,
            velocity=math.inf if "velocity" in kinds else None,
            effort=math.inf if "effort" in kinds else None)
    t0 = time.process_time()
    r = gd.adapt(demo, h, robot, method="optimal", **kw)
    cpu = time.process_time() - t0
    L = lambda rb: np.mean([rb.legs[s].length for s in ("left", "right")])
    ratio = L(robot) / L(h)
    trav = lambda q: float(np.hypot(*(q[-1, :2] - q[0, :2])))
    if robot.base == "planar":  # x, z, pitch: the travel is along x
        ix = robot.idx_q("base_x")
        own = abs(float(r.motion.q[-1, ix] - r.motion.q[0, ix]))
    else:
        own = trav(r.motion.q)
    travel = own / (trav(demo.q) * ratio)
    dur = (r.motion.t[-1] - r.motion.t[0]) / (demo.t[-1] - demo.t[0])
    sim = {}
    if simulate == "1":
        m = gd.sim.simulate(robot, r).metrics
        sim = {"fell": bool(m.fell), "slip_cm": 100 * float(m.slip_max)}
    print("RESULT " + json.dumps({**sim,
        "feasible": bool(r.audit.feasible), "binding": list(r.audit.binding[:3]),
        "iterations": int(r.solver.iterations), "cpu_s": cpu, "travel": travel,
        "speed": travel / dur, "retry": r.solver.retry,
        "unmet": [[u.name, round(float(u.violation), 4)] for u in r.solver.unmet[:2]]}))
""")

#: the sfu clip: ``gdimitate adapt FILE --imitator ROBOT`` in a process of its own, then the
#: same numbers as _CHILD's from what it wrote
_CLI_CHILD = textwrap.dedent("""
    import json, resource, subprocess, sys, warnings
    from pathlib import Path
    import numpy as np
    warnings.simplefilter("ignore")
    path, name, folder, simulate = sys.argv[1:5]
    for run in ("first", "again"):  # again where the first compiled the robot's derivatives
        out = Path(folder) / run
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        p = subprocess.run([sys.executable, "-m", "gdimitate.apps.cli", "adapt", path,
                            "--imitator", name, "--out", str(out)], capture_output=True,
                           text=True)
        use = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = use.ru_utime + use.ru_stime - before.ru_utime - before.ru_stime
        if not (out / "report.json").is_file():
            print("RESULT " + json.dumps({"error": f"exit {p.returncode}: " + (
                p.stderr.strip().splitlines() or ["no output"])[-1][:70]}))
            sys.exit()
        rep = json.loads((out / "report.json").read_text())
        if not (rep.get("solver") or {}).get("compiled"):
            break
    import gdimitate as gd
    from gdimitate.io.demonstration import load_demonstration
    from gdimitate.model.motion import Motion
    d = load_demonstration(path)
    robot = gd.Robot.from_library(name)
    motion = Motion.from_npz(out / "imitator_motion.npz")
    L = lambda rb: np.mean([rb.legs[s].length for s in ("left", "right")])
    trav = lambda q: float(np.hypot(*(q[-1, :2] - q[0, :2])))
    travel = trav(motion.q) / (trav(d.motion.q) * L(robot) / L(d.robot))
    dur = (motion.t[-1] - motion.t[0]) / (d.motion.t[-1] - d.motion.t[0])
    sim = {}
    if simulate == "1":
        from gdimitate.export.writers import read_wrenches
        from gdimitate.sim.reference import Plan
        npz = out / "imitator_motion.npz"
        plan = load_demonstration(npz)
        m = gd.sim.simulate(plan.robot, Plan(plan.motion, read_wrenches(npz),
                                             dict(plan.robot.require_contacts()))).metrics
        sim = {"fell": bool(m.fell), "slip_cm": 100 * float(m.slip_max)}
    aud, sol = rep.get("audit") or {}, rep.get("solver") or {}
    print("RESULT " + json.dumps({**sim,
        "feasible": bool(aud.get("feasible")), "binding": list(aud.get("binding", [])[:3]),
        "iterations": int(sol.get("iterations", -1)), "cpu_s": cpu, "travel": travel,
        "speed": travel / dur, "exit": p.returncode, "retry": sol.get("retry", ""),
        "unmet": [[u["name"], round(float(u["violation"]), 4)] for u in (
            (rep.get("verdict") or {}).get("unmet") or sol.get("unmet", []))[:2]]}))
""")


def sfu_file(folder: Path, variant: str) -> Path | None:
    """The sfu clip's file for ``variant`` (asis, turnD, trim) written into ``folder`` by this
    tree's writer; None for a variant it is not made for."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    from gdimitate.io.bvh import parse_bvh
    from tests.helpers.bvh import SFU_STYLE, rewrite_bvh, write_sfu_style

    base = write_sfu_style(folder / "sfu_style.bvh")
    if variant == "asis":
        return base
    keep = {**SFU_STYLE, "heading": None, "scale": 0.0254}
    if variant.startswith("turn"):
        return rewrite_bvh(parse_bvh(base), folder / f"sfu_{variant}.bvh",
                           yaw=math.radians(float(variant[4:])), **keep)
    if variant == "trim":
        return rewrite_bvh(parse_bvh(base), folder / "sfu_trim.bvh", start=0.3,
                           **{**keep, "duration": SFU_STYLE["duration"] - 0.6})
    return None


def run(tree: Path, clip: str, variant: str, robot: str, scaling: str, simulate: bool,
        lift: str = "") -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree), "OMP_NUM_THREADS": "1",
           "GDIMITATE_COMPILE": "wait"}  # every case timed compiled
    if clip == "sfu":
        if scaling != "geometric" or lift:
            return {"error": "the sfu clip runs the command line's defaults"}
        with tempfile.TemporaryDirectory() as tmp:
            path = sfu_file(Path(tmp), variant)
            if path is None:
                return {"error": f"{variant}: not made for the sfu file (asis, turnD, trim)"}
            p = subprocess.run([sys.executable, "-c", _CLI_CHILD, str(path), robot,
                                tmp, "1" if simulate else "0"], cwd=tree,
                               env=env, capture_output=True, text=True, timeout=1800)
        return _result(p)
    p = subprocess.run([sys.executable, "-c", _CHILD, clip, variant, robot, scaling,
                        "1" if simulate else "0", lift], cwd=tree,
                       env=env, capture_output=True, text=True, timeout=1800)
    return _result(p)


def _result(p: subprocess.CompletedProcess) -> dict:
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"error": (p.stderr.strip().splitlines() or ["no output"])[-1][:80]}


def row(tag: str, clip: str, variant: str, robot: str, r: dict) -> str:
    if "error" in r:
        return f"| {tag} | {clip} | {variant} | {robot} | error: {r['error']} |||||"
    feas = "yes" if r["feasible"] else "NO " + ",".join(r["binding"])
    if r.get("exit"):  # the command's exit status (sfu), where not 0, and the goals unmet
        feas += f" (exit {r['exit']}" + "".join(f"; {n} {v:.3g}" for n, v in r["unmet"]) + ")"
    kept = 0.8 <= r["travel"] <= 1.25
    retry = re.match(r"travel ([0-9.]+) .*, (kept|not kept)", r.get("retry") or "")
    again = f" (solved again from {retry[1]}: {retry[2]})" if retry else ""
    sim = ("" if "fell" not in r else
           f" {'FELL' if r['fell'] else 'walked'}, slip {r['slip_cm']:.2f} cm |")
    return (f"| {tag} | {clip} | {variant} | {robot} | {feas} | {r['travel']:.2f}"
            f"{'' if kept else ' (gait not kept)'}{again} | {r['speed']:.2f} | {r['iterations']} | "
            f"{r['cpu_s']:.1f} |{sim}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robots", default="g1,talos,icub,romeo")
    ap.add_argument("--clips", default="stride,whole,cmu")
    ap.add_argument("--variants", default="asis,turn90,turn180,turn-137,rate30,rate60,"
                                          "rate240,trim,mirror,noise")
    ap.add_argument("--baseline-rev", default=None,
                    help="a git revision run the same way on --baseline-robots")
    ap.add_argument("--baseline-robots", default="g1")
    ap.add_argument("--scaling", default="geometric", choices=["geometric", "froude"],
                    help="gait_scaling= of every case (a baseline before it had none: "
                         "geometric only)")
    ap.add_argument("--lift", default="", help="the robots' limits lifted, kinds of "
                    "position (to ±3 rad), velocity, effort (to infinity), comma-separated: "
                    "which limits shorten a gait (not for sfu or a baseline revision)")
    ap.add_argument("--simulate", action="store_true",
                    help="also run each result in MuJoCo under the tracking controller")
    add_flag(ap)
    a = ap.parse_args()
    lift = ",".join(k for k in a.lift.split(",") if k)
    if set(lift.split(",")) - {"", "position", "velocity", "effort"}:
        ap.error(f"--lift takes position, velocity, effort; got {a.lift!r}")
    print(f"gait scaling: {a.scaling}" + (f"; limits lifted: {lift}" if lift else ""))
    print("| tree | clip | variant | robot | audit feasible | travel ratio | speed ratio | "
          "iterations | CPU s |" + (" MuJoCo |" if a.simulate else ""))
    print("|---|---|---|---|---|---|---|---|---|" + ("---|" if a.simulate else ""))
    trees = [("now", ROOT, a.robots.split(","))]
    tmp = None
    if a.baseline_rev:
        tmp = tempfile.TemporaryDirectory()
        trees.append((a.baseline_rev, checkout(a.baseline_rev, tmp.name),
                      a.baseline_robots.split(",")))
    for clip in a.clips.split(","):
        for variant in a.variants.split(","):
            for tag, tree, robots in trees:
                for robot in robots:
                    r = run(tree, clip, variant, robot, a.scaling, a.simulate,
                            lift if tag == "now" else "")
                    print(row(tag, clip, variant, robot, r), flush=True)
    if tmp is not None:
        tmp.cleanup()


if __name__ == "__main__":
    with recording("corpus", "--results" in sys.argv[1:]):
        main()
