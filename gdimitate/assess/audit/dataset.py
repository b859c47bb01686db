"""Audit a robot motion from any retargeter: is it physically feasible before training on it?

:func:`audit_motion` takes a bare robot motion (joint trajectory, as GMR, holosoma or a
BeyondMimic pipeline writes it): velocities and accelerations by differencing where the motion
has none (:func:`gdimitate.model.motion.differentiate`), the stance schedule from the motion's own
``contact`` or else from the soles' height and speed (:func:`gdimitate.io.bvh.detect_contacts`),
the contact wrenches that best explain its inverse dynamics inside each sole's cone
(:func:`gdimitate.assess.wrenches.estimate_wrenches`), then the independent audit
(:func:`gdimitate.assess.audit.audit`). :class:`MotionAudit` holds the report, the wrenches and a
few
numbers per clip read from the report (never recomputed).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ...errors import InvalidInputError
from ...jsonable import jsonable
from ...model.contact import SoleContact
from ...model.motion import Motion
from ..wrenches import WrenchEstimate
from .report import AuditReport, AuditTolerances

__all__ = ["MotionAudit", "audit_motion", "stance_schedule"]

SIDES = ("left", "right")


@dataclass(frozen=True, eq=False)
class MotionAudit:
    """The audit of one robot motion and its numbers per clip, all read from :attr:`report`.

    - ``report``: the :class:`~gdimitate.audit.AuditReport`; ``wrenches``: the
      :class:`~gdimitate.wrenches.WrenchEstimate` audited with the motion;
    - ``contact_source``: where the stance schedule came from (``"motion"``, ``"height and
      speed"`` or ``"height alone"``); ``frames``: T; ``duration`` [s];
    - ``share_feasible`` [-]: ``report.knot_feasible.mean()``;
    - ``torque_ratio`` [-], ``torque_joint``: the largest |τ|/limit over joints with a limit
      (:attr:`JointAudit.torque_ratio`; NaN and ``""`` where none has one);
    - ``slip`` [m], ``slip_side``: the largest stance drift of a sole (``FootAudit.slip``);
    - ``penetration`` [m]: the deepest sole corner below the floor (``report.penetration``;
      negative: every corner above it at every knot); ``hover`` [m]: the highest corner of a
      stance sole above the floor (``FootAudit.contact_gap``);
    - ``cop_margin`` [m]: the smallest centre-of-pressure margin inside a stance sole
      (``FootAudit.cop``; negative: outside); ``friction`` [-]: the largest |f_t|/f_z of a
      stance foot (``FootAudit.friction``), ``mu``: that foot's friction coefficient;
    - ``self_collision`` [m]: the closest approach of two collision geometries
      (``report.self_collision.distance``; None where the robot has no collision geometry).
    NaN where a quantity has no knot to be measured at (no stance).
    """

    report: AuditReport
    wrenches: WrenchEstimate
    contact_source: str
    frames: int
    duration: float
    share_feasible: float
    torque_ratio: float
    torque_joint: str
    slip: float
    slip_side: str
    penetration: float
    hover: float
    cop_margin: float
    friction: float
    mu: float
    self_collision: float | None

    @property
    def feasible(self) -> bool:
        """The audit's verdict (every check passed)."""
        return self.report.feasible

    def summary_dict(self) -> dict:
        """The per-clip numbers (not the report) as plain JSON types (NaN → None)."""
        keys = ("contact_source", "frames", "duration", "share_feasible", "torque_ratio",
                "torque_joint", "slip", "slip_side", "penetration", "hover", "cop_margin",
                "friction", "mu", "self_collision")
        return jsonable({"feasible": self.feasible, "binding": list(self.report.binding),
                         **{k: getattr(self, k) for k in keys}})

    def to_dict(self) -> dict:
        """``{"summary": summary_dict(), "audit": report.to_dict()}``."""
        return {"summary": self.summary_dict(), "audit": self.report.to_dict()}

    def lines(self) -> list[str]:
        """Console lines: the verdict, the per-clip numbers, each failed check's numbers."""
        from ..verdict import EXIT_NOT_FEASIBLE

        head = "feasible" if self.feasible else (
            f"NOT feasible (exit status {EXIT_NOT_FEASIBLE}); failed: "
            + ", ".join(self.report.binding[:6])
            + (f" (and {len(self.report.binding) - 6} more)" if len(self.report.binding) > 6
               else ""))
        sc = ("not checked" if self.self_collision is None
              else f"{self.self_collision:.3g} m")
        out = [head,
               f"{self.frames} frames, {self.duration:.2f} s; contacts from "
               f"{self.contact_source}; knots feasible {100 * self.share_feasible:.1f} %",
               f"torque/limit max {self.torque_ratio:.3g} ({self.torque_joint or '-'}); "
               f"slip {self.slip:.3g} m ({self.slip_side or '-'}); penetration "
               f"{self.penetration:.3g} m; hover {self.hover:.3g} m",
               f"CoP margin {self.cop_margin:.3g} m; friction {self.friction:.3g} "
               f"(mu {self.mu:.3g}); self-collision {sc}"]
        return out + [f"  {r}" for r in self.failed()]

    def failed(self) -> list[str]:
        """Each failed check, most violated first, as ``"cop:left: -0.0031 m < -1e-06 at knot
        12"`` (the audit's value, bound and worst knot)."""
        out = []
        for c in sorted((c for c in self.report.checks if not c.passed),
                        key=lambda c: -c.violation):
            op = ">" if c.sense == "max" else "<"
            unit = f" {c.unit}" if c.unit not in ("", "-") else ""
            out.append(f"{c.name}: {c.value:.4g}{unit} {op} {c.bound:.4g} at knot {c.knot}")
        return out


def _worst_of(values: list[tuple[float, str]], sense: str) -> tuple[float, str]:
    """The largest (``"max"``) or smallest (``"min"``) finite value and its label;
    ``(NaN, "")`` when none is finite."""
    finite = [(v, n) for v, n in values if np.isfinite(v)]
    if not finite:
        return float("nan"), ""
    pick = max if sense == "max" else min
    return pick(finite, key=lambda x: x[0])


def summarise(report: AuditReport, wrenches: WrenchEstimate, motion: Motion,
              contact_source: str) -> MotionAudit:
    """The :class:`MotionAudit` of ``report`` (the audit of ``motion`` with ``wrenches``):
    every number read from the report's own fields."""
    feet = report.feet.values()
    tau, joint = _worst_of([(j.torque_ratio, j.name) for j in report.joints], "max")
    slip, side = _worst_of([(f.slip.value, f.side) for f in feet], "max")
    hover, _ = _worst_of([(f.contact_gap.value, f.side) for f in feet], "max")
    cop, _ = _worst_of([(f.cop.value, f.side) for f in feet], "min")
    fr, fside = _worst_of([(f.friction.value, f.side) for f in feet], "max")
    mu = report.feet[fside].mu if fside else float("nan")
    sc = report.self_collision
    return MotionAudit(
        report=report, wrenches=wrenches, contact_source=contact_source, frames=motion.T,
        duration=float(motion.t[-1] - motion.t[0]),
        share_feasible=float(np.mean(report.knot_feasible)), torque_ratio=float(tau),
        torque_joint=joint, slip=float(slip), slip_side=side,
        penetration=float(report.penetration.depth), hover=float(hover),
        cop_margin=float(cop), friction=float(fr), mu=float(mu),
        self_collision=None if sc is None else float(sc.distance))


def stance_schedule(robot, motion: Motion) -> tuple[dict[str, np.ndarray], str]:
    """The stance flags ``{side: (T,) bool}`` of ``motion`` and where they came from: the
    motion's own ``contact`` when it has both feet, else the sole corners' height and speed
    (:func:`gdimitate.io.bvh.detect_contacts`, thresholds in hip heights); a foot that never
    stands still there (a treadmill) → height alone."""
    if all(s in motion.contact for s in SIDES):
        return {s: np.asarray(motion.contact[s], bool) for s in SIDES}, "motion"
    from ...io.bvh.contacts import kinematic_stance

    if motion.T < 3:
        raise InvalidInputError(f"a motion of {motion.T} frame(s) cannot be audited: its "
                                "velocities need at least 3 frames")
    return kinematic_stance(robot, motion.q, motion.t)


def audit_motion(robot, motion: Motion, contacts: Mapping[str, SoleContact] | None = None, *,
                 tolerances: AuditTolerances | None = None,
                 collision_margin: float = 0.0) -> MotionAudit:
    """Audit a robot motion from any source for physical feasibility.

    ``robot``: a :class:`gdimitate.Robot` with a free-flyer or planar base; ``motion``: its
    :class:`~gdimitate.Motion` (``t`` ``(T,)`` [s], ``q`` ``(T, nq)``; ``v``/``a`` ``(T, nv)``
    are differenced from ``q`` where it has none; ``contact`` ``{side: (T,) bool}`` used where
    it has both feet, else :func:`stance_schedule` finds them); ``contacts``
    ``{side: SoleContact}`` (default: the robot's); ``tolerances``, ``collision_margin`` [m]:
    as :func:`gdimitate.assess.audit.audit`.

    The contact wrenches are :func:`gdimitate.assess.wrenches.estimate_wrenches` (``method="cone"``:
    inside each sole's cone, the least unexplained base wrench where none explains the motion
    — the audit then fails ``base_residual``). Returns a :class:`MotionAudit`. Raises
    :class:`~gdimitate.errors.InvalidInputError` for a motion that is not the robot's, too
    short, or a fixed-base robot.
    """
    from ...model.motion import differentiate
    from ..wrenches import estimate_wrenches
    from .core import audit

    if not isinstance(motion, Motion):
        raise InvalidInputError(f"motion must be a gdimitate.Motion; got {type(motion).__name__}")
    if motion.q.shape[1] != robot.model.nq:
        raise InvalidInputError(f"the motion has {motion.q.shape[1]} q columns; robot "
                                f"{robot.name!r} has nq = {robot.model.nq}: pass the robot the "
                                "motion was made for")
    schedule, source = stance_schedule(robot, motion)
    motion = motion.replace(contact=schedule)
    if motion.v is None or motion.a is None:
        motion = differentiate(robot.model, motion)
    w = estimate_wrenches(robot, motion, contacts)
    report = audit(robot, motion, w.wrenches, contacts, tolerances=tolerances,
                   collision_margin=collision_margin)
    return summarise(report, w, motion, source)
