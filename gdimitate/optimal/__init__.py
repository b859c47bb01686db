"""The optimal adaptor (DESIGN §6): CasADi/IPOPT trajectory optimisation over the knots.

Entry points: :func:`adapt_optimal` (what ``gdimitate.adapt(..., method="optimal")`` calls),
:class:`StreamingAdaptor` (one small problem per frame, for online imitation),
:class:`Limits` (override URDF limits), :class:`Weights` (cost weights) and
:func:`retarget_humanoid` (the real human walk onto an example-robot-data humanoid).
"""

from .humanoids import HUMANOIDS, format_table, retarget_humanoid, retarget_table
from .limits import Limits, ResolvedLimits, resolve_limits
from .model import SagittalModel, difference_matrices
from .problem import TrajectoryProblem, Weights
from .solve import MODES, adapt_optimal, sagittal_model
from .streaming import STREAMING_FORCE_MODELS, StreamingAdaptor, adapt_per_frame
from .targets import CONTACT_MODES, Targets, demonstration_targets, slice_motion

__all__ = [
    "CONTACT_MODES",
    "HUMANOIDS",
    "Limits",
    "MODES",
    "ResolvedLimits",
    "STREAMING_FORCE_MODELS",
    "SagittalModel",
    "StreamingAdaptor",
    "Targets",
    "TrajectoryProblem",
    "Weights",
    "adapt_optimal",
    "adapt_per_frame",
    "demonstration_targets",
    "difference_matrices",
    "format_table",
    "resolve_limits",
    "retarget_humanoid",
    "retarget_table",
    "sagittal_model",
    "slice_motion",
]
