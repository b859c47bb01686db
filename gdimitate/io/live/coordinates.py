"""The channel layout of an OpenSim model's coordinates: one sample is one row of a ``.mot``
with ``inDegrees=yes`` — each coordinate by its name (``pelvis_tilt``, ``pelvis_tx``,
``hip_flexion_r``, ``knee_angle_r`` …; rotational ones in degrees, translational ones in
metres) — plus ``contact.left`` and ``contact.right`` (:data:`~.layout.CONTACT_LABELS`).
A frame gives the configuration :func:`gdimitate.opensim.read_coordinates` gives that row
(the ground→pelvis coordinates as the free-flyer, a walker knee's spline-driven axes following
their coordinate)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...model.osim.joints import follow_coordinates, pelvis_to_freeflyer, root_joint
from ...model.robot import Robot
from ..opensim.coordinates import robot_coordinates
from .layout import CONTACT_LABELS, Layout

__all__ = ["OpenSimLayout"]


class OpenSimLayout(Layout):
    """The coordinates of the OpenSim model ``osim`` as channels (module docstring):
    ``labels`` are the model's coordinates that drive a joint (the root joint's last), then
    the stance; ``frame_time`` [s]: ``frame_time`` (the default frame period where a stream
    does not give its rate)."""

    def __init__(self, osim: str | Path, frame_time: float = 1 / 60):
        self.path = Path(osim)
        self.robot = Robot.from_osim(self.path)
        self.frame_time = float(frame_time)
        conv = self.robot.osim
        self._plans = conv.plans
        self._model = conv.model
        followed = {s.coordinate for pl in self._plans for s in pl.steps if s.follows is not None}
        kinds = {j: k for j, k in robot_coordinates(self.robot).items() if j not in followed}
        self._joints = [(j, k, self.robot.idx_q(j)) for j, k in kinds.items()]
        root = root_joint(self._model).coordinates
        self._root = [(c.name, c.motion_type == "rotational") for c in root]
        self._defaults = np.array([np.rad2deg(c.default) if c.motion_type == "rotational"
                                   else c.default for c in root])
        self.labels = (*(j for j, _, _ in self._joints), *(c for c, _ in self._root),
                       *CONTACT_LABELS.values())

    def decode(self, sample: np.ndarray, t: float = 0.0) -> tuple[np.ndarray, dict[str, bool]]:
        """One sample ``(len(labels),)`` in this layout's order at time ``t`` [s] → ``(q (nq,),
        {side: stance})`` (the stance's channels both NaN: detected, :meth:`Layout.decode`):
        degrees → radians for the rotational coordinates; an unbounded joint's angle as
        (cos, sin); the root's coordinates → the free-flyer
        (:func:`~gdimitate.opensim.joints.pelvis_to_freeflyer`)."""
        x, contact = self._checked(sample)
        q = np.array(self.robot.neutral, float)
        for n, (_, kind, i) in enumerate(self._joints):
            v = np.deg2rad(x[n]) if kind != "translational" else x[n]
            if kind == "unbounded":
                q[i], q[i + 1] = np.cos(v), np.sin(v)
            else:
                q[i] = v
        if self._plans:
            follow_coordinates(self._plans, q[None], self.robot.idx_q)
        k = len(self._joints)
        values = {c: np.array([np.deg2rad(x[k + m]) if rot else x[k + m]])
                  for m, (c, rot) in enumerate(self._root)}
        q[:7] = pelvis_to_freeflyer(values, self._model)[0]
        return q, self._stance(t, q, contact)

    def warm_up_samples(self, k: int) -> np.ndarray:
        """``k`` frames of the model at its default coordinates (the joints' zero, the root's
        defaults: the model's own standing pose), both feet in stance."""
        x = np.zeros((k, len(self.labels)))
        n = len(self._joints)
        x[:, n:n + len(self._root)] = self._defaults
        x[:, -2:] = 1.0
        return x
