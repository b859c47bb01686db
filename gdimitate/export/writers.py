"""Write a robot's motion in the formats other tools read, and read them back.

Formats (:data:`FORMATS`; ``gdimitate export`` and
:meth:`gdimitate.AdaptedMotion.save` call :func:`export_motion`):

- ``"csv"``: a header row, then one row per frame: ``time`` [s], the floating base's pose
  ``base_x, base_y, base_z`` [m] and ``base_qx, base_qy, base_qz, base_qw`` (the base link's
  orientation in the world, unit quaternion, scalar LAST — Pinocchio's order; our planar base
  written as the same 3-D pose, y = 0), then every joint [rad or m] in Pinocchio order (an
  unbounded revolute as its angle). A fixed base has no base columns. :func:`read_csv`.
- ``"npz"``: :meth:`Motion.to_npz` with the robot recorded (name, source, fingerprint: read
  back with :func:`gdimitate.io.demonstration.load_demonstration` without naming the robot),
  ``v``/``a`` ``(T, nv)`` where the motion has them, and, for an adaptor's output, the contact
  wrenches ``wrench_left``/``wrench_right`` ``(T, 6)`` ``[f; τ]`` [N, N·m] in each sole frame
  (``wrench_frame_left``/``_right`` name it) with, where the motion has ``v`` and ``a``,
  the joint torques they imply, ``joint_torque`` ``(T, D)`` [N·m, N] (the audit's inverse
  dynamics ``rnea(q, v, a) − Σ Jᵀw`` without the base's rows; ``joint_torque_names``, the
  actuated joints in Pinocchio's order). :func:`read_wrenches`.
- ``"mujoco"``: an NPZ with ``time`` ``(T,)``, ``qpos`` ``(T, nq_mj)`` (and ``qvel``
  ``(T, nv_mj)`` where the motion has ``v``) in MuJoCo's joint order and conventions (free
  joint: position, then quaternion w, x, y, z; linear velocity in the world, angular in the
  body) for the model :func:`gdimitate.sim.build_model` makes of the robot; ``joint_names``
  (MuJoCo's joints in order) and ``mjcf`` (that model's MJCF text, so the file can be played
  without gdimitate). :func:`read_mujoco`.
- ``"lafan1_csv"``: the retargeted-motion CSV of unitreerobotics' LAFAN1_Retargeting_Dataset,
  the input of BeyondMimic's ``whole_body_tracking`` (``scripts/csv_to_npz.py``) and of
  mjlab's motion-tracking task: no header, one row per frame at a fixed rate (``fps``,
  default 30 Hz, the dataset's), ``x, y, z`` [m], quaternion ``qx, qy, qz, qw`` (their loader
  reorders it to w, x, y, z), then the joint angles [rad] in the robot's URDF order (for
  Unitree G1: left leg, right leg, waist, left arm, right arm — Pinocchio's order). Needs a
  free-flyer robot with 1-DoF joints; the motion is resampled onto the fps grid (joints and
  position linearly, the quaternion by slerp). :func:`read_lafan1_csv`.
- ``"gmr"``: the motion pickle of GMR (General Motion Retargeting, YanjieZe/GMR) that
  tracking pipelines read: a dict with ``fps``, ``root_pos`` ``(N, 3)`` [m], ``root_rot``
  ``(N, 4)`` (x, y, z, w), ``dof_pos`` ``(N, D)`` [rad] (the 1-DoF joints in Pinocchio's
  order, which is the URDF's and MuJoCo's), ``local_body_pos`` ``(N, B, 3)`` [m] (each body's
  origin in the root body's frame: root at the origin, unrotated) and ``link_body_list``
  (``B`` names). :func:`read_gmr`.
- ``"isaaclab_amp"``: the motion NPZ of Isaac Lab's AMP tasks (``humanoid_amp``'s
  ``MotionLoader``): ``fps`` (int), ``dof_names`` ``(D,)``, ``body_names`` ``(B,)``,
  ``dof_positions``/``dof_velocities`` ``(N, D)`` [rad, rad/s], ``body_positions``
  ``(N, B, 3)`` [m] and ``body_rotations`` ``(N, B, 4)`` (w, x, y, z) in the world,
  ``body_linear_velocities``/``body_angular_velocities`` ``(N, B, 3)`` [m/s, rad/s] in the
  world (of each body's origin); float64 (the loader casts to float32).
  :func:`read_isaaclab_amp`.
- ``"beyondmimic_npz"``: the motion NPZ BeyondMimic's ``whole_body_tracking`` trains from (its
  ``csv_to_npz.py`` makes it by replaying a CSV in Isaac Sim; mjlab and holosoma read the same
  keys): ``fps`` ``(1,)``, ``joint_pos``/``joint_vel`` ``(N, J)`` [rad, rad/s] in MuJoCo's
  joint order (``joint_names``), and for every body of the MuJoCo model
  :func:`gdimitate.sim.build_model` makes (``body_names``, MuJoCo's order, the world left
  out) ``body_pos_w`` ``(N, B, 3)`` [m], ``body_quat_w`` ``(N, B, 4)`` (w, x, y, z),
  ``body_lin_vel_w``/``body_ang_vel_w`` ``(N, B, 3)`` [m/s, rad/s] of the body frame's origin
  in the world — MuJoCo's own ``mj_forward`` and ``mj_objectVelocity`` on that model; float64
  (the loaders cast to float32). With ``wrenches`` it also carries gdimitate's
  ``contact_wrench_<side>`` ``(N, 6)`` [N, N·m] (each sole frame, ``contact_frame_<side>``)
  and the joint torques they imply, ``joint_torque`` ``(N, J)`` [N·m] in ``joint_names``'
  order (as ``"npz"``'s, interpolated onto the frames like the wrenches).
  Isaac Sim numbers an articulation's bodies breadth-first; the file's ``body_names`` say which
  body is which. :func:`read_beyondmimic_npz`.

Both resample onto the ``fps`` grid (as ``"lafan1_csv"``) and need a free-flyer robot with
1-DoF joints. Bodies are the robot's moving links: the root and the child link of every joint
(links on fixed joints belong to their parent, as MuJoCo's and Isaac Lab's URDF importers merge
them). Their ORDER is stated in the file (``"gmr"``: ``body_order`` key; ``"isaaclab_amp"``:
``body_order`` array) and chosen with ``body_order=``: ``"depth"`` — depth-first, the URDF's
tree order as MuJoCo numbers bodies (``"gmr"``'s default) — or ``"breadth"`` — breadth-first,
as PhysX numbers an articulation's links (``"isaaclab_amp"``'s default). Reading a file with
the other order's index lists has broken training elsewhere: check ``body_names``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import ExportError, FileFormatError, OutputError
from ..model.kinematics import base_joint_id
from ..model.motion import Motion, check_base_quaternion, check_motion_layout
from ..model.robot import PLANAR_BASE, SIDES, Robot
from ..safety import check_array_size, check_positive

__all__ = ["BODY_ORDERS", "FORMATS", "BeyondMimicMotion", "MujocoMotion", "body_links",
           "export_motion", "read_beyondmimic_npz", "read_csv", "read_gmr", "read_isaaclab_amp",
           "read_lafan1_csv", "read_mujoco", "read_wrenches"]

#: Export formats and the file each one writes.
FORMATS: dict[str, str] = {
    "csv": "CSV: time, base pose (x, y, z, qx, qy, qz, qw), every joint",
    "npz": "NPZ: q, v, a, contact wrenches, robot metadata (gdimitate's own)",
    "mujoco": "NPZ: MuJoCo qpos/qvel for gdimitate.sim's model, with its MJCF",
    "lafan1_csv": "CSV without header at 30 Hz: x, y, z, qx, qy, qz, qw, joints "
                  "(LAFAN1 retargeted; BeyondMimic whole_body_tracking / mjlab)",
    "gmr": "pickle: fps, root_pos, root_rot (x y z w), dof_pos, local_body_pos, "
           "link_body_list (GMR; bodies depth-first)",
    "isaaclab_amp": "NPZ: fps, dof_names, body_names, dof/body positions, rotations (w x y z), "
                    "velocities (Isaac Lab AMP; bodies breadth-first)",
    "beyondmimic_npz": "NPZ: fps, joint_pos/vel, body_pos_w, body_quat_w (w x y z), "
                       "body_lin/ang_vel_w from MuJoCo (BeyondMimic, mjlab, holosoma)",
}
#: Body orders of the ``"gmr"``/``"isaaclab_amp"`` exports (see the module docstring).
BODY_ORDERS = ("depth", "breadth")
BASE_COLUMNS = ("base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw")


def export_motion(robot: Robot, motion: Motion, path: str | Path, format: str = "npz", *,
                  wrenches: Mapping[str, np.ndarray] | None = None, fps: float = 30.0,
                  body_order: str | None = None) -> Path:
    """Write ``motion`` (of ``robot``) to ``path`` in ``format`` (:data:`FORMATS`).

    ``wrenches``: ``{"left": (T, 6), "right": (T, 6)}`` sole-frame contact wrenches [N, N·m]
    (``"npz"`` and ``"beyondmimic_npz"`` store them); ``fps`` [Hz]: the frame rate of
    ``"lafan1_csv"``, ``"gmr"``, ``"isaaclab_amp"`` and ``"beyondmimic_npz"`` (BeyondMimic's
    own ``csv_to_npz.py`` writes 50); ``body_order``: ``"depth"`` or ``"breadth"`` for
    ``"gmr"`` and ``"isaaclab_amp"`` (default: ``"depth"`` for ``"gmr"``, ``"breadth"`` for
    ``"isaaclab_amp"``). Returns the
    path written. Raises :class:`~gdimitate.errors.ExportError` for an unknown format or a
    robot/motion the format cannot hold, :class:`~gdimitate.errors.ResourceLimitError` for an
    ``fps`` whose frames exceed :data:`~gdimitate.safety.MAX_ARRAY_BYTES`,
    :class:`~gdimitate.errors.OutputError` for a ``path`` that is a folder, in a folder that
    does not exist, or cannot be written."""
    from ..model.inputs import path_arg

    if not isinstance(robot, Robot):
        raise ExportError(f"robot must be a gdimitate.Robot; got {type(robot).__name__}")
    if not isinstance(motion, Motion):
        raise ExportError(f"motion must be a gdimitate.Motion; got {type(motion).__name__}")
    if not isinstance(format, str) or format not in FORMATS:
        raise ExportError(f"unknown export format {format!r:.40}; choose one of "
                          + ", ".join(f"{k} ({v})" for k, v in FORMATS.items()))
    fps = check_positive("fps (frames per second)", fps, error=ExportError)
    if tuple(robot.joint_names) != motion.joint_names:
        raise ExportError(f"the motion's joints are not robot {robot.name!r}'s")
    # the layout (base_nq from the robot, never the motion's own) and every quaternion
    motion = check_motion_layout(robot, motion, f"export of {robot.name!r}", ExportError,
                                 recorded=False)
    path = path_arg("path", path).expanduser()
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a folder; give a file name")
    if not path.parent.is_dir():
        raise OutputError(f"cannot write {path}: folder {path.parent} does not exist; create "
                          "it first")
    if body_order is not None and (format not in ("gmr", "isaaclab_amp")
                                   or body_order not in BODY_ORDERS):
        raise ExportError(f"body_order={body_order!r}: 'depth' or 'breadth', for the gmr and "
                          "isaaclab_amp formats")
    writer = {"csv": _write_csv, "npz": _write_npz, "mujoco": _write_mujoco,
              "lafan1_csv": _write_lafan1, "gmr": _write_gmr,
              "isaaclab_amp": _write_isaaclab_amp, "beyondmimic_npz": _write_beyondmimic}[format]
    try:
        writer(robot, motion, path, wrenches=wrenches, fps=fps, body_order=body_order)
    except OSError as e:
        raise OutputError(f"cannot write {path}: {e.strerror or e}") from None
    return path


# ---------------------------------------------------------------------- base pose
def base_pose(robot: Robot, q: np.ndarray) -> np.ndarray:
    """The base link's world pose ``(T, 7)`` ``[x, y, z, qx, qy, qz, qw]`` for q ``(T, nq)``
    (forward kinematics; a free-flyer's is ``q[:, :7]`` up to the quaternion's sign)."""
    j = base_joint_id(robot)
    m, d = robot.model, robot.model.createData()
    out = np.empty((len(q), 7))
    for k, qk in enumerate(q):
        pin.forwardKinematics(m, d, qk)
        out[k] = pin.SE3ToXYZQUAT(d.oMi[j])
    if robot.base == "free":  # keep the file's own sign (q and −q are one rotation)
        flip = np.sum(out[:, 3:7] * q[:, 3:7], axis=1) < 0
        out[flip, 3:7] *= -1
    return out


def _joint_columns(robot: Robot, q: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Names and values ``(T, n)`` of every non-base joint (unbounded revolutes as angles)."""
    m = robot.model
    names, cols = [], []
    for j in range(1, m.njoints):
        jm, name = m.joints[j], m.names[j]
        if (robot.base == "free" and j == 1) or name in PLANAR_BASE:
            continue
        i = jm.idx_q
        if jm.nq == 1:
            cols.append(q[:, i])
        elif jm.nq == 2 and jm.nv == 1:
            cols.append(np.arctan2(q[:, i + 1], q[:, i]))
        else:
            raise ExportError(f"joint {name!r} ({jm.shortname()}) has {jm.nq} coordinates; "
                              "the CSV formats hold 1-DoF joints only")
        names.append(name)
    return names, np.column_stack(cols) if cols else np.zeros((len(q), 0))


def _require_pose(pose: np.ndarray | None, robot: Robot, where: object) -> np.ndarray:
    """The base pose ``(T, 7)``, or FileFormatError: a moving base needs one."""
    if pose is None:
        raise FileFormatError(f"{where}: no base pose columns for robot {robot.name!r}, whose "
                              f"base is {robot.base!r}")
    return pose


def _q_from_columns(robot: Robot, pose: np.ndarray | None, joints: np.ndarray,
                    names: list[str], where: object) -> np.ndarray:
    """Pinocchio q ``(T, nq)`` from a base pose ``(T, 7)`` and joint columns."""
    m = robot.model
    T = joints.shape[0]
    q = np.tile(pin.neutral(m), (T, 1))
    for k, name in enumerate(names):
        jm = m.joints[m.getJointId(name)]
        if jm.nq == 2:
            q[:, jm.idx_q], q[:, jm.idx_q + 1] = np.cos(joints[:, k]), np.sin(joints[:, k])
        else:
            q[:, jm.idx_q] = joints[:, k]
    if robot.base == "free":
        pose = _require_pose(pose, robot, where)
        check_base_quaternion(pose, 7, where)
        q[:, :7] = pose
    elif robot.base == "planar":
        pose = _require_pose(pose, robot, where)
        R = [pin.Quaternion(*p[[6, 3, 4, 5]]).normalized().matrix() for p in pose]
        q[:, robot.idx_q("base_x")] = pose[:, 0]
        q[:, robot.idx_q("base_z")] = pose[:, 2]
        q1 = pin.neutral(m)
        q1[robot.idx_q("base_pitch")] = 1.0  # the pitch axis: the rotation 1 rad makes
        axis = pin.log3(pin.XYZQUATToSE3(base_pose(robot, q1[None])[0]).rotation)
        q[:, robot.idx_q("base_pitch")] = [float(pin.log3(r) @ axis) for r in R]
        back = base_pose(robot, q)
        err = np.abs(back[:, :3] - pose[:, :3]).max()
        if err > 1e-6:
            raise FileFormatError(f"{where}: the base pose is not a sagittal one (x, z, pitch) "
                                  f"of robot {robot.name!r} (off by {err:.3g} m)")
    return q


# ---------------------------------------------------------------------- csv
def _write_csv(robot, motion, path, **_) -> None:
    names, cols = _joint_columns(robot, motion.q)
    base = [] if robot.base == "fixed" else [base_pose(robot, motion.q)]
    head = ["time", *(BASE_COLUMNS if base else ()), *names]
    data = np.column_stack([motion.t, *base, cols])
    np.savetxt(path, data, delimiter=",", header=",".join(head), comments="", fmt="%.17g")


def read_csv(path: str | Path, robot: Robot) -> Motion:
    """Read a ``"csv"`` export back onto ``robot`` → :class:`Motion` (no contacts, v or a).

    Raises :class:`~gdimitate.errors.FileFormatError` when the header's columns are not the
    robot's (naming the missing and extra ones)."""
    path = Path(path)
    try:
        head = path.read_text().splitlines()[0].split(",")
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, IndexError, ValueError) as e:
        raise FileFormatError(f"{path}: not a gdimitate CSV export ({e})") from None
    names, _ = _joint_columns(robot, np.tile(robot.neutral, (1, 1)))
    want = ["time", *(BASE_COLUMNS if robot.base != "fixed" else ()), *names]
    if head != want:
        raise FileFormatError(f"{path}: columns do not match robot {robot.name!r}: missing "
                              f"{sorted(set(want) - set(head))}, extra "
                              f"{sorted(set(head) - set(want))}")
    nb = 7 if robot.base != "fixed" else 0
    q = _q_from_columns(robot, data[:, 1:1 + nb] if nb else None, data[:, 1 + nb:], names, path)
    return Motion(t=data[:, 0], joint_names=robot.joint_names, q=q,
                  base_nq={"free": 7, "planar": 3}.get(robot.base, 0),
                  joint_nq=tuple(robot.model.joints[j].nq for j in range(1, robot.model.njoints)))


# ---------------------------------------------------------------------- npz
def _checked_wrenches(motion: Motion, wrenches) -> dict[str, np.ndarray]:
    """``wrenches`` as float arrays, each ``(T, 6)`` (else :class:`ExportError`)."""
    out = {}
    for s in SIDES:
        w = np.asarray(wrenches[s], dtype=float)
        if w.shape != (motion.T, 6):
            raise ExportError(f"wrenches[{s!r}] must have shape ({motion.T}, 6); got {w.shape}")
        out[s] = w
    return out


def _joint_torques(robot: Robot, motion: Motion, wrenches) -> np.ndarray | None:
    """The actuated joints' torques ``(T, nv − base)`` [N·m, N] in Pinocchio's velocity order
    that the motion's ``v``, ``a`` and the contact ``wrenches`` imply — the audit's own inverse
    dynamics (:func:`gdimitate.assess.audit.checks.joint_torques`) — or None without wrenches, ``v``
    or ``a`` (nothing to compute them from)."""
    if wrenches is None or motion.v is None or motion.a is None:
        return None
    from ..assess.audit.checks import joint_torques

    return joint_torques(robot, motion, wrenches)[:, _base_nv(robot):]


def _base_nv(robot: Robot) -> int:
    """The base's velocity dimension: 6 (free), 3 (planar) or 0 (fixed)."""
    return {"free": 6, "planar": 3}.get(robot.base, 0)


def _torque_names(robot: Robot) -> list[str]:
    """A name per actuated velocity column: the joint's, ``joint[i]`` for a multi-DoF one."""
    m, names = robot.model, []
    for j in range(1, m.njoints):
        if m.joints[j].idx_v < _base_nv(robot):
            continue
        nv = m.joints[j].nv
        names += [m.names[j]] if nv == 1 else [f"{m.names[j]}[{i}]" for i in range(nv)]
    return names


def _write_npz(robot, motion, path, wrenches=None, **_) -> None:
    extra = {}
    if wrenches is not None:
        wrenches = _checked_wrenches(motion, wrenches)
        for s in SIDES:
            extra[f"wrench_{s}"] = wrenches[s]
            c = robot.contacts.get(s)
            extra[f"wrench_frame_{s}"] = np.array(c.frame if c else robot.legs[s].sole)
        tau = _joint_torques(robot, motion, wrenches)
        if tau is not None:
            extra["joint_torque"] = tau
            extra["joint_torque_names"] = np.array(_torque_names(robot))
    with open(path, "wb") as f:  # a file object: np.savez would append ".npz" to a name
        motion.to_npz(f, robot=robot, extra=extra)


def read_wrenches(path: str | Path) -> dict[str, np.ndarray] | None:
    """The contact wrenches ``{side: (T, 6)}`` of an ``"npz"`` export, or None."""
    from ..safety import open_npz

    with open_npz(path) as z:
        if not all(f"wrench_{s}" in z.files for s in SIDES):
            return None
        return {s: z[f"wrench_{s}"] for s in SIDES}


# ---------------------------------------------------------------------- mujoco
@dataclass(frozen=True)
class MujocoMotion:
    """A ``"mujoco"`` export: ``time`` ``(T,)`` [s]; ``qpos`` ``(T, nq_mj)``; ``qvel``
    ``(T, nv_mj)`` or None; ``joint_names`` (MuJoCo joint order); ``mjcf`` (the model's
    MJCF text)."""

    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray | None
    joint_names: tuple[str, ...]
    mjcf: str


def _write_mujoco(robot, motion, path, **_) -> None:
    import mujoco

    from ..model.mjcf import build_model

    sim = build_model(robot)
    qpos = np.array([sim.qpos_from_q(q) for q in motion.q])
    arrays = dict(time=motion.t, qpos=qpos,
                  joint_names=np.array([mujoco.mj_id2name(sim.mj, mujoco.mjtObj.mjOBJ_JOINT, i)
                                        for i in range(sim.mj.njnt)]),
                  mjcf=np.array(sim.spec.to_xml()))
    if motion.v is not None:
        arrays["qvel"] = np.array([sim.qvel_from_v(q, v) for q, v in zip(motion.q, motion.v)])
    with open(path, "wb") as f:
        np.savez(f, **arrays)


def read_mujoco(path: str | Path) -> MujocoMotion:
    """Read a ``"mujoco"`` export."""
    from ..safety import open_npz

    with open_npz(path, ("time", "qpos", "joint_names", "mjcf")) as z:
        return MujocoMotion(z["time"], z["qpos"], z["qvel"] if "qvel" in z.files else None,
                            tuple(str(n) for n in z["joint_names"]), str(z["mjcf"]))


# ---------------------------------------------------------------------- lafan1 csv
def _resample(robot: Robot, motion: Motion, t: np.ndarray) -> np.ndarray:
    """q ``(len(t), nq)`` at times ``t``: linear in every column, the base quaternion by
    slerp between the neighbouring frames."""
    q = np.column_stack([np.interp(t, motion.t, motion.q[:, i]) for i in range(motion.q.shape[1])])
    k = np.clip(np.searchsorted(motion.t, t, side="right") - 1, 0, motion.T - 2)
    u = (t - motion.t[k]) / (motion.t[k + 1] - motion.t[k])
    for r, (i, ui) in enumerate(zip(k, u)):
        a = pin.Quaternion(*motion.q[i, [6, 3, 4, 5]])
        b = pin.Quaternion(*motion.q[i + 1, [6, 3, 4, 5]])
        q[r, 3:7] = a.slerp(float(np.clip(ui, 0.0, 1.0)), b).normalized().coeffs()
    return q


def _fps_grid(robot: Robot, motion: Motion, fps, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Times ``(N,)`` on the ``fps`` grid over the motion and q ``(N, nq)`` resampled onto
    them, for a free-flyer robot with 1-DoF joints."""
    if robot.base != "free":
        raise ExportError(f"{what} holds a free-floating base; robot {robot.name!r} has a "
                          f"{robot.base} base")
    if any(robot.model.joints[j].nq != 1 for j in range(2, robot.model.njoints)):
        raise ExportError(f"{what} holds 1-DoF joints only")
    fps = check_positive("fps (frames per second)", fps, error=ExportError)
    n = check_array_size(f"{what} at {fps:g} frames/s over {motion.t[-1] - motion.t[0]:g} s",
                         (np.floor((motion.t[-1] - motion.t[0]) * fps + 1e-9) + 1,
                          motion.q.shape[1]))[0]
    t = motion.t[0] + np.arange(n) / fps
    return t, _resample(robot, motion, t)


def _write_lafan1(robot, motion, path, fps=30.0, **_) -> None:
    t, q = _fps_grid(robot, motion, fps, "lafan1_csv")
    names, cols = _joint_columns(robot, q)
    np.savetxt(path, np.column_stack([q[:, :7], cols]), delimiter=",", fmt="%.17g")


def read_lafan1_csv(path: str | Path, robot: Robot, fps: float = 30.0) -> Motion:
    """Read a ``"lafan1_csv"`` file (ours or the dataset's) onto a free-flyer ``robot``
    whose 1-DoF joints, in Pinocchio order, are the file's joint columns → :class:`Motion`
    (``t = k / fps``, no contacts)."""
    path = Path(path)
    try:
        data = np.loadtxt(path, delimiter=",", ndmin=2)
    except (OSError, ValueError) as e:
        raise FileFormatError(f"{path}: not a LAFAN1-style CSV of numbers ({e})") from None
    names, _ = _joint_columns(robot, np.tile(robot.neutral, (1, 1)))
    if robot.base != "free" or data.shape[1] != 7 + len(names):
        raise FileFormatError(f"{path}: {data.shape[1]} columns; robot {robot.name!r} needs "
                              f"7 + {len(names)} (free-flyer pose + its joints)")
    q = _q_from_columns(robot, data[:, :7], data[:, 7:], names, path)
    return Motion(t=np.arange(len(data)) / fps, joint_names=robot.joint_names, q=q, base_nq=7,
                  joint_nq=tuple(robot.model.joints[j].nq for j in range(1, robot.model.njoints)))


# ---------------------------------------------------------------------- bodies (gmr, amp)
def body_links(robot: Robot, order: str = "depth") -> list[tuple[str, int]]:
    """The robot's moving links ``[(link name, Pinocchio frame id), …]``: the root and the
    child link of every joint, ``"depth"``-first (Pinocchio's joint order: the URDF tree as
    MuJoCo numbers its bodies) or ``"breadth"``-first (PhysX's articulation order)."""
    if order not in BODY_ORDERS:
        raise ExportError(f"body order {order!r}: choose 'depth' or 'breadth'")
    m = robot.model
    link = {}
    for i, f in enumerate(m.frames):
        if f.type == pin.FrameType.BODY and f.parentJoint not in link and \
                m.frames[f.parentFrame].type == pin.FrameType.JOINT:
            link[f.parentJoint] = i
    joints = list(range(1, m.njoints))
    if order == "breadth":
        children = {j: [c for c in joints if m.parents[c] == j] for j in [0, *joints]}
        joints, queue = [], list(children[0])
        while queue:
            j = queue.pop(0)
            joints.append(j)
            queue += children[j]
    return [(m.frames[link[j]].name, link[j]) for j in joints]


def _body_kinematics(robot: Robot, q: np.ndarray, v: np.ndarray, ids: list[int]):
    """World position ``(N, B, 3)``, rotation ``(N, B, 3, 3)``, linear and angular velocity
    ``(N, B, 3)`` (of each body origin, world axes) of the frames ``ids``."""
    m, d = robot.model, robot.model.createData()
    N, B = len(q), len(ids)
    p, R = np.empty((N, B, 3)), np.empty((N, B, 3, 3))
    lin, ang = np.empty((N, B, 3)), np.empty((N, B, 3))
    for k in range(N):
        pin.forwardKinematics(m, d, q[k], v[k])
        pin.updateFramePlacements(m, d)
        for b, i in enumerate(ids):
            p[k, b], R[k, b] = d.oMf[i].translation, d.oMf[i].rotation
            nu = pin.getFrameVelocity(m, d, i, pin.LOCAL_WORLD_ALIGNED)
            lin[k, b], ang[k, b] = nu.linear, nu.angular
    return p, R, lin, ang


def _training_frames(robot, motion, fps, what):
    """The resampled motion (t, q, v) for the gmr/isaaclab_amp writers."""
    from ..model.motion import differentiate

    t, q = _fps_grid(robot, motion, fps, what)
    if len(t) < 2:
        raise ExportError(f"{what}: the motion spans less than one frame at {fps:g} frames/s")
    nq = tuple(robot.model.joints[j].nq for j in range(1, robot.model.njoints))
    m = differentiate(robot.model, Motion(t, robot.joint_names, q, base_nq=7, joint_nq=nq))
    return t, q, m.v


def _write_gmr(robot, motion, path, fps=30.0, body_order=None, **_) -> None:
    import pickle

    order = body_order or "depth"
    t, q, v = _training_frames(robot, motion, fps, "gmr")
    links = body_links(robot, order)
    p, R, _, _ = _body_kinematics(robot, q, v, [i for _, i in links])
    root = [pin.XYZQUATToSE3(qk[:7]) for qk in q]
    local = np.array([(p[k] - root[k].translation) @ root[k].rotation for k in range(len(q))])
    data = {"fps": float(fps), "root_pos": q[:, :3].copy(), "root_rot": q[:, 3:7].copy(),
            "dof_pos": q[:, 7:].copy(), "local_body_pos": local,
            "link_body_list": [n for n, _ in links], "body_order": order,
            "dof_names": list(robot.joint_names[1:])}
    with open(path, "wb") as f:
        pickle.dump(data, f, protocol=4)


def _write_isaaclab_amp(robot, motion, path, fps=30.0, body_order=None, **_) -> None:
    order = body_order or "breadth"
    if abs(fps - round(fps)) > 1e-9:
        raise ExportError(f"isaaclab_amp stores fps as an integer; got {fps!r}")
    t, q, v = _training_frames(robot, motion, fps, "isaaclab_amp")
    links = body_links(robot, order)
    p, R, lin, ang = _body_kinematics(robot, q, v, [i for _, i in links])
    wxyz = np.array([[pin.Quaternion(Rb).coeffs()[[3, 0, 1, 2]] for Rb in Rk] for Rk in R])
    with open(path, "wb") as f:
        np.savez(f, fps=np.int64(round(fps)), dof_names=np.array(robot.joint_names[1:]),
                 body_names=np.array([n for n, _ in links]), body_order=np.array(order),
                 dof_positions=q[:, 7:], dof_velocities=v[:, 6:], body_positions=p,
                 body_rotations=wxyz, body_linear_velocities=lin, body_angular_velocities=ang)


def _free_motion(robot: Robot, t, root_xyzquat, dof, where) -> Motion:
    names, _ = _joint_columns(robot, np.tile(robot.neutral, (1, 1)))
    if dof.shape[1] != len(names):
        raise FileFormatError(f"{where}: {dof.shape[1]} joint columns; robot {robot.name!r} "
                              f"has {len(names)}")
    q = _q_from_columns(robot, root_xyzquat, dof, names, where)
    return Motion(t=t, joint_names=robot.joint_names, q=q, base_nq=7,
                  joint_nq=tuple(robot.model.joints[j].nq for j in range(1, robot.model.njoints)))


def read_gmr(path: str | Path, robot: Robot) -> Motion:
    """Read a ``"gmr"`` pickle onto a free-flyer ``robot`` → :class:`Motion` (``t = k /
    fps``). Only the arrays are used (``pickle`` runs code from the file: read only files you
    trust, as GMR itself does)."""
    import pickle

    path = Path(path)
    try:
        with open(path, "rb") as f:
            d = pickle.load(f)
        fps, rp, rr, dof = (d["fps"], np.asarray(d["root_pos"], float),
                            np.asarray(d["root_rot"], float), np.asarray(d["dof_pos"], float))
    except (OSError, KeyError, TypeError, pickle.UnpicklingError, EOFError) as e:
        raise FileFormatError(f"{path}: not a GMR motion pickle ({e!r})") from None
    return _free_motion(robot, np.arange(len(rp)) / float(fps), np.column_stack([rp, rr]), dof,
                        path)


def read_isaaclab_amp(path: str | Path, robot: Robot) -> Motion:
    """Read an ``"isaaclab_amp"`` NPZ onto a free-flyer ``robot`` → :class:`Motion` (the root
    body's pose and ``dof_positions`` by ``dof_names``; ``t = k / fps``)."""
    from ..safety import open_npz

    keys = ("fps", "dof_names", "body_names", "dof_positions", "body_positions",
            "body_rotations")
    with open_npz(path, keys) as z:
        fps, names = int(z["fps"]), [str(n) for n in z["dof_names"]]
        dof, bp, br = z["dof_positions"], z["body_positions"], z["body_rotations"]
    want = list(robot.joint_names[1:])
    if sorted(names) != sorted(want):
        raise FileFormatError(f"{path}: dof_names are not robot {robot.name!r}'s joints")
    dof = dof[:, [names.index(n) for n in want]]
    root = np.column_stack([bp[:, 0], br[:, 0][:, [1, 2, 3, 0]]])
    return _free_motion(robot, np.arange(len(dof)) / fps, root, dof, path)


# ---------------------------------------------------------------------- beyondmimic npz
def _write_beyondmimic(robot, motion, path, fps=30.0, wrenches=None, **_) -> None:
    import mujoco

    from ..model.mjcf import build_model

    t, q, v = _training_frames(robot, motion, fps, "beyondmimic_npz")
    sim = build_model(robot)
    mj = sim.mj
    d = mujoco.MjData(mj)
    N, B = len(t), mj.nbody - 1
    pos, quat = np.empty((N, B, 3)), np.empty((N, B, 4))
    lin, ang = np.empty((N, B, 3)), np.empty((N, B, 3))
    qpos, qvel = np.empty((N, mj.nq)), np.empty((N, mj.nv))
    vel = np.empty(6)
    for k in range(N):
        d.qpos[:], d.qvel[:] = sim.qpos_from_q(q[k]), sim.qvel_from_v(q[k], v[k])
        mujoco.mj_forward(mj, d)
        qpos[k], qvel[k] = d.qpos, d.qvel
        pos[k], quat[k] = d.xpos[1:], d.xquat[1:]
        for b in range(1, mj.nbody):  # [angular; linear] at the body frame's origin
            # (XBODY: the body frame; BODY would be its inertial frame), world axes
            mujoco.mj_objectVelocity(mj, d, mujoco.mjtObj.mjOBJ_XBODY, b, vel, 0)
            ang[k, b - 1], lin[k, b - 1] = vel[:3], vel[3:]
    name = mujoco.mjtObj
    free = int(mj.jnt_type[0]) == int(mujoco.mjtJoint.mjJNT_FREE) if mj.njnt else False
    joints = [mujoco.mj_id2name(mj, name.mjOBJ_JOINT, j) for j in range(int(free), mj.njnt)]
    arrays: dict[str, Any] = dict(fps=np.array([fps]), joint_names=np.array(joints),
                  body_names=np.array([mujoco.mj_id2name(mj, name.mjOBJ_BODY, b)
                                       for b in range(1, mj.nbody)]),
                  joint_pos=qpos[:, 7 if free else 0:], joint_vel=qvel[:, 6 if free else 0:],
                  body_pos_w=pos, body_quat_w=quat, body_lin_vel_w=lin, body_ang_vel_w=ang)
    if wrenches is not None:  # gdimitate's extras, on the same frames
        wrenches = _checked_wrenches(motion, wrenches)
        for s, w in wrenches.items():
            arrays[f"contact_wrench_{s}"] = _on_grid(t, motion.t, w)
            arrays[f"contact_frame_{s}"] = np.array(robot.require_contacts()[s].frame)
        tau = _joint_torques(robot, motion, wrenches)
        if tau is not None:  # the joints' columns in the file's (MuJoCo's) joint order
            col = {n: i for i, n in enumerate(_torque_names(robot))}
            arrays["joint_torque"] = _on_grid(t, motion.t, tau[:, [col[n] for n in joints]])
    with open(path, "wb") as f:
        np.savez(f, **arrays)


def _on_grid(t: np.ndarray, t_motion: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``x`` ``(T, n)`` on the motion's times, linearly interpolated onto ``t`` ``(N,)``."""
    return np.column_stack([np.interp(t, t_motion, x[:, i]) for i in range(x.shape[1])])


@dataclass(frozen=True)
class BeyondMimicMotion:
    """A ``"beyondmimic_npz"`` file: ``fps`` [Hz], ``joint_names``, ``joint_pos``/
    ``joint_vel`` ``(N, J)``, ``body_names``, ``body_pos_w`` ``(N, B, 3)``, ``body_quat_w``
    ``(N, B, 4)`` (w, x, y, z), ``body_lin_vel_w``/``body_ang_vel_w`` ``(N, B, 3)``."""

    fps: float
    joint_names: tuple[str, ...]
    joint_pos: np.ndarray
    joint_vel: np.ndarray
    body_names: tuple[str, ...]
    body_pos_w: np.ndarray
    body_quat_w: np.ndarray
    body_lin_vel_w: np.ndarray
    body_ang_vel_w: np.ndarray


def read_beyondmimic_npz(path: str | Path) -> BeyondMimicMotion:
    """Read a ``"beyondmimic_npz"`` file (ours; BeyondMimic's own files have the same keys
    but no ``joint_names``/``body_names``: an empty tuple then)."""
    from ..safety import open_npz

    keys = ("fps", "joint_pos", "joint_vel", "body_pos_w", "body_quat_w", "body_lin_vel_w",
            "body_ang_vel_w")
    with open_npz(path, keys) as z:
        names = {k: tuple(str(n) for n in z[k]) if k in z.files else ()
                 for k in ("joint_names", "body_names")}
        return BeyondMimicMotion(float(np.ravel(z["fps"])[0]), names["joint_names"],
                                 z["joint_pos"], z["joint_vel"], names["body_names"],
                                 *(z[k] for k in keys[3:]))
