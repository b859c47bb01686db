"""Helpers shared by the tests in every folder (not tests themselves): where the repository
and the tests' own data lie, and the modules :mod:`tests.helpers.printed` (numbers a command
printed) and :mod:`tests.helpers.isolated` (one library call in a capped child process)."""

from pathlib import Path

#: the tests' folder (``tests/``: its ``data/`` and ``opensim_ref/``)
TESTS = Path(__file__).resolve().parents[1]
#: the repository's root (``gdimitate/``, ``benchmarks/``, ``docs/``, ``notebooks/``)
ROOT = TESTS.parent
