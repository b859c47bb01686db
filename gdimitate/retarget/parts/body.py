"""The whole body, faithfully: the parts every whole-body adaptation adds to
:func:`~.default_parts` for an imitator — the joints its body map leaves out held within
:data:`~gdimitate.retarget.bodymap.HOLD_RANGE` of their rest pose (:class:`.PostureRange`;
:func:`~.self_collision.rest_pose`: the neutral pose with the limbs moved clear of each
other) and its limbs kept apart (:class:`.SelfCollision`, robots with collision geometry)."""

from __future__ import annotations

from collections.abc import Sequence

from ...model.robot import Robot
from .base import Part
from .posture_range import PostureRange
from .self_collision import SelfCollision, leg_separation, rest_floors, rest_pose, sphere_pairs

__all__ = ["body_parts"]


def body_parts(imitator: Robot, act_names: Sequence[str]) -> tuple[Part, ...]:
    """``(PostureRange, SelfCollision)`` for ``imitator`` (a :class:`~gdimitate.Robot`) and
    its actuated joints ``act_names`` (which of them the body map leaves out is a parameter of
    the posture range; the self-collision part is left out for a robot without collision
    geometry)."""
    from ..bodymap import HOLD_RANGE

    out: list[Part] = []
    rest = rest_pose(imitator)
    if act_names:
        idx = tuple(int(imitator.idx_q(j)) for j in act_names)
        out.append(PostureRange(idx, tuple(float(rest[i]) for i in idx), HOLD_RANGE))
    pairs, legs = sphere_pairs(imitator, q=rest), leg_separation(imitator)
    if pairs or legs:
        out.append(SelfCollision(pairs, legs, rest_floors(imitator, pairs, rest)))
    return tuple(out)
