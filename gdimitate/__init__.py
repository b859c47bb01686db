"""gdimitate — goal-directed imitation of rhythmic motion between robots of different bodies."""

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

__version__ = "0.1.0"

__all__ = [
    "GdimitateError",
    "InvalidInputError",
    "LegDetectionError",
    "LegMatchError",
    "OscillatorError",
    "SolverError",
    "TimeGridError",
    "UnknownNameError",
    "UnknownRobotError",
    "UnsupportedJointError",
    "URDFError",
    "ViewerError",
]
