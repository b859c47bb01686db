"""What ``gdimitate adapt`` (and ``stream``, for the frames it streamed) writes for an
adaptation: ``imitator_joints.csv``, ``imitator_motion.npz``, ``report.json`` (the kinematic
report, the verdict, the audit, the solver, the gait, the push-direction errors) and
``gait.png``, each written under a temporary name and renamed when complete
(:func:`gdimitate.safety.atomic_write`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..assess.result import AdaptedMotion
from ..model.motion import Motion
from ..model.robot import Robot
from ..safety import atomic_write

__all__ = ["ADAPT_FILES", "write_adapted"]

#: the files :func:`write_adapted` writes
ADAPT_FILES = ("imitator_joints.csv", "imitator_motion.npz", "report.json", "gait.png")


def write_adapted(out: Path, demonstrator: Robot, demo: Motion, result: AdaptedMotion,
                  extra: dict[str, Any] | None = None) -> str:
    """Write :data:`ADAPT_FILES` of ``result`` (an adaptation of ``demo`` by
    ``demonstrator``) into the folder ``out``; ``extra``: more top-level entries of
    report.json. Returns report.json's text (what the console prints from)."""
    from ..assess.verdict import push_errors, solver_record, verdict
    from .figures import plot_gait

    v = verdict(result)
    with atomic_write(out / "imitator_joints.csv") as tmp:
        result.save(tmp, "csv")
    with atomic_write(out / "imitator_motion.npz") as tmp:
        result.save(tmp, "npz")
    report = {**result.report.to_dict(), "verdict": v.to_dict(),
              "audit": result.audit.to_dict() if result.audit is not None else None,
              "solver": solver_record(result.solver),
              "gait": result.gait.to_dict() if result.gait is not None else None,
              "push_direction_error": {s: {"rad": e, "knot": k, "measure": m} for s, (
                  e, k, m) in push_errors(result).items()},
              **(extra or {})}
    text = json.dumps(report, indent=2, default=str)
    with atomic_write(out / "report.json") as tmp:
        tmp.write_text(text)
    plot_gait(demonstrator, demo, result, out / "gait.png")
    return text
