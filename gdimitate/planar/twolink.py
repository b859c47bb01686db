"""Planar two-link legs: forward/inverse kinematics and the paper's Eq. (1) adaptor (docs/design.md
§4).

Angles from the downward vertical, positive when the distal end is in front (+x); θ1 is the
absolute thigh angle, θ2 the knee angle relative to the thigh (negative in flexion)::

    knee  = hip  + l1·(sin θ1, −cos θ1)
    ankle = knee + l2·(sin(θ1+θ2), −cos(θ1+θ2))
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import InvalidInputError

__all__ = ["Eq1Result", "eq1", "fk2", "ik2", "ROUNDOFF"]

#: |arg| up to 1 + ROUNDOFF counts as feasible: floating-point round-off of a reachable pose
#: (e.g. a straight leg, arg = 1 + 2e-16) is not an infeasible frame.
ROUNDOFF = 1e-12


def _real_array(a, name: str) -> np.ndarray:
    """``a`` as a float array if it holds real numbers (bool, int, float); strings, complex
    numbers and objects raise :class:`InvalidInputError` (NumPy would parse ``"0.3"`` or drop
    an imaginary part silently)."""
    arr = np.asarray(a)
    if arr.dtype.kind not in "biuf":
        raise InvalidInputError(f"{name} must be real numbers [rad or m]; got {arr.dtype} "
                                f"values ({a!r:.60})")
    return arr.astype(float)


def _lengths(pair, what: str) -> tuple[float, float]:
    try:
        arr = _real_array(pair, what)
    except InvalidInputError:
        arr = None
    if arr is None or arr.shape != (2,):
        raise InvalidInputError(f"{what} must be a pair (thigh, shank) in metres; got {pair!r}")
    l1, l2 = float(arr[0]), float(arr[1])
    if not (np.isfinite(l1) and np.isfinite(l2) and l1 > 0 and l2 > 0):
        raise InvalidInputError(f"{what} lengths must be finite and positive; got {(l1, l2)}")
    return l1, l2


def _angles(*arrays, names):
    out = [_real_array(a, n) for a, n in zip(arrays, names)]
    try:
        shape = np.broadcast_shapes(*(a.shape for a in out))
    except ValueError:
        raise InvalidInputError(
            f"{' and '.join(names)} must broadcast together; got shapes "
            f"{[a.shape for a in out]}") from None
    for a, n in zip(out, names):
        if not np.all(np.isfinite(a)):
            raise InvalidInputError(f"{n} contains NaN or inf")
    return [np.broadcast_to(a, shape) for a in out]


class Eq1Result(NamedTuple):
    """Result of :func:`eq1`, every field the broadcast shape of the inputs.

    ``theta1``, ``theta2``: imitator thigh (absolute) and knee (relative) angles [rad];
    ``argument``: the unclipped argument of arccos; ``feasible``: ``|argument| ≤ 1`` (up to
    :data:`ROUNDOFF`). Where not
    feasible, the argument is clipped to ±1 (the nearest reachable angle) and the frame flagged.
    """

    theta1: np.ndarray
    theta2: np.ndarray
    argument: np.ndarray
    feasible: np.ndarray


def eq1(theta1, theta2, demonstrator=(0.4, 0.6), imitator=(0.1, 0.1)) -> Eq1Result:
    """The paper's Eq. (1): imitator leg angles keeping the shank direction θ1+θ2 and the
    leg-length-scaled vertical projection of the demonstrator's leg.

    ``theta1``, ``theta2``: demonstrator angles [rad], any broadcastable shapes;
    ``demonstrator``, ``imitator``: ``(thigh, shank)`` lengths [m]. The sign of the imitator's
    thigh angle follows the demonstrator's (``+`` where θm1 = 0).
    """
    lm1, lm2 = _lengths(demonstrator, "demonstrator")
    lr1, lr2 = _lengths(imitator, "imitator")
    th1, th2 = _angles(theta1, theta2, names=("theta1", "theta2"))
    Lm, Lr = lm1 + lm2, lr1 + lr2
    shank = th1 + th2
    arg = ((Lr * lm1 / Lm) * np.cos(th1) + ((Lr * lm2 / Lm) - lr2) * np.cos(shank)) / lr1
    feasible = np.abs(arg) <= 1.0 + ROUNDOFF
    sign = np.where(th1 < 0.0, -1.0, 1.0)
    r1 = sign * np.arccos(np.clip(arg, -1.0, 1.0))
    return Eq1Result(theta1=r1, theta2=shank - r1, argument=arg, feasible=feasible)


def fk2(theta1, theta2, lengths) -> tuple[np.ndarray, np.ndarray]:
    """Knee and ankle positions ``(..., 2)`` [m] (x, z) relative to the hip."""
    l1, l2 = _lengths(lengths, "lengths")
    th1, th2 = _angles(theta1, theta2, names=("theta1", "theta2"))
    knee = np.stack([l1 * np.sin(th1), -l1 * np.cos(th1)], axis=-1)
    ankle = knee + np.stack([l2 * np.sin(th1 + th2), -l2 * np.cos(th1 + th2)], axis=-1)
    return knee, ankle


def ik2(dx, dz, lengths) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse kinematics of the two-link leg, knee bending backwards (θ2 ≤ 0).

    ``dx``, ``dz``: ankle minus hip [m]. Returns ``(theta1, theta2, reachable)``; unreachable
    targets (too far or too near) are flagged and solved for the nearest reachable distance.
    """
    l1, l2 = _lengths(lengths, "lengths")
    dx, dz = _angles(dx, dz, names=("dx", "dz"))
    r2 = dx**2 + dz**2
    c = (r2 - l1**2 - l2**2) / (2 * l1 * l2)
    reachable = np.abs(c) <= 1.0
    th2 = -np.arccos(np.clip(c, -1.0, 1.0))
    th1 = np.arctan2(dx, -dz) - np.arctan2(l2 * np.sin(th2), l1 + l2 * np.cos(th2))
    th1 = np.mod(th1 + np.pi, 2 * np.pi) - np.pi  # in [-π, π)
    return th1, th2, reachable
