"""One file of a batch: load the demonstration, adapt it, optionally simulate, save, and
describe the outcome in one :class:`BatchRow`.

:func:`process_file` is what a worker process runs. It receives only plain values (a path,
the output folder and the frozen :class:`BatchOptions`), never a :class:`~gdimitate.Robot`
(Pinocchio models do not pickle reliably); each worker process builds the imitator once and
keeps it (:func:`load_robot`, cached by its spec).
"""

from __future__ import annotations

import functools
import json
import math
import os
import socket
import time
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from ..errors import InvalidInputError, UnknownNameError
from ..types import AdaptMethod, ForceModel

__all__ = ["BatchOptions", "BatchRow", "GRF_SUFFIX", "STATUSES", "grf_file", "load_robot",
           "output_paths", "process_file", "read_finished"]

#: Row statuses: adapted in this run, finished by an earlier run (its output kept), failed.
STATUSES = ("done", "skipped", "failed")

#: Adaptation methods a batch can run (those of :func:`gdimitate.adapt`).
_METHODS = ("analytic", "copy", "optimal")
#: Force-direction models without measured forces, plus ``"measured"`` (needs a GRF file).
_FORCES = ("segment", "com", "dynamics", "measured")


@dataclass(frozen=True)
class BatchOptions:
    """What is done to every file of a batch.

    - ``imitator``: the imitator robot, a library name (:func:`gdimitate.list_robots`) or a
      ``.urdf``/``.osim`` path (:meth:`gdimitate.Robot.load`);
    - ``method``: ``"optimal"`` (whole-body adaptor, default), ``"analytic"`` (the paper's
      Eq. 1; planar sagittal demonstrations) or ``"copy"``;
    - ``force``: the force-direction model of the goal (``"segment"``, ``"com"``,
      ``"dynamics"``, ``"measured"``: the latter needs the file's measured forces);
    - ``simulate``: also replay the result in MuJoCo (:func:`gdimitate.sim.simulate`; needs
      ``method="optimal"``, whose plan carries velocities, accelerations and wrenches);
    - ``demonstrator``: the demonstrator robot (name or ``.osim``/``.urdf`` path) for inputs
      that need one (a full-body OpenSim ``.mot``); ``None``: each reader's own;
    - ``verbose``: the optimiser's progress lines (off in batches: workers would interleave).
    """

    imitator: str
    method: AdaptMethod = "optimal"
    force: ForceModel = "segment"
    simulate: bool = False
    demonstrator: str | None = None
    verbose: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.imitator, str) or not self.imitator:
            raise InvalidInputError(f"imitator must be a robot name or model path; got "
                                    f"{self.imitator!r}")
        if self.method not in _METHODS:
            raise UnknownNameError("method", self.method, _METHODS)
        if self.force not in _FORCES:
            raise UnknownNameError("force model", self.force, _FORCES)
        if self.simulate and self.method != "optimal":
            raise InvalidInputError(
                f"simulate=True needs method='optimal' (the physics check tracks a plan with "
                f"velocities, accelerations and contact wrenches; method {self.method!r} "
                "gives joint angles only)")

    def key(self) -> dict[str, Any]:
        """The options that determine an output (a finished output made with other options is
        not reused)."""
        return {"imitator": self.imitator, "method": self.method, "force": self.force,
                "simulate": self.simulate, "demonstrator": self.demonstrator}


@dataclass(frozen=True)
class BatchRow:
    """One file's line in the summary table (CSV column = field; ``None`` = not applicable).

    - ``file``: the input's name relative to the input folder; ``output``: the NPZ written
      (name in the output folder), ``""`` when it failed; ``status``: one of
      :data:`STATUSES`; ``error``: ``"ErrorType: message"`` of a failed file;
    - ``frames``, ``duration_s`` [s]: the demonstration's length;
    - ``feasible``: :attr:`gdimitate.AdaptedMotion.feasible` (the audit's verdict for the
      optimal method; Eq. 1's reachability and the position limits otherwise);
    - kinematic report (every method): ``infeasible_frames`` (both legs),
      ``force_direction_error_max_rad``, ``joint_limit_violation_max_rad``,
      ``ground_penetration_max_m``;
    - ``goals_unmet`` (optimal method): the goals the optimiser's least-infeasible fallback
      leaves unmet, ``name violation@knot``, ``;``-separated (``""``: all met; see
      :mod:`gdimitate.assess.verdict`);
    - the audit's main margins (optimal method): ``audit_binding`` (failed checks, most
      violated first, ``;``-separated), ``torque_ratio_max`` (worst |τ|/limit),
      ``base_residual_max`` [N, N·m], ``penetration_max_m`` (deepest sole corner; negative:
      clearance), ``cop_margin_min_m`` (inside the sole: positive), ``friction_ratio_max``,
      ``audit_force_direction_max_rad``;
    - the physics check (``simulate``): ``sim_fell``, ``sim_fall_time_s``, ``sim_slip_max_m``,
      ``sim_torque_saturation``, ``sim_joint_rmse``, ``sim_qp_failures``;
    - ``seconds``: wall time of this file's work [s] (load to save; of the earlier run for a
      skipped file); ``worker``: ``host:pid`` of the process that did it.
    """

    file: str
    output: str
    status: str
    method: str
    imitator: str
    frames: int | None = None
    duration_s: float | None = None
    feasible: bool | None = None
    infeasible_frames: int | None = None
    force_direction_error_max_rad: float | None = None
    joint_limit_violation_max_rad: float | None = None
    ground_penetration_max_m: float | None = None
    goals_unmet: str | None = None
    audit_binding: str | None = None
    torque_ratio_max: float | None = None
    base_residual_max: float | None = None
    penetration_max_m: float | None = None
    cop_margin_min_m: float | None = None
    friction_ratio_max: float | None = None
    audit_force_direction_max_rad: float | None = None
    sim_fell: bool | None = None
    sim_fall_time_s: float | None = None
    sim_slip_max_m: float | None = None
    sim_torque_saturation: float | None = None
    sim_joint_rmse: float | None = None
    sim_qp_failures: int | None = None
    seconds: float | None = None
    worker: str = ""
    error: str = ""

    @property
    def ok(self) -> bool:
        """Done (or skipped), feasible, every goal met, and not fallen in the simulation."""
        return (self.status != "failed" and self.feasible is not False
                and not self.goals_unmet and not self.sim_fell)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON values (NaN/inf become ``None``)."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in asdict(self).items()}

    @classmethod
    def columns(cls) -> tuple[str, ...]:
        """The field names, in table order."""
        return tuple(f.name for f in fields(cls))


def output_paths(path: str | os.PathLike, out_dir: str | os.PathLike,
                 options: BatchOptions) -> tuple[Path, Path]:
    """``(npz, record)``: where the result of input ``path`` goes in ``out_dir`` —
    ``<input name>.<imitator>.<method>.npz`` and the row's ``.json`` beside it (written last:
    its presence marks the output complete)."""
    robot = Path(options.imitator).stem if options.imitator.endswith((".urdf", ".osim")) \
        else options.imitator
    stem = f"{Path(path).name}.{robot}.{options.method}"
    out = Path(out_dir)
    return out / f"{stem}.npz", out / f"{stem}.json"


def read_finished(path: str | os.PathLike, out_dir: str | os.PathLike,
                  options: BatchOptions) -> BatchRow | None:
    """The row of an earlier run's finished output of ``path`` with the same options (its
    status set to ``"skipped"``), or ``None`` when there is none, it is incomplete (NPZ or
    record missing, unreadable record) or it was made with other options."""
    npz, record = output_paths(path, out_dir, options)
    if not (npz.is_file() and record.is_file()):
        return None
    try:
        data = json.loads(record.read_text())
        if data.get("options") != options.key():
            return None
        row = BatchRow(**data["row"])
    except (OSError, ValueError, TypeError, KeyError, AttributeError):
        return None
    if row.status != "done":
        return None
    return BatchRow(**{**asdict(row), "status": "skipped"})


@functools.lru_cache(maxsize=8)
def load_robot(spec: str):
    """The robot named (or at the model path) ``spec``, built once per process
    (:meth:`gdimitate.Robot.load`)."""
    from ..model.robot import Robot

    return Robot.load(spec)


#: Stem suffix of a ground-reaction-force file that belongs to the demonstration beside it
#: (``walk.mot`` + ``walk_grf.mot``); such files are not inputs of their own.
GRF_SUFFIX = "_grf"


def grf_file(path: Path) -> Path | None:
    """The measured ground reaction forces of demonstration ``path``: ``<stem>_grf.mot`` or
    ``<stem>_grf.sto`` beside it, or ``None``."""
    for ext in (".mot", ".sto"):
        g = path.with_name(f"{path.stem}{GRF_SUFFIX}{ext}")
        if g.is_file():
            return g
    return None


def _load(path: Path, options: BatchOptions):
    """``(demonstrator, motion, forces)`` of one input file
    (:func:`gdimitate.io.demonstration.load_demonstration`, with its GRF file where one lies
    beside it)."""
    from ..io.demonstration import load_demonstration

    robot = load_robot(options.demonstrator) if options.demonstrator else None
    grf = grf_file(path) if path.suffix.lower() in (".mot", ".sto") else None
    d = load_demonstration(path, robot=robot, grf=grf)
    return d.robot, d.motion, d.forces


def _finite(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _audit_margins(audit) -> dict[str, Any]:
    ratios = [j.torque_ratio for j in audit.joints if math.isfinite(j.torque_ratio)]
    feet = list(audit.feet.values())
    stance = [f for f in feet if f.stance_knots > 0]
    fd = [f.force_direction.error_max for f in feet if f.force_direction is not None]
    return dict(
        audit_binding=";".join(audit.binding),
        torque_ratio_max=_finite(max(ratios)) if ratios else None,
        base_residual_max=_finite(audit.base_residual.value),
        penetration_max_m=_finite(audit.penetration.depth),
        cop_margin_min_m=_finite(min(f.cop.value for f in stance)) if stance else None,
        friction_ratio_max=_finite(max(f.friction.value for f in stance)) if stance else None,
        audit_force_direction_max_rad=_finite(max(fd)) if fd else None,
    )


def _sim_metrics(m) -> dict[str, Any]:
    return dict(sim_fell=bool(m.fell),
                sim_fall_time_s=None if m.fall_time is None else float(m.fall_time),
                sim_slip_max_m=_finite(m.slip_max), sim_torque_saturation=_finite(
                    m.torque_saturation), sim_joint_rmse=_finite(m.joint_rmse),
                sim_qp_failures=int(m.qp_failures))


def _save(adapted, path: Path) -> None:
    """The adapted motion as NPZ (:meth:`AdaptedMotion.save`: the motion with ``v``/``a``,
    the contact wrenches and the imitator's record, read back by
    :func:`gdimitate.io.demonstration.load_demonstration` and :meth:`Motion.from_npz`)."""
    from ..safety import atomic_write

    with atomic_write(path) as tmp:
        adapted.save(tmp)


def _adapt_one(path: Path, options: BatchOptions) -> tuple[Any, dict[str, Any]]:
    from ..adaptation.adaptor import adapt
    from ..assess.verdict import verdict

    demonstrator, motion, forces = _load(path, options)
    imitator = load_robot(options.imitator)
    kw: dict[str, Any] = {}
    if options.method == "optimal":
        kw["verbose"] = options.verbose
        if forces is not None:
            kw["forces"] = forces
    elif options.force == "measured":
        raise InvalidInputError(f"force='measured' needs method='optimal'; got "
                                f"{options.method!r}")
    adapted = adapt(motion, demonstrator, imitator, options.method, force=options.force, **kw)
    r = adapted.report
    cols: dict[str, Any] = dict(
        frames=motion.T, duration_s=float(motion.t[-1] - motion.t[0]),
        feasible=bool(adapted.feasible),
        infeasible_frames=int(sum(r.infeasible_frames.values())),
        force_direction_error_max_rad=_finite(r.force_direction_error_max),
        joint_limit_violation_max_rad=_finite(r.joint_limit_violation_max),
        ground_penetration_max_m=_finite(r.ground_penetration_max))
    if adapted.audit is not None:
        cols.update(_audit_margins(adapted.audit))
    if adapted.solver is not None:
        cols["goals_unmet"] = "; ".join(verdict(adapted).unmet_texts())
    if options.simulate:
        from ..sim import simulate

        cols.update(_sim_metrics(simulate(imitator, adapted, demo_forces=forces).metrics))
    return adapted, cols


def process_file(path: str | os.PathLike, out_dir: str | os.PathLike,
                 options: BatchOptions, relative: str | None = None) -> BatchRow:
    """Adapt one demonstration file and write its result into ``out_dir`` (the NPZ, then its
    record: both atomically, :func:`gdimitate.safety.atomic_write`).

    Never raises for a bad file: any ``Exception`` becomes a row with ``status="failed"`` and
    the error's type and message (``KeyboardInterrupt``/``SystemExit`` propagate). ``relative``:
    the name shown in the table (default: the file name)."""
    from ..safety import atomic_write

    p = Path(path)
    name = relative or p.name
    worker = f"{socket.gethostname()}:{os.getpid()}"
    start = time.perf_counter()
    npz, record = output_paths(p, out_dir, options)
    try:
        adapted, cols = _adapt_one(p, options)
        _save(adapted, npz)
        row = BatchRow(file=name, output=npz.name, status="done", method=options.method,
                       imitator=options.imitator, seconds=time.perf_counter() - start,
                       worker=worker, **cols)
        with atomic_write(record) as tmp:
            tmp.write_text(json.dumps({"options": options.key(), "row": row.to_dict()},
                                      indent=1))
        return row
    except Exception as e:  # noqa: BLE001 — one bad file must not stop the batch
        return BatchRow(file=name, output="", status="failed", method=options.method,
                        imitator=options.imitator, seconds=time.perf_counter() - start,
                        worker=worker, error=f"{type(e).__name__}: {e}")
