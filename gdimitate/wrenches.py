"""Contact wrenches that explain a motion's whole-body dynamics (Newton–Euler of the base)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .contact import SoleContact
from .motion import Motion

__all__ = ["WrenchEstimate", "estimate_wrenches", "METHODS"]

METHODS = ("cone", "lstsq")


@dataclass(frozen=True)
class WrenchEstimate:
    """Estimated contact wrenches of a motion.

    - ``wrenches`` ``{side: (T, 6)}``: ``[f; τ]`` [N, N·m] the ground applies to each foot, in
      its contact frame at the frame's origin (zeros in swing; planar bases: f_y = τ_x = τ_z
      = 0);
    - ``residual`` ``(T, 6)``: the part of the base rows of the inverse dynamics the wrenches do
      not explain, ``rnea(q, v, a)_base − Σ_c (J_cᵀ w_c)_base``, as a wrench at the base origin
      [N, N·m] — free-flyer: in the base's local frame (Pinocchio's convention); planar
      (x, z, pitch) bases: world-aligned axes, f_y = τ_x = τ_z = 0;
    - ``net`` ``(T, 6)``: the explained part Σ_c (J_cᵀ w_c)_base, same convention;
    - ``method``; ``solve_time`` [s]: total time of the per-knot solves.
    """

    wrenches: Mapping[str, np.ndarray]
    residual: np.ndarray
    net: np.ndarray
    method: str
    solve_time: float = 0.0


def estimate_wrenches(robot, motion: Motion, contacts: Mapping[str, SoleContact] | None = None,
                      *, method: str = "cone", f_min: float = 0.0) -> WrenchEstimate:
    """Contact wrenches that explain the base rows of the inverse dynamics of ``motion``.

    Per knot, with ``b = rnea(q, v, a)`` restricted to the base rows and ``A_c`` the base rows
    of the contact Jacobian transpose (LOCAL frame of ``contacts[side].frame``):

    - ``method="cone"``: a small QP (DAQP) — first ``min ‖w‖²`` s.t. ``Σ_c A_c w_c = b`` with
      each stance foot's wrench in its contact wrench cone (16 rows) and ``f_z ≥ f_min``; where
      the cones cannot explain ``b`` exactly, the least (scaled) residual plus a small
      regularisation instead. Double support is split by the QP; swing feet get zeros.
    - ``method="lstsq"``: the minimum-norm least-squares solution without any cone (what a
      kinematic retargeter implicitly asks of the floor: feet may pull).

    ``motion`` needs ``v``, ``a`` (:func:`gdimitate.motion.differentiate`) and ``contact``.
    Free-flyer and planar (x, z, pitch) bases; fixed bases raise
    :class:`~gdimitate.errors.InvalidInputError` (nothing to explain). Returns a
    :class:`WrenchEstimate`.
    """
    raise NotImplementedError
