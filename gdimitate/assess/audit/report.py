"""The audit's result types: tolerances, one :class:`Check` per bound, per-joint and per-foot
summaries, and the :class:`AuditReport` that holds them (JSON-safe through ``to_dict``)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import NamedTuple

import numpy as np

from ...jsonable import jsonable

__all__ = [
    "AuditTolerances",
    "Check",
    "Worst",
    "JointAudit",
    "Penetration",
    "ForceDirectionAudit",
    "FootAudit",
    "AuditReport",
    "CORNER_NAMES",
    "AT_BOUND",
    "AT_POSITION",
    "at_bound",
]

#: A joint whose torque or velocity is at least this share of its limit is at its bound.
AT_BOUND = 0.99
#: A joint within this distance [rad or m] of a position limit is at its bound.
AT_POSITION = 1e-3
def at_bound(rows, share: float = AT_BOUND) -> list[str]:
    """The limits at their bound among ``rows`` of ``(joint, torque ratio, velocity ratio,
    position margin)`` (NaN: no such limit): a torque or velocity at ≥ ``share`` of its limit
    as ``"torque:J 1.00"``, most used first, then a position within :data:`AT_POSITION` of a
    limit as ``"position:J"`` — the one reading of "at its bound" every output uses."""
    out: list[tuple[float, str]] = []
    for name, tr, vr, pm in rows:
        for kind, r in (("torque", tr), ("velocity", vr)):
            if np.isfinite(r) and r >= share:
                out.append((float(r), f"{kind}:{name} {r:.2f}"))
        if np.isfinite(pm) and pm <= AT_POSITION:
            out.append((0.0, f"position:{name}"))
    return [x for _, x in sorted(out, key=lambda p: -p[0])]


#: Names of the four sole corners in :meth:`gdimitate.model.contact.SoleContact.corners` order.
CORNER_NAMES = ("front-left", "front-right", "back-right", "back-left")


@dataclass(frozen=True)
class AuditTolerances:
    """How far past each bound a motion may go and still count as feasible.

    - ``base_residual`` [N, N·m]: largest |component| of the unactuated (base) rows of
      ``rnea(q, v, a) − Σ_c J_cᵀ w_c``;
    - ``torque`` [-]: fraction over an effort limit (1e-3: 0.1 % over);
    - ``velocity`` [-]: fraction over a velocity limit (1e-2: 1 % over);
    - ``position`` [rad or m]: beyond a position limit;
    - ``velocity_consistency`` [rad/s or m/s]: distance of a forward difference of ``q`` from
      the interval spanned by the velocities at its two knots (widened by ``h·|Δa| / 2``, the
      third-order term central differences leave);
    - ``normal`` [N]: below zero normal force in stance;
    - ``friction`` [-]: friction ratio over μ; ``cop`` [m]: centre of pressure outside the
      sole; ``yaw`` [N·m]: yaw moment beyond its bounds (these three where the foot does not
      pull; a pulling foot fails ``normal``);
    - ``penetration`` [m]: a sole corner under the floor (z = 0);
    - ``contact_gap`` [m]: a stance foot's highest sole corner above the floor (a flat contact
      — the wrench cone's premise — needs the whole sole on the floor);
    - ``slip`` [m], ``slip_rotation`` [rad]: a stance foot's drift from where its stance began;
    - ``stance_velocity`` [m/s, rad/s]: a stance foot's sole-frame velocity ``J_c(q_k) v_k``
      at a stance knot (its linear and angular norms, each less half its change
      ``(J_c(q_k) − J_c(q_k ⊖ h_k v_k)) v_k`` along the step ``v_k`` spans: a foot whose pose
      is held across a one-step scheme's step ends it at about that half) — a foot on the floor
      is still;
    - ``force_direction`` [rad]: angle of the push beyond the audit's ``cone_half_angle``;
    - ``swing_wrench`` [N, N·m]: largest |component| of a swing foot's wrench;
    - ``self_collision`` [m]: how far two of the robot's own collision geometries (limb–limb,
      limb–trunk; :mod:`gdimitate.model.selfcollision`) may come closer than the audit's
      ``collision_margin``.
    """

    base_residual: float = 1e-6
    torque: float = 1e-3
    velocity: float = 1e-2
    position: float = 1e-6
    velocity_consistency: float = 1e-2
    normal: float = 1e-6
    friction: float = 1e-6
    cop: float = 1e-6
    yaw: float = 1e-6
    penetration: float = 1e-3
    contact_gap: float = 1e-3
    slip: float = 1e-3
    slip_rotation: float = 1e-3
    stance_velocity: float = 1e-3
    force_direction: float = 1e-3
    swing_wrench: float = 1e-6
    self_collision: float = 1e-3

    def __post_init__(self) -> None:
        from ...errors import InvalidInputError

        for f in fields(self):
            v = getattr(self, f.name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise InvalidInputError(
                    f"AuditTolerances.{f.name} must be a finite number ≥ 0; got {v!r}")


class Worst(NamedTuple):
    """The worst value of a quantity over the knots and the knot where it is (−1: no knot)."""

    value: float
    knot: int


@dataclass(frozen=True)
class Check:
    """One bound of the audit.

    ``name`` (e.g. ``"torque:leg_left_4_joint"``, ``"cop:left"``, ``"penetration"``);
    ``value``: the worst value over the knots, in ``unit``; ``bound``: what it is compared with,
    tolerance included (``sense`` ``"max"``: value ≤ bound; ``"min"``: value ≥ bound); ``knot``:
    where the worst value is (−1 where the check has no knots, e.g. a foot never in stance);
    ``passed``; ``violation`` ≥ 0: how far past the bound, made dimensionless by a stated
    scale (0 when passed) — it orders :attr:`AuditReport.binding`; ``failures``: at how many
    knots it fails (:meth:`AuditReport.check_knots` says which).
    """

    name: str
    value: float
    bound: float
    knot: int
    passed: bool
    violation: float
    unit: str
    sense: str
    failures: int = 0


@dataclass(frozen=True)
class JointAudit:
    """One actuated joint (its worst degree of freedom where it has several).

    ``torque_max`` [N·m or N] worst |τ| and ``torque_knot``; ``effort_limit`` (inf: none in the
    model — listed in :attr:`AuditReport.unlimited`); ``torque_ratio`` |τ|/limit (NaN without a
    limit). ``velocity_max`` [rad/s or m/s]: worst of |v| and |forward difference of q|, at
    ``velocity_knot``; ``velocity_limit`` (inf: none); ``velocity_ratio``. ``position_margin``
    [rad or m]: smallest distance to a position limit (negative: outside), at
    ``position_knot`` (inf, −1: no finite limits)."""

    name: str
    torque_max: float
    torque_knot: int
    effort_limit: float
    torque_ratio: float
    velocity_max: float
    velocity_knot: int
    velocity_limit: float
    velocity_ratio: float
    position_margin: float
    position_knot: int


class Penetration(NamedTuple):
    """The deepest sole corner under the floor: ``depth`` [m] (positive: under z = 0; negative:
    the lowest corner's clearance), ``knot``, ``foot`` (side) and ``corner`` (index into
    :data:`CORNER_NAMES`)."""

    depth: float
    knot: int
    foot: str
    corner: int


@dataclass(frozen=True)
class ForceDirectionAudit:
    """A stance foot's push direction ``−f`` (world frame) against the demonstrator's target:
    ``error_max`` [rad] the largest angle between them and its ``knot``; ``error_rms`` [rad];
    ``sagittal_max``/``frontal_max`` [rad]: the largest |difference| of the angles from the
    downward vertical in the x–z plane (positive forward) and the y–z plane (positive left), at
    ``sagittal_knot``/``frontal_knot``; ``knots``: how many knots had both a target and a
    non-zero force."""

    side: str
    error_max: float
    knot: int
    error_rms: float
    sagittal_max: float
    sagittal_knot: int
    frontal_max: float
    frontal_knot: int
    knots: int


@dataclass(frozen=True)
class FootAudit:
    """One foot: ``stance_knots``; the worst ``normal`` force [N] (smallest f_z in stance),
    ``friction`` ratio |f_t|/f_z [-] against ``mu``, ``cop`` margin [m] (inside positive),
    ``yaw`` margin [N·m] (see :func:`gdimitate.model.contact.cone_margin`), ``slip`` [m] and
    ``slip_rotation`` [rad] (drift of the sole frame since the stance began), ``stance_velocity``
    (largest sole-frame speed ``max(‖v‖ [m/s], ‖ω‖ [rad/s])`` at a stance knot), ``swing_wrench``
    (largest |component| while in swing), ``contact_gap`` [m] (highest sole corner above the
    floor in stance), ``penetration`` (this foot's deepest corner, all knots),
    ``force_direction`` (None without a target)."""

    side: str
    stance_knots: int
    mu: float
    normal: Worst
    friction: Worst
    cop: Worst
    yaw: Worst
    slip: Worst
    slip_rotation: Worst
    swing_wrench: Worst
    contact_gap: Worst
    penetration: Penetration
    force_direction: ForceDirectionAudit | None
    stance_velocity: Worst = Worst(float("nan"), -1)


@dataclass(frozen=True)
class SelfCollisionAudit:
    """The closest approach of the robot's own collision geometries over the motion:
    ``distance`` [m] (signed: negative where two overlap) between ``pair`` (geometry names) at
    ``knot``; ``margin`` [m] the bound; ``pairs``: how many pairs were checked; ``excluded``
    ``((a, b, distance at the neutral pose [m] or NaN for neighbouring bodies), …)``: the
    pairs left out (:func:`gdimitate.model.selfcollision.self_collision`)."""

    distance: float
    knot: int
    pair: tuple[str, str]
    margin: float
    pairs: int
    excluded: tuple[tuple[str, str, float], ...] = ()


@dataclass(frozen=True, eq=False)
class AuditReport:
    """The recomputed feasibility of a motion with its contact wrenches.

    ``feasible``: every check passed; ``binding``: the names of the failed checks, most
    violated first (by :attr:`Check.violation`); ``checks``: every check; ``feet``
    ``{side: FootAudit}``; ``joints``: one :class:`JointAudit` per actuated joint;
    ``unlimited``: ``(joint, "effort" | "velocity")`` pairs of actuated joints without that
    limit in the model (not checked — reported, not skipped); ``base_residual`` [N, N·m]
    (largest |component| of the base rows, and its knot); ``penetration``: the deepest sole
    corner of all feet; ``velocity_consistency`` [rad/s, m/s]; ``knot_feasible`` ``(T,)``: every
    per-knot check holds at that knot (forward differences count at their first knot);
    ``tau`` ``(T, nv)`` [N·m, N]: the recomputed ``rnea(q, v, a) − Σ_c J_cᵀ w_c`` (the base
    rows are the residual, the others the joint torques); ``knot_checks`` ``(n_checks, T)``
    bool: each check's per-knot pass flags, rows in ``checks`` order; ``tolerances``;
    ``cone_half_angle`` [rad]; ``self_collision``: the closest approach of the robot's own
    collision geometries (:class:`SelfCollisionAudit`; ``None``: the robot has no collision
    geometry — not checked, and the summary says so); ``joint_use`` ``(T, n_joints, 3)``: per
    knot and actuated joint (``joints``' order) the torque ratio |τ|/limit, the velocity ratio
    and the position margin [rad or m] (NaN: no such limit), what :meth:`limits_at` reads.
    """

    feasible: bool
    binding: tuple[str, ...]
    checks: tuple[Check, ...]
    feet: Mapping[str, FootAudit]
    joints: tuple[JointAudit, ...]
    unlimited: tuple[tuple[str, str], ...]
    base_residual: Worst
    penetration: Penetration
    velocity_consistency: Worst
    knot_feasible: np.ndarray
    tau: np.ndarray
    knot_checks: np.ndarray
    tolerances: AuditTolerances = field(default_factory=AuditTolerances)
    cone_half_angle: float = 0.0
    self_collision: SelfCollisionAudit | None = None
    joint_use: np.ndarray | None = None

    def limits_at(self, knot: int, share: float = AT_BOUND) -> list[str]:
        """The actuated joints' limits at their bound at ``knot`` (torque or velocity at ≥
        ``share`` of its limit, most used first, as ``"torque:J 1.00"``; then positions within
        :data:`AT_POSITION` of a limit, ``"position:J"``): what may hold a goal back there
        (at their bound, not proven to be the cause); empty without :attr:`joint_use`."""
        if self.joint_use is None or not 0 <= knot < len(self.joint_use):
            return []
        return at_bound(((j.name, *use) for j, use in zip(self.joints, self.joint_use[knot])),
                        share)

    @property
    def force_direction_error(self) -> dict[str, ForceDirectionAudit | None]:
        """``{side: ForceDirectionAudit | None}`` (None where no target was given)."""
        return {s: f.force_direction for s, f in self.feet.items()}

    def check(self, name: str) -> Check:
        """The check called ``name``; :class:`~gdimitate.errors.UnknownNameError` lists them."""
        from ...errors import UnknownNameError

        for c in self.checks:
            if c.name == name:
                return c
        raise UnknownNameError("check", name, [c.name for c in self.checks])

    def check_knots(self, name: str) -> np.ndarray:
        """``(T,)`` bool: the knots where check ``name`` holds."""
        self.check(name)
        return self.knot_checks[[c.name for c in self.checks].index(name)]

    def joint(self, name: str) -> JointAudit:
        """The :class:`JointAudit` of joint ``name``."""
        from ...errors import UnknownNameError

        for j in self.joints:
            if j.name == name:
                return j
        raise UnknownNameError("joint", name, [j.name for j in self.joints])

    def to_dict(self) -> dict:
        """Everything but the arrays ``tau``, ``knot_checks`` and ``joint_use`` as plain JSON
        types (NaN and inf become ``None``)."""
        return jsonable({f.name: getattr(self, f.name) for f in fields(self)
                         if f.name not in ("tau", "knot_checks", "joint_use")})

    def summary(self, only_failed: bool = False) -> str:
        """A text table: one line per check (value, bound, unit, worst knot, status)."""
        head = (f"feasible: {'yes' if self.feasible else 'NO'}"
                + (f"; binding: {', '.join(self.binding)}" if self.binding else ""))
        lines = [head, f"{'check':<36} {'value':>12} {'bound':>12} {'unit':<6} {'knot':>5}  ok"]
        order = sorted(self.checks, key=lambda c: (c.passed, -c.violation))
        for c in order:
            if only_failed and c.passed:
                continue
            op = "≤" if c.sense == "max" else "≥"
            lines.append(f"{c.name:<36} {c.value:>12.4g} {op}{c.bound:>11.4g} {c.unit:<6} "
                         f"{c.knot:>5}  {'yes' if c.passed else 'NO'}")
        if self.unlimited:
            lines.append("no limit in the model (not checked): " + ", ".join(
                f"{j} ({k})" for j, k in self.unlimited))
        sc = self.self_collision
        if sc is None:
            lines.append("self-collision: not checked (the robot has no collision geometry)")
        else:
            lines.append(f"self-collision: {sc.pairs} pairs, closest {sc.distance:.4g} m "
                         f"({sc.pair[0]} – {sc.pair[1]}, knot {sc.knot}); "
                         f"{len(sc.excluded)} pairs left out (neighbours or touching at the "
                         "neutral pose)")
        return "\n".join(lines)
