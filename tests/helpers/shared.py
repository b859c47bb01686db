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
