import functools

import pytest

from gdimitate.robot import Robot


@functools.cache
def _robot(name: str) -> Robot:
    return Robot.from_library(name)


@pytest.fixture
def robot():
    """robot(name) → a cached Robot (models are read-only in the tests)."""
    return _robot
