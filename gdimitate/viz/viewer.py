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

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import meshcat
import numpy as np
import pinocchio as pin
from meshcat.animation import Animation

from ..errors import ViewerError
from .animate import (
    Frames,
    MotionMismatchError,
    arrow_pose,
    check_motion,
    place_frame,
    push_vectors,
    record_frames,
    sample_frames,
)
from .export import check_writable, inline_html, write_html
from .scene import (
    Style,
    draw_arrow,
    draw_geometry,
    draw_ground,
    draw_marker,
    draw_polyline,
    has_visuals,
    skeleton_geometry,
)
from .server import MeshcatServer, connect

__all__ = ["Track", "Viewer", "leg_length"]


@dataclass
class Track:
    """One robot shown over one motion (what :meth:`Viewer.show` records).

    Attributes:
        name: meshcat node name under ``/meshcat``.
        model: the robot's Pinocchio model.
        visual_model: the geometry drawn (the robot's, or a skeleton).
        t, q: ``(T,)`` [s] and ``(T, nq)``, validated.
        soles: leg name → sole frame name.
        force_directions: leg name → ``(T, 3)`` unit push vectors (may be empty).
        com: ``(T, 3)`` [m] given by the caller, ``None`` for Pinocchio's, ``False`` for none.
        offset: ``(3,)`` [m] translation of the whole track; scale: its uniform scale.
        nodes: meshcat node names of the visual objects.
        size: the robot's leg length [m], the unit of :class:`Style` sizes.
        foot_paths: whether the soles' paths are drawn.
        frames: sampled kinematics of the last animation (or of frame 0).
    """

    name: str
    model: pin.Model
    visual_model: pin.GeometryModel
    t: np.ndarray
    q: np.ndarray
    soles: dict[str, str]
    force_directions: dict[str, np.ndarray]
    com: np.ndarray | None | bool
    offset: np.ndarray
    scale: float
    nodes: list[str]
    size: float = 1.0
    foot_paths: bool = True
    frames: Frames | None = field(default=None, repr=False)


def leg_length(robot: object) -> float:
    """Hip-to-sole distance [m] of the robot's first leg (``.legs[...]`` with ``.hip`` joint
    and ``.sole`` frame) in its neutral configuration; ``nan`` if it has no such leg."""
    model: pin.Model = robot.model
    for leg in (getattr(robot, "legs", None) or {}).values():
        hip, sole = getattr(leg, "hip", None), getattr(leg, "sole", None)
        if hip and sole and model.existJointName(hip) and model.existFrame(sole):
            data = model.createData()
            pin.framesForwardKinematics(model, data, pin.neutral(model))
            a = data.oMi[model.getJointId(hip)].translation
            b = data.oMf[model.getFrameId(sole)].translation
            return float(np.linalg.norm(a - b))
    return float("nan")


def _soles(robot: object) -> dict[str, str]:
    legs = getattr(robot, "legs", None) or {}
    out = {}
    for name, leg in legs.items():
        sole = getattr(leg, "sole", None)
        if sole:
            out[str(name)] = str(sole)
    return out


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
             force_directions: Mapping[str, np.ndarray] | None = None,
             com: np.ndarray | bool | None = True, foot_paths: bool = True,
             skeleton: bool = False) -> str:
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
                ``gdimitate.metrics.ForceDirection`` (e.g. from ``force_direction``), ``(T, 3)``
                vectors or ``(T,)`` sagittal angles [rad] from the downward vertical, NaN in
                swing; drawn in 3-D as arrows whose tip touches the sole, hidden when NaN.
            com: ``True`` marks Pinocchio's centre of mass; a ``(T, 3)`` array [m] marks that
                path instead; ``False``/``None`` draws no marker.
            foot_paths: draw each sole's path over the whole motion as a line.
            skeleton: draw joints and rods if the robot has no visual geometry (otherwise
                that raises :class:`ViewerError`).

        Returns:
            The track name.

        Raises:
            ViewerError: no visual geometry (and ``skeleton=False``), a motion that does not
                fit the robot (:class:`~gdimitate.viz.animate.MotionMismatchError`), a bad
                force-direction or CoM array, a server that does not answer.
        """
        model = getattr(robot, "model", None)
        if not isinstance(model, pin.Model):
            raise ViewerError(f"robot must have a Pinocchio .model; got {type(robot)!r}")
        rname = str(getattr(robot, "name", None) or model.name or "robot")
        visual = getattr(robot, "visual_model", None)
        if not has_visuals(visual):
            if not skeleton:
                raise ViewerError(
                    f"robot {rname!r} has no visual geometry; pass skeleton=True to draw its "
                    "joints and links as a stick figure"
                )
            visual = skeleton_geometry(model)
        t, q = check_motion(model, motion)
        if not np.isfinite(scale) or scale <= 0:
            raise ViewerError(f"scale must be a positive number, got {scale}")
        off = np.asarray(offset, dtype=float).reshape(-1)
        if off.shape != (3,) or not np.all(np.isfinite(off)):
            raise ViewerError(f"offset must be 3 finite numbers [m], got {offset!r}")
        track_name = self._unique(name or rname)
        size = leg_length(robot)
        size = size if np.isfinite(size) and size > 1e-3 else 1.0
        com_arg: np.ndarray | None | bool = com
        if com is True:
            com_arg = None
        elif com is None or com is False:
            com_arg = False
        soles = _soles(robot)
        force = {str(k): push_vectors(v) for k, v in (force_directions or {}).items()}
        unknown = [leg for leg in force if leg not in soles]
        if unknown:
            raise ViewerError(f"force directions given for legs {unknown} but robot {rname!r} "
                              f"has sole frames only for legs {sorted(soles)}")
        for leg, a in force.items():
            if a.shape != (t.size, 3):
                raise MotionMismatchError(f"force direction of leg {leg!r} has {a.shape[0]} "
                                          f"samples; expected {t.size} (one per motion frame)")
        if isinstance(com_arg, np.ndarray):
            com_arg = np.asarray(com_arg, dtype=float)
            if com_arg.shape != (len(t), 3):
                raise MotionMismatchError(f"com has shape {com_arg.shape}; expected "
                                          f"({len(t)}, 3)")
        # Frame 0 only (cheap): the pose drawn until the animation is set.
        frames = sample_frames(model, visual, t[:1], q[:1], 1.0, soles,
                               {k: v[:1] for k, v in force.items()},
                               com_arg[:1] if isinstance(com_arg, np.ndarray) else None)
        root = self.vis[track_name]
        root.set_transform(_root_transform(off, float(scale)))
        nodes = draw_geometry(root["robot"], visual, color, opacity)
        track = Track(track_name, model, visual, t, q, soles, force, com_arg, off,
                      float(scale), nodes, size, bool(foot_paths), frames)
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
        lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
        for track in self.tracks.values():
            pts = [track.frames.placements[:, :, :3, 3].reshape(-1, 3)]
            pts += list(track.frames.sole_paths.values())
            xy = np.concatenate(pts)[:, :2] * track.scale + track.offset[:2]
            lo, hi = np.minimum(lo, xy.min(axis=0)), np.maximum(hi, xy.max(axis=0))
        m = self.style.ground_margin
        draw_ground(self.vis["ground"], lo - m, hi + m, self.style.ground_color)
        # meshcat's own grid and axes would poke through and clutter the view.
        self.vis["/Grid"].set_property("visible", False)
        self.vis["/Axes"].set_property("visible", False)

    def _frame_camera(self) -> None:
        coms = [tr.frames.com * tr.scale + tr.offset for tr in self.tracks.values()]
        pts = np.concatenate(coms)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        target = (lo + hi) / 2.0
        span = float(max(hi[0] - lo[0], hi[1] - lo[1], 2.0 * hi[2], 0.5))
        self._place_camera(target + np.array([0.3, -1.0, 0.2]) * (span + 0.4), target)

    def look_at_track(self, name: str, position: Sequence[float]) -> None:
        """Place the camera at ``position`` (3,) [m], looking at the mean centre of mass (x, z;
        y = 0) of the animated track ``name`` (call after :meth:`animate`)."""
        track = self.tracks[name]
        com = track.frames.com + track.offset
        self.set_camera(position, np.array([com[:, 0].mean(), 0.0, com[:, 2].mean()]))

    def set_camera(self, position: Sequence[float], target: Sequence[float] = (0.0, 0.0, 0.8)
                   ) -> None:
        """Place the camera at ``position`` (3,) [m, world], looking at ``target`` (3,) [m].

        meshcat has no look-at call and its orbit controls always turn around the world
        origin, so the whole scene (``/meshcat``) is shifted by ``-target`` and the camera is
        put at ``position - target`` (in the y-up frame of ``/Cameras/default/rotated``). The
        mouse then orbits around ``target``. Without a call, :meth:`animate` frames all
        centres of mass from the front left.
        """
        self._place_camera(position, target)
        self._camera_set = True

    def _place_camera(self, position: Sequence[float], target: Sequence[float]) -> None:
        p = np.asarray(position, dtype=float) - np.asarray(target, dtype=float)
        T = np.eye(4)
        T[:3, 3] = -np.asarray(target, dtype=float)
        self.vis.set_transform(T)
        self.vis["/Cameras/default"].set_transform(np.eye(4))
        self.vis["/Cameras/default/rotated/<object>"].set_property(
            "position", [float(p[0]), float(p[2]), float(-p[1])])

    # -- output --------------------------------------------------------------------------
    def _ensure_animated(self) -> None:
        if self.tracks and not self._animated:
            self.animate()

    def html(self) -> str:
        """The scene as one self-contained HTML page (viewer, meshes and animation embedded;
        ~14 MB for a Talos). Animates first if :meth:`animate` was not called since the last
        :meth:`show`."""
        self._ensure_animated()
        return self.vis.static_html()

    def save_html(self, path: str | Path) -> Path:
        """Write :meth:`html` to ``path``; the file plays offline. Returns the absolute path.

        Raises:
            ViewerError: the folder does not exist or the file cannot be written (checked
                before the scene is fetched).
        """
        p = check_writable(path)  # fail before the (slow) scene transfer
        return write_html(self.html(), p)

    def display(self, height: int = 480, live: bool = False) -> object:
        """Show the scene in a Jupyter cell and return the ``IPython.display.HTML`` object.

        ``live=False`` (default) embeds the self-contained page (works with a remote kernel
        and offline, frozen at this moment); ``live=True`` embeds the server's page in an
        iframe (follows later changes; the browser must reach :attr:`url`). Outside a
        notebook nothing is displayed and nothing blocks; the object is just returned.
        """
        from IPython.display import HTML

        if live:
            obj = HTML(
                f'<div style="height: {int(height)}px; width: 100%; resize: both; '
                f'overflow: hidden"><iframe src="{self.url}" style="width: 100%; '
                'height: 100%; border: none"></iframe></div>')
        else:
            obj = HTML(inline_html(self.html(), height))
        try:
            from IPython import get_ipython

            shell = get_ipython()
        except ImportError:  # pragma: no cover
            shell = None
        if shell is not None and getattr(shell, "kernel", None) is not None:
            from IPython.display import display

            display(obj)
        return obj

    def __repr__(self) -> str:
        return f"Viewer({self.url!r}, tracks={list(self.tracks)})"
