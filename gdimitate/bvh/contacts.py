"""Foot contacts of a recorded motion from the feet's height and speed.

A foot is in stance at a frame when the lowest corner of its sole rectangle is within
``height`` of the floor and that corner moves horizontally slower than ``speed``; both
thresholds are fractions of the skeleton's hip height (so they hold for any body size and
unit): 0.04 × hip height ≈ 3.6 cm and 0.6 × hip height per second ≈ 0.54 m/s for an adult.
The floor is estimated from the clip: the median over frames of the lower foot's lowest
corner (a walk always has a foot on the floor). Swing gaps shorter than ``gap`` [s] between two
stance runs are closed (marker jitter at a flat foot); stance runs shorter than ``min_stance``
[s] are dropped (a swinging foot grazing the floor).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError
from ..kinematics import frame_placements

__all__ = ["ContactRule", "detect_contacts", "estimate_floor", "sole_corners", "close_gaps"]


@dataclass(frozen=True)
class ContactRule:
    """Thresholds of :func:`detect_contacts`: ``height`` and ``speed`` in hip heights and hip
    heights per second [-, 1/s], ``gap`` and ``min_stance`` [s]."""

    height: float = 0.04
    speed: float = 0.6
    gap: float = 0.05
    min_stance: float = 0.05

    def __post_init__(self) -> None:
        for k in ("height", "speed"):
            if not getattr(self, k) > 0:
                raise InvalidInputError(f"ContactRule.{k} must be > 0; got {getattr(self, k)!r}")
        for k in ("gap", "min_stance"):
            if not getattr(self, k) >= 0:
                raise InvalidInputError(f"ContactRule.{k} must be ≥ 0; got {getattr(self, k)!r}")


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
    if floor is None:
        floor = estimate_floor(corners)
    dt = float(np.median(np.diff(t)))
    out = {}
    for s, p in corners.items():
        low = p[..., 2].min(axis=1)
        vel = np.gradient(p[..., :2], t, axis=0)  # (T, 4, 2)
        k = p[..., 2].argmin(axis=1)
        speed = np.linalg.norm(vel[np.arange(len(t)), k], axis=1)
        raw = (low - floor < rule.height * hip_height) & (speed < rule.speed * hip_height)
        out[s] = close_gaps(raw, int(round(rule.gap / dt)), int(round(rule.min_stance / dt)))
    return out
