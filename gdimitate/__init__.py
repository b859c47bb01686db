"""gdimitate — goal-directed imitation of rhythmic motion between robots of different bodies.

The pipeline (docs/design.md §2)::

    human, walk, forces = gdimitate.gait.human_walk_3d()     # OpenSim subject01, measured GRF
    robot = gdimitate.Robot.from_library("g1")
    adapted = gdimitate.adapt(walk, human, robot, force="measured", forces=forces)  # optimal
    adapted.audit.feasible                                   # recomputed with Pinocchio
    result = gdimitate.sim.simulate(robot, adapted, demo_forces=forces)   # MuJoCo
    cpg = gdimitate.entrain(robot, adapted.motion)           # Matsuoka network, free replay

Gait-lab data: ``gdimitate.load_demonstration("model.osim", markers="trial.c3d")`` (marker
inverse kinematics, force plates to feet; :mod:`gdimitate.io.c3d`, imported on first use).
The paper's planar case: ``gdimitate.adapt(demo, robot_m, imitator, "analytic")`` (Eq. 1).
Viewers live in :mod:`gdimitate.viz` (imported on demand: it starts meshcat servers).
Scenario code (the demo, the paper's figures, the baselines) lives in :mod:`gdimitate.apps`,
which is not API.
"""

# Every public name is imported on first use (PEP 562 module ``__getattr__``), so that
# ``import gdimitate`` and ``gdimitate --help`` stay quick and load no engine (Pinocchio,
# CasADi, MuJoCo, meshcat, numba ...) until a name that needs one is touched. Static type
# checkers and IDEs read the ``TYPE_CHECKING`` imports below; both lists name the same things
# (tests/project/test_architecture.py checks that every name resolves).
from __future__ import annotations

import importlib
import importlib.util
from typing import TYPE_CHECKING, Any

from .errors import (
    BodyMapError,
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

if TYPE_CHECKING:
    from . import (
        oscillator,
        planar,
        retarget,
        sim,
    )
    from .adaptation.adaptor import adapt
    from .adaptation.repairer import RepairResult, repair
    from .apps.cases import paper_case
    from .assess import audit, metrics, wrenches
    from .assess.audit.dataset import MotionAudit, audit_motion
    from .assess.metrics import ForceDirection
    from .assess.result import AdaptationReport, AdaptedMotion
    from .export.writers import export_motion
    from .io import bvh, c3d, gait, opensim
    from .io.demonstration import Demonstration, load_demonstration
    from .model import contact
    from .model.contact import ContactForces, FootForces, SoleContact
    from .model.library import list_robots
    from .model.motion import Motion
    from .model.robot import Leg, Robot
    from .oscillator import MatsuokaBank, MatsuokaParams, self_adjust
    from .oscillator.replay import CPGReplay, entrain
    from .planar.walking import HUMAN_GAIT, ROBOT_GAIT, GaitSpec, walking_motion
    from .retarget import Limits, StreamingAdaptor, Weights
    from .walker import walk

__version__ = "0.1.0"

#: public name -> the submodule that defines it (imported when the name is first read)
_LAZY_NAMES: dict[str, str] = {
    "adapt": ".adaptation.adaptor",
    "AdaptationReport": ".assess.result",
    "AdaptedMotion": ".assess.result",
    "paper_case": ".apps.cases",
    "audit_motion": ".assess.audit.dataset",
    "MotionAudit": ".assess.audit.dataset",
    "ContactForces": ".model.contact",
    "FootForces": ".model.contact",
    "SoleContact": ".model.contact",
    "CPGReplay": ".oscillator.replay",
    "entrain": ".oscillator.replay",
    "Demonstration": ".io.demonstration",
    "load_demonstration": ".io.demonstration",
    "export_motion": ".export.writers",
    "list_robots": ".model.library",
    "ForceDirection": ".assess.metrics",
    "Motion": ".model.motion",
    "MatsuokaBank": ".oscillator",
    "MatsuokaParams": ".oscillator",
    "self_adjust": ".oscillator",
    "Limits": ".retarget",
    "StreamingAdaptor": ".retarget",
    "Weights": ".retarget",
    "Leg": ".model.robot",
    "Robot": ".model.robot",
    "HUMAN_GAIT": ".planar.walking",
    "ROBOT_GAIT": ".planar.walking",
    "GaitSpec": ".planar.walking",
    "walking_motion": ".planar.walking",
    "repair": ".adaptation.repairer",
    "RepairResult": ".adaptation.repairer",
    "walk": ".walker",
}

#: public subpackages / modules (``gdimitate.sim`` etc.) -> where they live, imported on first use
_LAZY_MODULES: dict[str, str] = {
    "audit": ".assess.audit",
    "bvh": ".io.bvh",
    "c3d": ".io.c3d",
    "contact": ".model.contact",
    "gait": ".io.gait",
    "metrics": ".assess.metrics",
    "opensim": ".io.opensim",
    "oscillator": ".oscillator",
    "planar": ".planar",
    "retarget": ".retarget",
    "sim": ".sim",
    "wrenches": ".assess.wrenches",
}


def __getattr__(name: str) -> Any:
    """Import a public name (or any submodule, e.g. ``gdimitate.viz``) on first use."""
    if name in _LAZY_NAMES:
        value = getattr(importlib.import_module(_LAZY_NAMES[name], __name__), name)
    elif name in _LAZY_MODULES:
        value = importlib.import_module(_LAZY_MODULES[name], __name__)
    elif not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}"):
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'gdimitate' has no attribute {name!r}")
    globals()[name] = value  # later reads skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


__all__ = [
    "AdaptationReport",
    "AdaptedMotion",
    "BodyMapError",
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
    "MotionAudit",
    "OscillatorError",
    "Robot",
    "ROBOT_GAIT",
    "RepairResult",
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
    "audit_motion",
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
    "repair",
    "retarget",
    "self_adjust",
    "sim",
    "walk",
    "walking_motion",
    "wrenches",
]
