"""The :class:`Viewer`: robots and motions in a meshcat scene, played back, exported.

A viewer holds one meshcat scene and a list of *tracks* (one robot + one motion each). Every
:meth:`Viewer.show` draws its robot at the motion's first frame right away; :meth:`Viewer.animate`
records all tracks into one meshcat animation (play / pause / scrub in the page's "Animations"
panel). Three ways to look at it: the live server page (:attr:`Viewer.url`), a notebook cell
(:meth:`Viewer.display`) and a self-contained file (:meth:`Viewer.save_html`).

Scene layout (meshcat paths)::

    /meshcat/ground
    /meshcat/<track>                 offset and uniform scale of the track (static)
    /meshcat/<track>/robot/<geom>    rigid placement of each visual object (animated)
    /meshcat/<track>/com             centre-of-mass marker (animated)
    /meshcat/<track>/force/<leg>     force-direction arrow, hidden in swing (animated)
    /meshcat/<track>/paths/<leg>     foot path (static line)
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path

import meshcat
import numpy as np
from meshcat.animation import Animation
from numpy.typing import ArrayLike

from ..errors import ViewerError
from .animate import (
    Frames,
    PushDirections,
    arrow_pose,
    place_frame,
    record_frames,
    sample_frames,
)
from .camera import framing, ground_extent, place_camera
from .export import check_writable, notebook_display, with_legend, write_html
from .scene import (
    Style,
    draw_arrow,
    draw_geometry,
    draw_ground,
    draw_marker,
    draw_polyline,
)
from .server import MeshcatServer, connect
from .track import Track, leg_length, track_inputs

__all__ = ["Track", "Viewer", "leg_length"]


def _root_transform(offset: np.ndarray, scale: float) -> np.ndarray:
    T = np.diag([scale, scale, scale, 1.0])
    T[:3, 3] = offset
    return T


class Viewer:
    """A meshcat scene of robots and motions.

    Create with :meth:`start` (own server; prints the URL) or :meth:`connect` (existing
    server). Use as a context manager, or call :meth:`close`.

    Example::

        with Viewer.start() as v:
            v.show(demonstrator, demo_motion, offset=(0, -0.6, 0))
            v.show(imitator, adapted, offset=(0, 0.6, 0))
            v.animate(fps=30)
            v.save_html("walk.html")
    """

    def __init__(self, vis: meshcat.Visualizer, server: MeshcatServer | None = None,
                 style: Style | None = None):
        self.vis = vis
        self.server = server
        self.style = style or Style()
        self.tracks: dict[str, Track] = {}
        self._animated = False
        self._camera_set = False

    # -- lifecycle -----------------------------------------------------------------------
    @classmethod
    def start(cls, port: int | None = None, open_browser: bool = False, *,
              style: Style | None = None, quiet: bool = False, timeout_s: float = 30.0,
              host: str = "127.0.0.1") -> Viewer:
        """Start our own meshcat server (see :class:`MeshcatServer`) and connect to it.

        Args:
            port: web port 1–65535; ``None`` picks a free one. A taken port raises
                :class:`~gdimitate.viz.server.PortInUseError` (a :class:`ViewerError`).
            open_browser: open :attr:`url` in the system's browser (never blocks).
            style: sizes and colours of the decorations.
            quiet: do not print the URL.
            timeout_s: limit for the server start and for every request [s].
            host: address the page listens on (default: this machine only; ``"0.0.0.0"``
                serves the whole network — on purpose only).

        Ctrl-C or SIGTERM during the start stops the half-started server; the server also
        exits by itself when this process is gone.
        """
        server = MeshcatServer.start(port, timeout_s=timeout_s, host=host)
        try:
            viewer = cls(server.visualizer(timeout_s), server, style)
            viewer.clear()
        except BaseException:
            server.close()
            raise
        if not quiet:
            print(f"gdimitate viewer: open {viewer.url}")
        if open_browser:
            import webbrowser

            webbrowser.open(viewer.url, new=2)
        return viewer

    @classmethod
    def connect(cls, zmq_url: str, *, style: Style | None = None, timeout_s: float = 30.0
                ) -> Viewer:
        """Use a meshcat server that is already running at ``zmq_url`` (not stopped by
        :meth:`close`)."""
        return cls(connect(zmq_url, timeout_s=timeout_s), None, style)

    @property
    def url(self) -> str:
        """The live page of the server, e.g. ``http://127.0.0.1:7001/static/``."""
        return self.vis.url()

    def check_alive(self) -> None:
        """Raise :class:`ViewerError` (with the end of the server's log) if the server this
        viewer started has exited; nothing for a viewer on someone else's server."""
        if self.server is not None:
            self.server.check_alive()

    def close(self) -> None:
        """Close the connection and stop the server if this viewer started it."""
        try:
            self.vis.window.close()
        finally:
            if self.server is not None:
                self.server.close()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def clear(self) -> None:
        """Remove every track, the ground and the animation."""
        self.vis.delete()
        self.tracks.clear()
        self._animated = False
        self._camera_set = False

    # -- drawing -------------------------------------------------------------------------
    def show(self, robot: object, motion: object, *, name: str | None = None,
             offset: Sequence[float] = (0.0, 0.0, 0.0), scale: float = 1.0,
             color: Sequence[float] | None = None, opacity: float = 1.0,
             force_directions: PushDirections | None = None,
             com: np.ndarray | bool | None = True, foot_paths: bool = True,
             skeleton: bool = False, label: str | None = None) -> str:
        """Add a robot following a motion; draw it at the motion's first frame.

        Args:
            robot: a ``gdimitate.Robot`` (or any object with ``.name``, ``.model``,
                ``.visual_model`` and optionally ``.legs[leg].sole``).
            motion: a ``Motion`` (``.t (T,)`` [s], ``.q (T, nq)``, ``.joint_names``) or an
                ``AdaptedMotion`` (its ``.motion`` is shown).
            name: node name of the track (default: the robot's name, made unique).
            offset: ``(3,)`` [m] translation of the whole track (side-by-side layouts).
            scale: uniform scale of the whole track, motion included (a scaled ghost).
            color: RGB in [0, 1] for every part, or ``None`` for the URDF's colours.
            opacity: in [0, 1]; < 1 draws a translucent ghost.
            force_directions: leg name → the foot's push on the ground: a
                ``gdimitate.assess.metrics.ForceDirection`` (e.g. from ``force_direction``), ``(T,
                3)``
                vectors or ``(T,)`` sagittal angles [rad] from the downward vertical, NaN in
                swing; drawn in 3-D as arrows whose tip touches the sole, hidden when NaN.
            com: ``True`` marks Pinocchio's centre of mass; a ``(T, 3)`` array [m] marks that
                path instead; ``False``/``None`` draws no marker.
            foot_paths: draw each sole's path over the whole motion as a line.
            skeleton: draw joints and rods if the robot has no visual geometry (otherwise
                that raises :class:`ViewerError`).
            label: the track's line in the saved page's legend (default: ``"<robot>:
                <name>"``, e.g. ``"g1: plan"``).

        Returns:
            The track name.

        Raises:
            ViewerError: no visual geometry (and ``skeleton=False``), a motion that does not
                fit the robot (:class:`~gdimitate.viz.animate.MotionMismatchError`), a bad
                force-direction or CoM array, a server that does not answer.
        """
        inp = track_inputs(robot, motion, offset=offset, scale=scale,
                           force_directions=force_directions, com=com, skeleton=skeleton)
        track_name = self._unique(name or inp.name)
        # Frame 0 only (cheap): the pose drawn until the animation is set.
        frames = sample_frames(inp.model, inp.visual, inp.t[:1], inp.q[:1], 1.0, inp.soles,
                               {k: v[:1] for k, v in inp.force.items()},
                               inp.com[:1] if isinstance(inp.com, np.ndarray) else None)
        root = self.vis[track_name]
        root.set_transform(_root_transform(inp.offset, float(scale)))
        nodes = draw_geometry(root["robot"], inp.visual, color, opacity)
        default = inp.name if track_name == inp.name else f"{inp.name}: {track_name}"
        track = Track(track_name, inp.model, inp.visual, inp.t, inp.q, inp.soles, inp.force,
                      inp.com, inp.offset, float(scale), nodes, inp.size, bool(foot_paths),
                      frames, label or default,
                      None if color is None else (float(color[0]), float(color[1]),
                                                  float(color[2])))
        self.tracks[track_name] = track
        self._draw_decorations(track, opacity)
        self._place(track, frames, 0)
        self._animated = False
        return track_name

    def _unique(self, base: str) -> str:
        base = re.sub(r"[^A-Za-z0-9_.-]", "_", base) or "robot"
        name, k = base, 2
        while name in self.tracks:
            name, k = f"{base}_{k}", k + 1
        return name

    def _draw_decorations(self, track: Track, opacity: float) -> None:
        root, st, L = self.vis[track.name], self.style, track.size
        if track.com is not False:
            draw_marker(root["com"], st.com_radius * L, st.com_color, opacity)
        for leg in track.force_directions:
            draw_arrow(root["force"][leg], st.arrow_length * L, st.arrow_radius * L,
                       st.arrow_color(leg), opacity)

    def _arrow_pose(self, track: Track, leg: str, sole: np.ndarray, push: np.ndarray
                    ) -> np.ndarray:
        s = self.style.arrow_side_offset * track.size
        side = s if leg == "left" else -s if leg == "right" else 0.0
        d = push if np.all(np.isfinite(push)) else np.array([0.0, 0.0, -1.0])
        return arrow_pose(sole, d, self.style.arrow_length * track.size, side)

    def _place(self, track: Track, frames: Frames, k: int) -> None:
        root = self.vis[track.name]
        place_frame([root["robot"][n] for n in track.nodes], frames.placements[k])
        if track.com is not False:
            T = np.eye(4)
            T[:3, 3] = frames.com[k]
            root["com"].set_transform(T)
        for leg, push in frames.force.items():
            node = root["force"][leg]
            node.set_transform(self._arrow_pose(track, leg, frames.soles[leg][k], push[k]))
            node.set_property("visible", bool(np.all(np.isfinite(push[k]))))

    # -- animation -----------------------------------------------------------------------
    def animate(self, fps: float = 30.0, *, play: bool = True, loop: bool = True,
                ground: bool = True) -> None:
        """Record every track into one meshcat animation and send it.

        Args:
            fps: frames per second of motion time (each track is sampled at the motion
                sample nearest to each frame time; never more often than the motion).
            play: start playing when the page opens.
            loop: repeat forever (else play once and stop on the last frame).
            ground: draw a ground slab (top at z = 0) under all feet.
        """
        if not self.tracks:
            raise ViewerError("nothing to animate: call show(robot, motion) first")
        anim = Animation(default_framerate=float(fps))
        for track in self.tracks.values():
            frames = sample_frames(track.model, track.visual_model, track.t, track.q, fps,
                                   track.soles, track.force_directions or None,
                                   track.com if isinstance(track.com, np.ndarray) else None)
            track.frames = frames
            root = self.vis[track.name]
            # First frame as static transforms before the animation is set (docs/design.md §10).
            self._place(track, frames, 0)
            for g, n in enumerate(track.nodes):
                record_frames(anim, root["robot"][n], frames.t, frames.placements[:, g])
            if track.com is not False:
                poses = np.tile(np.eye(4), (len(frames.t), 1, 1))
                poses[:, :3, 3] = frames.com
                record_frames(anim, root["com"], frames.t, poses)
            for leg, push in frames.force.items():
                finite = np.all(np.isfinite(push), axis=1)
                poses = np.stack([self._arrow_pose(track, leg, s, d)
                                  for s, d in zip(frames.soles[leg], push, strict=True)])
                record_frames(anim, root["force"][leg], frames.t, poses, visible=finite)
            for leg, path in frames.sole_paths.items() if track.foot_paths else ():
                draw_polyline(root["paths"][leg], path, self.style.path_color(leg))
        if ground:
            self._draw_ground()
        if not self._camera_set:
            self._frame_camera()
        self.vis.set_animation(anim, play=play, repetitions=10**6 if loop else 1)
        self._animated = True

    def _draw_ground(self) -> None:
        lo, hi = ground_extent(self.tracks.values(), self.style.ground_margin)
        draw_ground(self.vis["ground"], lo, hi, self.style.ground_color)
        # meshcat's own grid and axes would poke through and clutter the view.
        self.vis["/Grid"].set_property("visible", False)
        self.vis["/Axes"].set_property("visible", False)

    def _frame_camera(self) -> None:
        place_camera(self.vis, *framing(self.tracks.values()))

    def look_at_track(self, name: str, position: ArrayLike) -> None:
        """Place the camera at ``position`` (3,) [m], looking at the mean centre of mass (x, z;
        y = 0) of the animated track ``name`` (call after :meth:`animate`)."""
        track = self.tracks[name]
        if track.frames is None:  # show() samples frame 0: not reached
            raise ViewerError(f"track {name!r} has no frames: call show() and animate() first")
        com = track.frames.com + track.offset
        self.set_camera(position, np.array([com[:, 0].mean(), 0.0, com[:, 2].mean()]))

    def set_camera(self, position: ArrayLike, target: ArrayLike = (0.0, 0.0, 0.8)
                   ) -> None:
        """Place the camera at ``position`` (3,) [m, world], looking at ``target`` (3,) [m].

        meshcat has no look-at call and its orbit controls always turn around the world
        origin, so the whole scene (``/meshcat``) is shifted by ``-target`` and the camera is
        put at ``position - target`` (in the y-up frame of ``/Cameras/default/rotated``). The
        mouse then orbits around ``target``. Without a call, :meth:`animate` frames all
        centres of mass from the front left.
        """
        place_camera(self.vis, position, target)
        self._camera_set = True

    # -- output --------------------------------------------------------------------------
    def _ensure_animated(self) -> None:
        if self.tracks and not self._animated:
            self.animate()

    def html(self, title: str | None = None) -> str:
        """The scene as one self-contained HTML page (viewer, meshes and animation embedded;
        ~14 MB for a Talos), with a ``title`` (default: ``"gdimitate: "`` and the tracks'
        labels) and a legend naming each track (:func:`~.export.with_legend`). Animates first
        if :meth:`animate` was not called since the last :meth:`show`."""
        self._ensure_animated()
        entries = [(t.label or t.name, t.color) for t in self.tracks.values()]
        name = title or "gdimitate: " + ", ".join(label for label, _ in entries)
        return with_legend(self.vis.static_html(), name, entries)

    def save_html(self, path: str | os.PathLike[str], title: str | None = None) -> Path:
        """Write :meth:`html` to ``path``; the file plays offline. Returns the absolute path.

        Raises:
            ViewerError: the folder does not exist or the file cannot be written (checked
                before the scene is fetched).
        """
        p = check_writable(path)  # fail before the (slow) scene transfer
        return write_html(self.html(title), p)

    def display(self, height: int = 480, live: bool = False) -> object:
        """Show the scene in a Jupyter cell and return the ``IPython.display.HTML`` object.

        ``live=False`` (default) embeds the self-contained page (works with a remote kernel
        and offline, frozen at this moment); ``live=True`` embeds the server's page in an
        iframe (follows later changes; the browser must reach :attr:`url`). Outside a
        notebook nothing is displayed and nothing blocks; the object is just returned.
        """
        return notebook_display(self.html, self.url, height, live)

    def __repr__(self) -> str:
        return f"Viewer({self.url!r}, tracks={list(self.tracks)})"
