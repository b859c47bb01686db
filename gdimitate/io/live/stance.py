"""Stance detected frame by frame, for a stream without stance channels: the rule of
:func:`gdimitate.bvh.detect_contacts` (a foot is in stance while the lowest corner of its sole
is within ``height`` hip heights of the floor and moves horizontally slower than ``speed`` hip
heights per second, staying so while within ``hysteresis`` times both) applied causally —
each frame judged from it and the ones before, never later ones: the corners low-passed by a
one-pole filter at ``cutoff`` Hz instead of the recorded clip's zero-lag Butterworth, no gap
closing or short-stance removal (they need the frames after). The floor is z = 0 (a BVH
skeleton's floor as found from its file, an OpenSim model's ground)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...model.legs import hip_height
from ...model.robot import SIDES, Robot
from ..bvh.contacts import ContactRule

__all__ = ["CausalStance"]


class CausalStance:
    """``detector(t, q)`` → ``{side: stance}`` for the frame at time ``t`` [s] with the
    demonstrator's configuration ``q`` ``(nq,)`` (module docstring); ``rule``: the
    thresholds (:class:`~gdimitate.bvh.ContactRule`: height, speed, cutoff, hysteresis)."""

    def __init__(self, robot: Robot, rule: ContactRule | None = None):
        self.robot, self.rule = robot, rule or ContactRule()
        self.hip = hip_height(robot)
        contacts = robot.require_contacts()
        model = robot.model
        self._soles = {s: (model.getFrameId(contacts[s].frame), contacts[s].corners())
                       for s in SIDES}
        self._data = model.createData()
        self.reset()

    def reset(self) -> None:
        """Forget the previous frames."""
        self._t: float | None = None
        self._p: dict[str, np.ndarray] = {}
        self._on = {s: False for s in SIDES}

    def __call__(self, t: float, q: np.ndarray) -> dict[str, bool]:
        r = self.rule
        model, data = self.robot.model, self._data
        pin.forwardKinematics(model, data, np.asarray(q, float))
        dt = None if self._t is None else t - self._t
        for s in SIDES:
            fid, local = self._soles[s]
            M = pin.updateFramePlacement(model, data, fid)
            raw = local @ M.rotation.T + M.translation  # (4, 3) [m]: the sole's corners
            prev = self._p.get(s)
            if prev is None or dt is None or dt <= 0:
                p, speed = raw, 0.0
            else:
                a = 1.0 if r.cutoff <= 0 else dt / (dt + 1.0 / (2 * np.pi * r.cutoff))
                p = prev + a * (raw - prev)
                k = int(np.argmin(p[:, 2]))
                speed = float(np.linalg.norm(p[k, :2] - prev[k, :2]) / dt)
            self._p[s] = p
            x = max(float(p[:, 2].min()) / (r.height * self.hip), speed / (r.speed * self.hip))
            self._on[s] = x < (r.hysteresis if self._on[s] else 1.0)
        self._t = t
        return dict(self._on)
