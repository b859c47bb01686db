"""The shipped subject01 trial (OpenSim's example data, ``gdimitate/data/gait``) written as a
gait-lab C3D file: its 41 markers (60 Hz) and one force plate per foot (the measured ground
reaction at the file's 600 Hz; each plate the rectangle around that foot's centres of
pressure, 10 cm wider on every side). The README's gait-lab example, the docs' figure and a
user trying the marker pipeline read it like a lab's own file::

    path = gd.c3d.write_subject01("subject01_walk1.c3d")
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .reader import ForcePlate
from .writer import write_c3d

__all__ = ["write_subject01"]


def write_subject01(path: str | Path) -> Path:
    """Write the shipped subject01 walk as a C3D at ``path`` (module docstring); returns the
    path."""
    from ..gait import human_walk_3d_folder
    from ..opensim import read_grf, read_trc
    from ..robot import Robot

    folder = human_walk_3d_folder()
    robot = Robot.from_osim(folder / "subject01.osim")
    forces = read_grf(folder / "subject01_walk1_grf.mot", robot,
                      folder / "subject01_walk1_grf.xml")
    with warnings.catch_warnings():  # the trial's own marker gaps, reported when it is read
        warnings.simplefilter("ignore")
        markers = read_trc(folder / "subject01_walk1.trc")
    plates = []
    for k, side in enumerate(("right", "left"), start=1):
        f = forces[side]
        c = f.cop[f.contact]
        lo, hi, z = c.min(0) - 0.1, c.max(0) + 0.1, float(c[:, 2].mean())
        corners = np.array([[lo[0], lo[1], z], [hi[0], lo[1], z], [hi[0], hi[1], z],
                            [lo[0], hi[1], z]])
        plates.append(ForcePlate(forces.t, f.force, f.cop, f.torque, corners, k))
    return write_c3d(path, markers, plates)
