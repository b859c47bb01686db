"""The parts of the whole-body problem — costs and constraints, one small class each
(:mod:`.base` says what a part declares) — and :func:`default_parts`, the list the adaptor
sums. A new part is a class in its own module added to that list (or passed by a caller):
the weight layout, the elastic slacks, the row labels and the cache key follow from it."""

from __future__ import annotations

from .base import Constraint, Cost, PairConstraint, Part, Spec, per_side_labels
from .cone import WrenchCone
from .contact import ContactHold, FlatContact, liftoff_knots, velocity_knots
from .dynamics import BaseDynamics, TorqueLimits
from .force import ForceDirection
from .integration import Integration, QuaternionNorm
from .keypoints import Foot, Height, Placement, Segments, Shank, Thigh
from .regularisation import Joints, Smoothness, WrenchRegularisation
from .swing import SwingClearance

__all__ = ["Part", "Cost", "Constraint", "PairConstraint", "Spec", "per_side_labels",
           "default_parts", "BaseDynamics", "TorqueLimits", "FlatContact", "ContactHold",
           "WrenchCone", "SwingClearance", "ForceDirection", "Integration", "QuaternionNorm",
           "Height", "Placement", "Shank", "Thigh", "Foot", "Segments", "Joints",
           "Smoothness", "WrenchRegularisation", "liftoff_knots", "velocity_knots"]


def default_parts(segment_frames: tuple[str, ...], q_index: tuple[int, ...]) -> tuple[Part, ...]:
    """The adaptor's problem (docs/design.md §6): ``segment_frames`` the imitator's mapped
    segment frames, ``q_index`` its actuated joints' indices into ``q``."""
    return (
        # constraints at one knot, in row order
        BaseDynamics(), TorqueLimits(), FlatContact(), WrenchCone(), SwingClearance(),
        ForceDirection(), QuaternionNorm(),
        # constraints between neighbouring knots
        Integration(), ContactHold(),
        # costs
        Height(), Placement(), Shank(), Thigh(), Foot(), Segments(tuple(segment_frames)),
        Joints(tuple(int(i) for i in q_index)), Smoothness(), WrenchRegularisation(),
    )
