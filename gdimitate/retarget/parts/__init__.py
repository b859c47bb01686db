"""The parts of the whole-body problem — costs and constraints, one small class each
(:mod:`.base` says what a part declares: the abstract :class:`Part` and its kinds, with the
value objects a constraint states, :class:`Rows` and :class:`Bounds`) — and
:func:`default_parts`, the list the adaptor sums. A new part is a class in its own module
added to that list (or passed by a caller): the weight layout, the elastic slacks, the row
labels and the cache key follow from it."""

from __future__ import annotations

from .base import (
    Bound,
    Bounds,
    Box,
    Constraint,
    Cost,
    PairConstraint,
    Part,
    Rows,
    Spec,
    per_side_labels,
)
from .base_dynamics import BaseDynamics
from .cone import WrenchCone
from .contact_hold import ContactHold
from .flat_contact import FlatContact, liftoff_knots, velocity_knots
from .foot import Foot
from .force import ForceDirection
from .height import Height
from .integration import Integration
from .joints import Joints
from .over_feet import OverFeet
from .placement import Placement
from .quaternion import QuaternionNorm
from .segments import Segments
from .shank import Shank
from .smoothness import Smoothness
from .steps import Steps
from .swing import SwingClearance
from .thigh import Thigh
from .torque_limits import TorqueLimits
from .wrench import WrenchRegularisation

__all__ = ["Part", "Cost", "Constraint", "PairConstraint", "Bound", "Spec", "Rows", "Bounds",
           "Box", "per_side_labels",
           "default_parts", "BaseDynamics", "TorqueLimits", "FlatContact", "ContactHold",
           "WrenchCone", "SwingClearance", "ForceDirection", "Integration", "QuaternionNorm",
           "Height", "OverFeet", "Placement", "Shank", "Thigh", "Foot", "Segments", "Joints",
           "Smoothness", "Steps", "WrenchRegularisation", "liftoff_knots", "velocity_knots"]


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
