"""``gdimitate audit``: robot motion files from any retargeter audited for physical
feasibility (:func:`gdimitate.assess.audit.audit_motion`), one after the other on this process.

Files read (:data:`AUDIT_FORMATS`, by extension and content): gdimitate's ``.npz`` (robot
recorded: no robot needed), the ``"csv"`` export (a header row), the LAFAN1 / BeyondMimic
``.csv`` (no header; ``fps``), a GMR ``.pkl`` pickle, an Isaac Lab AMP ``.npz``
(``dof_positions``), a MuJoCo qpos ``.npz`` (``qpos``, our ``"mujoco"`` export). All but
gdimitate's own need the robot they were made for.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..assess.audit.dataset import MotionAudit
from ..errors import FileFormatError, InvalidInputError
from ..model.motion import Motion
from ..model.robot import Robot

__all__ = ["AUDIT_FORMATS", "AUDIT_SUFFIXES", "AuditedFile", "audit_csv", "audit_files",
           "audit_table", "find_motion_files", "read_robot_motion"]

#: The motion files ``gdimitate audit`` reads, and how it tells them apart.
AUDIT_FORMATS: dict[str, str] = {
    "npz": ".npz with q (gdimitate's own; the robot recorded)",
    "isaaclab_amp": ".npz with dof_positions (Isaac Lab AMP)",
    "mujoco": ".npz with qpos (MuJoCo qpos, gdimitate's mujoco export)",
    "beyondmimic_npz": ".npz with joint_pos and body_pos_w (BeyondMimic / mjlab / holosoma)",
    "csv": ".csv with a header row (gdimitate's csv export)",
    "lafan1_csv": ".csv without header: x y z qx qy qz qw joints (LAFAN1 / BeyondMimic)",
    "gmr": ".pkl (GMR motion pickle; pickle runs code: only files you trust)",
}
AUDIT_SUFFIXES = (".npz", ".csv", ".pkl")

#: loads the robot the command names (None: none named)
RobotLoader = Callable[[], "Robot | None"]


@dataclass(frozen=True)
class AuditedFile:
    """One file's audit: ``path``, its ``format`` (:data:`AUDIT_FORMATS`), ``robot`` (its
    name) and the :class:`~gdimitate.assess.audit.dataset.MotionAudit`."""

    path: Path
    format: str
    robot: str
    audit: MotionAudit

    def to_dict(self) -> dict:
        """``{"file", "format", "robot", "summary", "audit"}`` as plain JSON types."""
        return {"file": str(self.path), "format": self.format, "robot": self.robot,
                **self.audit.to_dict()}


def find_motion_files(args: Sequence[str | Path]) -> list[Path]:
    """The files named by ``args``: a file as given, a folder as every file directly in it
    with an extension of :data:`AUDIT_SUFFIXES` (hidden files left out), sorted by name.
    Raises :class:`InvalidInputError` for a path that does not exist or a folder with none."""
    out: list[Path] = []
    for a in args:
        p = Path(a).expanduser()
        if p.is_dir():
            found = sorted(f for f in p.iterdir() if f.is_file() and not f.name.startswith(".")
                           and f.suffix.lower() in AUDIT_SUFFIXES)
            if not found:
                raise InvalidInputError(f"{p} holds no motion file ({', '.join(AUDIT_SUFFIXES)})"
                                        "; give files or a folder of them")
            out.extend(found)
        elif p.is_file():
            out.append(p)
        else:
            raise InvalidInputError(f"{p} does not exist; give motion files or folders")
    return out


def _npz_format(path: Path) -> str:
    from ..safety import open_npz

    with open_npz(path) as z:
        keys = set(z.files)
    for fmt, key in (("npz", "q"), ("isaaclab_amp", "dof_positions"), ("mujoco", "qpos"),
                     ("beyondmimic_npz", "joint_pos")):
        if key in keys:
            return fmt
    raise FileFormatError(f"{path}: an .npz with none of the keys q (gdimitate), "
                          "dof_positions (Isaac Lab AMP), qpos (MuJoCo), joint_pos "
                          "(BeyondMimic); cannot audit it")


def motion_format(path: Path) -> str:
    """The :data:`AUDIT_FORMATS` key of ``path``, by extension and content; raises
    :class:`FileFormatError` listing the formats read for any other file."""
    suffix = path.suffix.lower()
    if suffix == ".npz":
        return _npz_format(path)
    if suffix == ".pkl":
        return "gmr"
    if suffix == ".csv":
        with open(path, encoding="utf-8", errors="replace") as f:
            first = f.readline()
        try:
            float(first.split(",")[0])
        except ValueError:
            return "csv"  # a header row
        return "lafan1_csv"
    raise FileFormatError(f"{path}: unknown motion format {path.suffix or '(no extension)'!r};"
                          " gdimitate audit reads " + "; ".join(
                              f"{k} ({v})" for k, v in AUDIT_FORMATS.items()))


def read_robot_motion(path: Path, robot: Robot | None, fps: float = 30.0
                      ) -> tuple[Robot, Motion, str]:
    """``(robot, motion, format)`` of a motion file. ``robot``: the robot it was made for
    (None: only gdimitate's ``.npz``, which records its robot); ``fps`` [Hz]: the frame rate
    of a LAFAN1 CSV. Raises :class:`InvalidInputError` naming ``--robot`` when one is needed."""
    from ..export import writers as export

    fmt = motion_format(path)
    if fmt == "npz":
        from ..io.demonstration import load_demonstration
        from ..model.motion import RobotRecord

        if robot is None and RobotRecord.from_npz(path) is None:
            raise InvalidInputError(f"{path} records no robot: pass the robot it was made "
                                    "for (--robot NAME|URDF; Python: robot=)")
        demo = load_demonstration(path, robot=robot)
        return demo.robot, demo.motion, fmt
    if robot is None:
        raise InvalidInputError(f"{path} ({fmt}: {AUDIT_FORMATS[fmt]}) records no robot: pass "
                                "the robot it was made for (--robot NAME|URDF)")
    if fmt == "csv":
        return robot, export.read_csv(path, robot), fmt
    if fmt == "lafan1_csv":
        return robot, export.read_lafan1_csv(path, robot, fps=fps), fmt
    if fmt == "gmr":
        return robot, export.read_gmr(path, robot), fmt
    if fmt == "isaaclab_amp":
        return robot, export.read_isaaclab_amp(path, robot), fmt
    if fmt == "beyondmimic_npz":
        return robot, _read_beyondmimic(path, robot), fmt
    return robot, _read_mujoco(path, robot), fmt


def _read_beyondmimic(path: Path, robot: Robot) -> Motion:
    """A BeyondMimic motion NPZ onto a free-flyer ``robot``: the root pose from its first
    body (the free joint's), the joints by the file's ``joint_names`` where it has them (ours),
    else in MuJoCo's order for the model :func:`gdimitate.sim.build_model` makes."""
    import mujoco

    from ..export.writers import read_beyondmimic_npz
    from ..model.mjcf import build_model

    bm = read_beyondmimic_npz(path)
    sim = build_model(robot)
    mj = sim.mj
    if not mj.njnt or int(mj.jnt_type[0]) != int(mujoco.mjtJoint.mjJNT_FREE):
        raise FileFormatError(f"{path}: a BeyondMimic motion is of a free-floating robot; "
                              f"{robot.name!r} has no free base")
    names = [mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(1, mj.njnt)]
    pos = np.asarray(bm.joint_pos, float)
    if bm.joint_names:
        missing = [n for n in names if n not in bm.joint_names]
        if missing:
            raise FileFormatError(f"{path}: joint_names lacks {robot.name!r}'s joints "
                                  f"{missing[:5]}; is it another robot's motion?")
        pos = pos[:, [list(bm.joint_names).index(n) for n in names]]
    if pos.ndim != 2 or pos.shape[1] != len(names) or bm.body_pos_w.shape[:1] != pos.shape[:1]:
        raise FileFormatError(f"{path}: joint_pos has shape {pos.shape}; robot {robot.name!r} "
                              f"has {len(names)} joints in its MuJoCo model")
    qpos = np.column_stack([bm.body_pos_w[:, 0], bm.body_quat_w[:, 0], pos])
    return _from_qpos(sim, robot, np.arange(len(qpos)) / bm.fps, qpos)


def _read_mujoco(path: Path, robot: Robot) -> Motion:
    """A MuJoCo qpos NPZ onto ``robot`` (the model :func:`gdimitate.sim.build_model` makes)."""
    from ..export.writers import read_mujoco
    from ..model.mjcf import build_model

    mm = read_mujoco(path)
    sim = build_model(robot)
    if mm.qpos.ndim != 2 or mm.qpos.shape[1] != sim.mj.nq:
        raise FileFormatError(f"{path}: qpos has shape {mm.qpos.shape}; robot {robot.name!r}'s "
                              f"MuJoCo model has nq = {sim.mj.nq}")
    return _from_qpos(sim, robot, np.asarray(mm.time, float), mm.qpos)


def _from_qpos(sim, robot: Robot, t: np.ndarray, qpos: np.ndarray) -> Motion:
    """The :class:`Motion` of ``robot`` on times ``t`` ``(N,)`` [s] from MuJoCo ``qpos``
    ``(N, nq_mj)`` of its model ``sim`` (:func:`gdimitate.sim.build_model`)."""
    q = np.array([sim.q_from_qpos(x) for x in qpos])
    return Motion(t=t, joint_names=robot.joint_names, q=q,
                  base_nq={"free": 7, "planar": 3}.get(robot.base, 0),
                  joint_nq=tuple(robot.model.joints[j].nq for j in range(1, robot.model.njoints)))


def audit_files(paths: Sequence[Path], robot: RobotLoader, fps: float = 30.0
                ) -> list[AuditedFile]:
    """Each file read (:func:`read_robot_motion`, the robot from ``robot()`` loaded once
    where needed) and audited (:func:`gdimitate.assess.audit.audit_motion`), in order."""
    from ..assess.audit.dataset import audit_motion

    given: list[Robot | None] = []
    out = []
    for p in paths:
        if not given:
            given.append(robot())
        bot, motion, fmt = read_robot_motion(p, given[0], fps)
        out.append(AuditedFile(p, fmt, bot.name, audit_motion(bot, motion)))
    return out


#: the columns of ``audit.csv`` and of the console table
CSV_COLUMNS = ("file", "format", "robot", "frames", "share_feasible", "torque_ratio",
               "torque_joint", "slip_m", "penetration_m", "hover_m", "cop_margin_m",
               "friction", "feasible", "binding")


def _row(f: AuditedFile) -> list:
    a = f.audit
    return [f.path.name, f.format, f.robot, a.frames, f"{a.share_feasible:.4f}",
            f"{a.torque_ratio:.4g}", a.torque_joint, f"{a.slip:.4g}", f"{a.penetration:.4g}",
            f"{a.hover:.4g}", f"{a.cop_margin:.4g}", f"{a.friction:.4g}",
            "yes" if a.feasible else "no", ";".join(a.report.binding)]


def audit_csv(files: Sequence[AuditedFile]) -> str:
    """``audit.csv``'s text: a header (:data:`CSV_COLUMNS`), one row per file."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(CSV_COLUMNS)
    w.writerows(_row(f) for f in files)
    return buf.getvalue()


def audit_table(files: Sequence[AuditedFile]) -> list[str]:
    """The console table: a header and one line per file (name, frames, share of knots
    feasible, worst torque/limit and joint, slip, penetration, CoP margin, verdict)."""
    head = (f"{'file':<28} {'frames':>6} {'ok knots':>8} {'torque/lim':>10} {'joint':<16} "
            f"{'slip m':>9} {'pen. m':>9} {'CoP m':>9}  feasible")
    lines = [head]
    for f in files:
        a = f.audit
        lines.append(f"{f.path.name[:28]:<28} {a.frames:>6} {100 * a.share_feasible:>7.1f}% "
                     f"{a.torque_ratio:>10.3g} {a.torque_joint[:16]:<16} {a.slip:>9.3g} "
                     f"{a.penetration:>9.3g} {a.cop_margin:>9.3g}  "
                     + ("yes" if a.feasible else "NO"))
    return lines
