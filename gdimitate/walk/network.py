"""The whole-body oscillator network that carries a periodic gait cycle (docs/design.md §7,
§14): one Matsuoka oscillator per actuated joint that moves in the cycle, one shared
frequency, tuned by :func:`gdimitate.oscillator.self_adjust` to the cycle's joint angles, then
run step by step (RK4) with an input ``g`` from outside (the ground's feedback).

Its phase: the network's state ``(x_e, x_f, v_e, v_f)`` of all oscillators, projected on the
plane of its two principal components over the free-running limit cycle, gives an angle; a
calibration table over one free period maps that angle to the fraction of the period elapsed
(an asymptotic phase, uniform in time on the limit cycle), and one offset — the shift that
best aligns the network's joint read-out with the cycle's joints — makes fraction 0 the
cycle's first knot (the heel strike). The phase is therefore a property of the network's
state, not of a clock: an input that speeds up or delays the oscillators moves it.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ..oscillator import SelfAdjustResult, self_adjust
from ..oscillator.bank import _rhs
from ..robot import PLANAR_BASE, Robot

__all__ = ["WalkNetwork", "cycle_joints"]

#: Joints whose angle moves less than this over the cycle [rad] get no oscillator (the plan
#: holds them).
MIN_RANGE = 1e-4


def cycle_joints(robot: Robot, q: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Names and ``q`` indices of the actuated 1-DoF joints that move over ``q`` ``(T, nq)``."""
    m = robot.model
    names, idx = [], []
    for j in range(1, m.njoints):
        jm, n = m.joints[j], m.names[j]
        if jm.nq == 1 and n not in PLANAR_BASE and np.ptp(q[:, jm.idx_q]) > MIN_RANGE:
            names.append(n)
            idx.append(jm.idx_q)
    return names, np.array(idx, int)


class WalkNetwork:
    """A tuned network (module docstring). Build with :meth:`tune`.

    ``result``: the :class:`~gdimitate.oscillator.SelfAdjustResult`; ``q_index`` ``(n,)``:
    the joints' columns of ``q``; ``period`` [s] and ``t0`` [s]: the cycle's; ``frequency``
    [Hz]: the network's own, measured on its free-running limit cycle; ``state`` ``(4, n)``."""

    def __init__(self, result: SelfAdjustResult, q_index: np.ndarray, period: float, t0: float):
        self.result, self.q_index = result, q_index
        self.period, self.t0 = float(period), float(t0)
        self.params, self.W = result.params, result.coupling
        self.coupled = bool(np.any(self.W))
        self.state = result.x0.copy()
        self._calibrate()

    @classmethod
    def tune(cls, robot: Robot, cycle, repeats: int = 3, **options) -> WalkNetwork:
        """Tune to ``cycle`` (a periodic plan's ``motion``: knots 0…T−1, the last = the
        first shifted by one stride), its joints repeated ``repeats`` times; ``options`` go
        to :func:`~gdimitate.oscillator.self_adjust` (its frequency: the cycle's)."""
        mo = cycle
        names, idx = cycle_joints(robot, mo.q)
        if not names:
            raise InvalidInputError("no joint moves in the cycle; nothing for a network")
        P = float(mo.t[-1] - mo.t[0])
        one = mo.q[:-1][:, idx]
        X = np.vstack([one] * repeats + [one[:1]])
        t = mo.t[0] + np.r_[np.concatenate([mo.t[:-1] - mo.t[0] + r * P
                                            for r in range(repeats)]), repeats * P]
        options.setdefault("frequency", 1.0 / P)
        res = self_adjust(t, X, joint_names=names, **options)
        return cls(res, idx, P, float(mo.t[0]))

    # ------------------------------------------------------------------ dynamics
    def step(self, dt: float, g: np.ndarray | None = None) -> None:
        """Advance the state by ``dt`` [s] (RK4) under the input ``g`` ``(n,)`` (held)."""
        p, W, c, x = self.params, self.W, self.coupled, self.state
        k1 = _rhs(x, g, p, W, c)
        k2 = _rhs(x + 0.5 * dt * k1, g, p, W, c)
        k3 = _rhs(x + 0.5 * dt * k2, g, p, W, c)
        k4 = _rhs(x + dt * k3, g, p, W, c)
        self.state = x + (dt / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)

    def input_at(self, fraction: float) -> np.ndarray:
        """The taught input ``(n,)`` at a cycle fraction (what the teacher gave the network
        there; the feedback drives the network with it at the ground's phase)."""
        return self.result.teaching_input(np.array([self.t0 + (fraction % 1.0) * self.period]))[0]

    def joints(self, state: np.ndarray | None = None) -> np.ndarray:
        """The read-out joint angles ``(n,)`` [rad] of a state (default: the current)."""
        s = self.state if state is None else state
        return self.result.read_out(s[:, None, :])[0]

    def fraction(self, state: np.ndarray | None = None) -> float:
        """The cycle fraction in [0, 1) of a state (default: the current; module docstring)."""
        s = self.state if state is None else state
        z = s.reshape(-1) - self._mean
        ang = (np.arctan2(z @ self._axes[1], z @ self._axes[0]) - self._ang0) % (2 * np.pi)
        return float((np.interp(ang, self._cal_ang, self._cal_frac) + self.offset) % 1.0)

    # ------------------------------------------------------------------ calibration
    def _free_run(self, cycles: float, dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
        bank = self.result.bank()
        P = 1.0 / self.result.frequency
        t = np.arange(0.0, cycles * P, dt)
        tr = bank.simulate(t, None, self.result.x0)
        return t, tr.states()  # (4, N, n)

    def _calibrate(self) -> None:
        t, S = self._free_run(6.0)
        Pn = 1.0 / self.result.frequency
        keep = t >= 2 * Pn
        t, S = t[keep], S[:, keep]
        Z = np.moveaxis(S, 1, 0).reshape(t.size, -1)
        self._mean = Z.mean(axis=0)
        _, _, Vt = np.linalg.svd(Z - self._mean, full_matrices=False)
        self._axes = Vt[:2].copy()
        ang = np.unwrap(np.arctan2((Z - self._mean) @ self._axes[1],
                                   (Z - self._mean) @ self._axes[0]))
        if ang[-1] < ang[0]:
            self._axes[1] *= -1
            ang = -ang
        slope = np.polyfit(t, ang, 1)[0]
        self.frequency = float(slope / (2 * np.pi))
        Pf = 1.0 / self.frequency
        w = t < t[0] + Pf
        self._ang0 = float(ang[0] % (2 * np.pi))
        a = np.maximum.accumulate(ang[w] - ang[0])
        self._cal_ang = np.r_[a, 2 * np.pi]
        self._cal_frac = np.r_[(t[w] - t[0]) / Pf, 1.0]
        self.offset = 0.0
        q_ro = self.result.read_out(S[:, w])
        frac = np.array([self.fraction(S[:, i]) for i in np.flatnonzero(w)])
        shifts = np.linspace(0.0, 1.0, 400, endpoint=False)
        teacher = self.result.teacher
        ptp = np.maximum(np.ptp(q_ro, axis=0), 1e-9)
        cost = [np.mean(((q_ro - teacher(self.t0 + ((frac + d) % 1.0) * self.period)) / ptp)**2)
                for d in shifts]
        self.offset = float(shifts[int(np.argmin(cost))])
        self.alignment_nrmse = float(np.sqrt(np.min(cost)))
        self.state = S[:, int(np.flatnonzero(w)[0])].copy()

    def start_at(self, fraction: float = 0.0) -> None:
        """Put the network on its limit cycle at a cycle fraction (from the calibration
        run)."""
        t, S = self._free_run(3.0)
        keep = np.flatnonzero(t >= 1.0 / self.result.frequency)
        fr = np.array([self.fraction(S[:, i]) for i in keep])
        d = np.abs((fr - fraction + 0.5) % 1.0 - 0.5)
        self.state = S[:, keep[int(np.argmin(d))]].copy()
