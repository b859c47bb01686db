"""What the imitator should keep: per-frame targets measured on the demonstration.

All quantities are DESIGN §4/§5's sagittal ones, measured on the demonstrator's own motion with
:mod:`gdimitate.metrics` and :mod:`gdimitate.sagittal` (Pinocchio forward kinematics), so that
the optimiser's constraints and the report's measurements are the same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidInputError, UnknownNameError
from ..metrics import FORCE_MODELS, angle_down, force_direction, hip_height_ratio
from ..motion import Motion
from ..robot import SIDES, Robot
from ..sagittal import frame_paths, joint_paths, leg_angles, robot_motion

__all__ = ["Targets", "demonstration_targets", "slice_motion", "contact_links", "CONTACT_MODES"]

#: ``"all"``: every stance foot stays where it landed (physical no-slip);
#: ``"anchor"``: only the foot that has been down longest is fixed, the other stance foot only
#: touches the ground (what Eq. (1) with :func:`gdimitate.sagittal.ground_base` satisfies).
CONTACT_MODES = ("all", "anchor")


@dataclass(frozen=True)
class Targets:
    """Per-frame demonstration targets, arrays ``(T,)`` unless said otherwise.

    ``t`` [s]; ``contact`` ``{side: bool}``; ``torso`` [rad]; ``angles`` ``{side: (T, 3)}``
    planar θ1, θ2, θ3 [rad]; ``height`` ``{side}``: hip-over-ankle height / leg length;
    ``shank`` ``{side}``: absolute angle of knee → ankle (→ sole without ankle) [rad];
    ``force`` ``{side}``: push direction under ``model`` [rad] (NaN in swing);
    ``placement`` ``{side}``: (sole x − hip x) / leg length.
    """

    model: str
    t: np.ndarray
    contact: dict[str, np.ndarray]
    torso: np.ndarray
    angles: dict[str, np.ndarray]
    height: dict[str, np.ndarray]
    shank: dict[str, np.ndarray]
    force: dict[str, np.ndarray]
    placement: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def T(self) -> int:
        """Number of frames."""
        return int(self.t.size)


def slice_motion(motion: Motion, idx) -> Motion:
    """The frames ``idx`` (slice or index array) of ``motion`` as a new :class:`Motion`."""
    t = motion.t[idx]
    if np.asarray(t).size < 2:
        raise InvalidInputError(f"selecting frames {idx!r} leaves fewer than 2 frames")
    return motion.replace(t=t, q=motion.q[idx],
                          contact={s: c[idx] for s, c in motion.contact.items()})


def demonstration_targets(demonstrator: Robot, motion: Motion, model: str = "segment"
                          ) -> Targets:
    """Measure :class:`Targets` on the demonstrator's ``motion`` under force ``model``."""
    if model not in FORCE_MODELS:
        raise UnknownNameError("force model", model, FORCE_MODELS)
    motion = robot_motion(demonstrator, motion.t, motion.q, motion.contact)
    torso, angles = leg_angles(demonstrator, motion.q)
    legs = demonstrator.legs
    shank, placement = {}, {}
    for s in SIDES:
        leg = legs[s]
        jp = joint_paths(demonstrator, motion.q, [leg.hip, leg.knee]
                         + ([leg.ankle] if leg.ankle else []))
        sole = frame_paths(demonstrator, motion.q, [leg.sole])[leg.sole]
        ankle = jp[leg.ankle] if leg.ankle else sole
        shank[s] = angle_down(ankle - jp[leg.knee])
        placement[s] = (sole[:, 0] - jp[leg.hip][:, 0]) / leg.length
    return Targets(
        model=model, t=motion.t.copy(),
        contact={s: np.asarray(motion.contact[s], bool).copy() for s in SIDES},
        torso=torso, angles=angles, height=hip_height_ratio(demonstrator, motion),
        shank=shank, force=force_direction(demonstrator, motion, model), placement=placement)


def contact_links(contact: dict[str, np.ndarray], mode: str = "all") -> dict[str, np.ndarray]:
    """``{side: (T,) bool}``: True at knot k when that foot's sole x must equal its x at k − 1.

    ``mode="all"``: whenever the foot is in stance at k − 1 and k. ``mode="anchor"``: only for
    the anchor foot — the stance foot down longest, kept until it lifts, as
    :func:`gdimitate.sagittal.ground_base` chooses it.
    """
    if mode not in CONTACT_MODES:
        raise UnknownNameError("contact mode", mode, CONTACT_MODES)
    c = {s: np.asarray(contact[s], bool) for s in SIDES}
    T = c[SIDES[0]].size
    links = {s: np.zeros(T, bool) for s in SIDES}
    if mode == "all":
        for s in SIDES:
            links[s][1:] = c[s][1:] & c[s][:-1]
        return links
    anchor, since = None, {s: -1 for s in SIDES}
    for i in range(T):
        for s in SIDES:
            since[s] = -1 if not c[s][i] else (since[s] if since[s] >= 0 else i)
        if anchor is None or not c[anchor][i]:
            cands = [s for s in SIDES if c[s][i]]
            anchor = min(cands, key=lambda s: since[s]) if cands else None
        if anchor is not None and i > 0 and c[anchor][i - 1]:
            links[anchor][i] = True
    return links
