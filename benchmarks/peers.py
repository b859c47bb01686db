"""Baselines in the physics-check harness: the same demonstration retargeted several ways, each
audited (``gdimitate.audit.audit``) and simulated (``gdimitate.sim.simulate``) alike.

Run: ``python benchmarks/peers.py [--robots talos g1 hoap2] [--no-optimal] [--out FILE]
[--save-plans DIR | --plans DIR] [--holosoma-python PYTHON] [--gmr-python PYTHON --gmr-repo
DIR] [--repair | --repair-only] [--save-motions DIR]`` (``--plans``: audit and simulate the
optimal plans a ``--save-plans`` run wrote, with the adaptation time it measured, instead of
adapting anew).
Prints one markdown table and writes it to ``benchmarks/peers.md`` (or ``--out``); the repair
table (``--repair``) goes into its own block of that file (``<!-- results: repair -->``), which
``--repair-only`` (the repair rows alone, G1's peers) replaces leaving the rest of the file as
it is.

The demonstration is the shipped 3-D walk (OpenSim subject01, 211 frames at 60 Hz, measured
ground reaction forces; ``gdimitate.gait.human_walk_3d()``). Methods:

- ``copy`` — joint-angle copy: 3-D (``gdimitate.apps.baselines.joint_copy``) onto the free-flyer
  robots, the planar copy (``adapt(method="copy")``: sagittal hip/knee/ankle angles) onto the
  HOAP-2-sized planar model;
- ``Eq. (1)`` — the paper's analytic adaptor (``adapt(method="analytic")``), planar only;
- ``diff IK`` — a per-frame kinematic retargeter of the kind today's humanoid tools use:
  differential IK on leg-length-scaled keypoints with joint limits, on Pink
  (``gdimitate.apps.baselines.diff_ik``); free-flyer robots;
- ``OmniRetarget (holosoma)`` — a real peer: OmniRetarget's retargeter as published on PyPI
  (``holosoma-retargeting`` 0.1.0: an interaction-mesh SQP with foot sticking, joint limits
  and its own G1 model), fed the demonstrator's global joint positions in its ``smplx``
  layout (:func:`smplx_joints`) and run with its defaults in its own Python
  (``--holosoma-python``, ``benchmarks/holosoma_run.py``); its G1 motion is put on our G1 by
  joint name. G1 only (its model);
- ``GMR`` — General Motion Retargeting (github.com/YanjieZe/GMR, not on PyPI: a checkout at
  ``--gmr-repo``, its dependencies in the Python ``--gmr-python``; ``benchmarks/gmr_run.py``),
  the most-used kinematic retargeter: mink IK on its own G1 model with its BVH → G1 config,
  run on the shipped BVH walk (CMU 02_01, 343 frames at 120 Hz: GMR reads BVH, not the
  OpenSim walk), its G1 motion put on our G1 by joint name (the same kinematics: body
  positions equal within 1e-5 m). Repair table only (no measured forces for the main table's
  push columns). G1 only;
- ``optimal`` — gdimitate's whole-body adaptor (``adapt(method="optimal", force="measured")``).

``--repair`` adds a second table: each kinematic output (free-flyer robots: the 3-D copy, diff
IK, holosoma's, GMR's) handed over as its q alone — what a retargeter writes — to
``gdimitate.repair`` (the whole-body adaptor from the robot to itself,
:mod:`gdimitate.adaptation.repairer`) and audited before and after by
``gdimitate.audit_motion`` (share of knots feasible, verdict), both run in MuJoCo
(``gdimitate.apps.repair.simulate_both``: fell [s] or "no"), the keypoints kept (RMS distance
of hips, knees, ankles, soles from the input's), the retargeter's own wall time per clip and
the repair's. ``--save-motions DIR`` writes each kinematic output as GMR's pickle
(``DIR/<robot>_<method>.pkl``, q alone) for ``gdimitate audit DIR --robot g1``.

Kinematic methods get the wrenches their motion implicitly asks of the floor
(``estimate_wrenches(method="lstsq")``: no cone). Columns:

- frames/s: demonstration frames per second of the retargeting's wall time (kinematic
  methods: wrenches not included; optimal: the whole ``adapt`` call, on its 50 Hz knots);
- CoP out: stance knots of either foot whose wrench has its centre of pressure outside the
  sole or pulls on the floor, in % of all stance knots (the audit's ``cop:<side>`` and
  ``normal:<side>`` checks);
- τ/τmax: the audit's worst torque ratio over the actuated joints;
- plan push err: RMS angle between the plan's push and the measured one (the audit's
  ``force_direction``);
- fell: seconds after the start when the simulated robot fell ("no": it walked the plan);
- slip: the simulation's largest stance-foot slip;
- sim push RMSE: RMS error of the simulated push against the measured one in single support,
  per foot, left / right (sagittal and frontal angle, until the fall; planar robots:
  sagittal only).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from results import add_flag, recording
from results import replace as replace_block

import gdimitate as gd
from gdimitate.apps.baselines import diff_ik, joint_copy, kinematic_plan
from gdimitate.assess.audit import audit
from gdimitate.export.writers import read_wrenches
from gdimitate.io.demonstration import load_demonstration
from gdimitate.sim.reference import Plan

SIDES = ("left", "right")


@dataclass(frozen=True)
class Row:
    """One method on one robot (units in the column names of :func:`table`)."""

    robot: str
    method: str
    frames_per_s: float
    cop_out_pct: float
    torque_ratio: float
    plan_push_deg: float
    fell_after: float | None
    slip_cm: float
    sim_sag_deg: tuple[float, float]
    sim_front_deg: tuple[float, float]
    feasible: bool
    note: str = ""


def _per_foot(agreements: dict, attr: str) -> tuple[float, float]:
    return tuple(float(getattr(agreements[s], attr)) if s in agreements else float("nan")
                 for s in SIDES)


def evaluate(robot, plan, frames_per_s: float, forces, method: str, note: str = "") -> Row:
    """Audit and simulate ``plan`` (``.motion`` with v, a; ``.wrenches``; ``.contacts``)
    against the measured ``forces``."""
    mo = plan.motion
    push = measured_push(forces, mo.t)
    if robot.base == "planar":  # the plane has no lateral push: compare in the x–z plane
        push = {s: _unit_xz(p) for s, p in push.items()}
    rep = audit(robot, mo, plan.wrenches, plan.contacts, target=push)
    stance = sum(int(np.sum(mo.contact[s])) for s in SIDES)
    out = 0
    for s in SIDES:
        ok = rep.check_knots(f"cop:{s}") & rep.check_knots(f"normal:{s}")
        out += int(np.sum(np.asarray(mo.contact[s], bool) & ~ok))
    ratios = [j.torque_ratio for j in rep.joints if np.isfinite(j.torque_ratio)]
    fd = [f for f in rep.force_direction_error.values() if f is not None and f.knots]
    plan_push = float(np.sqrt(sum(f.knots * f.error_rms ** 2 for f in fd)
                              / max(sum(f.knots for f in fd), 1)))
    try:
        res = gd.sim.simulate(robot, plan, demo_forces=forces)
    except gd.GdimitateError as e:  # e.g. a URDF MuJoCo cannot take: report it as a row
        nan = float("nan")
        return Row(robot.name, method, frames_per_s, 100.0 * out / max(stance, 1),
                   max(ratios, default=nan), float(np.degrees(plan_push)), nan, nan, (nan, nan),
                   (nan, nan),
                   bool(rep.feasible), f"{note}; not simulated: {e}".lstrip("; ")[:160])
    m, nan = res.metrics, float("nan")
    vs = m.force_vs_demo or {}
    return Row(robot.name, method, frames_per_s, 100.0 * out / max(stance, 1),
               max(ratios, default=float("nan")), float(np.degrees(plan_push)),
               None if m.fall_time is None else float(m.fall_time - mo.t[0]),
               100.0 * m.slip_max, _per_foot(vs, "rmse_sagittal_deg"),
               (nan, nan) if robot.base == "planar" else _per_foot(vs, "rmse_frontal_deg"),
               bool(rep.feasible), note)


def _unit_xz(p: np.ndarray) -> np.ndarray:
    p = np.array(p, dtype=float)
    p[:, 1] = 0.0
    with np.errstate(invalid="ignore"):
        return p / np.linalg.norm(p, axis=1, keepdims=True)


def measured_push(forces, t: np.ndarray) -> dict[str, np.ndarray]:
    """The demonstrator's measured unit push on the ground ``{side: (T, 3)}`` on the times
    ``t`` [s] (linear interpolation; NaN where the foot carries no measured force)."""
    out = {}
    for s in SIDES:
        f = forces[s]
        F = np.column_stack([np.interp(t, forces.t, f.force[:, i]) for i in range(3)])
        on = np.interp(t, forces.t, f.contact.astype(float)) > 0.5
        n = np.linalg.norm(F, axis=1)
        u = np.full_like(F, np.nan)
        ok = on & (n > 1e-9)
        u[ok] = -F[ok] / n[ok, None]
        out[s] = u
    return out


def _timed(f):
    t0 = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t0


def _optimal(demo, demonstrator, robot, forces, rows, save: Path | None = None):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a, sec = _timed(lambda: gd.adapt(demo, demonstrator, robot, method="optimal",
                                             force="measured", forces=forces, verbose=False))
    except Exception as e:  # report, don't hide: the adaptor is the product under test
        nan = float("nan")
        rows.append(Row(robot.name, "optimal", nan, nan, nan, nan, None, nan, (nan, nan),
                        (nan, nan), False, f"failed: {type(e).__name__}: {e}"[:120]))
        return
    if save is not None:  # for `gdimitate simulate`, --plans and a closer look
        save.mkdir(parents=True, exist_ok=True)
        a.save(save / f"{robot.name}_optimal.npz")
        (save / f"{robot.name}_optimal.json").write_text(json.dumps({"seconds": sec}))
    _optimal_row(robot, a, demo, forces, sec, rows)


def _optimal_row(robot, a, demo, forces, sec: float, rows, note: str = "") -> None:
    row = evaluate(robot, a, demo.T / sec, forces, "optimal",
                   f"{a.motion.T} knots, {sec:.0f} s{note}")
    if not row.feasible:
        binding = audit(robot, a.motion, a.wrenches, a.contacts,
                        target=measured_push(forces, a.motion.t)).binding
        row = replace(row, note=f"{row.note}; audit fails {', '.join(binding[:3])}")
    rows.append(row)


def _saved_optimal(folder: Path, robot, demo, forces, rows) -> None:
    """The optimal row from a plan that ``--save-plans`` wrote (and the time its adaptation
    took then): audited and simulated anew, e.g. after a change of the controller."""
    path = folder / f"{robot.name}_optimal.npz"
    loaded = load_demonstration(path)
    plan = Plan(loaded.motion, read_wrenches(path), dict(robot.require_contacts()))
    sec = json.loads((folder / f"{robot.name}_optimal.json").read_text())["seconds"]
    _optimal_row(robot, plan, demo, forces, sec, rows, f" (plan of {path.name}, re-simulated)")


#: holosoma-retargeting's ``smplx`` joint layout (its ``SMPLX_DEMO_JOINTS``), in order.
SMPLX_JOINTS = ("Pelvis", "L_Hip", "R_Hip", "Spine1", "L_Knee", "R_Knee", "Spine2", "L_Ankle",
                "R_Ankle", "Spine3", "L_Foot", "R_Foot", "Neck", "L_Collar", "R_Collar",
                "Head", "L_Shoulder", "R_Shoulder", "L_Elbow", "R_Elbow", "L_Wrist", "R_Wrist")
#: The CMU BVH joints whose mean is each SMPL-X joint (the BVH robot's links of those names;
#: CMU's LowerBack, Neck and shoulder joints sit where their parents end: averaged with the
#: next joint so that no two points coincide in holosoma's interaction mesh).
_BVH_SMPLX = {"Pelvis": ("Hips",), "L_Hip": ("LeftUpLeg",), "R_Hip": ("RightUpLeg",),
              "Spine1": ("LowerBack", "Spine"), "L_Knee": ("LeftLeg",),
              "R_Knee": ("RightLeg",), "Spine2": ("Spine",), "L_Ankle": ("LeftFoot",),
              "R_Ankle": ("RightFoot",), "Spine3": ("Spine", "Spine1"),
              "L_Foot": ("LeftToeBase",), "R_Foot": ("RightToeBase",), "Neck": ("Neck1",),
              "L_Collar": ("Spine1", "LeftArm"), "R_Collar": ("Spine1", "RightArm"),
              "Head": ("Head",), "L_Shoulder": ("LeftArm",), "R_Shoulder": ("RightArm",),
              "L_Elbow": ("LeftForeArm",), "R_Elbow": ("RightForeArm",),
              "L_Wrist": ("LeftHand",), "R_Wrist": ("RightHand",)}


def _frame_paths(robot, motion, frames) -> dict[str, np.ndarray]:
    import pinocchio as pin

    m, d = robot.model, robot.model.createData()
    out = {f: np.empty((motion.T, 3)) for f in frames}
    R = {f: np.empty((motion.T, 3, 3)) for f in frames}
    for k, q in enumerate(motion.q):
        pin.framesForwardKinematics(m, d, q)
        for f in frames:
            M = d.oMf[m.getFrameId(f)]
            out[f][k], R[f][k] = M.translation, M.rotation
    return out, R


def smplx_joints(robot, motion) -> tuple[np.ndarray, float]:
    """The demonstrator's global joint positions ``(T, 22, 3)`` [m] in holosoma's ``smplx``
    layout (:data:`SMPLX_JOINTS`) and its standing height [m]. A BVH skeleton: its joints by
    name (``_BVH_SMPLX``, CMU's names). An OpenSim gait model: hip, knee, ankle and toe joint
    centres (the body origins); the spine, neck and head along the torso from the lumbar joint
    to the ``Top.Head`` marker; shoulders 4 cm below the acromion markers and, the model having no
    arms, elbows and wrists hanging 0.29 m and 0.54 m below them along the torso (stated in
    the row's note)."""
    m = robot.model
    bvh = sorted({f for fs in _BVH_SMPLX.values() for f in fs})
    if all(m.existFrame(f) for f in bvh):
        P, _ = _frame_paths(robot, motion, bvh)
        J = np.stack([np.mean([P[f] for f in _BVH_SMPLX[j]], axis=0) for j in SMPLX_JOINTS],
                     axis=1)
    else:
        names = ["femur_l", "femur_r", "tibia_l", "tibia_r", "talus_l", "talus_r", "toes_l",
                 "toes_r", "torso", "L.Acromium", "R.Acromium", "Top.Head"]
        P, R = _frame_paths(robot, motion, names)
        up = R["torso"][:, :, 2]  # the torso's own up axis (the URDF's z)
        top = P["Top.Head"]
        base = P["torso"]
        along = lambda u: base + u * (top - base)  # noqa: E731
        sh = {s: P[f"{s}.Acromium"] - 0.04 * up for s in "LR"}
        J = {"Pelvis": 0.5 * (P["femur_l"] + P["femur_r"]) + 0.05 * up,
             "L_Hip": P["femur_l"], "R_Hip": P["femur_r"], "L_Knee": P["tibia_l"],
             "R_Knee": P["tibia_r"], "L_Ankle": P["talus_l"], "R_Ankle": P["talus_r"],
             "L_Foot": P["toes_l"], "R_Foot": P["toes_r"], "Spine1": along(0.15),
             "Spine2": along(0.35), "Spine3": along(0.5), "Neck": along(0.8),
             "Head": along(0.92), "L_Collar": along(0.72) + 0.5 * (sh["L"] - along(0.72)),
             "R_Collar": along(0.72) + 0.5 * (sh["R"] - along(0.72)),
             "L_Shoulder": sh["L"], "R_Shoulder": sh["R"],
             "L_Elbow": sh["L"] - 0.29 * up, "R_Elbow": sh["R"] - 0.29 * up,
             "L_Wrist": sh["L"] - 0.54 * up, "R_Wrist": sh["R"] - 0.54 * up}
        J = np.stack([J[j] for j in SMPLX_JOINTS], axis=1)
    height = float(np.median(J[:, SMPLX_JOINTS.index("Head"), 2]
                             - J[:, [10, 11], 2].min(axis=1))) + 0.12
    return J, height


def qpos_motion(robot, t: np.ndarray, qpos: np.ndarray, names: list[str],
                contact: dict | None = None):
    """A MuJoCo G1 ``qpos`` ``(T, 7 + n)`` (free joint x y z, quaternion w x y z; joints
    ``names``) as a Motion of ``robot`` on times ``t`` ``(T,)`` [s] (``contact``: its stance,
    or none), joints by name (the others at ``robot``'s neutral pose); and the joints
    ``robot`` lacks."""
    m = robot.model
    q = np.tile(robot.neutral, (len(qpos), 1))
    q[:, :3] = qpos[:, :3]
    q[:, 3:7] = qpos[:, [4, 5, 6, 3]]  # w x y z → x y z w
    q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    missing = [n for n in names if not m.existJointName(n)]
    for k, n in enumerate(names):
        if m.existJointName(n):
            q[:, m.joints[m.getJointId(n)].idx_q] = qpos[:, 7 + k]
    motion = gd.Motion(np.asarray(t, float).copy(), robot.joint_names, q,
                       {s: np.asarray(contact[s], bool).copy() for s in SIDES}
                       if contact else {}, 7,
                       tuple(m.joints[j].nq for j in range(1, m.njoints)))
    return motion, missing


def holosoma_motion(robot, demo, qpos: np.ndarray, names: list[str]):
    """Holosoma's G1 ``qpos`` as a Motion of ``robot`` on ``demo``'s times and contacts
    (:func:`qpos_motion`); and the joints ``robot`` lacks."""
    return qpos_motion(robot, demo.t, qpos, names, demo.contact)


def holosoma_plan(demo, demonstrator, robot, python: str):
    """OmniRetarget's retargeter (holosoma-retargeting, run by ``python`` in a subprocess:
    ``benchmarks/holosoma_run.py``) on the demonstrator's joint positions, its G1 output
    put on ``robot``'s joints by name → ``(BaselinePlan, note)``."""
    import subprocess
    import sys
    import tempfile

    J, height = smplx_joints(demonstrator, demo)
    J = J - np.r_[J[:, 0, :2].mean(axis=0), 0.0]  # centred on the origin (holosoma's ground)
    with tempfile.TemporaryDirectory() as tmp:
        src, out = Path(tmp) / "in.npz", Path(tmp) / "out.npz"
        np.savez(src, global_joint_positions=J, height=height)
        run = subprocess.run([python or sys.executable, str(Path(__file__).parent /
                              "holosoma_run.py"), str(src), str(out)], capture_output=True,
                             text=True, timeout=3600)
        if run.returncode != 0:
            raise RuntimeError(f"holosoma failed: {run.stderr[-400:]}")
        res = np.load(out)
        qpos, names, sec = res["qpos"], [str(n) for n in res["joint_names"]], float(
            res["seconds"])
        asked = float(res["scale"]) * float(np.linalg.norm(J[-1, 0, :2] - J[0, 0, :2]))
    motion, missing = holosoma_motion(robot, demo, qpos, names)
    went = float(np.linalg.norm(qpos[-1, :2] - qpos[0, :2]))
    note = (f"holosoma G1, its defaults (ground grid widened to the walk); {len(qpos)} frames "
            f"in {sec:.0f} s; its pelvis travels {went:.1f} m of the {asked:.1f} m asked"
            + (f"; joints not on {robot.name}: {missing}" if missing else ""))
    return kinematic_plan(robot, motion, "holosoma", sec), note


#: The shipped BVH walk GMR is run on (CMU 02_01; frame 0 is its calibration pose).
CMU_BVH = Path(gd.__file__).parent / "data" / "gait" / "cmu_02_01" / "cmu_02_01.bvh"


def gmr_motion(robot, python: str, repo: str, bvh: Path = CMU_BVH):
    """GMR (``benchmarks/gmr_run.py`` run by ``python`` with its checkout ``repo``) on the BVH
    walk ``bvh`` → its G1, put on ``robot``'s joints by name → ``(motion, seconds, note)``:
    the motion (q alone, on its BVH's clock from 0), GMR's wall time and a note."""
    import subprocess
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.npz"
        run = subprocess.run([python, str(Path(__file__).parent / "gmr_run.py"), str(repo),
                              str(bvh), str(out)], capture_output=True, text=True,
                             timeout=3600)
        if run.returncode != 0:
            raise RuntimeError(f"GMR failed: {run.stderr[-400:]}")
        res = np.load(out)
        qpos, names = res["qpos"], [str(n) for n in res["joint_names"]]
        fps, sec, height = float(res["fps"]), float(res["seconds"]), float(res["height"])
    motion, missing = qpos_motion(robot, np.arange(len(qpos)) / fps, qpos, names)
    note = (f"GMR's G1 (bvh_to_g1.json) on {bvh.stem}: {len(qpos)} frames at {fps:.0f} Hz in "
            f"{sec:.1f} s, human height {height:.2f} m"
            + (f"; joints not on {robot.name}: {missing}" if missing else ""))
    return motion, sec, note


@dataclass(frozen=True)
class RepairRow:
    """One kinematic output repaired on its own robot (``gdimitate.repair``): the clip it was
    made from, the retargeter's wall time for it [s], the share of knots the audit finds
    feasible and its verdict before/after, MuJoCo's fall time [s from the start]
    before/after (None: walked), the keypoints' RMS distance from the input [m], the push
    kept (RMS angle from the input's estimate, worse foot) [deg] and the repair's wall time
    [s]."""

    robot: str
    method: str
    clip: str
    retarget_seconds: float
    frames: int
    share_before: float
    share_after: float
    feasible_before: bool
    feasible_after: bool
    fell_before: float | None
    fell_after: float | None
    keypoint_rms: float
    push_deg: float
    seconds: float
    note: str = ""


def repair_row(robot, motion, method: str, clip: str, retarget_seconds: float,
               save: Path | None = None) -> RepairRow:
    """``motion`` (a kinematic output of ``method`` made from ``clip`` in
    ``retarget_seconds``) as its q alone repaired on ``robot`` and both run in MuJoCo;
    ``save``: a folder to write the input to as GMR's pickle first."""
    from gdimitate.apps.repair import simulate_both

    motion = motion.replace(contact={}, v=None, a=None)
    if save is not None:
        save.mkdir(parents=True, exist_ok=True)
        slug = "".join(c if c.isalnum() else "_" for c in method.lower()).strip("_")
        gd.export_motion(robot, motion, save / f"{robot.name}_{slug}.pkl", "gmr",
                         fps=round(1.0 / float(np.median(np.diff(motion.t))), 6))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r, sec = _timed(lambda: gd.repair(robot, motion))
    except gd.InvalidInputError as e:  # refused, with what to fix: a row that says it
        before = gd.audit_motion(robot, motion)
        nan = float("nan")
        return RepairRow(robot.name, method, clip, retarget_seconds, motion.T,
                         before.share_feasible, nan, before.feasible, False, None, None, nan,
                         nan, nan, str(e))
    sim = simulate_both(robot, motion, r)
    return RepairRow(robot.name, method, clip, retarget_seconds, motion.T,
                     r.before.share_feasible,
                     r.after.share_feasible, r.before.feasible, r.after.feasible,
                     sim["before"]["fall_time"], sim["after"]["fall_time"], r.keypoint_rms,
                     float(np.degrees(np.nanmax(list(r.push_error_rms.values())))), sec)


def repair_table(rows: list[RepairRow]) -> str:
    """The repair rows as a markdown table."""
    lines = ["| robot | input | clip, frames | retarget [s] | knots feasible before → after [%] "
             "| audit before → after | MuJoCo fell before → after [s] | keypoints kept RMS [cm] "
             "| push kept [deg RMS] | repair [s] |", "|---|---|---|---|---|---|---|---|---|---|"]
    refused = [r for r in rows if r.note]

    def fell(x: float | None) -> str:
        return "no" if x is None else f"{x:.2f}"

    def ok(x: bool) -> str:
        return "feasible" if x else "infeasible"

    def sec(x: float) -> str:
        return f"{x:.2g}" if x < 10 else f"{x:.0f}"

    for r in rows:
        head = f"| {r.robot} | {r.method} | {r.clip}, {r.frames} | {sec(r.retarget_seconds)} "
        lines.append(f"{head}| {100 * r.share_before:.0f} → "
                     f"{100 * r.share_after:.0f} | {ok(r.feasible_before)} → "
                     f"{ok(r.feasible_after)} | {fell(r.fell_before)} → {fell(r.fell_after)} "
                     f"| {100 * r.keypoint_rms:.1f} | {r.push_deg:.1f} | {r.seconds:.0f} |"
                     if not r.note else
                     f"{head}| {100 * r.share_before:.0f} → — | "
                     f"{ok(r.feasible_before)} → refused | — | — | — | — |")
    return "\n".join(lines + [f"\nRefused: {r.method} on {r.robot}: {r.note}" for r in refused])


def run(robots: list[str], optimal: bool = True, save: Path | None = None,
        plans: Path | None = None, holosoma: str | None = None,
        repaired: list[RepairRow] | None = None, gmr: tuple[str, str] | None = None,
        repair_only: bool = False, motions: Path | None = None) -> list[Row]:
    """Every method on every robot in ``robots`` (library names); ``save``: a folder for the
    optimal plans (``<robot>_optimal.npz`` and the adaptation's seconds in ``.json``);
    ``plans``: such a folder to take the optimal plans from instead of adapting anew;
    ``holosoma``: the Python that has ``holosoma-retargeting`` (its G1 row, G1 only);
    ``repaired``: a list to append each kinematic output's :func:`repair_row` to (None: no
    repair); ``gmr``: ``(python, repo)`` for GMR's repair row (G1, with ``repaired``);
    ``repair_only``: the repair rows alone (no main-table rows, no optimal adaptation);
    ``motions``: a folder to write each repaired input to (GMR's pickle)."""
    demonstrator, demo, forces = gd.gait.human_walk_3d()
    walk = "OpenSim walk"
    rows: list[Row] = []

    def ev(robot, plan, fps, label, note=""):
        if not repair_only:
            rows.append(evaluate(robot, plan, fps, forces, label, note))

    for name in robots:
        robot = gd.Robot.from_library(name)
        if robot.base == "planar":
            if repair_only:
                continue
            for method, label in (("copy", "copy (planar)"), ("analytic", "Eq. (1)")):
                a, sec = _timed(lambda m=method, r=robot: gd.adapt(demo, demonstrator, r,
                                                                    method=m))
                plan = kinematic_plan(robot, a.motion, method, sec)
                bad = sum(a.report.infeasible_frames.values())
                rows.append(evaluate(robot, plan, demo.T / sec, forces, label,
                                     f"{bad} leg-frames unreachable" if bad else ""))
        else:
            plan = joint_copy(demo, demonstrator, robot)
            ev(robot, plan, plan.frames_per_s, "copy (3-D)")
            if repaired is not None:
                repaired.append(repair_row(robot, plan.motion, "copy (3-D)", walk,
                                           plan.seconds, motions))
            plan = diff_ik(demo, demonstrator, robot)
            note = (f"keypoint error median {100 * np.median(plan.residual):.1f} cm; "
                    f"{int(plan.relaxed.sum())} frames feet held by cost")
            ev(robot, plan, plan.frames_per_s, "diff IK (Pink)", note)
            if repaired is not None:
                repaired.append(repair_row(robot, plan.motion, "diff IK (Pink)", walk,
                                           plan.seconds, motions))
            if holosoma and name.startswith("g1"):
                plan, note = holosoma_plan(demo, demonstrator, robot, holosoma)
                ev(robot, plan, plan.frames_per_s, "OmniRetarget (holosoma)", note)
                if repaired is not None:
                    repaired.append(repair_row(robot, plan.motion, "OmniRetarget (holosoma)",
                                               walk, plan.seconds, motions))
            if gmr and name.startswith("g1") and repaired is not None:
                motion, sec, note = gmr_motion(robot, *gmr)
                print(note, file=sys.stderr)
                repaired.append(repair_row(robot, motion, "GMR", "CMU BVH walk", sec, motions))
        if repair_only:
            continue
        if optimal and plans is not None:
            _saved_optimal(plans, robot, demo, forces, rows)
        elif optimal:
            _optimal(demo, demonstrator, robot, forces, rows, save)
    return rows


def _f(x: float, fmt: str) -> str:
    return "—" if x is None or not np.isfinite(x) else format(x, fmt)


def _pair(x: tuple[float, float]) -> str:
    return f"{_f(x[0], '.1f')} / {_f(x[1], '.1f')}"


def table(rows: list[Row]) -> str:
    """The rows as a markdown table."""
    head = ("| robot | method | frames/s | CoP out [% stance] | τ/τmax | plan push err [deg] "
            "| fell [s] | slip [cm] | sim push RMSE sagittal L / R [deg] "
            "| frontal L / R [deg] | audit | notes |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in rows:
        fell = "no" if r.fell_after is None else (
            f"{r.fell_after:.2f}" if np.isfinite(r.fell_after) else "not simulated")
        if not np.isfinite(r.frames_per_s):
            fell = "—"
        lines.append(
            f"| {r.robot} | {r.method} | "
            f"{_f(r.frames_per_s, ',.0f' if r.frames_per_s >= 10 else '.2g')} | "
            f"{_f(r.cop_out_pct, '.0f')} | {_f(r.torque_ratio, '.1f')} | "
            f"{_f(r.plan_push_deg, '.1f')} | {fell} | {_f(r.slip_cm, '.1f')} | "
            f"{_pair(r.sim_sag_deg)} | {_pair(r.sim_front_deg)} | "
            f"{'feasible' if r.feasible else 'infeasible'} | {r.note} |")
    return "\n".join(lines)


def negative_control(rows: list[Row]) -> str:
    """The physics check's negative control in words: does the 3-D joint copy fall or slip
    more than 5 cm on each free-flyer robot?"""
    out = []
    for r in rows:
        if r.method != "copy (3-D)":
            continue
        if r.fell_after is not None and not np.isfinite(r.fell_after):
            out.append(f"- {r.robot}: not simulated ({r.note})")
            continue
        fails = r.fell_after is not None or r.slip_cm > 5.0
        out.append(f"- {r.robot}: the 3-D joint copy "
                   + (f"fell after {r.fell_after:.2f} s" if r.fell_after is not None
                      else "did not fall")
                   + f", slip {r.slip_cm:.1f} cm — the negative control "
                   + ("fails the physics check, as it must." if fails else
                      "PASSES the physics check (see tests/apps/test_baselines.py)."))
    return "\n".join(out)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robots", nargs="+", default=["hoap2", "talos", "g1"])
    p.add_argument("--no-optimal", action="store_true", help="skip gdimitate's own adaptor")
    p.add_argument("--out", default=str(Path(__file__).with_name("peers.md")))
    p.add_argument("--save-plans", type=Path, default=None, metavar="DIR",
                   help="also write each optimal plan to DIR/<robot>_optimal.npz")
    p.add_argument("--plans", type=Path, default=None, metavar="DIR",
                   help="take the optimal plans from DIR (written by --save-plans) instead of "
                        "adapting anew: audit and simulate them again")
    p.add_argument("--holosoma-python", default=None, metavar="PYTHON",
                   help="a Python with holosoma-retargeting installed ('.[peers]', or a venv of "
                        "its own: it pins numpy==2.3.5): adds OmniRetarget's row on G1")
    p.add_argument("--repair", action="store_true",
                   help="also repair each kinematic output on its own robot (gdimitate.repair) "
                        "and print the before/after table")
    p.add_argument("--repair-only", action="store_true",
                   help="the repair table alone (G1's kinematic outputs and peers), written "
                        "into its block of --out, the rest of the file kept")
    p.add_argument("--gmr-python", default=None, metavar="PYTHON",
                   help="a Python with GMR's dependencies (mink, mujoco, qpsolvers[proxqp], "
                        "loop_rate_limiters, rich, tqdm, natsort): adds GMR's repair row on G1")
    p.add_argument("--gmr-repo", default=None, metavar="DIR",
                   help="a checkout of github.com/YanjieZe/GMR (with --gmr-python)")
    p.add_argument("--save-motions", type=Path, default=None, metavar="DIR",
                   help="write each repaired input to DIR as GMR's pickle (for gdimitate audit)")
    add_flag(p)
    a = p.parse_args(argv)
    if bool(a.gmr_python) != bool(a.gmr_repo):
        p.error("--gmr-python and --gmr-repo go together")
    t0 = time.perf_counter()
    repaired: list[RepairRow] | None = [] if (a.repair or a.repair_only) else None
    rows = run(["g1"] if a.repair_only else a.robots, optimal=not a.no_optimal,
               save=a.save_plans, plans=a.plans, holosoma=a.holosoma_python, repaired=repaired,
               gmr=(a.gmr_python, a.gmr_repo) if a.gmr_python else None,
               repair_only=a.repair_only, motions=a.save_motions)
    out = Path(a.out)
    if repaired is not None:
        cmd = " ".join(sys.argv[1:] if argv is None else argv)
        for flag, what in (("--holosoma-python", "PYTHON"), ("--gmr-python", "PYTHON"),
                           ("--gmr-repo", "DIR"), ("--save-motions", "DIR"), ("--out", "FILE")):
            cmd = re.sub(rf"{flag} \S+", f"{flag} {what}", cmd)
        block = (f"Written by `python benchmarks/peers.py {cmd}`"
                 f" ({time.perf_counter() - t0:.0f} s, {os.cpu_count()} CPUs, load "
                 f"{os.getloadavg()[0]:.1f}):\n\n" + repair_table(repaired))
        print(block)
    old = out.read_text() if out.exists() else ""
    if a.repair_only:
        out.write_text(with_repair(old or "# Baselines in the physics-check harness\n", block))
        return
    text = (table(rows)
            + "\n\nNegative control (physics check):\n" + negative_control(rows)
            + f"\n\nDemonstration: OpenSim subject01 walk (3-D, measured GRF), 211 frames, 3.5 s; "
            f"simulation: MuJoCo, 1 kHz QP tracking controller; run took "
            f"{time.perf_counter() - t0:.0f} s.\n")
    print(text)
    text = ("# Baselines in the physics-check harness\n\nWritten by `python benchmarks/peers.py`; "
            "columns explained in its docstring.\n\n" + text)
    if REPAIR_HEAD in old:  # the repair section of an earlier run stays
        text = text.rstrip("\n") + "\n\n" + old[old.index(REPAIR_HEAD):]
    out.write_text(text if repaired is None else with_repair(text, block))


#: The heading of peers.md's repair section (its table in the block ``repair``).
REPAIR_HEAD = "## Repaired on the same robot"


def with_repair(text: str, block: str) -> str:
    """``text`` (peers.md) with its repair block holding ``block``; the section (heading and
    block) appended if absent."""
    if REPAIR_HEAD not in text:
        text = (text.rstrip("\n") + f"\n\n{REPAIR_HEAD} (issue 36)\n\n<!-- results: repair -->\n"
                "<!-- /results: repair -->\n")
    return replace_block(text, "repair", block)


if __name__ == "__main__":
    with recording("peers", "--results" in sys.argv[1:]):
        main()
