"""What the optimal adaptor's modes share below them: the soles a solve uses
(:func:`resolve_contacts`) and the robot the audit judges (:func:`limited_robot`). ``solve``
(the trajectory mode) and ``streaming`` (the per-frame mode) both import them from here, so
neither imports the other's module; the solver record they fill (:class:`SolverInfo`) lives
with the result type that holds it (:mod:`gdimitate.assess.solver`)."""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ..model.contact import SoleContact
from ..model.robot import SIDES, Robot
from . import limits
from .params import Contact

__all__ = ["resolve_contacts", "limited_robot"]


def resolve_contacts(imitator: Robot, opts: Contact, given) -> dict[str, SoleContact]:
    cs = dict(imitator.require_contacts())
    if given:
        for s, c in dict(given).items():
            if s not in SIDES:
                raise InvalidInputError(f"contacts= keys must be 'left'/'right'; got {s!r}")
            if not isinstance(c, SoleContact):
                c = cs[s].replace(**dict(c))
            if c.frame != cs[s].frame:
                raise InvalidInputError(f"contacts[{s!r}] must keep the frame {cs[s].frame!r} "
                                        "(pass a different frame through Robot(contacts=))")
            cs[s] = c
    if opts.mu is not None:
        cs = {s: c.replace(mu=opts.mu) for s, c in cs.items()}
    for s, c in cs.items():
        if opts.cop_margin >= min(c.half_length, c.half_width):
            raise InvalidInputError(f"cop_margin {opts.cop_margin} m leaves nothing of the "
                                    f"{s} sole ({c.half_length:.3f} × {c.half_width:.3f} m)")
    return cs


def limited_robot(robot: Robot, lim: limits.Resolved) -> Robot:
    """A copy of ``robot`` whose model carries the limits the motion was adapted to (the
    URDF's with :class:`~.params.Limits` overrides), for the audit."""
    import copy

    import pinocchio as pin

    out = copy.copy(robot)
    m = pin.Model(robot.model)
    vi = np.asarray([robot.idx_v(n) for n in lim.names], int)
    el, vl = np.array(m.effortLimit), np.array(m.velocityLimit)
    lo, hi = np.array(m.lowerPositionLimit), np.array(m.upperPositionLimit)
    el[vi], vl[vi] = lim.effort, lim.velocity
    big = np.finfo(float).max
    lo[lim.q_index] = np.where(np.isfinite(lim.lower), lim.lower, -big)
    hi[lim.q_index] = np.where(np.isfinite(lim.upper), lim.upper, big)
    m.effortLimit, m.velocityLimit = el, vl
    m.lowerPositionLimit, m.upperPositionLimit = lo, hi
    out.model, out.data = m, m.createData()
    return out
