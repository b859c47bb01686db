"""The whole-body, contact-consistent optimal adaptor (docs/design.md §6).

One formulation, assembled from named parts, for the trajectory mode (:mod:`.trajectory`;
:func:`adapt_optimal`, what ``gdimitate.adapt(..., method="optimal")`` runs); the streaming
mode (:mod:`.streaming`; :class:`StreamingAdaptor`, ``mode="per_frame"``) shares its body map,
limits, targets and soles (this folder's modules) and solves one whole-body inverse-dynamics
QP per frame instead (:mod:`.streaming.receding`):

- decision variables per knot (:mod:`.knot`): the imitator's full configuration ``q``, its
  velocity ``v`` and acceleration ``a`` (Pinocchio's conventions), one contact wrench per foot
  in its sole frame (6-D; planar models 3-D) and elastic slacks (0 unless the fallback runs);
- tasks (:mod:`.tasks`): scaled keypoints and segment orientations through a body map
  (:mod:`.bodymap`), joint similarity, smoothness, wrench regularisation;
- constraints (:mod:`.constraints`): integration, dynamics with every joint's torque limit,
  joint position and velocity limits, flat-foot contact, the contact wrench cone of each sole
  rectangle, swing clearance of every sole corner, the force direction (the goal);
- one knot's functions mapped over the knots and the NLP cached per problem shape
  (:mod:`.trajectory.problem`); IPOPT; the least-infeasible (elastic, L1) fallback; Ctrl-C
  stops a solve (:mod:`.trajectory.interrupt`); the report recomputed by
  :func:`gdimitate.assess.audit.audit`.
"""

from ..assess.solver import SolverInfo, Unmet
from .bodymap import BodyMap, UnmappedJointsWarning, body_map
from .optimal import MODES, OPTIONS, adapt_optimal
from .params import DEFAULT_RATE, Contact, Limits, Weights
from .streaming.adaptor import FrameResult, StreamingAdaptor
from .targets import Targets, resample, schedule
from .trajectory.problem import clear_cache

__all__ = [
    "BodyMap",
    "Contact",
    "DEFAULT_RATE",
    "FrameResult",
    "Limits",
    "MODES",
    "OPTIONS",
    "SolverInfo",
    "StreamingAdaptor",
    "Targets",
    "UnmappedJointsWarning",
    "Unmet",
    "Weights",
    "adapt_optimal",
    "body_map",
    "clear_cache",
    "resample",
    "schedule",
]
