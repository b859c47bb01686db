"""Flat-foot contact: a stance foot lies flat on the floor, keeps its pose and lands still.

At a stance knot the sole frame's origin is at z = 0 and its normal is vertical (rows
``p_z``, ``R[2, 0]``, ``R[2, 1]``; planar models ``p_z``, ``R[2, 0]``). Between two
consecutive stance knots of the same foot it neither slides nor turns (hold rows
``Δp_x``, ``Δp_y`` and ``sin Δψ`` of the sole's x axis; planar ``Δp_x``). At the first knot of
a stance — a touch-down (the foot swung at the knot before) or a stance at knot 0 — the sole
frame's spatial velocity ``J_c(q_k) v_k`` vanishes (Pinocchio's ``LOCAL_WORLD_ALIGNED`` frame
Jacobian: the origin's velocity [m/s], then the angular velocity [rad/s], world axes; 6 rows,
planar models the x, z and pitch rows). Never relaxed.

Why the velocity rows are imposed there and not at every stance knot. With semi-implicit
Euler (:mod:`.integration`, ``q_k = q_{k−1} ⊕ h v_k``) ``v_k`` is the velocity of the whole
step (k − 1, k). Where the foot is down at both ends the hold rows already make the foot's
displacement over that step zero, i.e. its mean velocity along the step; ``J_c(q) v_k`` still
changes along the step, by ``(J_c(q_k) − J_c(q_{k−1})) v_k`` = O(h·|v|²·ℓ), so it ends the
step at about half of that (what :func:`gdimitate.assess.audit.audit`'s ``stance_velocity`` check
allows for there). Asking for ``J_c(q_k) v_k = 0`` at those knots as well would over-determine
the step: the velocities of the base and the stance leg (6 + 6 in 3-D, 3 + 3 planar) would
have to meet as many pose and velocity rows, which near a still robot only v = 0 does — the
body could not move over its stance foot (with them, Case I of the paper is left with 2e-4 of
unmet integration rows).
At the first knot of a stance nothing holds the step that brought the foot down: without the
rows the plan lands its foot moving (0.5 m/s on G1, 1 m/s on HOAP-2 for the shipped 3-D walk)
and at knot 0 it starts moving; with them the foot arrives at rest. A foot that an
``"anchor"`` rule takes over while it is already down (Eq. (1)'s rule) does not touch down
there and gets no velocity rows.

Lift-off mirrors touch-down. ``a_k`` is the acceleration of the step (k, k + 1)
(``v_{k+1} = v_k + h a_k``), so at the last stance knot k of a stance it is the acceleration
that takes the foot off the floor — while the dynamics at knot k still give that foot its
stance wrench. Without more rows the plan asks a loaded flat foot to accelerate away from the
floor (118 rad/s² of heel-lift on G1 under 350 N for the shipped 3-D walk), which no contact
can do: a tracking controller that holds its stance feet then meets a plan whose
accelerations and wrenches contradict each other at every lift-off. So the foot stays down,
unloaded, one knot longer: at the first swing knot after a stance (the *lift-off knot*) its
pose rows hold (flat on the floor) and the hold rows link it to the last stance knot; its
wrench is zero (it is not in stance) and it leaves the floor with that knot's acceleration.
Then every stance knot's wrench acts on a foot that is, to the scheme's order, not
accelerating: ``J_c (v_{k+1} − v_k)/h`` is O(h) there, as at every other stance knot.
Under Eq. (1)'s ``"anchor"`` rule (a kinematic rule: the anchor foot lifts with the
demonstrator's, at the knot where the anchor passes to the other foot) there are no lift-off
knots (``Spec.liftoff``), so that the optimum is still Eq. (1) there (docs/design.md §6).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...model.robot import SIDES
from ..knot import Knot
from .base import Bounds, Constraint, Spec, per_side_labels

__all__ = ["FlatContact", "velocity_knots", "liftoff_knots", "PLANAR_VELOCITY_ROWS"]

#: Rows of the sole frame's spatial velocity ``[v; ω]`` kept by planar models (x, z, pitch).
PLANAR_VELOCITY_ROWS = (0, 2, 4)


def _per_side(planar: bool) -> tuple[int, int]:
    """``(pose rows, velocity rows)`` of one foot."""
    return (2, len(PLANAR_VELOCITY_ROWS)) if planar else (3, 6)


def sole_velocity(k: Knot, side: str) -> ca.SX:
    """``(6,)`` ``J_c(q) v`` of the foot's sole frame (``[m/s; rad/s]``, world axes; Pinocchio's
    ``LOCAL_WORLD_ALIGNED``), planar models its x, z, pitch rows ``(3,)``."""
    V = ca.mtimes(k.sym.frame_jacobian(k.contacts[side].frame)(k.q), k.v)
    return V[list(PLANAR_VELOCITY_ROWS)] if k.planar else V


def velocity_knots(stance: np.ndarray, swing: np.ndarray) -> np.ndarray:
    """``(T,)`` bool: the stance knots whose velocity rows are imposed — the first knot after a
    swing knot (the touch-down) and a stance at knot 0, where no hold row links ``v_k`` to a
    still foot (see the module docstring). A foot that an ``"anchor"`` rule takes over while it
    is already down (``swing`` False before) is not touching down there."""
    st, sw = np.asarray(stance, bool), np.asarray(swing, bool)
    return st & np.r_[True, sw[:-1]]


def liftoff_knots(stance: np.ndarray, swing: np.ndarray) -> np.ndarray:
    """``(T,)`` bool: the lift-off knots — a swing knot right after a stance knot, where the
    foot is still held flat on the floor, unloaded (see the module docstring); what
    ``Spec.liftoff`` holds under the ``"all"`` contact rule."""
    st, sw = np.asarray(stance, bool), np.asarray(swing, bool)
    return sw & np.r_[False, st[:-1]]



@dataclass(frozen=True)
class FlatContact(Constraint):
    """Per foot: pose rows ``p_z``, ``R[2, 0]`` (, ``R[2, 1]``), then the sole velocity rows."""

    name: str = "flat contact"
    relaxable: bool = False

    def rows(self, k: Knot) -> ca.SX:
        """``(18, 1)``: per foot ``p_z`` [m], ``R[2, 0]``, ``R[2, 1]``, then ``J_c v``
        ``(6,)`` [m/s, rad/s] (planar ``(10, 1)``: ``p_z``, ``R[2, 0]`` and 3 velocity rows
        per foot)."""
        out = []
        for s in SIDES:
            p, R = k.sole_p[s], k.sole_R[s]
            out += [p[2], R[2, 0]] + ([] if k.planar else [R[2, 1]])
            out.append(sole_velocity(k, s))
        return ca.vertcat(*out)

    def labels(self, k: Knot) -> list[str]:
        return per_side_labels(self.name, sum(_per_side(k.planar)))

    def bounds(self, spec: Spec) -> Bounds:
        """0 for the pose rows at stance and lift-off knots and for the velocity rows at
        :func:`velocity_knots`, free elsewhere; each ``(T, n)``."""
        npose, nvel = _per_side(spec.planar)
        n = npose + nvel
        lo = np.full((spec.T, 2 * n), -np.inf)
        for i, s in enumerate(SIDES):
            o = i * n
            lo[spec.stance[s] | spec.liftoff[s], o:o + npose] = 0.0
            lo[velocity_knots(spec.stance[s], spec.swing[s]), o + npose:o + n] = 0.0
        return Bounds(lo, np.where(np.isfinite(lo), 0.0, np.inf))

    def start_velocity_rows(self, spec: Spec) -> np.ndarray:
        """Indices, within this part's rows, of the velocity rows of both feet (a caller that
        fixes knot 0's ``v`` to a previous solve's — the streaming window — frees them at
        knot 0: that velocity was the previous step's, held by that step's rows)."""
        npose, nvel = _per_side(spec.planar)
        n = npose + nvel
        return np.array([i * n + j for i in range(len(SIDES)) for j in range(npose, n)], int)
