"""A walk's footsteps (docs/design.md §13): where each stance phase puts its foot, the steps
between them, and the gait of an imitator against its demonstrator scaled to its legs.

- A **footprint** is one stance phase of one foot (a run of its contact flags): its knots and
  its horizontal place, the mean of the sole frame's horizontal position over the phase (a
  human sole rolls heel to toe and slides under its contact flags; a robot's flat sole stays
  put, so for it the mean is where it stands).
- A **step** begins where a foot lands: from that footprint's first knot to the next landing
  of the other foot (its ``duration``); ``length`` and ``width`` are the landing footprint's
  place relative to the other foot's footprint at that moment, along and across the walk's
  heading there (the demonstrator's base facing, :func:`gdimitate.model.heading.facing_yaw`, at the
  landing); ``stride`` the landing footprint's place relative to the same foot's previous one,
  along the heading.
- **Scaling** (:data:`SCALINGS`): lengths × r, the legs' ratio (imitator over demonstrator,
  hip to ankle), at the demonstrator's cadence (``"geometric"``, the paper's: Eq. (1) scales
  the legs' vertical projection by r) or with time also × √r (``"froude"``: equal v²/(gL)).
- **Travel** over a clip: the base's horizontal displacement from the first knot to the last;
  the travel ratio is the imitator's over the demonstrator's × r (1.0 for the same steps each
  r times as long, at either scaling).

:func:`compare_gait` pairs the imitator's steps with the demonstrator's in order of landing;
the demonstrator's numbers it reports are already scaled (lengths × r, durations × the time
scale).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .heading import facing_yaw
from .kinematics import frame_paths
from .motion import Motion
from .robot import SIDES, Robot

__all__ = ["SCALINGS", "KEPT", "sole_frames", "Footprint", "Step", "GaitComparison",
           "leg_ratio", "time_scale", "stance_phases", "footprints", "steps", "travel",
           "compare_gait", "walking_direction", "shift_by_stride"]

SCALINGS = ("geometric", "froude")
KEPT = (0.8, 1.25)
"""The travel ratios at which a gait counts as kept (docs/design.md §13)."""


def leg_ratio(demonstrator: Robot, imitator: Robot) -> float:
    """r = the imitator's mean leg length over the demonstrator's (hip to ankle) [-]."""
    return float(np.mean([imitator.legs[s].length for s in SIDES])
                 / np.mean([demonstrator.legs[s].length for s in SIDES]))


def time_scale(scaling: str, r: float) -> float:
    """The factor on the demonstration's durations under ``scaling``: 1 (geometric) or √r
    (Froude)."""
    return float(np.sqrt(r)) if scaling == "froude" else 1.0


@dataclass(frozen=True)
class Footprint:
    """One stance phase of foot ``side``: knots ``start`` … ``stop − 1``, horizontal place
    ``xy`` ``(2,)`` [m] (module docstring)."""

    side: str
    start: int
    stop: int
    xy: np.ndarray


def stance_phases(contact: np.ndarray) -> list[tuple[int, int]]:
    """``[(start, stop), …]``: the runs of True in ``contact`` ``(T,)`` (stop exclusive)."""
    c = np.r_[False, np.asarray(contact, bool), False].astype(int)
    d = np.diff(c)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def sole_frames(robot: Robot) -> dict[str, str]:
    """``{side: frame}``: the sole frame of each foot (its contact's, else the leg's sole)."""
    c = robot.contacts or {}
    return {s: c[s].frame if s in c else robot.legs[s].sole for s in SIDES}


def footprints(robot: Robot, motion: Motion, contact: Mapping[str, np.ndarray] | None = None
               ) -> list[Footprint]:
    """Every footprint of ``motion`` (``contact``: ``{side: (T,) bool}``, default
    ``motion.contact``), in order of landing (ties: left first)."""
    flags: Mapping[str, np.ndarray] = motion.contact if contact is None else contact
    frames = sole_frames(robot)
    paths = frame_paths(robot, motion.q, list(frames.values()))
    out = [Footprint(s, a, b, paths[frames[s]][a:b, :2].mean(axis=0))
           for s in SIDES for a, b in stance_phases(flags[s])]
    return sorted(out, key=lambda f: (f.start, SIDES.index(f.side)))


@dataclass(frozen=True)
class Step:
    """One step (module docstring): ``side`` the landing foot, ``knot`` its first stance
    knot, ``t`` [s] its time; ``length``, ``width``, ``stride`` [m] (``stride`` NaN for a
    foot's first footprint); ``duration`` [s] (NaN for the clip's last landing)."""

    side: str
    knot: int
    t: float
    length: float
    width: float
    stride: float
    duration: float


def _heading_at(robot: Robot, motion: Motion, k: int) -> np.ndarray:
    if robot.base != "free":
        return np.array([1.0, 0.0])
    yaw = float(facing_yaw(motion.q[k:k + 1], robot.base_rotation)[0])
    return np.array([np.cos(yaw), np.sin(yaw)])


def steps(robot: Robot, motion: Motion, contact: dict | None = None) -> list[Step]:
    """The steps of ``motion`` (module docstring): a landing with the other foot's footprint
    current (down, or the last one before) is a step; the clip's first footprints, which
    nothing lands before, are not."""
    fps = footprints(robot, motion, contact)
    out: list[Step] = []
    landings = [f for f in fps if f.start > 0 or not any(
        g.start == 0 and g.side != f.side for g in fps)]
    for i, f in enumerate(landings):
        other = [g for g in fps if g.side != f.side and g.start <= f.start]
        if not other:
            continue
        o = other[-1]
        prev = [g for g in fps if g.side == f.side and g.start < f.start]
        e = _heading_at(robot, motion, f.start)
        n = np.array([-e[1], e[0]])
        d = f.xy - o.xy
        nxt = [g for g in landings[i + 1:] if g.side != f.side]
        t = motion.t
        out.append(Step(f.side, f.start, float(t[f.start]), float(d @ e), float(abs(d @ n)),
                        float((f.xy - prev[-1].xy) @ e) if prev else float("nan"),
                        float(t[nxt[0].start] - t[f.start]) if nxt else float("nan")))
    return out


def travel(robot: Robot, motion: Motion) -> float:
    """The base's horizontal displacement from the first knot to the last [m] (planar
    models: along x)."""
    q = motion.q
    if robot.base == "free":
        return float(np.hypot(*(q[-1, :2] - q[0, :2])))
    if robot.base == "planar":
        i = robot.idx_q("base_x")
        return float(abs(q[-1, i] - q[0, i]))
    return 0.0


@dataclass(frozen=True)
class GaitComparison:
    """The imitator's gait against the demonstrator's scaled to its legs (module docstring).

    ``scaling`` (:data:`SCALINGS`), ``ratio`` r, ``time_scale`` (1 or √r); ``demo`` and
    ``imitator``: their steps, paired in order (``demo``'s lengths × r, durations × the time
    scale); ``travel_demo`` (× r) and ``travel`` [m], ``duration_demo`` (× the time scale) and
    ``duration`` [s] of the clip; ``travel_ratio``, ``speed_ratio`` (imitator over scaled
    demonstrator), ``stride_ratio`` (median over paired steps of stride over scaled stride;
    NaN with no stride) and ``step_ratio`` (likewise for step lengths)."""

    scaling: str
    ratio: float
    time_scale: float
    demo: tuple[Step, ...]
    imitator: tuple[Step, ...]
    travel_demo: float
    travel: float
    duration_demo: float
    duration: float

    @property
    def travel_ratio(self) -> float:
        return self.travel / self.travel_demo if self.travel_demo > 0 else float("nan")

    @property
    def speed_ratio(self) -> float:
        vd = self.travel_demo / self.duration_demo if self.duration_demo > 0 else 0.0
        v = self.travel / self.duration if self.duration > 0 else 0.0
        return v / vd if vd > 0 else float("nan")

    def _median_ratio(self, field: str) -> float:
        r = [getattr(b, field) / getattr(a, field) for a, b in zip(self.demo, self.imitator)
             if np.isfinite(getattr(a, field)) and np.isfinite(getattr(b, field))
             and abs(getattr(a, field)) > 1e-6]
        return float(np.median(r)) if r else float("nan")

    @property
    def stride_ratio(self) -> float:
        return self._median_ratio("stride")

    @property
    def step_ratio(self) -> float:
        return self._median_ratio("length")

    @property
    def kept(self) -> bool:
        """Whether the travel ratio is within :data:`KEPT` (docs/design.md §13's target)."""
        return bool(KEPT[0] <= self.travel_ratio <= KEPT[1])

    def lines(self) -> list[str]:
        """The comparison as console lines (no leading indentation)."""
        v = self.travel / self.duration if self.duration > 0 else float("nan")
        vd = self.travel_demo / self.duration_demo if self.duration_demo > 0 else float("nan")
        out = [f"gait ({self.scaling}, legs × {self.ratio:.3f}): travel {self.travel:.3f} m "
               f"for {self.travel_demo:.3f} m scaled, ratio {self.travel_ratio:.2f}; speed "
               f"{v:.2f} for {vd:.2f} m/s, ratio {self.speed_ratio:.2f}",
               f"steps {len(self.imitator)}: stride ratio {self.stride_ratio:.2f}, step ratio "
               f"{self.step_ratio:.2f} (median over steps)"]
        if not self.kept:
            out.append(f"gait NOT kept: travel ratio {self.travel_ratio:.2f} outside "
                       f"{KEPT[0]}–{KEPT[1]}")
        return out

    def to_dict(self) -> dict:
        """A JSON-ready summary: the ratios, the clip's travel and duration, every step."""
        def rows(ss):
            return [{"side": s.side, "t_s": s.t, "length_m": s.length, "width_m": s.width,
                     "stride_m": s.stride, "duration_s": s.duration} for s in ss]

        return {"scaling": self.scaling, "leg_ratio": self.ratio, "kept": self.kept,
                "time_scale": self.time_scale, "travel_ratio": self.travel_ratio,
                "speed_ratio": self.speed_ratio, "stride_ratio": self.stride_ratio,
                "step_ratio": self.step_ratio, "travel_m": self.travel,
                "travel_demo_scaled_m": self.travel_demo, "duration_s": self.duration,
                "duration_demo_scaled_s": self.duration_demo,
                "steps": rows(self.imitator), "steps_demo_scaled": rows(self.demo)}


def _scaled(s: Step, r: float, ts: float) -> Step:
    return Step(s.side, s.knot, s.t * ts, s.length * r, s.width * r, s.stride * r,
                s.duration * ts)


def compare_gait(demonstrator: Robot, demo: Motion, imitator: Robot, motion: Motion,
                 scaling: str = "geometric", demo_contact: dict | None = None,
                 contact: dict | None = None) -> GaitComparison:
    """The imitator's ``motion`` against the demonstration ``demo`` (on the demonstrator's
    own clock: the time scale is applied here) under ``scaling``; ``demo_contact`` /
    ``contact``: the stance flags (default: the motions' own)."""
    r = leg_ratio(demonstrator, imitator)
    ts = time_scale(scaling, r)
    sd = [_scaled(s, r, ts) for s in steps(demonstrator, demo, demo_contact)]
    si = steps(imitator, motion, contact)
    n = min(len(sd), len(si))
    return GaitComparison(scaling, r, ts, tuple(sd[:n]), tuple(si[:n]),
                          travel(demonstrator, demo) * r, travel(imitator, motion),
                          float(demo.t[-1] - demo.t[0]) * ts,
                          float(motion.t[-1] - motion.t[0]))



def walking_direction(robot, q: np.ndarray) -> np.ndarray:
    """``(2,)`` unit horizontal direction of ``robot``'s base displacement from ``q[0]`` to
    ``q[-1]`` (free flyer: x, y; planar: +x); (1, 0) when the base does not move."""
    if robot.base != "free":
        return np.array([1.0, 0.0])
    d = np.asarray(q[-1, :2] - q[0, :2], float)
    n = float(np.linalg.norm(d))
    return d / n if n > 1e-9 else np.array([1.0, 0.0])


def shift_by_stride(robot: Robot, q_first: np.ndarray, q_last: np.ndarray,
                    direction: np.ndarray) -> np.ndarray:
    """``q_first`` with its base advanced along ``direction`` ``(2,)`` by the stride of
    ``q_last`` (the component of ``q_last − q_first``'s horizontal base displacement along
    it; planar: ``base_x`` of ``q_last``)."""
    out = np.array(q_first, float)
    if robot.base == "free":
        d = np.asarray(direction, float)
        out[:2] = q_first[:2] + float((q_last[:2] - q_first[:2]) @ d) * d
    else:
        ix = robot.idx_q("base_x")
        out[ix] = q_last[ix]
    return out
