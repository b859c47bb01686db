"""Objects read once per test session and shared by every test that asks for them: the
library's robots and the shipped demonstrations. ``tests/conftest.py`` hands them out as
session fixtures (``robot("g1")``, ``walk_3d``, ``walk_sagittal``); a module-level constant
that needs one before any fixture runs calls these functions.

Shared means read-only: a test that changes a robot (its model, limits, contacts) or a
motion's arrays in place works on its own copy (``copy.copy(robot)`` with a new model,
``motion.q.copy()``), or loads its own with ``Robot.from_library``.
"""

from __future__ import annotations

import functools

from gdimitate.model.robot import Robot


@functools.cache
def library_robot(name: str) -> Robot:
    """``Robot.from_library(name)``, loaded once per session."""
    return Robot.from_library(name)


@functools.cache
def walk_3d():
    """``gd.gait.human_walk_3d()``: the shipped full-body 3-D walk ``(robot, motion, forces)``
    (OpenSim subject01 with its measured forces, turned overground), read once per session."""
    from gdimitate.io.gait import human_walk_3d

    return human_walk_3d()


@functools.cache
def walk_sagittal():
    """``gd.gait.human_walk()``: the shipped sagittal walk ``(robot, motion)`` with the
    measured-GRF contact, read once per session."""
    from gdimitate.io.gait import human_walk

    return human_walk()


def g1_measured_problem(walk, rate: float = 20.0):
    """G1's trajectory problem for ``walk`` ``(human, motion, forces)`` (e.g. :func:`walk_3d`
    or a stride of it) resampled to ``rate`` knots/s (the default parts, measured push,
    default weights, limits and contact), before any solve:
    ``(robot, targets, formulation, numbers)`` as ``solve.problem_for`` and ``solve.setup``
    make them (``numbers.x0`` the warm start, ``numbers.P`` the parameters)."""
    from gdimitate.model.kinematics import actuated_v_indices
    from gdimitate.retarget import Contact, Limits, Weights, limits, resample
    from gdimitate.retarget.bodymap import body_map
    from gdimitate.retarget.info import resolve_contacts
    from gdimitate.retarget.targets import demonstration_targets
    from gdimitate.retarget.trajectory import solve as S

    h, demo, fs = walk
    robot = library_robot("g1")
    copts = Contact()
    act = limits.resolve(robot, actuated_v_indices(robot), Limits()).names
    bmap = body_map(h, robot, None)
    tg = demonstration_targets(h, resample(h, demo, rate), robot, bmap, act, "measured", fs,
                               copts.rule)
    form = S.problem_for(robot, "measured", copts, bmap, act)
    num = S.setup(form, tg, robot, h, Weights(), Limits(), copts,
                  resolve_contacts(robot, copts, None))
    return robot, tg, form, num
