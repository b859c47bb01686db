"""The independent audit: is a motion with its contact wrenches physically feasible?

Everything is recomputed from the motion's own ``(q, v, a)`` and wrenches with Pinocchio —
never read from the optimiser that produced them: inverse dynamics (the unactuated base rows
must vanish, every actuated joint's torque within its effort limit), forward differences of
``q`` (against ``v`` and the velocity limits), position limits, each stance foot's wrench
against its contact wrench cone (Caron, Pham, Nakamura, ICRA 2015), slip of the stance feet,
every sole corner against the floor, the push direction against the demonstrator's, and the
distances between the robot's own collision geometries (limb–limb, limb–trunk).
"""

from .core import audit
from .dataset import MotionAudit, audit_motion
from .report import (
    CORNER_NAMES,
    AuditReport,
    AuditTolerances,
    Check,
    FootAudit,
    ForceDirectionAudit,
    JointAudit,
    Penetration,
    SelfCollisionAudit,
    Worst,
)

__all__ = [
    "CORNER_NAMES",
    "AuditReport",
    "AuditTolerances",
    "Check",
    "FootAudit",
    "ForceDirectionAudit",
    "JointAudit",
    "MotionAudit",
    "Penetration",
    "SelfCollisionAudit",
    "Worst",
    "audit",
    "audit_motion",
]
