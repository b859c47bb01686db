"""What one demonstration gives the whole-body problem: its per-knot :class:`Targets` and the
:class:`Context` a part's :meth:`~gdimitate.retarget.parts.Part.values` reads (the targets, both
robots, the weights, the resolved limits, the contact options and the soles).

Both are plain frozen records at the root of :mod:`gdimitate.retarget`, below the parts and
the two modes, so that a part's signature can name them: the parts import this module, the
trajectory and streaming modes build its records (:func:`.targets.demonstration_targets`,
:func:`.trajectory.solve.setup`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.contact import SoleContact
from ..model.motion import Motion
from ..model.robot import Robot
from .limits import Resolved
from .params import Contact, Weights

__all__ = ["Targets", "Context"]


@dataclass(frozen=True)
class Targets:
    """Per knot ``k`` of ``t`` ``(T,)`` [s]: ``stance`` ``{side: (T,) bool}`` (the imitator's
    contacts) and ``swing`` (feet held above the floor: not in the demonstrator's stance —
    under the ``"anchor"`` rule a second stance foot is neither); ``height`` ``{side: (T,)}``,
    ``placement`` ``{side: (T, 2)}``, ``shank`` and ``thigh`` ``{side: (T, 3)}`` unit vectors
    (the demonstrator's scaled keypoints), ``foot`` ``{side: (T, 3, 3)}`` its sole frames'
    world rotations;
    ``segments`` ``(T, n_seg, 3, 3)`` the imitator's segment frames' world rotations
    (:func:`.targets.segment_rotations`: the demonstrator's since its neutral pose); ``joints``
    ``(T, n_act)`` joint targets [rad] (unmapped joints: the rest pose,
    :func:`.parts.self_collision.rest_pose`) and
    ``mapped`` ``(n_act,)`` bool; ``push`` ``{side: (T, 3)}`` the demonstrator's unit
    push on the ground (NaN where there is none; projected onto the x–z plane for planar
    imitators, which can only keep its sagittal direction); ``demo``: the resampled
    demonstration."""

    t: np.ndarray
    stance: dict[str, np.ndarray]
    swing: dict[str, np.ndarray]
    height: dict[str, np.ndarray]
    placement: dict[str, np.ndarray]
    shank: dict[str, np.ndarray]
    thigh: dict[str, np.ndarray]
    foot: dict[str, np.ndarray]
    segments: np.ndarray
    joints: np.ndarray
    mapped: np.ndarray
    push: dict[str, np.ndarray]
    demo: Motion

    @property
    def T(self) -> int:
        return int(self.t.size)


@dataclass(frozen=True)
class Context:
    """What a part's :meth:`~gdimitate.retarget.parts.Part.values` may read: the
    demonstration's :class:`Targets` ``tg``, the ``imitator`` and the ``demonstrator``, the
    :class:`~.params.Weights`, the resolved limits ``lim`` (:class:`~.limits.Resolved`), the
    :class:`~.params.Contact` options and the soles ``cs`` ``{side: SoleContact}``."""

    tg: Targets
    imitator: Robot
    demonstrator: Robot
    weights: Weights
    lim: Resolved
    contact: Contact
    cs: dict[str, SoleContact]
