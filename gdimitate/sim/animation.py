"""Plan and simulation side by side in meshcat, through :class:`gdimitate.viz.Viewer`.

The plan (sampled on the simulation grid) is drawn at y = −gap/2, the simulated robot at
y = +gap/2, each with its feet's push direction (3-D, hidden when the foot is
unloaded) and its centre of mass; one animation plays both (the viewer's own recorder).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..model.robot import SIDES, Robot
from .simulate import SimResult

if TYPE_CHECKING:
    from ..viz import Viewer

__all__ = ["show_simulation"]


def _directions(forces: dict[str, np.ndarray], min_force: float) -> dict[str, np.ndarray]:
    """Push directions ``{side: (N, 3)}`` (the reverse of the force on the foot), NaN where
    the foot carries less than ``min_force`` [N]."""
    out = {}
    for s in SIDES:
        p = -np.asarray(forces[s], dtype=float)
        p[forces[s][:, 2] < min_force] = np.nan
        out[s] = p
    return out


def show_simulation(robot: Robot, result: SimResult, *, gap: float = 1.0, fps: float = 30.0,
                    html: str | os.PathLike[str] | None = None, viewer: Viewer | None = None,
                    port: int | None = None, open_browser: bool = False,
                    camera: Sequence[float] | None = None) -> Viewer:
    """Animate ``result``'s plan and simulation side by side; return the
    :class:`~gdimitate.viz.Viewer` (close it when done, unless you passed ``viewer``).

    ``gap`` [m]: distance between the two robots; ``fps``: animation frame rate; ``html``:
    also write the self-contained page there; ``viewer``: draw into this viewer (cleared
    first); ``port``/``open_browser``: for a new viewer; ``camera``: position (3,) [m].
    """
    from ..viz.compare import animated_scene

    min_force = 0.01 * robot.mass * 9.81

    def draw(v: Viewer) -> None:
        v.show(robot, result.plan_motion(), name="plan", offset=(0.0, -gap / 2, 0.0),
               force_directions=_directions(result.plan_forces, min_force),
               color=(0.55, 0.75, 1.0), opacity=0.6,
               label=f"{robot.name}: plan (the adaptor's motion, translucent)")
        v.show(robot, result.motion(), name="simulation", offset=(0.0, gap / 2, 0.0),
               force_directions=_directions(result.contact_forces, min_force),
               label=f"{robot.name}: MuJoCo simulation of the plan")

    return animated_scene(draw, track="simulation", fps=fps, html=html, viewer=viewer,
                          port=port, open_browser=open_browser, camera=camera)
