"""A periodic plan indexed by phase (docs/design.md §14): the plan of one gait cycle (a
periodic adaptation, ``adapt(..., periodic=True)``: its last knot is its first shifted by one
stride) read at any number of cycles ``c`` ≥ 0 — cycle ``n = ⌊c⌋`` at the fraction
``c − n`` of its period — with every position (base, centre of mass, soles) advanced by
``n`` strides. A tracking controller follows whatever phase it is given (e.g. an oscillator
network's), so the rhythm can come from outside the plan.

At a rate ``r`` (cycles per second relative to the plan's own, 1 = as planned) the
velocities are scaled by ``r`` and the accelerations by ``r²`` (the plan re-timed); the
wrenches are the plan's.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import PlanError
from ..model.robot import SIDES, Robot
from .reference import Reference, Sample, check_plan

__all__ = ["PeriodicReference"]


class PeriodicReference:
    """Phase-indexed samples of a periodic plan (module docstring).

    ``period`` [s]: the cycle's duration; ``stride`` ``(3,)`` [m]: the base displacement over
    one cycle (world frame); ``reference``: the one-cycle :class:`Reference`."""

    def __init__(self, robot: Robot, plan, seam_tol: float = 1e-6):
        plan = check_plan(robot, plan)
        mo = plan.motion
        if mo.T < 3:
            raise PlanError("a periodic plan needs at least 3 knots")
        self.robot, self.plan = robot, plan
        self.reference = Reference(robot, plan)
        self.period = float(mo.t[-1] - mo.t[0])
        self.t0 = float(mo.t[0])
        ref = self.reference
        self.stride = ref.com[-1, 0] - ref.com[0, 0]
        self.stride[2] = 0.0
        gap = max(float(np.max(np.abs(ref.foot_pos[s][-1] - ref.foot_pos[s][0] - self.stride)))
                  for s in SIDES if mo.contact[s][0] and mo.contact[s][-1])
        jumps = float(np.max(np.abs(mo.v[-1] - mo.v[0])))
        if gap > 1e-3 or jumps > 1e-3 or any(mo.contact[s][0] != mo.contact[s][-1]
                                             for s in SIDES):
            raise PlanError(f"the plan is not periodic (stance sole moved {gap:.3g} m more than "
                            f"the stride, velocity jump {jumps:.3g} across the seam): adapt it "
                            "with periodic=True")
        self._base_cols = ([0, 1] if robot.base == "free" else [robot.idx_q("base_x")])

    def at(self, cycles: float, rate: float = 1.0) -> Sample:
        """The plan at ``cycles`` (≥ 0; cycle ``⌊cycles⌋`` at its fraction), re-timed by
        ``rate`` (module docstring)."""
        n = int(np.floor(cycles))
        return self._shifted(self.reference.at(self._time(cycles - n)), n, rate)

    def _time(self, fraction: float) -> float:
        """Plan time of a cycle fraction, snapped onto a knot within 1e-9 s (so that a knot's
        fraction reads that knot, not the end of the step before it)."""
        tau = self.t0 + fraction * self.period
        t = self.reference.t
        k = int(np.clip(np.searchsorted(t, tau), 0, t.size - 1))
        for j in (k - 1, k):
            if 0 <= j < t.size and abs(t[j] - tau) < 1e-9:
                return float(t[j])
        return tau

    def _shifted(self, s: Sample, n: int, rate: float) -> Sample:
        D = n * self.stride
        q = s.q.copy()
        q[self._base_cols] += D[:2] if self.robot.base == "free" else D[0]
        r, r2 = float(rate), float(rate) ** 2
        return dataclasses.replace(
            s, q=q, v=s.v * r, a=s.a * r2, com=s.com + D, com_vel=s.com_vel * r,
            com_acc=s.com_acc * r2, base_omega=s.base_omega * r, base_alpha=s.base_alpha * r2,
            foot_pos={k: p + D for k, p in s.foot_pos.items()},
            foot_vel={k: x * r for k, x in s.foot_vel.items()},
            foot_acc={k: x * r2 for k, x in s.foot_acc.items()})

    def fraction_of_time(self, t: np.ndarray) -> np.ndarray:
        """Cycle fraction ``(N,)`` of plan times ``t`` ``(N,)`` [s]."""
        return (np.asarray(t, float) - self.t0) / self.period

    def strike_fractions(self) -> dict[str, float]:
        """Cycle fraction of each foot's heel strike (its stance's first knot after a swing;
        the cycle starts at one, fraction 0)."""
        mo = self.plan.motion
        out = {}
        for s in SIDES:
            c = np.asarray(mo.contact[s], int)
            k = np.flatnonzero(np.diff(c) == 1) + 1
            k = k[k < mo.T - 1]
            out[s] = float(self.fraction_of_time(mo.t[k[0]])) if k.size else 0.0
        return out
