"""Turning a motion into what the viewer draws: sampled frames and meshcat animation tracks.

:func:`sample_frames` runs Pinocchio's kinematics over a motion (at most ``fps`` frames per
second of motion time) and returns, per frame, the rigid placement of every visual geometry
object, the centre of mass, the soles and the force directions. :func:`record_frames` writes
those frames into a ``meshcat.animation.Animation`` (position + quaternion tracks; never a
scaled matrix, see :mod:`gdimitate.viz.scene`), and :func:`place_frame` shows one frame as
static transforms (the first frame is displayed before an animation is set, docs/design.md §10).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import meshcat
import numpy as np
import pinocchio as pin
from meshcat.animation import Animation, AnimationClip, AnimationTrack

from ..errors import InvalidInputError, ViewerError

__all__ = [
    "Frames",
    "MotionMismatchError",
    "arrow_pose",
    "check_motion",
    "frame_indices",
    "place_frame",
    "push_vectors",
    "record_frames",
    "sample_frames",
]


class MotionMismatchError(ViewerError, InvalidInputError):
    """A motion that does not fit the robot it is shown on (joint names, ``q`` width, times)."""


def check_motion(model: pin.Model, motion: Any) -> tuple[np.ndarray, np.ndarray]:
    """Validate ``motion`` against ``model``; return ``(t (T,), q (T, nq))`` as float arrays.

    Accepts a ``Motion`` or an ``AdaptedMotion`` (its ``.motion`` is used).

    Raises:
        MotionMismatchError: joint names differ from the model's, ``q`` is not ``(T, nq)``,
            ``t`` is not ``(T,)``, finite and non-decreasing, or values are not finite.
    """
    if hasattr(motion, "motion") and not hasattr(motion, "q"):
        motion = motion.motion
    for attr in ("t", "q"):
        if not hasattr(motion, attr):
            raise MotionMismatchError(f"a motion needs .t and .q arrays; got {type(motion)!r}")
    names = getattr(motion, "joint_names", None)
    expected = list(model.names)[1:]
    if names is not None and list(names) != expected:
        missing = [n for n in expected if n not in set(names)]
        extra = [n for n in names if n not in set(expected)]
        detail = (f"missing {missing[:8]}, unknown {extra[:8]}" if missing or extra
                  else "same names in another order")
        raise MotionMismatchError(
            f"the motion's joint names do not match robot model {model.name!r} ({detail}); "
            f"the robot's joints are {expected}"
        )
    t = np.asarray(motion.t, dtype=float)
    q = np.asarray(motion.q, dtype=float)
    if q.ndim != 2 or q.shape[1] != model.nq:
        raise MotionMismatchError(
            f"motion.q has shape {q.shape}; robot model {model.name!r} needs (T, {model.nq})")
    if t.shape != (q.shape[0],):
        raise MotionMismatchError(f"motion.t has shape {t.shape}; expected ({q.shape[0]},)")
    if len(t) == 0:
        raise MotionMismatchError("the motion has no samples")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
        raise MotionMismatchError("motion.t or motion.q holds NaN or inf")
    if np.any(np.diff(t) < 0):
        raise MotionMismatchError("motion.t must be non-decreasing")
    return t, q


def frame_indices(t: np.ndarray, fps: float) -> np.ndarray:
    """Indices into ``t`` (T,) [s] nearest to a grid of ``fps`` frames per second, unique and
    increasing, always including the first and the last sample."""
    if fps <= 0:
        raise ViewerError(f"fps must be positive, got {fps}")
    grid = np.arange(t[0], t[-1] + 0.5 / fps, 1.0 / fps)
    idx = np.clip(np.searchsorted(t, grid), 0, len(t) - 1)
    left = np.clip(idx - 1, 0, len(t) - 1)
    idx = np.where(np.abs(t[left] - grid) <= np.abs(t[idx] - grid), left, idx)
    return np.unique(np.concatenate([[0], idx, [len(t) - 1]]))


@dataclass
class Frames:
    """Sampled kinematics of one robot over one motion (``K`` frames).

    Attributes:
        t: ``(K,)`` times [s] from the motion's start.
        placements: ``(K, G, 4, 4)`` rigid placement of each visual geometry object (world).
        com: ``(K, 3)`` centre of mass [m].
        soles: per leg, ``(K, 3)`` sole-frame position [m].
        force: per leg, ``(K,)`` force direction from the downward vertical [rad], NaN in swing.
        sole_paths: per leg, ``(T, 3)`` sole position at every sample of the motion [m].
    """

    t: np.ndarray
    placements: np.ndarray
    com: np.ndarray
    soles: dict[str, np.ndarray] = field(default_factory=dict)
    force: dict[str, np.ndarray] = field(default_factory=dict)
    sole_paths: dict[str, np.ndarray] = field(default_factory=dict)


def sample_frames(model: pin.Model, visual_model: pin.GeometryModel, t: np.ndarray,
                  q: np.ndarray, fps: float, soles: Mapping[str, str] | None = None,
                  force_directions: Mapping[str, np.ndarray] | None = None,
                  com: np.ndarray | None = None) -> Frames:
    """Kinematics of ``q`` ``(T, nq)`` at times ``t`` ``(T,)`` [s], sampled at ``fps``.

    Args:
        soles: leg name → sole frame name (e.g. ``{"left": "left_sole"}``).
        force_directions: leg name → push directions, anything :func:`push_vectors` takes
            (e.g. ``gdimitate.assess.metrics.force_direction``'s result per foot), NaN in swing.
        com: ``(T, 3)`` centre of mass [m] to show instead of Pinocchio's.
    """
    soles = dict(soles or {})
    frame_ids = {}
    for leg, frame in soles.items():
        if not model.existFrame(frame):
            raise ViewerError(f"sole frame {frame!r} of leg {leg!r} is not a frame of "
                              f"robot model {model.name!r}")
        frame_ids[leg] = model.getFrameId(frame)
    T = len(t)
    forces = {}
    for leg, directions in (force_directions or {}).items():
        a = push_vectors(directions)
        if a.shape != (T, 3):
            raise MotionMismatchError(
                f"force direction of leg {leg!r} has {a.shape[0]} samples; expected {T}")
        forces[leg] = a
    if com is not None:
        com = np.asarray(com, dtype=float)
        if com.shape != (T, 3):
            raise MotionMismatchError(f"com has shape {com.shape}; expected ({T}, 3)")
    idx = frame_indices(t, fps)
    data = model.createData()
    gdata = pin.GeometryData(visual_model)
    G = visual_model.ngeoms
    placements = np.empty((len(idx), G, 4, 4))
    com_k = np.empty((len(idx), 3))
    paths = {leg: np.empty((T, 3)) for leg in frame_ids}
    wanted = np.zeros(T, dtype=bool)
    wanted[idx] = True
    k = 0
    for i in range(T):
        pin.forwardKinematics(model, data, q[i])
        for leg, fid in frame_ids.items():
            paths[leg][i] = pin.updateFramePlacement(model, data, fid).translation
        if not wanted[i]:
            continue
        pin.updateGeometryPlacements(model, data, visual_model, gdata)
        for g in range(G):
            placements[k, g] = gdata.oMg[g].homogeneous
        com_k[k] = pin.centerOfMass(model, data, q[i]) if com is None else com[i]
        k += 1
    return Frames(
        t=t[idx] - t[0], placements=placements, com=com_k,
        soles={leg: p[idx] for leg, p in paths.items()},
        force={leg: a[idx] for leg, a in forces.items()},
        sole_paths=paths,
    )


#: leg name -> a foot's push directions: a ``gdimitate.assess.metrics.ForceDirection``, ``(T, 3)``
#: vectors or ``(T,)`` sagittal angles [rad] (what :func:`push_vectors` reads)
PushDirections = Mapping[str, Any]


def push_vectors(directions: object) -> np.ndarray:
    """One foot's push directions as unit vectors ``(T, 3)`` (NaN rows where there is none)
    from a :class:`gdimitate.assess.metrics.ForceDirection`, vectors ``(T, 3)`` or sagittal angles
    ``(T,)`` [rad] from the downward vertical, positive forward (the planar case)."""
    v = getattr(directions, "vector", directions)
    a = np.asarray(v, dtype=float)
    if a.ndim == 1:
        return np.stack([np.sin(a), np.where(np.isnan(a), np.nan, 0.0), -np.cos(a)], axis=1)
    if a.ndim != 2 or a.shape[1] != 3:
        raise MotionMismatchError(f"a force direction must be (T,) angles or (T, 3) vectors; "
                                  f"got shape {a.shape}")
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / np.linalg.norm(a, axis=1, keepdims=True)


def arrow_pose(sole: np.ndarray, push: np.ndarray, length: float, side: float) -> np.ndarray:
    """``(4, 4)`` pose of an arrow (local +z, tail at origin) whose tip touches ``sole`` (3,),
    moved ``side`` [m] along world y, pointing along the foot's push ``push`` (3,) (a
    direction in the world frame, e.g. down into the floor)."""
    d = np.asarray(push, dtype=float) / np.linalg.norm(push)
    R = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), d).toRotationMatrix()
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(sole) + np.array([0.0, side, 0.0]) - length * d
    return T


def place_frame(nodes: Sequence[meshcat.Visualizer], poses: np.ndarray) -> None:
    """Static transforms: ``poses[i]`` ``(4, 4)`` on ``nodes[i]``."""
    for node, pose in zip(nodes, poses, strict=True):
        node.set_transform(pose)


def _clip(animation: Animation, node: meshcat.Visualizer) -> AnimationClip:
    if node.path not in animation.clips:
        animation.clips[node.path] = AnimationClip(fps=animation.default_framerate)
    return animation.clips[node.path]


def record_frames(animation: Animation, node: meshcat.Visualizer, times: np.ndarray,
                  poses: np.ndarray, visible: np.ndarray | None = None) -> None:
    """Add keyframes for ``node``: rigid ``poses`` ``(K, 4, 4)`` at ``times`` ``(K,)`` [s], and
    optionally a boolean ``visible`` ``(K,)`` track. Rotations must be proper (no scale)."""
    clip = _clip(animation, node)
    keys = [float(x) for x in np.asarray(times) * animation.default_framerate]
    pos = [[float(v) for v in p[:3, 3]] for p in poses]
    quat = []
    for p in poses:
        x, y, z, w = pin.Quaternion(p[:3, :3]).coeffs()
        quat.append([float(x), float(y), float(z), float(w)])
    clip.tracks["position"] = AnimationTrack("position", "vector3", list(keys), pos)
    clip.tracks["quaternion"] = AnimationTrack("quaternion", "quaternion", list(keys), quat)
    if visible is not None:
        clip.tracks["visible"] = AnimationTrack("visible", "boolean", list(keys),
                                                [bool(v) for v in visible])
