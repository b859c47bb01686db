"""A periodic gait cycle (docs/design.md §14): one stride of a demonstration, heel strike to
heel strike of the same foot, adapted so that its last knot is its first shifted by one
stride (``adapt(..., periodic=True)``).

- :func:`periodic_stride` cuts the stride from the contact schedule and makes its two ends
  one state: the last frame's contact flags (and measured forces) are the first frame's;
- :func:`periodic_rate` is the knot rate nearest the asked one that puts a knot exactly on
  the stride's end;
- the seam rows are :class:`~.parts.periodic.PeriodicSeam` (in the NLP);
- :func:`close_seam` makes the seam exact on the output's own numbers after the solve (the
  periodic counterpart of :func:`~.polish.make_consistent`): ``q`` of the last knot = the
  first's shifted by the solved stride, ``v`` of the first = the last's (by the integration
  rule), and the last knot's ``a`` and wrenches = the first's. Each correction is of the
  size of IPOPT's final constraint violation; the audit judges the result, and
  :func:`gdimitate.assess.audit.periodic.seam_audit` checks the seam itself.
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidInputError
from ...model.contact import ContactForces, FootForces
from ...model.footsteps import shift_by_stride, walking_direction
from ...model.motion import Motion
from ...model.robot import Robot
from .polish import make_consistent

__all__ = ["periodic_stride", "periodic_rate", "close_seam"]


def _strikes(contact: np.ndarray) -> np.ndarray:
    c = np.asarray(contact, int)
    strikes = np.flatnonzero(np.diff(c) == 1) + 1
    if strikes.size < 2 and c.size and c[0] == 1:  # a clip that begins with the strike
        strikes = np.r_[0, strikes]
    return strikes


def periodic_stride(motion: Motion, forces: ContactForces | None, side: str = "right"
                    ) -> tuple[Motion, ContactForces | None]:
    """The first full stride of ``motion`` from a heel strike of ``side`` to its next (a
    clip that starts in ``side``'s stance counts its first frame as a strike when it has
    only one later strike), with the last frame's contact flags — and measured forces, if
    given on the motion's frames — set to the first frame's. :class:`InvalidInputError` when
    there is no full stride."""
    if side not in motion.contact:
        raise InvalidInputError(f"the motion has no {side!r} contact schedule")
    st = _strikes(motion.contact[side])
    if st.size < 2:
        raise InvalidInputError(
            f"the demonstration has fewer than two {side} heel strikes in its contact "
            "schedule; a periodic cycle needs one full stride (heel strike to heel strike)")
    sl = slice(int(st[0]), int(st[1]) + 1)
    contact = {}
    for s, c in motion.contact.items():
        c = np.asarray(c, bool)[sl].copy()
        c[-1] = c[0]
        contact[s] = c
    m = motion.replace(t=motion.t[sl], q=motion.q[sl], v=None, a=None, contact=contact)
    if forces is None:
        return m, None
    if forces.t.shape != motion.t.shape or not np.allclose(forces.t, motion.t):
        raise InvalidInputError("periodic=True needs the measured forces on the motion's own "
                                "frames (gd.opensim.read_grf(..., t=motion.t))")
    feet = {}
    for s, f in forces.feet.items():
        arrs = [np.array(x[sl], copy=True) for x in (f.force, f.cop, f.torque, f.contact)]
        for x in arrs:
            x[-1] = x[0]
        feet[s] = FootForces(*arrs)
    return m, ContactForces(forces.t[sl], feet, forces.source,
                            forces.frame_note + f"; one periodic {side} stride")


def periodic_rate(motion: Motion, rate: float) -> float:
    """The knot rate [knots/s] nearest ``rate`` with a whole number (≥ 2) of steps over the
    clip, so that the last knot falls on the stride's end."""
    P = float(motion.t[-1] - motion.t[0])
    n = max(int(round(P * rate)), 2)
    return n / P


def close_seam(robot: Robot, demonstrator: Robot, demo_q: np.ndarray, t: np.ndarray,
               q: np.ndarray, v: np.ndarray, a: np.ndarray, W: dict[str, np.ndarray],
               stance: dict[str, np.ndarray], frames: dict[str, str], base_idx: np.ndarray,
               contacts=None, targets=None, half_angle: float = 0.0):
    """:func:`~.polish.make_consistent` with the seam exact (module docstring); ``demo_q``
    ``(T, nq_demo)`` gives the walking direction; ``contacts``, ``targets``, ``half_angle``:
    the soles' cones and the push directions the wrench corrections keep
    (:func:`~.polish.make_consistent`). Returns ``(q, v, a, W)``."""
    q = np.array(q, float)
    q[-1] = shift_by_stride(robot, q[0], q[-1], walking_direction(demonstrator, demo_q))
    q, v, a, W = make_consistent(robot, t, q, v, a, W, stance, frames, base_idx, contacts,
                                 targets, half_angle)
    v[0] = v[-1]
    a[0] = (v[1] - v[0]) / (t[1] - t[0])
    one = make_consistent(robot, t[:1], q[:1], v[:1], a[:1], {s: w[:1] for s, w in W.items()},
                          {s: c[:1] for s, c in stance.items()}, frames, base_idx, contacts,
                          None if targets is None else {s: x[:1] for s, x in targets.items()},
                          half_angle)
    a[-1] = a[0]
    for s in W:
        W[s][0] = one[3][s][0]
        W[s][-1] = W[s][0]
    return q, v, a, W
