"""gdimitate — goal-directed imitation of rhythmic motion between robots of different bodies.

The pipeline (DESIGN §2)::

    robot_m, demo = gdimitate.gait.human_walk()            # real walk → planar demonstrator
    imitator = gdimitate.Robot.from_library("hoap2")
    adapted = gdimitate.adapt(demo, robot_m, imitator)      # Eq. (1): keep the push direction
    adapted.report.force_direction_error_max                # [rad]
"""

from . import gait, metrics, planar
from .adapt import AdaptationReport, AdaptedMotion, adapt
from .cases import paper_case
from .errors import (
    GdimitateError,
    InvalidInputError,
    LegDetectionError,
    LegMatchError,
    OscillatorError,
    SolverError,
    TimeGridError,
    UnknownNameError,
    UnknownRobotError,
    UnsupportedJointError,
    URDFError,
    ViewerError,
)
from .library import list_robots
from .motion import Motion
from .robot import Leg, Robot
from .walking import HUMAN_GAIT, ROBOT_GAIT, GaitSpec, walking_motion

__version__ = "0.1.0"

__all__ = [
    "AdaptationReport",
    "AdaptedMotion",
    "GaitSpec",
    "GdimitateError",
    "HUMAN_GAIT",
    "InvalidInputError",
    "Leg",
    "LegDetectionError",
    "LegMatchError",
    "Motion",
    "OscillatorError",
    "ROBOT_GAIT",
    "Robot",
    "SolverError",
    "TimeGridError",
    "URDFError",
    "UnknownNameError",
    "UnknownRobotError",
    "UnsupportedJointError",
    "ViewerError",
    "adapt",
    "gait",
    "list_robots",
    "metrics",
    "paper_case",
    "planar",
    "walking_motion",
]
