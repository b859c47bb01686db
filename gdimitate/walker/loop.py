"""The closed loop of a walk (docs/design.md §14): every control period the oscillator network
advances under its input ``g``, its phase indexes the periodic plan
(:class:`~gdimitate.sim.periodic.PeriodicReference`), the tracking controller
(:class:`~gdimitate.sim.controller.TrackingController`) follows the plan at that phase in
MuJoCo, and the simulated feet feed back into ``g``.

Feedback (entrainment to the ground): a foot's contact onset in the simulation (its vertical
force rising above :data:`ONSET_FRACTION` of m·g after a swing — below :data:`OFF_FRACTION`
for at least :data:`MIN_SWING` of the period — and staying above :data:`OFF_FRACTION` for
:data:`MIN_LOAD` of the period: a scuff or a bounce of a few milliseconds is no heel strike)
says where in the cycle the body is. Only onsets within :data:`STRIKE_WINDOW` cycles of the
plan's heel strike of that foot count (a swing foot that scuffs the floor mid-swing is no heel
strike). The network is driven by ``g = gain · u(ground phase)``, ``u`` the input it was taught
with at that fraction (:meth:`~gdimitate.walker.network.WalkNetwork.input_at`): with ``gain`` 0
the network runs open loop (free), with ``gain`` > 0 it is pulled towards the body's rhythm.

The *ground phase* advances at the cycle's own rate and is corrected at each heel strike
towards where the body is: the body's phase at a strike of foot s is where the network's
phase stands at that foot's strikes (learnt: the first strike's, then moved by
:data:`STRIKE_LEARN` of each new strike's difference — the controller's touchdown lag is in
it, so it is no bias, and a first strike made while the walk still settles is forgotten);
the correction moves the ground phase by :data:`STRIKE_CORRECTION` of the gap between it and
that phase (half: a touchdown is a noisy reading of the body's phase — G1's vary by 10-25 ms
from strike to strike — and a full re-set passed that noise on, up to 1.2 % per step). The
network reads its phase on the orbit it has when locked to a drive at the cycle's rate
(:meth:`~gdimitate.walker.network.WalkNetwork.use_gain`), so in a walk that keeps its rhythm
network, ground and body agree, the gap is zero and the feedback does not move the network's
mean frequency. (An earlier version re-set the ground phase to its own value at each foot's
first strike and read the network on its free orbit: it left out the network's lead on its
drive and the transient of the first steps, every strike pushed the drive forward and the
loop ran 1.2–1.3 % fast.) After a push the body's strikes come early or late, the drive
follows them and the network with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from ..errors import SimulationError
from ..model.mjcf import build_model
from ..model.robot import SIDES, Robot
from ..sim.controller import ControllerGains, TrackingController
from ..sim.metrics import FallCriteria
from ..sim.periodic import PeriodicReference
from ..sim.simulate import measure_contacts, mujoco_warnings
from .network import WalkNetwork

__all__ = ["WalkPush", "Trace", "run_loop", "ONSET_FRACTION", "OFF_FRACTION",
           "STRIKE_CORRECTION", "STRIKE_LEARN", "WALK_GAINS"]

ONSET_FRACTION = 0.05
OFF_FRACTION = 0.01
MIN_SWING = 0.15
MIN_LOAD = 0.05
STRIKE_WINDOW = 0.2
STRIKE_CORRECTION = 0.5
STRIKE_LEARN = 0.5
#: The walk's controller: the defaults, with the centre of pressure kept 10 % of the sole's
#: half-sizes inside its edges (see :func:`run_loop`) and the centre of mass weighted 70
#: (the defaults' 30: G1's 45-knots/s cycle walked 20 steps with 3.1-5.8° per step; 50:
#: 1.8-6.3°; 70: 2.0-4.9°, Talos 1.8-4.8°; 100: G1 2.1-4.5°, Talos up to 5.1°).
WALK_GAINS = ControllerGains(cop_margin=0.1, w_com=70.0)


@dataclass(frozen=True)
class WalkPush:
    """A horizontal push ``force`` ``(3,)`` [N] (world) on the base for ``duration`` [s],
    starting at mid-stance of step ``step`` (0-based; the middle of its cycle interval)."""

    step: int
    force: tuple[float, float, float]
    duration: float = 0.1

    def __post_init__(self) -> None:
        f = np.asarray(self.force, float)
        if f.shape != (3,) or not np.all(np.isfinite(f)) or not self.duration > 0 \
                or self.step < 0:
            raise SimulationError(f"WalkPush needs step ≥ 0, 3 finite force components [N] and "
                                  f"duration > 0 s; got {self!r}")


Series = Any  # a list while recording, an ndarray after Trace.arrays()


@dataclass
class Trace:
    """One run, sampled every control period (``N`` samples): ``t`` [s], ``q``, ``v``,
    ``tau``; ``cycles`` the network's phase (cycles, unwrapped), ``ground`` the ground phase;
    ``force`` {side: (N, 3)} [N] MuJoCo's force of the ground on each foot (world);
    ``stance`` {side: (N,) bool} the plan's at that phase; ``height``/``plan_height`` [m],
    ``tilt`` [rad]; ``y`` ``(N, n)`` the oscillators' outputs; ``joints`` ``(N, n)`` their
    read-out [rad]; ``onsets`` [(t, side)] the contact onsets; ``fell_at`` [s] or None;
    ``push_window`` (start, end) [s] or None."""

    t: Series = field(default_factory=list)
    q: Series = field(default_factory=list)
    v: Series = field(default_factory=list)
    tau: Series = field(default_factory=list)
    cycles: Series = field(default_factory=list)
    ground: Series = field(default_factory=list)
    force: dict = field(default_factory=lambda: {s: [] for s in SIDES})
    stance: dict = field(default_factory=lambda: {s: [] for s in SIDES})
    height: Series = field(default_factory=list)
    plan_height: Series = field(default_factory=list)
    tilt: Series = field(default_factory=list)
    y: Series = field(default_factory=list)
    joints: Series = field(default_factory=list)
    onsets: list = field(default_factory=list)
    strike: dict = field(default_factory=dict)
    fell_at: float | None = None
    push_window: tuple[float, float] | None = None

    # typed as recorded (lists); :meth:`arrays` turns them into the arrays the docstring gives
    def arrays(self) -> None:
        """Turn the recorded lists into arrays (in place)."""
        for name, val in list(self.__dict__.items()):
            if isinstance(val, list) and name != "onsets":
                setattr(self, name, np.asarray(val))
            elif isinstance(val, dict) and name != "strike":
                setattr(self, name, {s: np.asarray(x) for s, x in val.items()})


def step_bounds(pref: PeriodicReference, steps: int) -> np.ndarray:
    """Cycle values ``(steps + 1,)`` where steps begin: the right strike (fraction 0) and the
    left one (its fraction), alternating."""
    fl = pref.strike_fractions()["left"]
    out: list[float] = []
    n = 0
    while len(out) < steps + 1:
        out += [n, n + fl]
        n += 1
    return np.array(out[:steps + 1], float)


def _tilt(data, sim, s) -> tuple[float, float, float]:
    b = sim.base_body
    R = data.xmat[b].reshape(3, 3)
    up = R @ (s.base_rot.T @ np.array([0.0, 0.0, 1.0]))
    return float(data.xpos[b][2]), float(s.base_height), float(np.arccos(np.clip(up[2], -1, 1)))


def run_loop(robot: Robot, pref: PeriodicReference, net: WalkNetwork, steps: int, gain: float,
             push: WalkPush | None = None, dt: float = 1e-3,
             gains: ControllerGains = WALK_GAINS,
             fall: FallCriteria = FallCriteria(),  # noqa: B008 (frozen)
             record_every: int = 1) -> Trace:
    """Walk ``steps`` steps (module docstring); stops early when the robot falls.

    ``gains``: the tracking controller's (default :data:`WALK_GAINS`: a CoP margin of 10 %).
    G1's periodic cycle puts the centre of pressure on the sole's lateral edge (3 cm from its
    centre) and, at one knot of left single support (fraction 0.838), moves it from the toe
    to the heel; tracked with the whole sole allowed, the simulated foot rolled over the edge
    and lost the floor for a few milliseconds at that fraction in every left stance (force
    spikes of 25-30°, the per-step push RMS vs measured 4.5-6.0° on left steps against
    2.4-4.2° on right ones, the lateral part 4°; low-passed over 25 ms 0.6°). With the margin:
    2.4-4.0° on every step; HOAP-2's stays within 2.8-5.0°."""
    sim = build_model(robot, contacts=pref.plan.contacts)
    ctl = TrackingController(sim, gains)
    data = sim.new_data()
    mo = pref.plan.motion
    sim.set_state(data, mo.q[0], mo.v[0])
    net.use_gain(gain)
    net.start_at(0.0)
    bounds = step_bounds(pref, steps)
    strike: dict[str, float | None] = {s: None for s in SIDES}
    planned = pref.strike_fractions()
    mg = robot.mass * 9.81
    P = pref.period
    c, ground = 0.0, 0.0
    loaded = {s: bool(mo.contact[s][0]) for s in SIDES}
    off_since = {s: None if loaded[s] else 0.0 for s in SIDES}
    pending: dict[str, tuple[float, float] | None] = {s: None for s in SIDES}
    push_c = None if push is None else 0.5 * (bounds[push.step] + bounds[push.step + 1]) \
        if push.step < steps else None
    push_t0 = None
    tr = Trace()
    t_max = (bounds[-1] * P) * 2.0 + 2.0
    k = 0
    with mujoco_warnings():
        while c < bounds[-1] and k * dt < t_max:
            t = k * dt
            q, v = sim.state(data)
            wr = measure_contacts(sim, data)
            for s in SIDES:  # heel strikes → ground phase
                ground = _strikes(s, wr[s][2] / mg, t, c, P, ground, off_since, pending,
                                  strike, planned, tr)
            g = gain * net.input_at(ground) if gain > 0 else None
            net.step(dt, g)
            ground += dt / P
            f = net.fraction()
            c = c + ((f - c + 0.5) % 1.0 - 0.5)
            s_ref = pref.at(max(c, 0.0))
            out = ctl.step(q, v, s_ref)
            data.ctrl[:] = out.tau
            h, ph, tilt = _tilt(data, sim, s_ref)
            if k % record_every == 0:
                _record(tr, t, q, v, out.tau, c, ground, wr, s_ref, h, ph, tilt, net)
            if h < fall.min_height_ratio * ph or tilt > fall.max_tilt:
                tr.fell_at = t
                break
            if push is not None and push_c is not None and push_t0 is None and c >= push_c:
                push_t0 = t
                tr.push_window = (t, t + push.duration)
            on = push is not None and push_t0 is not None and push_t0 <= t < push_t0 + push.duration
            data.xfrc_applied[sim.base_body, :3] = push.force if push is not None and on else 0.0
            mujoco.mj_step(sim.mj, data)
            k += 1
    tr.arrays()
    tr.strike = dict(strike)
    return tr


def _strikes(s, fz, t, c, P, ground, off_since, pending, strike, planned, tr) -> float:
    """Heel-strike detection of foot ``s`` (``fz``: vertical force / m·g) and the ground
    phase it corrects (module docstring); returns the ground phase. ``strike[s]``: the
    network's cycle fraction at the foot's strikes, learnt (the body's phase at a strike)."""
    if pending[s] is not None:
        t_on, off_before, c_on = pending[s]
        if fz < OFF_FRACTION:  # a scuff: the swing goes on
            pending[s], off_since[s] = None, off_before
        elif t - t_on >= MIN_LOAD * P:  # confirmed: a heel strike at t_on
            pending[s] = None
            g_on = ground - (t - t_on) / P  # the ground phase at the strike
            if strike[s] is None:
                strike[s] = c_on % 1.0  # where this foot lands, unperturbed
            gap = (strike[s] - g_on + 0.5) % 1.0 - 0.5
            ground += STRIKE_CORRECTION * gap
            strike[s] += STRIKE_LEARN * ((c_on - strike[s] + 0.5) % 1.0 - 0.5)
            tr.onsets.append((t_on, s))
        return ground
    swung = off_since[s] is not None and t - off_since[s] >= MIN_SWING * P
    near = abs((c - planned[s] + 0.5) % 1.0 - 0.5) < STRIKE_WINDOW
    if fz > ONSET_FRACTION:
        if swung and near:
            pending[s] = (t, off_since[s], c)
        off_since[s] = None
    elif fz < OFF_FRACTION and off_since[s] is None:
        off_since[s] = t
    return ground


def _record(tr, t, q, v, tau, c, ground, wr, s_ref, h, ph, tilt, net) -> None:
    tr.t.append(t)
    tr.q.append(q.copy())
    tr.v.append(v.copy())
    tr.tau.append(np.array(tau))
    tr.cycles.append(c)
    tr.ground.append(ground)
    for s in SIDES:
        tr.force[s].append(wr[s][:3].copy())
        tr.stance[s].append(bool(s_ref.stance[s]))
    tr.height.append(h)
    tr.plan_height.append(ph)
    tr.tilt.append(tilt)
    st = net.state
    tr.y.append(np.maximum(st[0], 0) - np.maximum(st[1], 0))
    tr.joints.append(net.joints())
