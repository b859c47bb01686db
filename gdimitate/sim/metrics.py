"""What a simulation measured: falls, slip, force direction, centre of pressure, torques, tracking.

Every function takes plain arrays on the simulation's time grid (time first) and returns a
typed result. Force directions follow the project's convention: the *push on the ground* (the
reverse of the ground reaction force on the foot), as two angles from the downward vertical —
sagittal (:func:`gdimitate.assess.metrics.angle_down`, positive forward) and frontal
``atan2(push_y, −push_z)`` (positive left).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..assess.metrics import angle_down
from ..errors import SimulationError
from ..model.contact import SoleContact, centre_of_pressure, cone_margin

__all__ = [
    "DirectionAgreement",
    "FallCriteria",
    "StanceSlip",
    "direction_agreement",
    "fall_time",
    "frontal_angle",
    "stance_intervals",
    "stance_slip",
    "cop_and_margin",
    "saturation_fraction",
]


@dataclass(frozen=True)
class FallCriteria:
    """When a simulated robot counts as fallen: its floating base is lower than
    ``min_height_ratio`` × the plan's base height at that time (heights above the floor), or
    its base is tilted by more than ``max_tilt`` [rad] from the plan's base orientation (the
    angle between the two "up" axes, yaw ignored)."""

    min_height_ratio: float = 0.7
    max_tilt: float = np.pi / 4

    def __post_init__(self) -> None:
        if not (0 < self.min_height_ratio < 1):
            raise SimulationError(f"min_height_ratio must be in (0, 1); got "
                                  f"{self.min_height_ratio!r}")
        if not (0 < self.max_tilt < np.pi):
            raise SimulationError(f"max_tilt must be in (0, π) rad; got {self.max_tilt!r}")


def fall_time(t: np.ndarray, base_z: np.ndarray, plan_base_z: np.ndarray, tilt: np.ndarray,
              criteria: FallCriteria) -> tuple[float | None, str]:
    """First time [s] a fall criterion holds, and which (``"height"`` / ``"tilt"``), or
    ``(None, "")``. ``base_z``, ``plan_base_z``, ``tilt`` ``(N,)`` [m, m, rad]."""
    low = base_z < criteria.min_height_ratio * plan_base_z
    tipped = tilt > criteria.max_tilt
    bad = np.flatnonzero(low | tipped)
    if bad.size == 0:
        return None, ""
    k = int(bad[0])
    return float(t[k]), "height" if low[k] else "tilt"


def frontal_angle(push: np.ndarray) -> np.ndarray:
    """Frontal angle [rad] of pushes ``(..., 3)`` on the ground from the downward vertical,
    positive left: ``atan2(push_y, −push_z)``."""
    push = np.asarray(push, dtype=float)
    return np.arctan2(push[..., 1], -push[..., 2])


@dataclass(frozen=True)
class DirectionAgreement:
    """Simulated push direction of one foot against a reference (the plan's, or the
    demonstrator's measured one). Over single-support samples (this foot the only one in
    stance in the plan, both forces present): ``rmse_sagittal_deg``, ``rmse_frontal_deg``
    [deg], Pearson correlations ``corr_sagittal``, ``corr_frontal`` [-] (NaN where fewer than
    3 samples or a constant signal), ``n`` samples. Over all samples where both feet's forces
    are present: ``stance_rmse_sagittal_deg``, ``stance_rmse_frontal_deg`` [deg],
    ``n_stance``."""

    rmse_sagittal_deg: float
    rmse_frontal_deg: float
    corr_sagittal: float
    corr_frontal: float
    n: int
    stance_rmse_sagittal_deg: float
    stance_rmse_frontal_deg: float
    n_stance: int


def _rmse_deg(a: np.ndarray, b: np.ndarray) -> float:
    if a.size == 0:
        return float("nan")
    d = np.angle(np.exp(1j * (a - b)))  # wrapped difference
    return float(np.degrees(np.sqrt(np.mean(d**2))))


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    if a.size < 3 or np.std(a) < 1e-12 or np.std(b) < 1e-12:
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])


def direction_agreement(force: np.ndarray, reference: np.ndarray, present: np.ndarray,
                        single: np.ndarray) -> DirectionAgreement:
    """Compare ground reaction forces on a foot ``force`` ``(N, 3)`` [N] with ``reference``
    ``(N, 3)`` (both the force *on the foot*, world frame). ``present`` ``(N,)`` bool: samples
    where both forces exist; ``single`` ``(N,)`` bool: the single-support samples of this foot.
    """
    push, ref = -np.asarray(force, dtype=float), -np.asarray(reference, dtype=float)
    sa, sf = angle_down(push), frontal_angle(push)
    ra, rf = angle_down(ref), frontal_angle(ref)
    ss = present & single
    return DirectionAgreement(
        rmse_sagittal_deg=_rmse_deg(sa[ss], ra[ss]), rmse_frontal_deg=_rmse_deg(sf[ss], rf[ss]),
        corr_sagittal=_corr(sa[ss], ra[ss]), corr_frontal=_corr(sf[ss], rf[ss]),
        n=int(ss.sum()),
        stance_rmse_sagittal_deg=_rmse_deg(sa[present], ra[present]),
        stance_rmse_frontal_deg=_rmse_deg(sf[present], rf[present]),
        n_stance=int(present.sum()))


@dataclass(frozen=True)
class StanceSlip:
    """One stance of one foot (from the plan's schedule): ``side``, ``start``/``end`` [s],
    ``slip`` [m] the largest horizontal distance of the simulated sole-frame origin from where
    it was when the stance began (its first loaded sample; NaN: never loaded)."""

    side: str
    start: float
    end: float
    slip: float


def stance_intervals(mask: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous True runs of ``mask`` ``(N,)`` as ``(first, last)`` index pairs."""
    m = np.asarray(mask, dtype=bool).astype(np.int8)
    edges = np.diff(np.r_[0, m, 0])
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1))


def stance_slip(t: np.ndarray, side: str, sole_xy: np.ndarray, stance: np.ndarray,
                loaded: np.ndarray | None = None) -> list[StanceSlip]:
    """Slip of each stance of one foot: ``sole_xy`` ``(N, 2)`` [m] simulated sole positions,
    ``stance`` ``(N,)`` the plan's schedule on the same grid, ``loaded`` ``(N,)`` where the
    simulated foot carries load (default: all). Each stance's slip is measured from the first
    loaded sample in it (a foot landing late is not slipping); NaN if it is never loaded."""
    loaded = np.ones(len(t), bool) if loaded is None else np.asarray(loaded, bool)
    out = []
    for i, j in stance_intervals(stance):
        on = np.flatnonzero(loaded[i:j + 1])
        if on.size == 0:
            out.append(StanceSlip(side, float(t[i]), float(t[j]), float("nan")))
            continue
        i0 = i + int(on[0])
        d = np.linalg.norm(sole_xy[i0:j + 1] - sole_xy[i0], axis=1)
        out.append(StanceSlip(side, float(t[i]), float(t[j]), float(d.max())))
    return out


def cop_and_margin(contact: SoleContact, wrench: np.ndarray, min_force: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Centre of pressure ``(N, 2)`` [m] in the sole frame of measured wrenches ``(N, 6)`` and
    its margin ``(N,)`` [m] inside the sole rectangle (negative outside); NaN where the normal
    force is below ``min_force`` [N]."""
    w = np.asarray(wrench, dtype=float)
    cop = centre_of_pressure(w)
    margin = cone_margin(contact, w)["cop"].astype(float)
    off = w[:, 2] < min_force
    cop[off] = np.nan
    margin[off] = np.nan
    return cop, margin


def saturation_fraction(tau: np.ndarray, limit: np.ndarray, tol: float = 1e-3
                        ) -> tuple[float, np.ndarray]:
    """Fraction of samples × joints (finite limits only) with |τ| ≥ (1 − tol)·limit, and the
    per-joint fractions ``(nu,)`` (NaN for unlimited joints). ``tau`` ``(N, nu)``."""
    tau = np.asarray(tau, dtype=float)
    lim = np.asarray(limit, dtype=float)
    fin = np.isfinite(lim)
    per = np.full(lim.shape, np.nan)
    if tau.shape[0] == 0 or not fin.any():
        return 0.0, per
    sat = np.abs(tau[:, fin]) >= (1 - tol) * lim[fin]
    per[fin] = sat.mean(axis=0)
    return float(sat.mean()), per
