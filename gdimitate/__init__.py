"""gdimitate — goal-directed imitation of rhythmic motion between robots of different bodies.

The pipeline (docs/design.md §2)::

    human, walk, forces = gdimitate.gait.human_walk_3d()     # OpenSim subject01, measured GRF
    robot = gdimitate.Robot.from_library("g1")
    adapted = gdimitate.adapt(walk, human, robot, force="measured", forces=forces)  # optimal
    adapted.audit.feasible                                   # recomputed with Pinocchio
    result = gdimitate.sim.simulate(robot, adapted, demo_forces=forces)   # MuJoCo
    cpg = gdimitate.entrain(robot, adapted.motion)           # Matsuoka network, free replay

Gait-lab data: ``gdimitate.load_demonstration("model.osim", markers="trial.c3d")`` (marker
inverse kinematics, force plates to feet; :mod:`gdimitate.c3d`, imported on first use).
The paper's planar case: ``gdimitate.adapt(demo, robot_m, imitator, "analytic")`` (Eq. 1).
Viewers live in :mod:`gdimitate.viz` (imported on demand: it starts meshcat servers).
"""

from . import (
    audit,
    bvh,
    contact,
    gait,
    metrics,
    opensim,
    oscillator,
    planar,
    retarget,
    sim,
    wrenches,
)
from .adapt import AdaptationReport, AdaptedMotion, adapt
from .cases import paper_case
from .contact import ContactForces, FootForces, SoleContact
from .cpg import CPGReplay, entrain
from .demonstration import Demonstration, load_demonstration
from .errors import (
    ContactError,
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
from .metrics import ForceDirection
from .motion import Motion
from .oscillator import MatsuokaBank, MatsuokaParams, self_adjust
from .retarget import Limits, StreamingAdaptor, Weights
from .robot import Leg, Robot
from .walking import HUMAN_GAIT, ROBOT_GAIT, GaitSpec, walking_motion

__version__ = "0.1.0"


def __getattr__(name: str):
    """``gdimitate.c3d`` (gait-lab C3D files) is imported on first use."""
    if name == "c3d":
        import importlib

        return importlib.import_module(".c3d", __name__)
    raise AttributeError(f"module 'gdimitate' has no attribute {name!r}")


__all__ = [
    "AdaptationReport",
    "AdaptedMotion",
    "ContactError",
    "ContactForces",
    "CPGReplay",
    "Demonstration",
    "FootForces",
    "ForceDirection",
    "GaitSpec",
    "GdimitateError",
    "HUMAN_GAIT",
    "InvalidInputError",
    "Leg",
    "LegDetectionError",
    "LegMatchError",
    "Limits",
    "MatsuokaBank",
    "MatsuokaParams",
    "Motion",
    "OscillatorError",
    "Robot",
    "ROBOT_GAIT",
    "SoleContact",
    "SolverError",
    "StreamingAdaptor",
    "TimeGridError",
    "UnknownNameError",
    "UnknownRobotError",
    "UnsupportedJointError",
    "URDFError",
    "ViewerError",
    "Weights",
    "adapt",
    "audit",
    "bvh",
    "c3d",
    "contact",
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
    "wrenches",
]
