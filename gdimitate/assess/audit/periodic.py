"""The seam of a periodic gait cycle, audited (docs/design.md §14): is the cycle's last knot
its first shifted by one stride?

Recomputed from the motion's own numbers: ``seam_position`` — the largest component of
``pin.difference(q_first shifted by the stride, q_last)`` (the shift: the base advanced
along the walking direction by the horizontal displacement the motion has along it; what is
left across it, in height, orientation and joints counts) [m, rad]; ``seam_velocity`` —
``max |v_last − v_first|`` [m/s, rad/s]; ``seam_acceleration`` and ``seam_wrench`` (the
last knot's ``a`` and wrenches against the first's, scaled by ``m·g``) and ``seam_contact``
(stance flags that differ). Each is a :class:`~.report.Check` at the last knot; the report's
``feasible`` holds only if they pass too.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin

from ...model.motion import Motion
from ...model.robot import SIDES, Robot
from .report import AuditReport, Check

__all__ = ["SEAM_TOL", "seam_errors", "seam_audit"]

SEAM_TOL = 1e-9
"""Seam tolerance (each component; scaled units for the wrench)."""


def seam_errors(robot: Robot, motion: Motion, wrenches: dict[str, np.ndarray],
                direction: np.ndarray) -> dict[str, float]:
    """``{"seam_position", "seam_velocity", "seam_acceleration", "seam_wrench",
    "seam_contact"}`` (module docstring); ``direction`` ``(2,)``: the walking direction."""
    from ...model.footsteps import shift_by_stride

    q, (v, a) = motion.q, motion.derivatives("the seam audit")
    shifted = shift_by_stride(robot, q[0], q[-1], direction)
    mg = robot.mass * float(np.linalg.norm(robot.model.gravity.linear))
    return {
        "seam_position": float(np.max(np.abs(pin.difference(robot.model, shifted, q[-1])))),
        "seam_velocity": float(np.max(np.abs(v[-1] - v[0]))),
        "seam_acceleration": float(np.max(np.abs(a[-1] - a[0]))),
        "seam_wrench": max(float(np.max(np.abs(wrenches[s][-1] - wrenches[s][0]))) / mg
                           for s in SIDES),
        "seam_contact": float(sum(bool(motion.contact[s][-1]) != bool(motion.contact[s][0])
                                  for s in SIDES)),
    }


_UNITS = {"seam_position": "m|rad", "seam_velocity": "m/s|rad/s",
          "seam_acceleration": "m/s²|rad/s²", "seam_wrench": "m·g", "seam_contact": "feet"}


def seam_audit(report: AuditReport, robot: Robot, motion: Motion,
               wrenches: dict[str, np.ndarray], demonstrator: Robot, demo_q: np.ndarray
               ) -> AuditReport:
    """``report`` (the audit of ``motion`` with ``wrenches`` ``{side: (T, 6)}``) with the
    seam checks added, ``feasible`` and ``binding`` updated; ``demo_q`` ``(T, nq)`` of
    ``demonstrator`` gives the walking direction."""
    from ...model.footsteps import walking_direction

    err = seam_errors(robot, motion, wrenches, walking_direction(demonstrator, demo_q))
    T = motion.T
    new, rows = [], []
    for name, value in err.items():
        bound = 0.0 if name == "seam_contact" else SEAM_TOL
        ok = value <= bound
        new.append(Check(name, value, bound, T - 1, ok,
                         0.0 if ok else float((value - bound) / max(SEAM_TOL, 1e-300)),
                         _UNITS[name], "max", 0 if ok else 1))
        row = np.ones(T, bool)
        row[-1] = ok
        rows.append(row)
    checks = tuple(report.checks) + tuple(new)
    failed = sorted((c for c in checks if not c.passed), key=lambda c: -c.violation)
    kc = np.vstack([report.knot_checks] + rows) if np.size(report.knot_checks) else np.array(rows)
    return dataclasses.replace(
        report, checks=checks, feasible=not failed, binding=tuple(c.name for c in failed),
        knot_checks=kc, knot_feasible=np.logical_and(report.knot_feasible, np.all(rows, axis=0)))

