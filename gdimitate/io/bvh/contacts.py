"""Foot contacts of a recorded motion from the feet's height and speed.

A foot is in stance at a frame when the lowest corner of its sole rectangle is within
``height`` of the floor and that corner moves horizontally slower than ``speed``; both
thresholds are fractions of the skeleton's hip height (so they hold for any body size and
unit): 0.04 × hip height ≈ 3.6 cm and 0.6 × hip height per second ≈ 0.54 m/s for an adult.
The floor is estimated from the clip: the median over frames of the lower foot's lowest
corner (a walk always has a foot on the floor). Swing gaps shorter than ``gap`` [s] between two
stance runs are closed (marker jitter at a flat foot); stance runs shorter than ``min_stance``
[s] are dropped (a swinging foot grazing the floor).

Recorded positions are noisy, and a speed is their derivative: 3 mm of white noise on the CMU
walk's positions (120 Hz) put every foot's speed above the threshold at every frame, and no
stance was found. So the corners are first low-passed (a zero-lag Butterworth of order 4 at
``cutoff`` [Hz], the usual filter of gait kinematics, where the clip is long enough for it),
and a foot that is in stance stays so while it is within ``hysteresis`` times both thresholds
(a foot lands under the thresholds and lifts off above them, not on every crossing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import InvalidInputError
from ...model.kinematics import frame_placements
from ...model.legs import hip_height

__all__ = ["ContactRule", "detect_contacts", "estimate_floor", "sole_corners", "close_gaps",
           "kinematic_stance",
           "low_pass"]


@dataclass(frozen=True)
class ContactRule:
    """Thresholds of :func:`detect_contacts`: ``height`` and ``speed`` in hip heights and hip
    heights per second [-, 1/s], ``gap`` and ``min_stance`` [s], the low-pass ``cutoff`` [Hz]
    (``0``: none) and the ``hysteresis`` factor (≥ 1) on both thresholds while in stance."""

    height: float = 0.04
    speed: float = 0.6
    gap: float = 0.05
    min_stance: float = 0.05
    cutoff: float = 6.0
    hysteresis: float = 1.5

    def __post_init__(self) -> None:
        for k in ("height", "speed"):
            if not getattr(self, k) > 0:
                raise InvalidInputError(f"ContactRule.{k} must be > 0; got {getattr(self, k)!r}")
        for k in ("gap", "min_stance", "cutoff"):
            if not getattr(self, k) >= 0:
                raise InvalidInputError(f"ContactRule.{k} must be ≥ 0; got {getattr(self, k)!r}")
        if not self.hysteresis >= 1:
            raise InvalidInputError(f"ContactRule.hysteresis must be ≥ 1; got "
                                    f"{self.hysteresis!r}")


def _runs(mask: np.ndarray, value: bool) -> list[tuple[int, int]]:
    """Half-open index ranges where ``mask == value``."""
    m = np.concatenate([[not value], mask == value, [not value]]).astype(int)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def close_gaps(mask: np.ndarray, max_gap: int, min_run: int = 0) -> np.ndarray:
    """``mask`` with False runs of at most ``max_gap`` frames between True runs set True, then
    True runs shorter than ``min_run`` frames set False."""
    out = np.asarray(mask, dtype=bool).copy()
    for a, b in _runs(out, False):
        if a > 0 and b < out.size and b - a <= max_gap:
            out[a:b] = True
    for a, b in _runs(out, True):
        if b - a < min_run:
            out[a:b] = False
    return out


def sole_corners(robot, q: np.ndarray) -> dict[str, np.ndarray]:
    """World positions ``(T, 4, 3)`` [m] of each foot's sole corners for q ``(T, nq)``."""
    P = frame_placements(robot, q, [c.frame for c in robot.contacts.values()])
    out = {}
    for s, c in robot.contacts.items():
        M = P[c.frame]
        out[s] = np.einsum("cj,tij->tci", c.corners(), M.rotation) + M.translation[:, None]
    return out


def kinematic_stance(robot, q: np.ndarray, t: np.ndarray) -> tuple[dict[str, np.ndarray], str]:
    """Stance flags ``{side: (T,) bool}`` of a motion ``q`` ``(T, nq)`` on times ``t``
    ``(T,)`` [s] from its sole corners' height and speed (:func:`detect_contacts`, thresholds
    in hip heights), and the rule used: a foot that never stands still (a treadmill trial: the
    stance feet ride the belt) → height alone."""
    robot.require_contacts()
    hip = hip_height(robot)
    corners = sole_corners(robot, q)
    contact = detect_contacts(corners, t, hip)
    if min(c.mean() for c in contact.values()) >= 0.1:
        return contact, "height and speed"
    return (detect_contacts(corners, t, hip, ContactRule(speed=1e6)),
            "height alone (the feet never stand still: a treadmill?)")


def estimate_floor(corners: dict[str, np.ndarray]) -> float:
    """The floor height [m]: the median over frames of the lower foot's lowest sole corner
    (``corners``: ``{side: (T, 4, 3)}`` world positions, :func:`sole_corners`)."""
    low = np.stack([p[..., 2].min(axis=1) for p in corners.values()])
    return float(np.median(low.min(axis=0)))


def detect_contacts(corners: dict[str, np.ndarray], t: np.ndarray, hip_height: float,
                    rule: ContactRule = ContactRule(), floor: float | None = None
                    ) -> dict[str, np.ndarray]:
    """Stance masks ``{"left": (T,) bool, "right": (T,) bool}`` from the sole corners
    ``{side: (T, 4, 3)}`` [m] (:func:`sole_corners`) on times ``t`` ``(T,)`` [s];
    ``hip_height`` [m] scales the thresholds, ``floor`` [m] defaults to
    :func:`estimate_floor` (see the module docstring)."""
    dt = float(np.median(np.diff(t)))
    corners = {s: low_pass(p, dt, rule.cutoff) for s, p in corners.items()}
    if floor is None:
        floor = estimate_floor(corners)
    out = {}
    for s, p in corners.items():
        low = p[..., 2].min(axis=1)
        vel = np.gradient(p[..., :2], t, axis=0)  # (T, 4, 2)
        k = p[..., 2].argmin(axis=1)
        speed = np.linalg.norm(vel[np.arange(len(t)), k], axis=1)
        h, v = (low - floor) / (rule.height * hip_height), speed / (rule.speed * hip_height)
        raw = _hysteresis(np.maximum(h, v), rule.hysteresis)
        out[s] = close_gaps(raw, int(round(rule.gap / dt)), int(round(rule.min_stance / dt)))
    return out


def _hysteresis(x: np.ndarray, factor: float) -> np.ndarray:
    """``(T,)`` bool: True from where ``x`` (both thresholds' ratios, worst) drops below 1
    until it rises above ``factor``."""
    out = np.zeros(x.size, bool)
    on = False
    for i, xi in enumerate(x):
        on = xi < (factor if on else 1.0)
        out[i] = on
    return out


def low_pass(p: np.ndarray, dt: float, cutoff: float) -> np.ndarray:
    """``p`` ``(T, ...)`` filtered along time by a zero-lag 4th-order Butterworth at
    ``cutoff`` [Hz] (sample time ``dt`` [s]); unchanged when ``cutoff`` is 0, at or above
    0.4 of the sampling rate, or the clip is too short for the filter's padding."""
    from scipy.signal import butter, filtfilt

    if cutoff <= 0 or cutoff >= 0.4 / dt:
        return p
    b, a = butter(4, cutoff * 2 * dt)
    if p.shape[0] <= 3 * max(len(a), len(b)):
        return p
    return filtfilt(b, a, p, axis=0)
