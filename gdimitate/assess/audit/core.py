"""``audit(robot, motion, wrenches, ...)``: recompute every feasibility check of a motion."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ...model.contact import SoleContact
from ...model.motion import Motion
from .report import AuditReport, AuditTolerances

__all__ = ["audit"]


def audit(robot, motion: Motion, wrenches: Mapping[str, np.ndarray],
          contacts: Mapping[str, SoleContact] | None = None, *,
          target: Mapping[str, np.ndarray] | None = None, cone_half_angle: float = 0.0,
          tolerances: AuditTolerances | None = None,
          collision_margin: float = 0.0) -> AuditReport:
    """Audit ``motion`` of ``robot`` (a :class:`gdimitate.Robot`) with its contact wrenches.

    - ``motion``: ``t`` ``(T,)`` [s], ``q`` ``(T, nq)``, ``v``/``a`` ``(T, nv)`` (Pinocchio
      conventions; use :func:`gdimitate.model.motion.differentiate` to add them to a recorded
      motion), ``contact`` ``{"left": (T,) bool, "right": (T,) bool}`` (True in stance);
    - ``wrenches`` ``{side: (T, 6)}``: the wrench ``[f; τ]`` [N, N·m] the ground applies to
      each foot, in its contact frame (``contacts[side].frame``) at that frame's origin;
    - ``contacts``: ``{side: SoleContact}``, default ``robot.require_contacts()``;
    - ``target`` ``{side: (T, 3)}``: unit push directions on the ground (world frame) of the
      demonstrator — the ground's force on the foot should point along −target; NaN rows where
      there is none;
    - ``cone_half_angle`` [rad]: the allowed angle between the push and its target;
    - ``tolerances``: :class:`AuditTolerances` (defaults stated there);
    - ``collision_margin`` [m]: the least distance between two of the robot's own collision
      geometries on different limbs, or on a limb and the trunk (pairs on neighbouring bodies
      or already closer at the neutral pose are left out and listed,
      :func:`gdimitate.model.selfcollision.self_collision`); 0: they may touch, not overlap.

    Checks (their names in :attr:`AuditReport.binding`): ``base_residual``; per actuated joint
    ``torque:<joint>``, ``velocity:<joint>`` (|v| and forward differences of ``q``),
    ``position:<joint>``; ``velocity_consistency``; per foot ``normal:<side>``,
    ``friction:<side>`` (Coulomb's circle), ``cop:<side>``, ``yaw:<side>``, ``slip:<side>``,
    ``slip_rotation:<side>``, ``stance_velocity:<side>`` (the sole frame's velocity ``J_c v`` at
    every stance knot), ``contact_gap:<side>`` (stance: the whole sole on the floor),
    ``swing_wrench:<side>``, ``force_direction:<side>`` (with a target); ``penetration`` (every
    sole corner, every knot); ``self_collision`` (the closest pair, every knot; robots without
    collision geometry: not checked, :attr:`AuditReport.self_collision` is ``None``).

    Returns an :class:`AuditReport`. Raises :class:`~gdimitate.errors.InvalidInputError` for
    missing ``v``/``a``, wrong shapes or non-finite values.
    """
    from .checks import run_audit

    return run_audit(robot, motion, wrenches, contacts, target, cone_half_angle,
                     tolerances or AuditTolerances(), collision_margin)
