"""What the demonstration asks of the imitator, knot by knot (all NumPy, computed with
Pinocchio on the demonstrator): the knot grid, the contact schedule, scaled keypoints, mapped
joint angles, segment orientations and the force direction of each stance foot."""

from __future__ import annotations

import numpy as np

from ..assess.metrics import force_direction
from ..errors import InvalidInputError
from ..model.contact import ContactForces
from ..model.footsteps import sole_frames
from ..model.kinematics import anchor_schedule, frame_placements
from ..model.motion import Motion
from ..model.robot import SIDES, Robot
from .bodymap import BodyMap
from .context import Targets

__all__ = ["Targets", "configurations_at", "resample", "schedule", "demonstration_targets",
           "direction_frame", "relative_rotations", "segment_rotations"]


def configurations_at(robot: Robot, motion: Motion, t: np.ndarray) -> np.ndarray:
    """``motion``'s q at times ``t`` ``(K,)`` [s], ``(K, nq)``: each column linearly
    interpolated, a free-flyer's quaternion re-normalised."""
    q = np.column_stack([np.interp(t, motion.t, motion.q[:, c])
                         for c in range(motion.q.shape[1])])
    if robot.base == "free":
        q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    return q


def resample(robot: Robot, motion: Motion, rate: float) -> Motion:
    """``motion`` on a uniform grid of ``rate`` knots/s from its first time to its last
    (linear interpolation of each column, a free-flyer's quaternion re-normalised; contact
    flags of the nearest original frame). Returns the motion itself when its grid already has
    that rate."""
    if not (isinstance(rate, (int, float, np.floating)) and np.isfinite(rate) and rate > 0):
        raise InvalidInputError(f"rate must be a positive number of knots per second; "
                                f"got {rate!r}")
    t = motion.t
    n = int(np.floor((t[-1] - t[0]) * rate + 1e-9)) + 1
    if n < 2:
        raise InvalidInputError(f"a {t[-1] - t[0]:.3f} s motion at {rate:g} knots/s has fewer "
                                "than 2 knots: raise the rate")
    tk = t[0] + np.arange(n) / rate
    if tk.size == t.size and np.allclose(tk, t, atol=1e-9):
        return motion
    q = configurations_at(robot, motion, tk)
    near = np.clip(np.searchsorted(t, tk - 0.5 / rate), 0, t.size - 1)
    near = np.array([min(range(max(i - 1, 0), min(i + 2, t.size)), key=lambda j: abs(t[j] - x))
                     for i, x in zip(near, tk)])
    contact = {s: np.asarray(c)[near] for s, c in motion.contact.items()}
    return motion.replace(t=tk, q=q, contact=contact, v=None, a=None)


def schedule(demo: Motion, forces: ContactForces | None, rule: str) -> dict[str, np.ndarray]:
    """The imitator's stance flags per knot: the demonstrator's measured contacts where
    ``forces`` are given, else ``demo.contact`` (its kinematics); ``rule="anchor"`` keeps only
    the foot down longest (Eq. (1)'s contact rule)."""
    if forces is not None:
        c = {s: np.interp(demo.t, forces.t, forces[s].contact.astype(float)) > 0.5
             for s in SIDES}
    else:
        if not demo.contact or any(s not in demo.contact for s in SIDES):
            raise InvalidInputError(
                "the demonstration has no contact schedule: give motion.contact "
                "{'left': (T,) bool, 'right': (T,) bool} or forces= (measured contacts)")
        c = {s: np.asarray(demo.contact[s], bool).copy() for s in SIDES}
    if not any(c[s].any() for s in SIDES):
        raise InvalidInputError("the demonstration never touches the ground (no stance knot "
                                "on either foot): nothing to push on")
    if rule == "anchor":
        anchors = np.array(anchor_schedule(c), dtype=object)
        c = {s: anchors == s for s in SIDES}
    return c


def direction_frame(d: np.ndarray, planar: bool) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``e1``, ``e2`` ``(T, 3)`` completing unit directions ``d`` ``(T, 3)`` to
    an orthonormal frame (planar: ``e1`` in the x–z plane, ``e2`` = 0). NaN rows stay zero."""
    e1, e2 = np.zeros_like(d), np.zeros_like(d)
    for k, dk in enumerate(d):
        if not np.all(np.isfinite(dk)):
            continue
        if planar:
            e1[k] = [-dk[2], 0.0, dk[0]]
            e1[k] /= np.linalg.norm(e1[k])
            continue
        ref = np.array([0.0, 1.0, 0.0]) if abs(dk[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
        u = ref - (ref @ dk) * dk
        e1[k] = u / np.linalg.norm(u)
        e2[k] = np.cross(dk, e1[k])
    return e1, e2


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def relative_rotations(R: np.ndarray, R0: np.ndarray, R0_target: np.ndarray) -> np.ndarray:
    """``R(t) · R0ᵀ · R0_target`` ``(T, 3, 3)``: the rotations ``R`` ``(T, 3, 3)`` since
    ``R0`` ``(3, 3)`` (a frame's world rotation at its robot's neutral pose), applied to
    another frame's neutral orientation ``R0_target`` ``(3, 3)``."""
    return np.einsum("tij,kj,kl->til", R, R0, R0_target)


def segment_rotations(demonstrator: Robot, imitator: Robot, bmap: BodyMap,
                      rot: dict[str, np.ndarray]) -> np.ndarray:
    """``(T, n_seg, 3, 3)``: the world rotation each body-map segment of the imitator
    (``bmap.segments``, in order) should take — its demonstrator frame's ``rot[frame]``
    ``(T, 3, 3)`` since the demonstrator's neutral pose, applied to the imitator frame's
    orientation at its neutral pose (:func:`relative_rotations`; both neutral poses stand
    facing +x). A body frame's axes are its file's convention, not a direction of the body:
    iCub's ``root_link`` looks back (π about z from the OpenSim pelvis at the neutral poses),
    its ``chest`` is 90° off; a BVH skeleton's ``Spine`` has its axes permuted (CMU's: 120°
    from every robot's torso). Copying the world rotation itself asked iCub's pelvis to turn
    about and CMU → G1's torso to lie down."""
    if not bmap.segments:
        return np.zeros((len(next(iter(rot.values()))), 0, 3, 3))
    d0 = frame_placements(demonstrator, demonstrator.neutral[None], list(bmap.segments))
    i0 = frame_placements(imitator, imitator.neutral[None], list(bmap.segments.values()))
    return np.stack([relative_rotations(rot[d], d0[d].rotation[0], i0[i].rotation[0])
                     for d, i in bmap.segments.items()], axis=1)


def demonstration_targets(demonstrator: Robot, demo: Motion, imitator: Robot, bmap: BodyMap,
                          act_names: tuple[str, ...], force: str,
                          forces: ContactForces | None, rule: str) -> Targets:
    """The :class:`Targets` of a (resampled) demonstration; see the module docstring."""
    stance = schedule(demo, forces, rule)
    down = schedule(demo, forces, "all")
    swing = {s: ~down[s] for s in SIDES}
    legs = demonstrator.legs
    frames = [f for s in SIDES for f in (legs[s].hip, legs[s].knee, legs[s].ankle or legs[s].sole)]
    seg_frames = list(bmap.segments)
    soles = list(sole_frames(demonstrator).values())
    placements = frame_placements(demonstrator, demo.q, frames + seg_frames + soles)
    pos = {f: p.translation for f, p in placements.items()}
    rot = {f: p.rotation for f, p in placements.items()}
    height: dict[str, np.ndarray] = {}
    placement: dict[str, np.ndarray] = {}
    shank: dict[str, np.ndarray] = {}
    thigh: dict[str, np.ndarray] = {}
    for s in SIDES:
        leg = legs[s]
        hip, knee, ankle = pos[leg.hip], pos[leg.knee], pos[leg.ankle or leg.sole]
        height[s] = (hip[:, 2] - ankle[:, 2]) / leg.length
        placement[s] = (ankle[:, :2] - hip[:, :2]) / leg.length
        shank[s] = _unit(ankle - knee)
        thigh[s] = _unit(knee - hip)
    foot = {s: rot[f] for s, f in zip(SIDES, soles)}
    segments = segment_rotations(demonstrator, imitator, bmap, rot)
    from .parts.self_collision import rest_pose  # unmapped joints: the limbs clear

    joints = np.tile(rest_pose(imitator)[[imitator.idx_q(j) for j in act_names]], (demo.T, 1))
    mapped = np.zeros(len(act_names), bool)
    for dj, (ij, scale, offset) in bmap.joints.items():
        if ij in act_names:
            i = act_names.index(ij)
            joints[:, i] = scale * demo.q[:, demonstrator.idx_q(dj)] + offset
            mapped[i] = True
    fd_demo = demo.replace(contact=stance) if rule == "all" else demo
    fd = force_direction(demonstrator, fd_demo, force, forces=forces)
    push = {s: np.where(stance[s][:, None], fd[s].vector, np.nan) for s in SIDES}
    if imitator.base == "planar":  # a planar robot can keep only the sagittal direction
        for s in SIDES:
            p = push[s] * np.array([1.0, 0.0, 1.0])
            push[s] = p / np.linalg.norm(p, axis=1, keepdims=True)
    return Targets(demo.t, stance, swing, height, placement, shank, thigh, foot, segments,
                   joints, mapped, push, demo)
