"""The whole-body oscillator network that carries a periodic gait cycle (docs/design.md §7,
§14): one Matsuoka oscillator per actuated joint that moves in the cycle, one shared
frequency, tuned by :func:`gdimitate.oscillator.self_adjust` to the cycle's joint angles, then
run step by step (RK4) with an input ``g`` from outside (the ground's feedback).

Its phase: the network's state ``(x_e, x_f, v_e, v_f)`` of all oscillators, projected on the
plane of its two principal components over one period of a reference orbit, gives an angle;
a table over that period maps the angle to a cycle fraction, uniform in time on the orbit.
The phase is therefore a property of the network's state, not of a clock: an input that
speeds up or delays the oscillators moves it. Two reference orbits:

- open loop (feedback gain 0): the free limit cycle, reached by running the network until
  one period repeats (:data:`SETTLE_TOL`; a whole-body network contracts onto it slowly —
  HOAP-2's by ~0.8 per period, its period lengthening by 1 % on the way; a table made on the
  first periods, as an earlier version did, read a phase whose rate swung by ±14 % within a
  stride); fraction 0 is put where the network's joint read-out best matches the cycle's
  first knot (the heel strike);
- with feedback (gain > 0, :meth:`WalkNetwork.use_gain`): the orbit of the network locked to
  its own taught input at that gain driven by a clock at the cycle's rate; the fraction is
  the clock's. A driven network leads its drive and its orbit is deformed by it; read on
  this orbit, the network's phase equals the drive's once locked, so in a walk that keeps
  its rhythm the ground phase and the network's agree and the feedback corrects nothing.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ..model.robot import PLANAR_BASE, Robot
from ..oscillator import SelfAdjustResult, self_adjust
from ..oscillator.bank import _rhs

__all__ = ["WalkNetwork", "cycle_joints"]

#: Joints whose angle moves less than this over the cycle [rad] get no oscillator (the plan
#: holds them).
MIN_RANGE = 1e-4
#: Settling of the free network onto its limit cycle before the phase is calibrated: the
#: state one period on must repeat within SETTLE_TOL of the cycle's spread (norm of the
#: states' standard deviations), runs of SETTLE_CHUNK periods, at most SETTLE_MAX periods;
#: the last SETTLE_KEEP periods are kept as the limit cycle.
SETTLE_TOL = 5e-3
SETTLE_CHUNK = 20
SETTLE_KEEP = 2
SETTLE_MAX = 200
#: Periods of drive over which :meth:`WalkNetwork.use_gain` lets the network lock.
LOCK_CYCLES = 40


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
    def _free_run(self, cycles: float, dt: float = 1e-3,
                  x0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        bank = self.result.bank()
        P = 1.0 / self.result.frequency
        t = np.arange(0.0, cycles * P, dt)
        tr = bank.simulate(t, None, self.result.x0 if x0 is None else x0)
        return t, tr.states()  # (4, N, n)

    def _settle(self, dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
        """Free-run from the tuned initial state until the state one period on repeats
        (within :data:`SETTLE_TOL` of the cycle's spread, at most :data:`SETTLE_MAX` periods)
        and return the last :data:`SETTLE_KEEP` periods ``(t, S)``, ``S`` ``(4, N, n)``: the
        limit cycle itself. A whole-body network contracts slowly onto it (HOAP-2's: by
        ~0.8 per period; its period lengthens by 1 % on the way), so a table calibrated on the
        first periods reads a phase that is not uniform on the limit cycle."""
        P = 1.0 / self.result.frequency
        k = int(round(P / dt))
        x0, done = self.result.x0, 0
        while True:
            t, S = self._free_run(SETTLE_CHUNK + SETTLE_KEEP, dt, x0)
            done += SETTLE_CHUNK + SETTLE_KEEP
            Z = np.moveaxis(S, 1, 0).reshape(t.size, -1)
            spread = float(np.linalg.norm(Z[-k:].std(axis=0)))
            i = np.arange(t.size - 2 * k, t.size - k)
            rep = float(np.max(np.linalg.norm(Z[i + k] - Z[i], axis=1))) / spread
            if rep < SETTLE_TOL or done >= SETTLE_MAX:
                self.settle_repeat = rep
                keep = t >= t[-1] - SETTLE_KEEP * P
                return t[keep] - t[keep][0], S[:, keep]
            x0 = S[:, -1]

    def _calibrate(self) -> None:
        t, S = self._settle()
        Pf = self._table(t, S, None)
        self.frequency = 1.0 / Pf
        w = t < t[0] + Pf
        q_ro = self.result.read_out(S[:, w])
        frac = np.array([self.fraction(S[:, i]) for i in np.flatnonzero(w)])
        shifts = np.linspace(0.0, 1.0, 400, endpoint=False)
        teacher = self.result.teacher
        ptp = np.maximum(np.ptp(q_ro, axis=0), 1e-9)
        cost = [np.mean(((q_ro - teacher(self.t0 + ((frac + d) % 1.0) * self.period)) / ptp)**2)
                for d in shifts]
        self.offset = float(shifts[int(np.argmin(cost))])
        self.alignment_nrmse = float(np.sqrt(np.min(cost)))
        self._orbit_states = S
        self._orbit_fraction = np.array([self.fraction(S[:, i]) for i in range(t.size)])
        self._free = (self._mean, self._axes, self._ang0, self._cal_ang, self._cal_frac,
                      self.offset, S, self._orbit_fraction)
        self.gain = 0.0
        self.state = S[:, 0].copy()

    def _table(self, t: np.ndarray, S: np.ndarray, frac: np.ndarray | None) -> float:
        """The angle → fraction table of the orbit ``S`` ``(4, N, n)`` on ``t`` ``(N,)``
        (at least one period): fractions ``frac`` ``(N,)`` (unwrapped, increasing) or, with
        None, time over the period, 0 at ``t[0]`` (``offset`` 0). Returns the period [s]: the
        time the angle takes to turn once (interpolated between samples)."""
        Z = np.moveaxis(S, 1, 0).reshape(t.size, -1)
        self._mean = Z.mean(axis=0)
        _, _, Vt = np.linalg.svd(Z - self._mean, full_matrices=False)
        self._axes = Vt[:2].copy()
        ang = np.unwrap(np.arctan2((Z - self._mean) @ self._axes[1],
                                   (Z - self._mean) @ self._axes[0]))
        if ang[-1] < ang[0]:
            self._axes[1] *= -1
            ang = -ang
        Pf = float(np.interp(2 * np.pi, ang - ang[0], t) - t[0])
        w = t < t[0] + Pf
        self._ang0 = float(ang[0] % (2 * np.pi))
        self._cal_ang = np.r_[np.maximum.accumulate(ang[w] - ang[0]), 2 * np.pi]
        if frac is None:
            self._cal_frac, self.offset = np.r_[(t[w] - t[0]) / Pf, 1.0], 0.0
        else:
            self._cal_frac = np.r_[frac[w] - frac[0], 1.0]
            self.offset = float(frac[0] % 1.0)
        return Pf

    def use_gain(self, gain: float, cycles: int = LOCK_CYCLES, dt: float = 1e-3) -> None:
        """Read the phase on the reference orbit for feedback ``gain`` (module docstring):
        the free limit cycle for 0; for ``gain`` > 0 the orbit locked to the drive
        ``gain · input_at(clock)``, the clock at the cycle's rate, after ``cycles`` periods
        (its last period). Sets :attr:`lock_residual`: the largest gap [cycles] between the
        network's phase and the clock's over the last period (0 when locked)."""
        if gain == self.gain:
            return
        (self._mean, self._axes, self._ang0, self._cal_ang, self._cal_frac, self.offset,
         S_free, frac_free) = self._free
        self._orbit_states, self._orbit_fraction, self.gain = S_free, frac_free, 0.0
        self.lock_residual = 0.0
        if gain <= 0:
            return
        self.start_at(0.0)
        t = np.arange(0.0, (cycles + 1) * self.period, dt)
        g = gain * self.result.teaching_input(self.t0 + (t / self.period % 1.0) * self.period)
        S = self.result.bank().simulate(t, g, self.state).states()
        keep = t >= t[-1] - 1.5 * self.period
        t, S = t[keep], S[:, keep]
        clock = t / self.period
        self._table(t, S, clock)
        self._orbit_states, self._orbit_fraction = S, clock % 1.0
        self.gain = float(gain)
        last = t >= t[-1] - self.period
        prev = np.array([self.fraction(S[:, i]) for i in np.flatnonzero(last)])
        self.lock_residual = float(np.max(np.abs((prev - clock[last] + 0.5) % 1.0 - 0.5)))

    def start_at(self, fraction: float = 0.0) -> None:
        """Put the network on its reference orbit at a cycle fraction."""
        d = np.abs((self._orbit_fraction - fraction + 0.5) % 1.0 - 0.5)
        self.state = self._orbit_states[:, int(np.argmin(d))].copy()
