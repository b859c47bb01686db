"""Session fixtures shared by every test folder: the library's robots, the shipped
demonstrations and one adapted G1 stride, each built once per test session
(:mod:`tests.helpers.shared`). They are read-only: no test changes them in place."""

import os

import pytest

# A cache miss compiles the adaptor's derivatives before the solve, as it did before the
# background build: every test then runs the same code whatever ran before it, and no
# detached compiler outlives a test's temporary cache folder. tests/retarget/trajectory/
# test_codegen.py sets "background" (the default for users) where it tests that mode.
os.environ.setdefault("GDIMITATE_COMPILE", "wait")

from tests.helpers.shared import library_robot, walk_3d, walk_sagittal


@pytest.fixture(scope="session")
def robot():
    """robot(name) → the library's Robot ``name``, loaded once per session (read-only)."""
    return library_robot


@pytest.fixture(scope="session", name="walk_3d")
def walk_3d_fixture():
    """``(demonstrator, motion, forces)``: the shipped full-body 3-D walk
    (``gd.gait.human_walk_3d()``), read once per session (read-only)."""
    return walk_3d()


@pytest.fixture(scope="session", name="walk_sagittal")
def walk_sagittal_fixture():
    """``(demonstrator, motion)``: the shipped sagittal walk with its measured-GRF contact
    (``gd.gait.human_walk()``), read once per session (read-only)."""
    return walk_sagittal()


@pytest.fixture(scope="session")
def g1_stride():
    """``(demonstrator, stride, forces, adapted)``: one right stride of the shipped 3-D walk
    adapted to G1 with the defaults (measured push), computed once per test session for the
    tests that compare other adaptations with it (read-only)."""
    import gdimitate as gd

    h, m, f = walk_3d()
    stride, fs = gd.gait.one_stride(m, f)
    r = gd.adapt(stride, h, library_robot("g1"), force="measured", forces=fs, verbose=False)
    return h, stride, fs, r
