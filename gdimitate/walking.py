"""Deprecated: moved to :mod:`gdimitate.planar.walking` (re-exported here, with a warning;
``gdimitate.walking_motion``, ``GaitSpec``, ``HUMAN_GAIT`` and ``ROBOT_GAIT`` stay
top-level names)."""

import warnings

from .planar.walking import HUMAN_GAIT, ROBOT_GAIT, GaitSpec, walking_motion

__all__ = ["GaitSpec", "HUMAN_GAIT", "ROBOT_GAIT", "walking_motion"]

warnings.warn("gdimitate.walking is deprecated: import its names from gdimitate.planar (or "
              "gdimitate.walking_motion etc. at the top level)", DeprecationWarning,
              stacklevel=2)
