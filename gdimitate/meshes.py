"""Mesh-file facts shared by the geometry users (sole measurement, viewer).

Collada files may declare ``<up_axis>Y_UP</up_axis>``. URDF authors place such meshes with
``<origin rpy=…>`` written for the file's raw vertices, but Pinocchio's loader (assimp) turns
Y-up Collada vertices to z-up first, so the vertices Pinocchio holds are rotated against what
the URDF meant (iCub's feet: a sole 0.16 m long ends up along y). :data:`ASSIMP_Y_UP_UNDO`
maps Pinocchio's vertices of such a file back to the raw ones (checked on iCub: the corrected
foot is 0.156 m long along x and 0.060 m wide, flat on the sole frame).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

__all__ = ["ASSIMP_Y_UP_UNDO", "collada_y_up"]

#: Rotation taking Pinocchio's (assimp-turned) vertices of a Y_UP Collada file back to the
#: file's raw coordinates: (x, y, z) → (x, −z, y).
ASSIMP_Y_UP_UNDO = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@functools.lru_cache(maxsize=256)
def collada_y_up(path: str) -> bool:
    """Whether ``path`` is a Collada (``.dae``) file that declares ``<up_axis>Y_UP``."""
    if Path(path).suffix.lower() != ".dae" or not Path(path).is_file():
        return False
    with open(path, encoding="utf-8", errors="replace") as f:
        head = f.read(4096)
    return "<up_axis>Y_UP</up_axis>" in head.replace(" ", "")
