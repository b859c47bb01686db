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


def adaptor_g1() -> Path:
    """The whole shipped 3-D walk adapted to G1: each sole's centre of pressure inside its
    rectangle, and the push direction of G1's planned wrenches vs the measured one."""
    import gdimitate as gd
    from gdimitate.metrics import ForceDirection, force_direction, frame_rotations
    from gdimitate.plots import plot_force_directions, plot_sole_cop

    human, walk, forces = gd.gait.human_walk_3d()
    robot = gd.Robot.from_library("g1")
    r = gd.adapt(walk, human, robot, "optimal", force="measured", forces=forces, verbose=False)
    M = r.motion
    plot_sole_cop(r.wrenches, r.contacts, M.contact,
                  "G1, whole 3-D walk: planned centre of pressure in each sole",
                  IMG / "adaptor_g1_cop.png")
    push = {s: -np.einsum("tij,tj->ti", frame_rotations(robot, M.q, r.contacts[s].frame),
                          r.wrenches[s][:, :3]) for s in ("left", "right")}
    mine = {s: ForceDirection.from_vectors(push[s], M.contact[s], "G1 plan")
            for s in ("left", "right")}
    path = IMG / "adaptor_g1_push.png"
    plot_force_directions(walk.t, {"measured (human)": force_direction(
        human, walk, "measured", forces=forces), "G1 plan (its wrenches)": mine},
        walk.contact, "push on the ground: G1's planned wrenches vs the subject's measured",
        path, times={"G1 plan (its wrenches)": M.t})
    return path


FIGURES = {"force_direction_3d": force_direction_3d, "adaptor_g1": adaptor_g1}

if __name__ == "__main__":
    names = sys.argv[1:] or list(FIGURES)
    for n in names:
        print("wrote", FIGURES[n]())
    np.seterr(all="ignore")
