"""Parameters of the whole-body optimal adaptor: cost weights, limit overrides, contact options.

All are frozen dataclasses validated in their constructors. Their numbers enter the cached NLP
as parameter values or bounds, so changing them never rebuilds the problem; only the flags
named in :class:`Contact` (``cone_half_angle`` > 0 or not) select a structurally different one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ..errors import InvalidInputError
from ..model.contact import DEFAULT_MU

__all__ = ["DEFAULT_RATE", "Weights", "Limits", "Contact", "IPOPT_DEFAULTS"]

IPOPT_DEFAULTS = {
    "print_level": 0, "sb": "yes", "tol": 1e-8, "constr_viol_tol": 1e-8,
    "acceptable_tol": 1e-6, "acceptable_constr_viol_tol": 1e-7, "acceptable_iter": 5,
    "max_iter": 150, "mu_strategy": "adaptive", "linear_solver": "mumps",
    "mumps_pivot_order": 0, "mumps_permuting_scaling": 0, "mumps_scaling": 0,
    "fixed_variable_treatment": "make_parameter", "bound_relax_factor": 0.0,
    "alpha_for_y": "min-dual-infeas", "obj_scaling_factor": 10.0,
}
"""IPOPT options (MUMPS, the solver of the PyPI CasADi wheel, with AMD ordering: steadier
than METIS here; no MUMPS scaling: its permuting scaling and row/column scaling are computed
at every factorisation and cost more than they save — G1 100 knots 23.1 → 9.9 s CPU, Talos
28.4 → 24.7 s, the same optimum; docs/design.md §6). The multipliers' step is the one that
least violates dual feasibility (``alpha_for_y``) and the cost is scaled by 10 (the barrier
parameter μ then weighs a tenth as much against it; the stop's μ test,
:data:`~.stopping.MU_TOL`, follows the scale): one cycle of the shipped walk, 100 knots,
Talos 57 → 39 iterations, G1 65 → 34, iCub 76 → 40, Romeo 54 → 47, the whole clip → G1
49 → 44, the CMU walk → G1 89 → 76, HOAP-2 44 → 29 (with the stop's feasibility at the
adaptor's ``tol``; docs/design.md §6). ``ipopt=`` adds to them. Kept here, not in
:mod:`.trajectory.problem`, so that tuning them does not change the compiled functions' key."""

#: Default knot rate [knots/s] of the trajectory mode: the demonstration is resampled onto a
#: grid of this rate. 50 Hz resolves walking (steps of ~0.5 s, contact phases of 0.1–0.6 s)
#: with ~25 knots per step.
DEFAULT_RATE = 50.0


def _nonneg(obj, allow_inf: bool = False) -> None:
    for f in fields(obj):
        v = getattr(obj, f.name)
        if v is None or isinstance(v, (tuple, frozenset, dict)):
            continue
        ok = isinstance(v, (int, float, np.floating)) and v >= 0 and (
            math.isfinite(v) or (allow_inf and v == math.inf))
        if not ok:
            raise InvalidInputError(f"{type(obj).__name__}.{f.name} must be a number ≥ 0; "
                                    f"got {v!r}")


@dataclass(frozen=True)
class Weights:
    """Cost weights (each residual is squared, summed over its rows and averaged over knots).

    Keypoints, through the body map (lengths divided by the robot's leg length):

    - ``height`` [1]: hip-over-ankle height / leg length − the demonstrator's, per leg;
    - ``shank`` [1]: unit shank direction (knee → ankle) − the demonstrator's (3 rows);
    - ``thigh`` [0]: unit thigh direction (hip → knee) − the demonstrator's;
    - ``placement`` [0.1]: horizontal ankle − hip offset / leg length − the demonstrator's;
    - ``steps`` [100]: in double support, the left sole's horizontal place relative to the
      right's / leg length − the demonstrator's footprints' (:mod:`.parts.steps`): its steps,
      and so its distance, scaled to the imitator's legs;
    - ``over_feet`` [30]: at every stance knot, the hips' midpoint relative to the stance
      soles along the demonstrator's facing / leg length − the demonstrator's
      (:mod:`.parts.over_feet`): the body carried over the feet, so that a clip that starts or
      ends in single support travels the scaled distance too;
    - ``foot`` [1]: each foot's world orientation (its sole frame's rotation matrix entries)
      − the demonstrator's;
    - ``torso`` [1]: orientation of the mapped torso/pelvis segments (rotation matrix
      entries, i.e. ≈ 2·(1 − cos angle)); planar: the base pitch [rad];
    - ``joints`` [0.1]: mapped joint angles − the demonstrator's (mapped) [rad];
    - ``posture`` [1e-3]: unmapped actuated joints − the imitator's neutral pose [rad];

    ``height``/``shank``/``foot`` and the torso are what Eq. (1) keeps; ``thigh`` and
    ``placement`` are what it gives up, so weights > 0 there move the optimum away from Eq. (1).

    - ``smoothness`` [1e-4 s⁴]: squared accelerations [rad/s², m/s²];
    - ``wrench`` [1e-3]: squared contact wrench / (m·g) (picks the double-support split);
    - ``elastic`` [1e3]: L1 penalty per unit of violation (relative to each row's scale) in
      the least-infeasible fallback solve.
    """

    height: float = 1.0
    shank: float = 1.0
    thigh: float = 0.0
    placement: float = 0.1
    steps: float = 100.0
    over_feet: float = 30.0
    foot: float = 1.0
    torso: float = 1.0
    joints: float = 0.1
    posture: float = 1e-3
    smoothness: float = 1e-4
    wrench: float = 1e-3
    elastic: float = 1e3

    def __post_init__(self) -> None:
        _nonneg(self)


@dataclass(frozen=True)
class Limits:
    """Overrides of the imitator's URDF limits (``None``: keep the URDF's).

    - ``effort`` [N·m or N]: one number for every actuated joint, or ``{joint: value}``;
    - ``velocity`` [rad/s or m/s]: likewise;
    - ``position``: ``{joint: (lower, upper)}`` [rad or m];
    - ``freeze``: joints held at ``freeze_at`` (default: the imitator's neutral pose); their
      torques still count in the dynamics and against their effort limits.

    ``math.inf`` lifts a limit.
    """

    effort: float | dict | None = None
    velocity: float | dict | None = None
    position: dict | None = None
    freeze: tuple[str, ...] = ()
    freeze_at: dict | None = None

    def __post_init__(self) -> None:
        for name in ("effort", "velocity"):
            v = getattr(self, name)
            vals = v.values() if isinstance(v, dict) else [] if v is None else [v]
            for x in vals:
                if not (isinstance(x, (int, float, np.floating)) and x > 0):
                    raise InvalidInputError(f"Limits.{name} values must be > 0 (math.inf to "
                                            f"lift a limit); got {x!r}")
        object.__setattr__(self, "freeze", tuple(self.freeze))


@dataclass(frozen=True)
class Contact:
    """Contact model and goal options.

    - ``mu`` [-]: friction coefficient of every foot (default
      :data:`gdimitate.model.contact.DEFAULT_MU`); ``None`` keeps each :class:`SoleContact`'s own;
    - ``f_min`` [N]: minimum normal force of a stance foot (unilateral contact, default 1 N);
    - ``cop_margin`` [m]: keep the centre of pressure this far inside the sole rectangle;
    - ``clearance`` [m]: every sole corner of a swing foot at least this high (default 0);
    - ``cone_half_angle`` [rad]: 0 — the force direction is an equality (parallel to the
      demonstrator's); > 0 — within a cone of that half-angle around it;
    - ``rule``: ``"all"`` — every stance foot of the schedule is a contact — or ``"anchor"`` —
      only the foot down longest (Eq. (1)'s contact rule; the other foot is treated as swing).
    """

    mu: float | None = DEFAULT_MU
    f_min: float = 1.0
    cop_margin: float = 0.0
    clearance: float = 0.0
    cone_half_angle: float = 0.0
    rule: str = "all"

    def __post_init__(self) -> None:
        if self.mu is not None and not (isinstance(self.mu, (int, float, np.floating))
                                        and math.isfinite(self.mu) and self.mu > 0):
            raise InvalidInputError(f"mu must be a finite number > 0 (mu ≤ 0 means no "
                                    f"friction: a foot cannot push); got {self.mu!r}")
        for name in ("f_min", "cop_margin", "clearance"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v >= 0):
                raise InvalidInputError(f"Contact.{name} must be a finite number ≥ 0; "
                                        f"got {v!r}")
        a = self.cone_half_angle
        if not (isinstance(a, (int, float, np.floating)) and 0 <= a < math.pi / 2):
            raise InvalidInputError(f"cone_half_angle must be in [0, π/2) rad; got {a!r}")
        if self.rule not in ("all", "anchor"):
            from ..errors import UnknownNameError

            raise UnknownNameError("contact rule", self.rule, ("all", "anchor"))
