"""What a walk measured (docs/design.md §14) and the files it writes.

Per step (a step: from one heel strike in the cycle to the next, alternating feet, in the
network's phase): the stride frequency the network ran at (cycles/s), and the RMS angle
between the simulated stance foot's force and the demonstrator's measured one at the same
cycle fraction, over the step's single-support samples where the plan has one stance foot,
the simulation loads it (> 1 % m·g) and the demonstrator's foot is in measured contact
(planar robots: the angle in the sagittal plane; 3-D robots: the 3-D angle). The body's
rhythm is the simulated heel strikes (the onsets :mod:`.loop` counts): after a push, the
steps to return to it count the strikes until two successive intervals are within
:data:`RHYTHM_TOL` of the period of the same walk's unpushed ones.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..assess.result import AdaptedMotion
from ..jsonable import jsonable
from ..model.contact import ContactForces
from ..model.motion import Motion
from ..model.robot import SIDES, Robot
from ..safety import atomic_write
from ..sim.periodic import PeriodicReference
from .loop import Trace, step_bounds
from .network import WalkNetwork

__all__ = ["WalkResult", "RHYTHM_TOL"]

RHYTHM_TOL = 0.05


@dataclass
class WalkResult:
    """A walk: the ``robot``, the periodic ``cycle`` (an :class:`~gdimitate.adapt.
    AdaptedMotion`), the ``network`` (:class:`~.network.WalkNetwork`), the ``trace``
    (:class:`~.loop.Trace`), the asked ``steps``, ``feedback_gain`` and the demonstrator's
    measured ``forces`` (or None)."""

    robot: Robot
    cycle: AdaptedMotion
    network: WalkNetwork
    reference: PeriodicReference
    trace: Trace
    steps: int
    feedback_gain: float
    forces: ContactForces | None

    # ------------------------------------------------------------------ measures
    @property
    def bounds(self) -> np.ndarray:
        return step_bounds(self.reference, self.steps)

    def step_times(self) -> np.ndarray:
        """``(k,)`` [s]: when the network's phase reached each step boundary (reached ones)."""
        c, t = self.trace.cycles, self.trace.t
        return np.array([t[np.argmax(c >= b)] for b in self.bounds if c.size and c[-1] >= b])

    @property
    def steps_completed(self) -> int:
        return max(len(self.step_times()) - 1, 0)

    @property
    def fell(self) -> bool:
        return self.trace.fell_at is not None

    def step_frequencies(self) -> list[float]:
        """Stride frequency [Hz] (cycles/s of the network's phase) over each completed step."""
        b, ts = self.bounds, self.step_times()
        return [float((b[i + 1] - b[i]) / (ts[i + 1] - ts[i])) for i in range(len(ts) - 1)]

    def simulated_stride(self) -> float:
        """[m] the simulated base's horizontal travel along the plan's stride direction per
        cycle of the network's phase, from the first to the last completed step boundary
        (NaN before one step is completed)."""
        ts, b = self.step_times(), self.bounds
        if len(ts) < 2:
            return float("nan")
        tr = self.trace
        i0, i1 = (int(np.argmax(tr.t >= t)) for t in (ts[0], ts[-1]))
        d = np.asarray(self.reference.stride[:2], float)
        if self.robot.base == "free":
            moved = tr.q[i1, :2] - tr.q[i0, :2]
            along = float(moved @ d / np.linalg.norm(d)) if np.linalg.norm(d) > 0 else 0.0
        else:
            ix = self.robot.idx_q("base_x")
            along = float(tr.q[i1, ix] - tr.q[i0, ix])
        return along / float(b[len(ts) - 1] - b[0])

    def scaled_stride(self) -> float:
        """[m] the demonstrator's stride scaled to the robot's legs (the cycle's gait
        comparison: its travel over the one-stride clip × the leg-length ratio; NaN for a
        cycle without one)."""
        g = self.cycle.gait
        return float(g.travel_demo) if g is not None else float("nan")

    def force_rmse_deg(self) -> list[float]:
        """Per completed step: the RMS force-direction angle [deg] (module docstring); NaN
        for a step without a comparable sample (or without measured forces)."""
        tr, pr = self.trace, self.reference
        if self.forces is None or tr.t.size == 0:
            return [float("nan")] * self.steps_completed
        frac = tr.cycles % 1.0
        td = pr.t0 + frac * pr.period
        mg = self.robot.mass * 9.81
        err = np.full(tr.t.size, np.nan)
        for s in SIDES:
            o = "right" if s == "left" else "left"
            ft = self.forces.feet[s]
            meas = np.column_stack([np.interp(td, self.forces.t, ft.force[:, i])
                                    for i in range(3)])
            on = ft.contact[np.clip(np.searchsorted(self.forces.t, td), 0, ft.contact.size - 1)]
            use = tr.stance[s] & ~tr.stance[o] & (tr.force[s][:, 2] > 0.01 * mg) & on
            err[use] = _angle_deg(tr.force[s][use], meas[use], self.robot.base == "planar")
        out = []
        b = self.bounds
        for i in range(self.steps_completed):
            w = (tr.cycles >= b[i]) & (tr.cycles < b[i + 1]) & np.isfinite(err)
            out.append(float(np.sqrt(np.mean(err[w] ** 2))) if w.any() else float("nan"))
        return out

    def steps_to_rhythm(self, baseline: WalkResult | None = None) -> int | None:
        """Steps (heel strikes) after the push until the body's rhythm is back: two
        successive strike intervals within :data:`RHYTHM_TOL` of the period of the
        ``baseline``'s (the same walk unpushed; the simulation is deterministic, so before
        the push they are equal). None without a push or a baseline, or when it never
        comes back."""
        tr = self.trace
        if tr.push_window is None or baseline is None:
            return None
        t0, P = tr.push_window[0], self.reference.period
        on = [t for t, _ in tr.onsets if t >= t0]
        ref = [t for t, _ in baseline.trace.onsets if t >= t0]
        good = 0
        for i in range(1, min(len(on), len(ref))):
            ok = abs((on[i] - on[i - 1]) - (ref[i] - ref[i - 1])) < RHYTHM_TOL * P
            good = good + 1 if ok else 0
            if good == 2:
                return i - 1
        return None

    def to_dict(self) -> dict[str, Any]:
        """``walk.json``'s content."""
        tr, net = self.trace, self.network
        f = self.step_frequencies()
        t_end = float(tr.t[-1]) if tr.t.size else 0.0
        f_cycle = 1.0 / self.reference.period
        return {
            "imitator": self.robot.name, "steps_requested": self.steps,
            "steps_completed": int(self.steps_completed), "fell": bool(self.fell),
            "fell_at_s": self.trace.fell_at,
            "per_step_force_direction_rmse_deg": self.force_rmse_deg(),
            "frequency_hz": float(tr.cycles[-1] / t_end) if t_end > 0 else None,
            "per_step_frequency_hz": f,
            "cycle_frequency_hz": f_cycle,
            "frequency_error_max": float(max(abs(x / f_cycle - 1) for x in f)) if f else None,
            "network_free_frequency_hz": float(net.frequency),
            "network_learned_frequency_hz": float(net.result.frequency),
            "network_joints": list(net.result.joint_names),
            "network_alignment_nrmse": float(net.alignment_nrmse),
            "feedback_gain": float(self.feedback_gain),
            "push_window_s": list(tr.push_window) if tr.push_window else None,
            "cycle_feasible": bool(self.cycle.feasible),
            "cycle_period_s": float(self.reference.period),
            "stride_m": [float(x) for x in self.reference.stride],
            "scaled_stride_m": self.scaled_stride(),
            "plan_stride_ratio": (float(self.cycle.gait.travel_ratio)
                                  if self.cycle.gait is not None else float("nan")),
            "simulated_stride_m": self.simulated_stride(),
            "simulated_stride_ratio": self.simulated_stride() / self.scaled_stride(),
            "cycle_gait": (self.cycle.gait.to_dict() if self.cycle.gait is not None
                           else None),
            # the cycle's audit: its verdict and the limits at their bound the console prints
            "cycle_audit": (self.cycle.audit.to_dict() if self.cycle.audit is not None
                            else None),
            "simulated_s": t_end,
        }

    def motion(self) -> Motion:
        """The simulated trajectory as a Motion (stance: measured force > 1 % m·g)."""
        tr, mo = self.trace, self.cycle.motion
        mg = self.robot.mass * 9.81
        return Motion(t=tr.t, joint_names=mo.joint_names, q=tr.q, v=tr.v,
                      contact={s: tr.force[s][:, 2] > 0.01 * mg for s in SIDES},
                      base_nq=mo.base_nq, joint_nq=mo.joint_nq)

    # ------------------------------------------------------------------ files
    def save(self, out: str | Path, html: bool = True) -> list[str]:
        """Write ``walk.json``, ``walk_trajectory.npz``, the plots and (``html``)
        ``walk.html`` into the folder ``out``; returns the file names."""
        from .plots import plot_walk

        out = Path(out)
        d = self.to_dict()
        with atomic_write(out / "walk.json") as tmp:
            tmp.write_text(json.dumps(jsonable(d), indent=2, default=str))
        tr = self.trace
        with atomic_write(out / "walk_trajectory.npz") as tmp:
            np.savez_compressed(tmp, t=tr.t, q=tr.q, v=tr.v, tau=tr.tau,
                                cycles=tr.cycles, ground_phase=tr.ground, y=tr.y,
                                network_joints=tr.joints,
                                **{f"force_{s}": tr.force[s] for s in SIDES},
                                **{f"plan_stance_{s}": tr.stance[s] for s in SIDES},
                                joint_names=np.array(self.cycle.motion.joint_names))
        files = ["walk.json", "walk_trajectory.npz"] + plot_walk(self, out)
        if html:
            files.append(self._html(out / "walk.html"))
        return files

    def _html(self, path: Path) -> str:
        from ..sim.animation import _directions
        from ..viz import Viewer

        m = self.motion()
        keep = np.arange(0, m.T, max(int(round(1 / 30 / max(m.dt, 1e-6))), 1))
        sub = m.replace(t=m.t[keep], q=m.q[keep], v=None,
                        contact={s: c[keep] for s, c in m.contact.items()})
        dirs = _directions({s: self.trace.force[s][keep] for s in SIDES},
                           0.01 * self.robot.mass * 9.81)
        v = Viewer.start(quiet=True)
        try:
            v.show(self.robot, sub, name="walk", force_directions=dirs)
            v.animate(fps=30)
            v.save_html(path)
        finally:
            v.close()
        return path.name


def _angle_deg(a: np.ndarray, b: np.ndarray, planar: bool) -> np.ndarray:
    if planar:
        d = np.arctan2(a[:, 0], a[:, 2]) - np.arctan2(b[:, 0], b[:, 2])
        return np.degrees((d + np.pi) % (2 * np.pi) - np.pi)
    c = np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
