"""gdimitate — goal-directed imitation of rhythmic motion between robots of different bodies.

The pipeline (docs/design.md §2)::

    human, walk, forces = gdimitate.gait.human_walk_3d()     # OpenSim subject01, measured GRF
    robot = gdimitate.Robot.from_library("g1")
    adapted = gdimitate.adapt(walk, human, robot, force="measured", forces=forces)  # optimal
    adapted.audit.feasible                                   # recomputed with Pinocchio
    result = gdimitate.sim.simulate(robot, adapted, demo_forces=forces)   # MuJoCo
    cpg = gdimitate.entrain(robot, adapted.motion)           # Matsuoka network, free replay

The paper's planar case: ``gdimitate.adapt(demo, robot_m, imitator, "analytic")`` (Eq. 1).
Viewers live in :mod:`gdimitate.viz` (imported on demand: it starts meshcat servers).
"""

from . import bvh, gait, metrics, opensim, oscillator, planar, retarget, sim
from .adapt import AdaptationReport, AdaptedMotion, adapt
from .cases import paper_case
from .cpg import CPGReplay, entrain
from .demonstration import Demonstration, load_demonstration
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
from .export import export_motion
from .library import list_robots
from .motion import Motion
from .oscillator import MatsuokaBank, MatsuokaParams, self_adjust
from .retarget import Limits, StreamingAdaptor, Weights
from .robot import Leg, Robot
from .walking import HUMAN_GAIT, ROBOT_GAIT, GaitSpec, walking_motion

__version__ = "0.1.0"

__all__ = [
    "AdaptationReport",
    "AdaptedMotion",
    "CPGReplay",
    "Demonstration",
    "GaitSpec",
    "GdimitateError",
    "HUMAN_GAIT",
    "InvalidInputError",
    "Leg",
    "Limits",
    "MatsuokaBank",
    "MatsuokaParams",
    "LegDetectionError",
    "LegMatchError",
    "Motion",
    "OscillatorError",
    "ROBOT_GAIT",
    "Robot",
    "SolverError",
    "StreamingAdaptor",
    "TimeGridError",
    "URDFError",
    "UnknownNameError",
    "UnknownRobotError",
    "UnsupportedJointError",
    "ViewerError",
    "Weights",
    "adapt",
    "bvh",
    "entrain",
    "export_motion",
    "gait",
    "list_robots",
    "load_demonstration",
    "metrics",
    "opensim",
    "oscillator",
    "paper_case",
    "planar",
    "retarget",
    "self_adjust",
    "sim",
    "walking_motion",
]
