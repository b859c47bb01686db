"""Baselines for comparison — not the product: what retargeting looks like without the goal.

gdimitate's adaptor (``adapt(..., method="optimal")``) keeps each stance foot's push direction
under the imitator's limits and the physics of contact. To show what that buys, the
benchmarks (``benchmarks/peers.py``) run the same demonstration through two kinematic
retargeters of the kinds in common use and audit and simulate them exactly like the adaptor's
output:

- :func:`joint_copy` — action-level imitation in 3-D: every joint the body map pairs
  (:func:`gdimitate.retarget.body_map`) copies the demonstrator's angle as ``scale · q + offset``
  (the map's signs come from the joint axes at the two neutral poses), the others stay at the
  imitator's neutral pose; the base turns as the demonstrator's pelvis turns (relative to the
  neutral poses) and is placed by the same rule as the planar copy
  (:func:`gdimitate.model.sagittal.ground_base`): the lowest stance sole on z = 0, the
  *anchor* foot (the stance foot down longest) staying where it landed in x and y. No joint
  limit is enforced (the audit reports them).
- :func:`diff_ik` — a per-frame kinematic retargeter of the kind today's humanoid tools use
  (differential inverse kinematics on scaled keypoints with joint limits, built on Pink,
  S. Caron et al., https://github.com/stephane-caron/pink): per frame, frame tasks on the
  imitator's pelvis and torso (orientation), hips and knees (position) and soles (pose)
  towards the demonstrator's keypoints scaled by the leg-length ratio about the point under
  the demonstrator's start (the floor stays at z = 0); a stance foot is held, flat on the
  floor (z = 0, yaw only), where it was when it touched down — by the QP's equality
  constraints once it is there (by cost on the touchdown frame, and where the constraints
  leave the QP without a solution); a posture task towards the neutral pose; Pink's position
  and velocity limits; a few QPs (DAQP) per frame, each velocity integrated over its share of
  the frame period.

Both give a :class:`BaselinePlan`: ``motion`` with ``v``, ``a`` (central differences,
:func:`gdimitate.model.motion.differentiate`) and the demonstrator's stance schedule, and the
contact wrenches the motion implicitly asks of the floor —
:func:`gdimitate.assess.wrenches.estimate_wrenches` with ``method="lstsq"`` (no cone: feet may pull,
the centre of pressure may leave the sole). A :class:`BaselinePlan` is a plan in the contract
of :func:`gdimitate.sim.simulate` and fits :func:`gdimitate.assess.audit.audit`.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InvalidInputError, LegMatchError, SolverError
from ..model.contact import SoleContact
from ..model.kinematics import anchored_base_offsets, frame_placements
from ..model.motion import Motion, differentiate
from ..model.robot import SIDES, Robot
from ..retarget.targets import relative_rotations

__all__ = ["BaselinePlan", "IKOptions", "joint_copy", "diff_ik", "kinematic_plan",
           "anchor_base", "scaled_keypoints", "leg_ratio"]


@dataclass(frozen=True)
class BaselinePlan:
    """A kinematic baseline's result, in the plan contract of :func:`gdimitate.sim.simulate`.

    ``motion``: the imitator's :class:`~gdimitate.model.motion.Motion` (``q`` ``(T, nq)``, ``v``,
    ``a`` ``(T, nv)``, ``contact`` = the demonstrator's stance schedule); ``wrenches`` ``{side:
    (T, 6)}`` [N, N·m]: the minimum-norm wrenches that explain the base rows of the inverse
    dynamics, in each sole frame at its origin (zeros in swing); ``contacts`` ``{side:
    SoleContact}``; ``method`` (``"copy"``, ``"diff_ik"`` or the planar adaptor's name);
    ``seconds`` [s]: wall-clock time of the retargeting itself (wrenches not included);
    ``frames_per_s`` = T / seconds; ``residual`` ``(T,)`` [m]: the largest position error of
    the IK's hip, knee and sole keypoints per frame (zeros for the copy); ``relaxed`` ``(T,)``
    bool: frames where the IK could not hold the stance feet exactly and held them by cost."""

    motion: Motion
    wrenches: dict[str, np.ndarray]
    contacts: dict[str, SoleContact]
    method: str
    seconds: float
    frames_per_s: float
    residual: np.ndarray
    relaxed: np.ndarray


@dataclass(frozen=True)
class IKOptions:
    """Weights and settings of :func:`diff_ik`.

    Costs (Pink's task costs, [1/m] for positions, [1/rad] for orientations): ``hip`` and
    ``knee`` (the hip and knee joints' positions), ``pelvis`` and ``torso`` (orientation
    only: the two bodies' frame origins lie at different places), ``swing_foot``,
    ``stance_foot`` (sole pose); ``posture`` [1/rad]
    towards the imitator's neutral pose; ``iterations``: QP iterations per frame, each
    integrating over ``frame period / iterations``, and more, up to ``max_iterations``, while
    a stance foot is farther than ``tolerance`` [-] (the norm of its pose error, m and rad
    together) from where it is held — each extra iteration integrates over the sub-step
    again, so the velocity limits hold over a frame only with ``max_iterations ==
    iterations`` (the default); ``damping`` (Levenberg–Marquardt, Pink's
    ``damping``); ``solver``: a qpsolvers name (``"daqp"``, ``"proxqp"``, …); ``settle``: extra
    iterations on the first frame, from the neutral pose, to reach the first targets;
    ``velocity_limits``: apply the model's velocity limits (Pink's ``VelocityLimit``);
    ``hard_stance``: hold stance feet by equality constraints of the QP (Pink's
    ``constraints``) instead of the ``stance_foot`` cost (after the first frame)."""

    hip: float = 1.0
    pelvis: float = 1.0
    torso: float = 0.3
    knee: float = 0.3
    swing_foot: float = 1.0
    stance_foot: float = 100.0
    posture: float = 1e-2
    iterations: int = 4
    max_iterations: int = 4
    tolerance: float = 1e-3
    damping: float = 1e-8
    solver: str = "daqp"
    settle: int = 200
    velocity_limits: bool = True
    hard_stance: bool = True

    def __post_init__(self) -> None:
        for name in ("hip", "pelvis", "torso", "knee", "swing_foot", "stance_foot", "posture",
                     "damping"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 0):
                raise InvalidInputError(f"IKOptions.{name} must be a finite number ≥ 0; "
                                        f"got {v!r}")
        if not (isinstance(self.tolerance, (int, float)) and self.tolerance > 0):
            raise InvalidInputError(f"IKOptions.tolerance must be > 0; got {self.tolerance!r}")
        if not (isinstance(self.max_iterations, int) and isinstance(self.iterations, int)
                and self.max_iterations >= self.iterations):
            raise InvalidInputError("IKOptions.max_iterations must be an int ≥ iterations; "
                                    f"got {self.max_iterations!r}")
        for name in ("iterations", "settle"):
            v = getattr(self, name)
            if not (isinstance(v, int) and v >= (1 if name == "iterations" else 0)):
                raise InvalidInputError(f"IKOptions.{name} must be an int ≥ "
                                        f"{1 if name == 'iterations' else 0}; got {v!r}")


# ---------------------------------------------------------------------------- shared pieces
def _check(demo: Motion, demonstrator: Robot, imitator: Robot) -> None:
    if not isinstance(demo, Motion):
        raise InvalidInputError(f"demo must be a gdimitate.Motion; got {type(demo).__name__}")
    if tuple(demo.joint_names) != demonstrator.joint_names or \
            demo.q.shape[1] != demonstrator.model.nq:
        raise InvalidInputError(f"the demonstration's joints do not match the demonstrator "
                                f"{demonstrator.name!r}: pass the Robot it was recorded on")
    for r in (demonstrator, imitator):
        if r.base != "free":
            raise LegMatchError(f"{r.name} has a {r.base!r} base; the 3-D baselines need "
                                "free-flyer robots (planar models: adapt(method='copy' | "
                                "'analytic'))")
        if set(r.legs) != set(SIDES):
            raise LegMatchError(f"{r.name}: legs {sorted(r.legs)} cannot be matched to {SIDES}")
    if any(s not in demo.contact for s in SIDES):
        raise InvalidInputError("the demonstration needs a stance schedule demo.contact "
                                "{'left': (T,) bool, 'right': (T,) bool}")
    imitator.require_contacts()


def _body_map(demonstrator: Robot, imitator: Robot, bmap):
    from ..retarget.bodymap import UnmappedJointsWarning, body_map

    with warnings.catch_warnings():  # unmapped joints stay at neutral: documented above
        warnings.simplefilter("ignore", UnmappedJointsWarning)
        return body_map(demonstrator, imitator, bmap)


def leg_ratio(demonstrator: Robot, imitator: Robot) -> float:
    """Imitator / demonstrator leg length (thigh + shank, mean of both legs) [-]."""
    return float(np.mean([imitator.legs[s].length for s in SIDES])
                 / np.mean([demonstrator.legs[s].length for s in SIDES]))


def _frame_poses(robot: Robot, q: np.ndarray, frames: list[str]) -> dict[str, np.ndarray]:
    """World placements ``{frame: (T, 4, 4)}`` of ``frames`` along ``q`` ``(T, nq)``."""
    out = {}
    for f, P in frame_placements(robot, q, frames).items():
        out[f] = np.tile(np.eye(4), (len(P.translation), 1, 1))
        out[f][:, :3, :3], out[f][:, :3, 3] = P.rotation, P.translation
    return out


def _anchor_offsets(rel: dict[str, np.ndarray], contact: Mapping[str, np.ndarray]
                    ) -> np.ndarray:
    """Base translations ``(T, 3)`` that put the soles ``rel`` ``{side: (T, 3)}`` (positions
    with the base translation at zero) on the floor by the anchor rule of :func:`anchor_base`."""
    off = anchored_base_offsets(rel, contact)
    if np.all(np.isnan(off[:, 2])):
        raise InvalidInputError("the demonstration has no stance knot: nothing to stand on")
    return off


def anchor_base(robot: Robot, q: np.ndarray, contact: Mapping[str, np.ndarray]) -> np.ndarray:
    """``q`` ``(T, nq)`` of a free-flyer with its base translation replaced so the motion walks
    on z = 0 without the anchor foot slipping — the 3-D form of
    :func:`gdimitate.model.sagittal.ground_base`: the lowest stance sole (contact frame
    origin) on z = 0 (interpolated through flight); in x and y the anchor foot (the stance foot
    down longest) stays where it landed, and when it lifts off the other stance foot becomes the
    anchor where it stands (a second stance foot may slide: the audit and the simulation
    measure it). The base starts at x = y = 0. Returns a new array."""
    q = np.array(q, dtype=float)
    q[:, :3] = 0.0
    contacts = robot.require_contacts()
    frames = [contacts[s].frame for s in SIDES]
    P = _frame_poses(robot, q, frames)
    rel: dict[str, np.ndarray] = {s: P[contacts[s].frame][:, :3, 3] for s in SIDES}
    q[:, :3] = _anchor_offsets(rel, contact)
    return q


def kinematic_plan(robot: Robot, motion: Motion, method: str, seconds: float,
                   residual: np.ndarray | None = None, relaxed: np.ndarray | None = None
                   ) -> BaselinePlan:
    """Wrap a kinematic ``motion`` (``q``, ``contact``) of ``robot`` as a :class:`BaselinePlan`:
    ``v``, ``a`` by :func:`gdimitate.model.motion.differentiate` (no filter) and the minimum-norm
    wrenches of :func:`gdimitate.assess.wrenches.estimate_wrenches` (``method="lstsq"``)."""
    from ..assess.wrenches import estimate_wrenches

    mo = differentiate(robot.model, motion)
    contacts = dict(robot.require_contacts())
    est = estimate_wrenches(robot, mo, contacts, method="lstsq")
    T = mo.T
    res = np.zeros(T) if residual is None else np.asarray(residual, float)
    rel = np.zeros(T, bool) if relaxed is None else np.asarray(relaxed, bool)
    return BaselinePlan(mo, {s: np.asarray(est.wrenches[s]) for s in SIDES}, contacts, method,
                        float(seconds), T / max(float(seconds), 1e-12), res, rel)


def _imitator_motion(imitator: Robot, demo: Motion, q: np.ndarray) -> Motion:
    m = imitator.model
    return Motion(t=demo.t.copy(), joint_names=imitator.joint_names, q=q,
                  contact={s: np.asarray(demo.contact[s], bool).copy() for s in SIDES},
                  base_nq=7, joint_nq=tuple(m.joints[j].nq for j in range(1, m.njoints)))


# ---------------------------------------------------------------------------- (a) joint copy
def joint_copy(demo: Motion, demonstrator: Robot, imitator: Robot, body_map=None
               ) -> BaselinePlan:
    """The 3-D joint-angle copy of ``demo`` onto ``imitator`` (module docstring): mapped joints
    ``scale · q_demo + offset`` [rad] (``body_map``: a :class:`~gdimitate.retarget.BodyMap`,
    dict or JSON path; default the preset for the pair), unmapped joints at the neutral pose,
    base orientation relative to the neutral pose as the demonstrator's pelvis, base position
    by :func:`anchor_base`. ``demo``: ``(T, nq_demo)`` with ``contact``; free-flyer robots."""
    _check(demo, demonstrator, imitator)
    t0 = time.perf_counter()
    bm = _body_map(demonstrator, imitator, body_map)
    T = demo.T
    q = np.tile(imitator.neutral, (T, 1))
    for dj, (ij, scale, offset) in bm.joints.items():
        q[:, imitator.idx_q(ij)] = scale * demo.q[:, demonstrator.idx_q(dj)] + offset
    Rd = np.array([pin.Quaternion(x).normalized().matrix() for x in demo.q[:, 3:7]])
    Rd0 = pin.Quaternion(demonstrator.neutral[3:7]).normalized().matrix()
    Ri0 = pin.Quaternion(imitator.neutral[3:7]).normalized().matrix()
    R = relative_rotations(Rd, Rd0, Ri0)
    q[:, 3:7] = np.array([pin.Quaternion(r).coeffs() for r in R])
    q = anchor_base(imitator, q, demo.contact)
    seconds = time.perf_counter() - t0
    return kinematic_plan(imitator, _imitator_motion(imitator, demo, q), "copy", seconds)


# ---------------------------------------------------------------------------- (c) diff IK
@dataclass(frozen=True)
class _Keypoints:
    """Imitator frame names and their targets ``(T, 4, 4)`` (world placements)."""

    frames: dict[str, str]  # role -> imitator frame
    targets: dict[str, np.ndarray]  # role -> (T, 4, 4)


def _flat(H: np.ndarray) -> np.ndarray:
    """The placement ``H`` ``(4, 4)`` put flat on the floor: z = 0 and only its yaw kept."""
    x = H[:3, 0]
    yaw = np.arctan2(x[1], x[0])
    out = np.eye(4)
    out[:3, :3] = pin.utils.rpyToMatrix(0.0, 0.0, yaw)
    out[:2, 3] = H[:2, 3]
    return out


def scaled_keypoints(demo: Motion, demonstrator: Robot, imitator: Robot, body_map=None
                     ) -> _Keypoints:
    """The demonstrator's keypoints as the imitator's targets, per frame: for the pelvis (root
    body), the torso (the body map's segments), both knees (the legs' knee joints) and both
    soles (contact frames) the world placement with its position scaled by
    :func:`leg_ratio` about the point on the floor under the demonstrator's first pelvis
    position, and its rotation since the neutral pose applied to the imitator frame's neutral
    orientation (:func:`diff_ik` holds the stance feet)."""
    bm = _body_map(demonstrator, imitator, body_map)
    dc, ic = demonstrator.require_contacts(), imitator.require_contacts()
    # segments: the one on the imitator's root body is "pelvis", the others keep their names
    pairs = {("pelvis" if imitator.model.frames[imitator.frame_id(iseg)].parentJoint == 1
              else dseg): (dseg, iseg) for dseg, iseg in bm.segments.items()}
    for s in SIDES:
        pairs[f"hip_{s}"] = (demonstrator.legs[s].hip, imitator.legs[s].hip)
        pairs[f"knee_{s}"] = (demonstrator.legs[s].knee, imitator.legs[s].knee)
        pairs[f"sole_{s}"] = (dc[s].frame, ic[s].frame)
    dframes = [d for d, _ in pairs.values()]
    P = _frame_poses(demonstrator, demo.q, dframes)
    P0 = _frame_poses(demonstrator, demonstrator.neutral[None], dframes)
    I0 = _frame_poses(imitator, imitator.neutral[None], [i for _, i in pairs.values()])
    ratio = leg_ratio(demonstrator, imitator)
    origin = np.r_[demo.q[0, :2], 0.0]
    targets = {}
    for role, (dn, iname) in pairs.items():
        H = np.tile(np.eye(4), (demo.T, 1, 1))
        H[:, :3, :3] = relative_rotations(P[dn][:, :3, :3], P0[dn][0, :3, :3],
                                           I0[iname][0, :3, :3])
        H[:, :3, 3] = origin + ratio * (P[dn][:, :3, 3] - origin)
        targets[role] = H
    return _Keypoints({r: i for r, (_, i) in pairs.items()}, targets)


def diff_ik(demo: Motion, demonstrator: Robot, imitator: Robot, body_map=None,
            options: IKOptions | None = None) -> BaselinePlan:
    """Per-frame differential inverse kinematics of ``demo`` onto ``imitator`` with Pink
    (module docstring): frame tasks towards :func:`scaled_keypoints` (stance feet weighted
    ``options.stance_foot``, swing feet ``swing_foot``; pelvis and torso orientation, hips and
    knees position), a posture task towards the neutral pose, Pink's configuration (position)
    and velocity limits; ``options.iterations`` QPs per frame. ``seconds`` in the result counts
    the per-frame loop (not the keypoints or the first frame's settling). Raises
    :class:`~gdimitate.errors.SolverError` when the QP solver fails."""
    try:
        import pink  # noqa: F401  (a declared dependency; checked before any work)
    except ImportError as e:  # pragma: no cover - a declared dependency
        raise SolverError(f"diff_ik needs the 'pin-pink' package: {e}") from None
    _check(demo, demonstrator, imitator)
    o = options or IKOptions()
    if not isinstance(o, IKOptions):
        raise InvalidInputError(f"options must be an IKOptions; got {type(o).__name__}")
    kp = scaled_keypoints(demo, demonstrator, imitator, body_map)
    ik = _PinkIK(demo, imitator, kp, o)
    period = np.diff(demo.t, prepend=demo.t[0] - (demo.t[1] - demo.t[0]))
    qs = np.empty((demo.T, imitator.model.nq))
    residual = np.empty(demo.T)
    t_loop = 0.0
    for k in range(demo.T):
        if k == 0:
            ik.iterate(0, o.settle, float(period[0]))
        else:
            t0 = time.perf_counter()
            ik.iterate(k, o.iterations, period[k] / o.iterations)
            t_loop += time.perf_counter() - t0
        qs[k] = ik.config.q
        residual[k] = ik.residual()
    seconds = t_loop * demo.T / max(demo.T - 1, 1)
    return kinematic_plan(imitator, _imitator_motion(imitator, demo, qs), "diff_ik", seconds,
                          residual, ik.relaxed)


class _PinkIK:
    """:func:`diff_ik`'s per-frame solver: Pink's configuration, the frame tasks (one per
    keypoint role), the posture task and the limits; the feet held since their touchdown."""

    def __init__(self, demo: Motion, imitator: Robot, kp: _Keypoints, o: IKOptions) -> None:
        import pink
        from pink.limits import ConfigurationLimit, VelocityLimit
        from pink.tasks import FrameTask, PostureTask

        m = imitator.model
        self.demo, self.kp, self.o = demo, kp, o
        self.tasks: dict[str, FrameTask] = {}
        for role, frame in kp.frames.items():
            if role.startswith(("hip", "knee")):
                cost = o.hip if role.startswith("hip") else o.knee
                self.tasks[role] = FrameTask(frame, position_cost=cost, orientation_cost=0.0)
            elif role.startswith("sole"):
                self.tasks[role] = FrameTask(frame, position_cost=o.swing_foot,
                                             orientation_cost=o.swing_foot)
            else:  # pelvis and torso: orientation only (their origins differ between bodies)
                cost = o.pelvis if role == "pelvis" else o.torso
                self.tasks[role] = FrameTask(frame, position_cost=0.0, orientation_cost=cost)
        self.posture = PostureTask(cost=o.posture)
        self.posture.set_target(imitator.neutral)
        self.limits = [ConfigurationLimit(m)]
        if o.velocity_limits:
            vmax = np.where(np.isfinite(m.velocityLimit) & (m.velocityLimit > 0),
                            m.velocityLimit, 1e3)
            vmax[:6] = 1e3  # the free flyer has no velocity limit
            self.limits.append(VelocityLimit(m, vmax))
        q = imitator.neutral.copy()
        q[:2] = np.mean([kp.targets[f"hip_{s}"][0, :2, 3] for s in SIDES], axis=0)
        self.config = pink.Configuration(m, m.createData(), q)
        self.contact: dict[str, np.ndarray] = {s: np.asarray(demo.contact[s], bool)
                                               for s in SIDES}
        self.held: dict[str, np.ndarray] = {}
        self.relaxed = np.zeros(demo.T, bool)

    def iterate(self, k: int, n: int, dt: float) -> None:
        """``n`` QPs of step ``dt`` [s] towards frame ``k``'s targets (more, up to
        ``max_iterations``, while a held foot is farther than ``tolerance`` from its hold)."""
        o, contact = self.o, self.contact
        hard, soft = [], [self.posture]
        for role, task in self.tasks.items():
            target = self.kp.targets[role][k]
            if role.startswith("sole"):
                side = role[5:]
                stance = contact[side][k]
                if stance and (k == 0 or not contact[side][k - 1]):  # touchdown: hold it here
                    self.held[side] = _flat(target if k == 0 else
                                            self.config.get_transform_frame_to_world(
                                                self.kp.frames[role]).homogeneous)
                target = self.held[side] if stance else target
                c = o.stance_foot if stance else o.swing_foot
                task.set_position_cost(c)
                task.set_orientation_cost(c)
                if stance and o.hard_stance and k > 0 and contact[side][k - 1]:
                    hard.append(task)
                    task.set_target(pin.SE3(target))
                    continue
            task.set_target(pin.SE3(target))
            soft.append(task)
        for i in range(max(o.max_iterations, n)):
            if i >= n and self.held_error(k) <= o.tolerance:
                break  # extra iterations only while a held foot is not there yet
            self.config.integrate_inplace(self.solve(k, soft, hard, dt), dt)

    def held_error(self, k: int) -> float:
        """The largest pose error (SE(3) log norm) of a stance foot from its hold at frame k."""
        return float(max((np.linalg.norm(pin.log6(self.config.get_transform_frame_to_world(
            self.kp.frames[f"sole_{s}"]).actInv(pin.SE3(self.held[s]))).vector)
            for s in SIDES if self.contact[s][k]), default=0.0))

    def solve(self, k: int, soft: list, hard: list, dt: float) -> np.ndarray:
        """One QP's velocity: the held feet as equality constraints, as costs where the QP
        has no solution with them (frame ``k`` marked relaxed); SolverError otherwise."""
        import pink
        from pink.exceptions import NoSolutionFound

        o = self.o

        def qp(cost: list, equal: list) -> np.ndarray:
            return pink.solve_ik(self.config, cost, dt, solver=o.solver, damping=o.damping,
                                 limits=self.limits, constraints=equal or None,
                                 safety_break=False)
        try:
            return qp(soft, hard)
        except NoSolutionFound as e:
            if not hard:
                raise SolverError(f"diff_ik: the {o.solver} QP failed at frame {k} "
                                  f"(t = {self.demo.t[k]:.3f} s): {e}") from None
        self.relaxed[k] = True  # the held feet cannot be kept exactly: as costs instead
        try:
            return qp(soft + hard, [])
        except NoSolutionFound as e:
            raise SolverError(f"diff_ik: the {o.solver} QP failed at frame {k} "
                              f"(t = {self.demo.t[k]:.3f} s): {e}") from None

    def residual(self) -> float:
        """The largest distance [m] of a hip, knee or sole frame from its task's target."""
        return float(max(np.linalg.norm(self.config.get_transform_frame_to_world(
            self.kp.frames[r]).translation - self.tasks[r].transform_target_to_world.translation)
            for r in self.kp.frames if r.startswith(("hip", "knee", "sole"))))
