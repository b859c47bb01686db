import functools

import pytest

from gdimitate.model.robot import Robot


@functools.cache
def _robot(name: str) -> Robot:
    return Robot.from_library(name)


@pytest.fixture
def robot():
    """robot(name) → a cached Robot (models are read-only in the tests)."""
    return _robot


@functools.cache
def _g1_stride():
    import gdimitate as gd

    h, m, f = gd.gait.human_walk_3d()
    stride, fs = gd.gait.one_stride(m, f)
    r = gd.adapt(stride, h, _robot("g1"), force="measured", forces=fs, verbose=False)
    return h, stride, fs, r


@pytest.fixture
def g1_stride():
    """``(demonstrator, stride, forces, adapted)``: one right stride of the shipped 3-D walk
    adapted to G1 with the defaults (measured push), computed once per test session for the
    tests that compare other adaptations with it (read-only)."""
    return _g1_stride()
