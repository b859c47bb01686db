"""Force plates → the feet they carried: :func:`assign_plates`.

Each plate's loaded intervals (vertical force above the threshold, contiguous samples on the
motion's time grid) go to the foot whose sole centre (the robot's contact frame, else its
leg's sole frame) is horizontally nearest the plate's centre of pressure: the nearest foot
must be the same in at least :data:`MAJORITY` of the interval's frames, otherwise the plate
carried both feet at once and its force cannot be split (a :class:`ForceDataError` saying
which plate and when). A foot on several plates (or one plate after another) gets their sum:
forces added, moments about the origin added, the centre of pressure recomputed on the
plates' mean surface height, the free moment about it.
"""

from __future__ import annotations

import numpy as np

from ...errors import ForceDataError
from ...model.contact import ContactForces, FootForces
from ...model.kinematics import frame_paths
from ..opensim.grf import CONTACT_THRESHOLD, _cop_on_plane

__all__ = ["MAJORITY", "MAX_DISTANCE", "assign_plates"]

#: Share of a loaded interval's frames in which one foot must be the nearest to the plate's
#: centre of pressure.
MAJORITY = 0.9
#: Largest mean horizontal distance [m] between a plate's centre of pressure and the foot it
#: is given to (a foot is ~0.26 m long): farther means the motion is not in the plates' frame.
MAX_DISTANCE = 0.3


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[(start, stop), …]`` of the True runs of a 1-D mask (stop exclusive)."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def _feet(robot, motion) -> dict[str, np.ndarray]:
    """World positions ``(T, 3)`` of each foot's sole centre along ``motion``."""
    frames = {s: (robot.contacts[s].frame if s in robot.contacts else robot.legs[s].sole)
              for s in ("left", "right")}
    paths = frame_paths(robot, motion.q, list(frames.values()))
    return {s: paths[f] for s, f in frames.items()}


def _resample(plate, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Force ``(T, 3)``, moment about the world origin ``(T, 3)`` (both linear in the
    measured signals, so they resample without the centre of pressure's division by a small
    force) and the centre of pressure on the plate's surface ``(T, 3)``, on ``t``."""
    z = float(plate.corners[:, 2].mean())
    cop = np.where(np.isnan(plate.cop), plate.corners.mean(axis=0), plate.cop)
    M0 = np.cross(cop, plate.force) + plate.free_moment
    F, M = (np.column_stack([np.interp(t, plate.t, x[:, k]) for k in range(3)])
            for x in (plate.force, M0))
    P = np.full_like(F, np.nan)
    on = np.abs(F[:, 2]) > 1e-9
    P[on] = _cop_on_plane(F[on], M[on], np.full(on.sum(), z), 2)
    return F, M, P


def _side(k: int, feet, cop, lo: int, hi: int, t: np.ndarray) -> str:
    dist = {s: np.linalg.norm(p[lo:hi, :2] - cop[lo:hi, :2], axis=1) for s, p in feet.items()}
    nearer_left = dist["left"] < dist["right"]
    share = float(nearer_left.mean())
    side = "left" if share >= 0.5 else "right"
    if max(share, 1 - share) < MAJORITY:
        raise ForceDataError(
            f"force plate {k} is stepped on by both feet during t = {t[lo]:.3f}–{t[hi - 1]:.3f} "
            f"s (its centre of pressure is nearer the left foot in {100 * share:.0f} % of "
            "those frames, the right in the rest): one plate's force cannot be split between "
            "two feet; cut that part of the trial")
    if dist[side].mean() > MAX_DISTANCE:
        raise ForceDataError(
            f"force plate {k}'s centre of pressure is {dist[side].mean():.2f} m from the "
            f"nearest foot ({side}) during t = {t[lo]:.3f}–{t[hi - 1]:.3f} s: is the motion in "
            "the plates' lab frame (the markers' frame, not moved overground)?")
    return side


def assign_plates(plates, robot, motion, *, threshold: float = CONTACT_THRESHOLD,
                  source: str = "") -> ContactForces:
    """The plates' forces on the feet of ``robot`` moving as ``motion`` → ContactForces.

    ``plates``: :class:`~gdimitate.c3d.ForcePlate` s in the frame of ``motion`` (the
    markers' lab frame); ``threshold`` [N]: loaded where the vertical force exceeds it; the
    result is on ``motion.t`` (plates interpolated linearly; ``motion.t`` must lie in the
    plates' time span). Per foot: ``force`` ``(T, 3)`` [N], ``cop`` ``(T, 3)`` [m] (NaN off
    the ground), ``torque`` ``(T, 3)`` [N·m] free moment, ``contact`` (vertical force above
    ``threshold``). Raises :class:`~gdimitate.errors.ForceDataError` (no plates, times out of
    range, a plate under both feet, a plate far from both feet)."""
    if not plates:
        raise ForceDataError(f"{source or 'the trial'} has no force plates")
    t = motion.t
    span = (max(p.t[0] for p in plates), min(p.t[-1] for p in plates))
    if t[0] < span[0] - 1e-9 or t[-1] > span[1] + 1e-9:
        raise ForceDataError(f"the motion spans t = {t[0]:g}–{t[-1]:g} s; the plates "
                             f"{span[0]:g}–{span[1]:g} s")
    feet = _feet(robot, motion)
    m = {s: np.zeros((motion.T, 3)) for s in feet}
    f = {s: np.zeros((motion.T, 3)) for s in feet}
    h: dict[str, list] = {s: [] for s in feet}
    for plate in plates:
        F, M, P = _resample(plate, t)
        for lo, hi in _runs(F[:, 2] > threshold):
            s = _side(plate.index, feet, P, lo, hi, t)
            f[s][lo:hi] += F[lo:hi]
            m[s][lo:hi] += M[lo:hi]
            h[s].append(float(plate.corners[:, 2].mean()))
    out = {}
    for s in feet:
        height = np.full(motion.T, np.mean(h[s]) if h[s] else 0.0)
        cop = np.full((motion.T, 3), np.nan)
        on = f[s][:, 2] > threshold
        cop[on] = _cop_on_plane(f[s][on], m[s][on], height[on], 2)
        tq = np.zeros((motion.T, 3))
        tq[on] = m[s][on] - np.cross(cop[on], f[s][on])
        out[s] = FootForces(f[s], cop, tq, on)
    note = (f"{len(plates)} force plate(s) assigned to the nearest foot per loaded interval; "
            f"stance where vertical force > {threshold:g} N")
    return ContactForces(t.copy(), out, source=source, frame_note=note)
