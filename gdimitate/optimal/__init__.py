"""The optimal adaptor (DESIGN §6): CasADi/IPOPT trajectory optimisation over the knots.

Entry points: :func:`adapt_optimal` (what ``gdimitate.adapt(..., method="optimal")`` calls),
:class:`StreamingAdaptor` (one small problem per frame, for online imitation),
:class:`Limits` (override URDF limits), :class:`Weights` (cost weights) and
:func:`retarget_humanoid` (the real human walk onto an example-robot-data humanoid).
"""

from .limits import Limits, ResolvedLimits, resolve_limits
from .model import SagittalModel, difference_matrices
from .problem import TrajectoryProblem, Weights
from .solve import MODES, adapt_optimal, sagittal_model
from .targets import CONTACT_MODES, Targets, demonstration_targets, slice_motion

__all__ = [
    "CONTACT_MODES",
    "Limits",
    "MODES",
    "ResolvedLimits",
    "SagittalModel",
    "Targets",
    "TrajectoryProblem",
    "Weights",
    "adapt_optimal",
    "demonstration_targets",
    "difference_matrices",
    "resolve_limits",
    "sagittal_model",
    "slice_motion",
]
