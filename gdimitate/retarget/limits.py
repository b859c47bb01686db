"""Joint position and velocity limits as bounds on the decision variables (URDF limits with
:class:`~gdimitate.retarget.params.Limits` overrides); frozen joints fixed at their pose with
zero velocity and acceleration; swing feet's wrenches fixed at zero. Because of the
integration constraints, bounds on ``v`` bound the forward differences of ``q``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError, UnknownNameError
from ..model.robot import Robot
from .params import Limits

__all__ = ["Resolved", "resolve"]


@dataclass(frozen=True)
class Resolved:
    """Per actuated velocity index: ``names``, ``q_index`` (into q), ``lower``/``upper``
    [rad, m], ``velocity`` [rad/s, m/s], ``effort`` [N·m, N] (inf: none), ``frozen`` (bool) and
    ``freeze_at`` (the held value)."""

    names: tuple[str, ...]
    q_index: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    frozen: np.ndarray
    freeze_at: np.ndarray


def _value(spec, name: str, urdf: float) -> float:
    if spec is None:
        return urdf
    if isinstance(spec, dict):
        return float(spec.get(name, urdf))
    return float(spec)


def resolve(robot: Robot, act_idx: np.ndarray, limits: Limits) -> Resolved:
    """Limits of the imitator's actuated joints (1-DoF joints, velocity order)."""
    m = robot.model
    names, qi = [], []
    for iv in act_idx:
        j = next(j for j in range(1, m.njoints)
                 if m.joints[j].idx_v <= iv < m.joints[j].idx_v + m.joints[j].nv)
        if m.joints[j].nq != 1:
            raise InvalidInputError(f"joint {m.names[j]!r} of {robot.name} has "
                                    f"{m.joints[j].nq} configuration entries; the whole-body "
                                    "adaptor handles 1-DoF actuated joints")
        names.append(m.names[j])
        qi.append(m.joints[j].idx_q)
    for d in (limits.effort, limits.velocity, limits.position or {}, limits.freeze_at or {}):
        if isinstance(d, dict):
            for k in d:
                if k not in names:
                    raise UnknownNameError("actuated joint", k, names)
    for k in limits.freeze:
        if k not in names:
            raise UnknownNameError("actuated joint", k, names)
    idx_q = np.array(qi, int)
    lo = np.array([m.lowerPositionLimit[i] for i in idx_q], float)
    hi = np.array([m.upperPositionLimit[i] for i in idx_q], float)
    bad = ~(lo < hi)  # no URDF range (e.g. continuous): free
    lo[bad], hi[bad] = -np.inf, np.inf
    for k, (a, b) in (limits.position or {}).items():
        i = names.index(k)
        lo[i], hi[i] = float(a), float(b)
    vel = np.array([_value(limits.velocity, n, m.velocityLimit[iv] if m.velocityLimit[iv] > 0
                           else np.inf) for n, iv in zip(names, act_idx)])
    eff = np.array([_value(limits.effort, n, m.effortLimit[iv] if m.effortLimit[iv] > 0
                           else np.inf) for n, iv in zip(names, act_idx)])
    frozen = np.array([n in limits.freeze for n in names], bool)
    at = robot.neutral[idx_q].copy()
    for k, v in (limits.freeze_at or {}).items():
        at[names.index(k)] = float(v)
    return Resolved(tuple(names), idx_q, lo, hi, vel, eff, frozen, at)
