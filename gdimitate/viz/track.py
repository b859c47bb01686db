"""One robot over one motion in the viewer: the :class:`Track` record and the checks of what
:meth:`~gdimitate.viz.viewer.Viewer.show` is given (robot, motion, offset, scale, force
directions, centre of mass), before anything is drawn."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import pinocchio as pin

from ..errors import ViewerError
from .animate import Frames, MotionMismatchError, PushDirections, check_motion, push_vectors
from .scene import has_visuals, skeleton_geometry

__all__ = ["Track", "TrackInputs", "leg_length", "track_inputs"]


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
        label: what the page's legend calls it; color: its RGB in [0, 1] (None: the URDF's).
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
    label: str = ""
    color: tuple[float, float, float] | None = None


def leg_length(robot: Any) -> float:
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


class TrackInputs(NamedTuple):
    """What :func:`track_inputs` checked, in the viewer's terms."""

    model: pin.Model
    name: str  # the robot's name
    visual: pin.GeometryModel  # the robot's visual geometry, or a skeleton
    t: np.ndarray  # (T,) [s]
    q: np.ndarray  # (T, nq)
    offset: np.ndarray  # (3,) [m]
    size: float  # leg length [m] (1 when the robot has no leg)
    com: np.ndarray | None | bool  # (T, 3) [m] given, None: Pinocchio's, False: none
    soles: dict[str, str]  # leg -> sole frame
    force: dict[str, np.ndarray]  # leg -> (T, 3) unit push vectors


def track_inputs(robot: object, motion: object, *, offset: Sequence[float], scale: float,
                 force_directions: PushDirections | None,
                 com: np.ndarray | bool | None, skeleton: bool) -> TrackInputs:
    """Check :meth:`~gdimitate.viz.viewer.Viewer.show`'s arguments (its docstring) and put
    them in the viewer's terms; ViewerError (MotionMismatchError for shapes that do not fit
    the motion) otherwise."""
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
    return TrackInputs(model, rname, visual, t, q, off, size, com_arg, soles, force)
