"""Where the viewer's camera and ground go: framing every track's centre of mass, the ground
slab under all feet, and meshcat's camera placed to look at a point (meshcat has no look-at
call)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["framing", "ground_extent", "place_camera"]


def framing(tracks: Iterable) -> tuple[np.ndarray, np.ndarray]:
    """``(position, target)`` (3,) [m, world] of a camera that frames every animated track's
    centre of mass (offset and scaled as drawn) from the front left."""
    coms = [tr.frames.com * tr.scale + tr.offset for tr in tracks]
    pts = np.concatenate(coms)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    target = (lo + hi) / 2.0
    span = float(max(hi[0] - lo[0], hi[1] - lo[1], 2.0 * hi[2], 0.5))
    return target + np.array([0.3, -1.0, 0.2]) * (span + 0.4), target


def ground_extent(tracks: Iterable, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)`` (2,) [m]: the x–y box of every animated track's bodies and sole paths (as
    drawn), grown by ``margin`` [m]."""
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    for track in tracks:
        pts = [track.frames.placements[:, :, :3, 3].reshape(-1, 3)]
        pts += list(track.frames.sole_paths.values())
        xy = np.concatenate(pts)[:, :2] * track.scale + track.offset[:2]
        lo, hi = np.minimum(lo, xy.min(axis=0)), np.maximum(hi, xy.max(axis=0))
    return lo - margin, hi + margin


def place_camera(vis, position: ArrayLike, target: ArrayLike) -> None:
    """Put meshcat's camera at ``position`` (3,) [m] looking at ``target`` (3,) [m]: its orbit
    controls turn around the world origin, so the scene (``/meshcat``) is shifted by
    ``-target`` and the camera put at ``position - target`` (in the y-up frame of
    ``/Cameras/default/rotated``)."""
    p = np.asarray(position, dtype=float) - np.asarray(target, dtype=float)
    T = np.eye(4)
    T[:3, 3] = -np.asarray(target, dtype=float)
    vis.set_transform(T)
    vis["/Cameras/default"].set_transform(np.eye(4))
    vis["/Cameras/default/rotated/<object>"].set_property(
        "position", [float(p[0]), float(p[2]), float(-p[1])])
