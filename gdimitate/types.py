"""Names of the closed sets of choices, as ``Literal`` types for signatures and type checkers.

Each alias matches the values its module checks at run time
(tests/project/test_architecture.py keeps them equal): :data:`Side` = :data:`SIDES`
(= :data:`gdimitate.model.legs.SIDES`), :data:`ForceModel` =
:data:`gdimitate.assess.metrics.FORCE_MODELS`, :data:`ContactRule` = the rules of
:class:`gdimitate.retarget.Contact`, :data:`BaseKind` = the values of ``Robot.base``.
Importing this module loads nothing else.
"""

from __future__ import annotations

from typing import Literal

__all__ = ["AdaptMethod", "BaseKind", "ContactRule", "ForceModel", "PlanarMethod", "SIDES",
           "Side"]

#: a leg
Side = Literal["left", "right"]
#: the legs, in the order every ``{side: …}`` mapping is filled
SIDES: tuple[str, str] = ("left", "right")  # str keys: {side: ...} dicts index by name
#: the force-direction model of the goal (docs/design.md §5)
ForceModel = Literal["measured", "dynamics", "com", "segment"]
#: ``Robot.base``: a 6-DoF free-flyer, the planar models' (x, z, pitch) base, or none
BaseKind = Literal["free", "planar", "fixed"]
#: which stance feet are contacts: every one of the schedule, or the anchor foot only
ContactRule = Literal["all", "anchor"]
#: the paper's planar adaptors (:func:`gdimitate.planar.adapt_planar`)
PlanarMethod = Literal["analytic", "copy"]
#: the methods of :func:`gdimitate.adapt`
AdaptMethod = Literal["analytic", "copy", "optimal"]
