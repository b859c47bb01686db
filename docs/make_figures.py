"""Regenerate the README's figures from the project's own functions (scenario code, not API).

    python docs/make_figures.py [NAME ...]      # default: all; writes docs/img/<name>.png
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

IMG = Path(__file__).parent / "img"


def force_direction_3d() -> Path:
    """Measured vs estimated (dynamics, com) force directions of the shipped 3-D walk."""
    import gdimitate as gd
    from gdimitate.metrics import force_direction
    from gdimitate.plots import plot_force_directions

    robot, motion, forces = gd.gait.human_walk_3d()
    dirs = {"measured": force_direction(robot, motion, "measured", forces=forces),
            "dynamics (kinematics only)": force_direction(robot, motion, "dynamics"),
            "com (measured CoP)": force_direction(robot, motion, "com", forces=forces)}
    path = IMG / "force_direction_3d.png"
    plot_force_directions(motion.t, dirs, motion.contact,
                          "subject01 walk: push on the ground, measured vs estimated", path)
    return path


FIGURES = {"force_direction_3d": force_direction_3d}

if __name__ == "__main__":
    names = sys.argv[1:] or list(FIGURES)
    for n in names:
        print("wrote", FIGURES[n]())
    np.seterr(all="ignore")
