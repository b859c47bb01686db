"""Joint limits for the optimal adaptor: read from the URDF, overridable by the user.

A :class:`Limits` holds *overrides*; :func:`resolve_limits` merges them with the robot's URDF
limits for the joints the adaptor drives and returns plain arrays. Each override may be

- a scalar (applies to every driven joint),
- a dict ``{joint name: value}`` (other joints keep the URDF value),
- an array of shape ``(nv,)`` in the robot's velocity order (Pinocchio ``idx_v``), or of shape
  ``(n_driven,)`` in :attr:`SagittalModel.driven` order.

Missing limits: a URDF value that is not finite, ≥ 1e30 or ≤ 0 (efforts, velocities), or a
position range with ``lower ≥ upper``, means *no limit* for that joint (Pinocchio fills absent
``<limit>`` tags with 0 or ±1.8e308; Romeo has limits on only some joints). Such joints are
listed in :attr:`ResolvedLimits.missing`. Values are otherwise taken as written — Bolt's
1000 N·m efforts are the URDF's placeholder, so override them to study Bolt's real margins.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError, UnknownNameError
from ..robot import Robot

__all__ = ["Limits", "ResolvedLimits", "resolve_limits"]

LimitValue = float | Mapping[str, float] | Sequence[float] | np.ndarray | None
_BIG = 1e30


@dataclass(frozen=True)
class Limits:
    """Overrides of the URDF joint limits (``None`` keeps the URDF's).

    ``lower``, ``upper`` [rad]: joint position limits; ``velocity`` [rad/s]: |q̇| bound;
    ``effort`` [N·m]: |τ| bound. Use ``float("inf")`` to remove a limit. See the module
    docstring for the accepted forms.
    """

    lower: LimitValue = None
    upper: LimitValue = None
    velocity: LimitValue = None
    effort: LimitValue = None


@dataclass(frozen=True)
class ResolvedLimits:
    """Limits of the driven joints, arrays of shape ``(n_driven,)`` in ``joints`` order;
    ``inf`` (or ``-inf`` for ``lower``) where there is none. ``missing``: ``{kind: [joints]}``
    whose URDF limit was absent or a placeholder and was not overridden."""

    joints: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    missing: dict[str, list[str]]

    @property
    def has_effort(self) -> bool:
        """True when at least one driven joint has a finite torque limit."""
        return bool(np.any(np.isfinite(self.effort)))


def _urdf(robot: Robot, joints: Sequence[str]) -> dict[str, np.ndarray]:
    m = robot.model
    iq = [robot.idx_q(j) for j in joints]
    iv = [robot.idx_v(j) for j in joints]
    lo = np.array(m.lowerPositionLimit)[iq].astype(float)
    hi = np.array(m.upperPositionLimit)[iq].astype(float)
    vel = np.array(m.velocityLimit)[iv].astype(float)
    eff = np.array(m.effortLimit)[iv].astype(float)
    bad_pos = ~(np.isfinite(lo) & np.isfinite(hi) & (lo < hi) & (np.abs(lo) < _BIG)
                & (np.abs(hi) < _BIG))
    lo[bad_pos], hi[bad_pos] = -np.inf, np.inf
    for arr in (vel, eff):
        arr[~(np.isfinite(arr) & (arr > 0) & (arr < _BIG))] = np.inf
    return {"lower": lo, "upper": hi, "velocity": vel, "effort": eff}


def _override(robot: Robot, joints: Sequence[str], kind: str, value: LimitValue,
              base: np.ndarray) -> np.ndarray:
    out = base.copy()
    if value is None:
        return out
    if isinstance(value, Mapping):
        for name, v in value.items():
            if name not in joints:
                if name in robot.joint_names:
                    raise InvalidInputError(
                        f"Limits.{kind}: joint {name!r} is not driven by the adaptor; driven "
                        f"joints: {list(joints)}")
                raise UnknownNameError("joint", name, joints)
            out[list(joints).index(name)] = float(v)
        return out
    arr = np.asarray(value, dtype=float)
    nv = robot.model.nv
    if arr.ndim == 0:
        out[:] = float(arr)
    elif arr.shape == (len(joints),):
        out[:] = arr
    elif arr.shape == (nv,):
        out[:] = arr[[robot.idx_v(j) for j in joints]]
    else:
        raise InvalidInputError(
            f"Limits.{kind} must be a scalar, a dict by joint name, or an array of shape "
            f"({nv},) (the robot's nv) or ({len(joints)},) (the driven joints "
            f"{list(joints)}); got shape {arr.shape}")
    if np.any(np.isnan(out)):
        raise InvalidInputError(f"Limits.{kind} contains NaN")
    return out


def resolve_limits(robot: Robot, joints: Sequence[str], limits: Limits | None = None
                   ) -> ResolvedLimits:
    """Merge the URDF limits of ``joints`` (driven joint names) with the overrides."""
    if limits is None:
        limits = Limits()
    if not isinstance(limits, Limits):
        raise InvalidInputError(
            f"limits must be a gdimitate.optimal.Limits; got {type(limits).__name__}")
    joints = tuple(joints)
    urdf = _urdf(robot, joints)
    res = {k: _override(robot, joints, k, getattr(limits, k), urdf[k]) for k in urdf}
    for k in ("velocity", "effort"):
        if np.any(res[k] <= 0):
            bad = [j for j, v in zip(joints, res[k]) if v <= 0]
            raise InvalidInputError(f"Limits.{k} must be positive; got ≤ 0 for {bad}")
    if np.any(res["lower"] > res["upper"]):
        bad = [j for j, lo, hi in zip(joints, res["lower"], res["upper"]) if lo > hi]
        raise InvalidInputError(f"Limits: lower > upper for {bad}")
    missing = {}
    for k in urdf:
        given = getattr(limits, k) is not None
        miss = [j for j, v in zip(joints, urdf[k]) if not np.isfinite(v)]
        if miss and not given:
            missing[k] = miss
    return ResolvedLimits(joints=joints, lower=res["lower"], upper=res["upper"],
                          velocity=res["velocity"], effort=res["effort"], missing=missing)
