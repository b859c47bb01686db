"""Demonstrator and imitator in one scene: side by side, or the demonstrator as a ghost."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import ViewerError
from .animate import PushDirections
from .scene import Style
from .viewer import Viewer, leg_length

__all__ = ["compare", "animated_scene"]

_GHOST_COLOR = (0.55, 0.75, 1.0)


def compare(demonstrator: object, demo_motion: object, imitator: object,
            imitator_motion: object, *, layout: str = "side", gap: float = 1.2,
            ghost_scale: float | None = None,
            demo_force: PushDirections | None = None,
            imitator_force: PushDirections | None = None,
            fps: float = 30.0, html: str | os.PathLike[str] | None = None,
            viewer: Viewer | None = None, port: int | None = None, open_browser: bool = False,
            camera: Sequence[float] | None = None, style: Style | None = None) -> Viewer:
    """Show a demonstrator and an imitator over their motions, animated, in one scene.

    Args:
        demonstrator, demo_motion: the demonstrating robot and its ``Motion``.
        imitator, imitator_motion: the imitating robot and its ``Motion`` or
            ``AdaptedMotion``.
        layout: ``"side"`` — the demonstrator at y = -gap/2, the imitator at y = +gap/2;
            ``"ghost"`` — the demonstrator as a translucent copy over the imitator, scaled
            by ``ghost_scale``.
        gap: distance [m] between the two in the ``"side"`` layout.
        ghost_scale: uniform scale of the ghost; default imitator leg length / demonstrator
            leg length (hip to sole, neutral pose), 1 if unknown.
        demo_force, imitator_force: leg name → push directions of each (``ForceDirection``,
            ``(T, 3)`` vectors or ``(T,)`` sagittal angles; see
            :meth:`Viewer.show`).
        fps: animation frames per second.
        html: if given, also write the self-contained page there.
        viewer: draw into this viewer (cleared first) instead of starting a new one.
        port, open_browser: for the new viewer (see :meth:`Viewer.start`).
        camera: camera position (3,) [m], looking at the middle of the imitator's path;
            default: framed by :meth:`Viewer.animate`.
        style: decoration sizes and colours.

    Returns:
        The viewer (call :meth:`Viewer.close` when done, unless you passed ``viewer``).
    """
    if layout not in ("side", "ghost"):
        raise ViewerError(f"unknown layout {layout!r}; valid layouts: 'side', 'ghost'")

    def draw(v: Viewer) -> None:
        if layout == "side":
            v.show(demonstrator, demo_motion, name="demonstrator", offset=(0, -gap / 2, 0),
                   force_directions=demo_force)
            v.show(imitator, imitator_motion, name="imitator", offset=(0, gap / 2, 0),
                   force_directions=imitator_force)
            return
        scale = ghost_scale
        if scale is None:
            ratio = leg_length(imitator) / leg_length(demonstrator)
            scale = ratio if np.isfinite(ratio) and ratio > 0 else 1.0
        v.show(imitator, imitator_motion, name="imitator", force_directions=imitator_force)
        v.show(demonstrator, demo_motion, name="demonstrator", scale=scale,
               color=_GHOST_COLOR, opacity=v.style.ghost_opacity,
               force_directions=demo_force, foot_paths=False)

    return animated_scene(draw, track="imitator", fps=fps, html=html, viewer=viewer,
                          port=port, open_browser=open_browser, camera=camera, style=style)


def animated_scene(draw: Callable[[Viewer], None], *, track: str, fps: float = 30.0,
                   html: str | os.PathLike[str] | None = None, viewer: Viewer | None = None,
                   port: int | None = None, open_browser: bool = False,
                   camera: Sequence[float] | None = None,
                   style: Style | None = None) -> Viewer:
    """A scene shown and animated, the one sequence of :func:`compare` and
    :func:`gdimitate.sim.animation.show_simulation`: ``viewer`` cleared (or a new viewer
    started with ``port``, ``open_browser``, ``style``), ``draw(viewer)`` adds the robots,
    then the animation at ``fps``, the camera at ``camera`` (3,) [m] looking along the path of
    track ``track``, and the self-contained page written to ``html``. A viewer started here
    is closed if any of it fails; returns the viewer."""
    own = viewer is None
    v = Viewer.start(port, open_browser, style=style) if viewer is None else viewer
    try:
        if not own:
            v.clear()
        draw(v)
        v.animate(fps=fps)
        if camera is not None:
            v.look_at_track(track, camera)
        if html is not None:
            v.save_html(html)
    except BaseException:
        if own:
            v.close()
        raise
    return v
