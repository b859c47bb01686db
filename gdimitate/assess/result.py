"""The result of an adaptation: :class:`AdaptedMotion` (the motion, the kinematic comparison
with the demonstration, and for the optimal method the wrenches, contacts, solver account and
audit) and :class:`AdaptationReport`, made by :func:`compare`. Every method returns one
(:func:`gdimitate.adaptation.adaptor.adapt`, which re-exports these names)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..model.contact import SoleContact
from ..model.footsteps import GaitComparison
from ..model.motion import Motion
from ..model.robot import SIDES, Robot
from .metrics import (
    angle_down,
    foot_heights,
    force_direction,
    hip_height_ratio,
    joint_limit_margins,
)

if TYPE_CHECKING:  # annotations only: the audit is below this module, the solver above it
    from .audit.report import AuditReport
    from .solver import SolverInfo

__all__ = ["AdaptationReport", "AdaptedMotion", "compare"]


@dataclass
class AdaptationReport:
    """What an adaptation achieved.

    ``feasible``: per leg ``(T,)`` bool, frames where the method met its constraints (Eq. 1:
    ``|arg| ≤ 1``); ``infeasible_frames``: their count per leg; ``force_direction_error``: per
    leg ``(T,)`` imitator − demonstrator push direction [rad] under ``force_model`` (NaN in
    swing), and its max; ``hip_height_ratio_error_max``: max |hip-over-ankle height / leg
    length − the demonstrator's| over all frames; ``joint_limit_violation``: per joint the
    largest excursion beyond a position limit [rad] (only joints that violate), and its max;
    ``ground_penetration_max``: deepest any sole frame goes below the ground z = 0 [m]. The
    physical checks (torques, cones, every sole corner) are the audit's
    (:attr:`AdaptedMotion.audit`).
    """

    method: str
    force_model: str
    feasible: dict[str, np.ndarray]
    infeasible_frames: dict[str, int]
    force_direction_error: dict[str, np.ndarray]
    force_direction_error_max: float
    hip_height_ratio_error_max: float
    joint_limit_violation: dict[str, float]
    joint_limit_violation_max: float
    ground_penetration_max: float = 0.0

    @property
    def all_feasible(self) -> bool:
        """True when every frame of both legs is feasible and no limit is violated."""
        return (all(v == 0 for v in self.infeasible_frames.values())
                and self.joint_limit_violation_max <= 1e-9)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary (no per-frame arrays except the feasibility masks)."""
        return {
            "method": self.method,
            "force_model": self.force_model,
            "infeasible_frames": dict(self.infeasible_frames),
            "frames": int(next(iter(self.feasible.values())).size),
            "force_direction_error_max_rad": self.force_direction_error_max,
            "hip_height_ratio_error_max": self.hip_height_ratio_error_max,
            "joint_limit_violation_max_rad": self.joint_limit_violation_max,
            "joint_limit_violation_rad": dict(self.joint_limit_violation),
            "ground_penetration_max_m": self.ground_penetration_max,
            "feasible": {s: m.astype(int).tolist() for s, m in self.feasible.items()},
        }


@dataclass(frozen=True)
class AdaptedMotion:
    """An adaptation's result.

    - ``motion``: the imitator's :class:`Motion` (the optimal method fills ``v``, ``a``
      ``(T, nv)`` in Pinocchio's conventions and ``contact`` with the schedule it used);
    - ``report``: the kinematic comparison with the demonstration (:class:`AdaptationReport`);
    - ``robot``: the imitator;
    - ``wrenches`` (optimal only): ``{"left": (T, 6), "right": (T, 6)}`` — ``[f; τ]`` [N, N·m]
      the ground applies to each foot, in its sole frame at the frame's origin (zeros in
      swing; planar models: f_y = τ_x = τ_z = 0);
    - ``contacts`` (optimal only): ``{"left": SoleContact, "right": SoleContact}`` used;
    - ``audit`` (optimal only): :class:`gdimitate.assess.audit.AuditReport` recomputed from
      ``motion`` and ``wrenches`` with Pinocchio (``audit.feasible``, ``audit.binding``);
    - ``solver`` (optimal only): :class:`gdimitate.retarget.SolverInfo`;
    - ``force_model``: the force-direction model of the goal;
    - ``frame_feasible`` (streaming mode only): ``(T,)`` per-frame audit flags;
    - ``gait`` (optimal only): :class:`gdimitate.model.footsteps.GaitComparison`, the imitator's
      steps, stride, travel and speed against the demonstrator's scaled to its legs.
    """

    motion: Motion
    report: AdaptationReport
    robot: Robot
    wrenches: dict[str, np.ndarray] | None = None
    contacts: dict[str, SoleContact] | None = None
    audit: AuditReport | None = None
    solver: SolverInfo | None = None
    force_model: str = "segment"
    frame_feasible: np.ndarray | None = None
    gait: GaitComparison | None = None

    def save(self, path, format: str = "npz", *, fps: float = 30.0,
             body_order: str | None = None):
        """Write the motion (and, in ``"npz"``, the contact wrenches and the robot's record)
        in ``format``: ``"csv"``, ``"npz"``, ``"mujoco"``, ``"lafan1_csv"``, ``"gmr"`` or
        ``"isaaclab_amp"`` (:func:`gdimitate.export.writers.export_motion` describes each; ``fps``
        [Hz] is the rate of the last three, ``body_order`` ``"depth"``/``"breadth"`` the body
        order of the last two). Returns the path written."""
        from ..export.writers import export_motion

        return export_motion(self.robot, self.motion, path, format, wrenches=self.wrenches,
                             fps=fps, body_order=body_order)

    @property
    def feasible(self) -> bool:
        """The audit's verdict (optimal method); for Eq. (1) and joint copying, whether every
        frame was reachable and within the position limits."""
        if self.audit is not None:
            return bool(self.audit.feasible)
        return self.report.all_feasible


def _nanmax_abs(arrs) -> float:
    vals = np.concatenate([np.abs(a[~np.isnan(a)]) for a in arrs])
    return float(vals.max()) if vals.size else 0.0


def compare(demonstrator: Robot, demo: Motion, imitator: Robot, motion: Motion, method: str,
            feasible: dict[str, np.ndarray], force: str = "segment",
            push_m: dict[str, np.ndarray] | None = None,
            push_r: dict[str, np.ndarray] | None = None) -> AdaptationReport:
    """Measure an imitator motion against the demonstration (used by every method).

    ``push_m``/``push_r``: ``{side: (T, 3)}`` push directions of the demonstrator/imitator
    when they are not computed by ``force_direction(robot, motion, force)`` (measured forces,
    an optimiser's wrenches)."""
    if push_m is None:
        fd_m = {s: f.sagittal for s, f in force_direction(demonstrator, demo, force).items()}
    else:
        fd_m = {s: angle_down(push_m[s]) for s in SIDES}
    if push_r is None:
        fd_r = {s: f.sagittal for s, f in force_direction(imitator, motion, force).items()}
    else:
        fd_r = {s: angle_down(push_r[s]) for s in SIDES}
    err = {s: fd_r[s] - fd_m[s] for s in SIDES}
    hr_m = hip_height_ratio(demonstrator, demo)
    hr_r = hip_height_ratio(imitator, motion)
    viol = {}
    for j, margin in joint_limit_margins(imitator, motion).items():
        worst = float(-margin.min())
        if worst > 1e-12:
            viol[j] = worst
    return AdaptationReport(
        method=method, force_model=force,
        feasible={s: np.asarray(feasible[s], bool) for s in SIDES},
        infeasible_frames={s: int((~np.asarray(feasible[s], bool)).sum()) for s in SIDES},
        force_direction_error=err,
        force_direction_error_max=_nanmax_abs(err.values()),
        hip_height_ratio_error_max=float(max(np.max(np.abs(hr_r[s] - hr_m[s])) for s in SIDES)),
        joint_limit_violation=viol,
        joint_limit_violation_max=max(viol.values(), default=0.0),
        ground_penetration_max=float(max(0.0, -min(h.min() for h in
                                                   foot_heights(imitator, motion).values()))),
    )
