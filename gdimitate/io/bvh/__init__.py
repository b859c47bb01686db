"""BVH motion capture → a free-flyer :class:`~gdimitate.model.robot.Robot` and its
:class:`~gdimitate.model.motion.Motion`.

``robot, motion = gdimitate.bvh.read_bvh(path)``: the skeleton becomes a URDF (a link per BVH
joint, one revolute joint per rotation channel in the file's order, the root as a
free-flyer), with units detected, the world turned from Y-up to z-up, segment masses and
inertias from de Leva (1996), a sole frame per foot and foot contacts detected from the feet's
height and speed. Modules: :mod:`.parse` (the strict reader), :mod:`.skeleton` (units, legs,
soles), :mod:`.inertia`, :mod:`.urdf`, :mod:`.contacts`, :mod:`.reader`.
"""

from .contacts import ContactRule, detect_contacts, estimate_floor, sole_corners
from .parse import BVHFile, BVHJoint, parse_bvh
from .reader import BVHInfo, bvh_to_q, channel_rotation, is_reference_frame, read_bvh
from .skeleton import UNITS, UP_TURNS

__all__ = [
    "BVHFile",
    "BVHInfo",
    "BVHJoint",
    "ContactRule",
    "UNITS",
    "UP_TURNS",
    "bvh_to_q",
    "channel_rotation",
    "detect_contacts",
    "estimate_floor",
    "is_reference_frame",
    "parse_bvh",
    "read_bvh",
    "sole_corners",
]
