"""Streaming mode: a demonstration adapted one frame at a time (``mode="per_frame"``, or
:class:`StreamingAdaptor` for live input), in real time.

Each frame is one quadratic program at the committed state (:mod:`.receding`): frame k's step
chooses knot k − 1's acceleration and contact wrenches at its configuration and velocity —
where the whole-body dynamics, the contact wrench cones and the torque limits are linear, so
they hold exactly, not linearised — and integrates them exactly (``v_k = v_{k−1} + h a``,
``q_k = q_{k−1} ⊕ h v_k``). So each frame is final one frame late: ``a`` and the wrenches of
frame k − 1 come with frame k's step, those of the last frame from :meth:`StreamingAdaptor.final`.
No frame waits for later ones (no latency beyond that one frame): the swing feet land early
and wait, still and flat, for the demonstration's touch-down (:mod:`.frameref`). The first
frame is the robot at rest in the demonstrator's first pose (:func:`.frameref.initial_pose`).

Each frame's feasibility flag is the audit's knot verdict (:func:`gdimitate.audit.audit`),
recomputed from the output, never read from the QP: by :class:`StreamingAdaptor` frame by
frame (:func:`.verdict_worker.knot_verdicts`, its one definition: on the frames it reads, the
same verdict as the audit of the whole assembled motion), by default in a worker process that
delivers frame k's verdict a few frames later without slowing the next frame
(``FrameResult.verdicts``, :meth:`StreamingAdaptor.verdicts`); for the whole motion, knot by
knot, in :func:`adapt_per_frame`. Force models: ``segment``,
``com`` and ``measured`` (the demonstrator's measured force of the frame, ``step(...,
forces=...)``); the goal — the robot's contact force along the demonstrator's — is a soft
task; ``dynamics`` needs the demonstrator's future accelerations.
"""

from __future__ import annotations

import time
import warnings
import weakref
from contextlib import nullcontext
from os import PathLike
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ...assess.audit import AuditTolerances
from ...assess.result import AdaptedMotion, compare
from ...assess.solver import SolverInfo
from ...errors import GdimitateWarning, InvalidInputError, UnknownNameError
from ...model.contact import ContactForces, SoleContact
from ...model.heading import Turn, facing_yaw
from ...model.kinematics import robot_motion
from ...model.motion import Motion
from ...model.robot import SIDES, Robot
from .. import limits as limits_mod
from ..bodymap import BodyMap, body_map
from ..info import limited_robot, resolve_contacts
from ..knot import base_dofs
from ..params import Contact, Limits, Weights
from ..threads import hold_one_thread, single_thread
from .frameref import FrameReference, initial_pose, initial_velocity
from .receding import FrameQP
from .verdict_worker import InlineVerdicts, VerdictWorker, can_fork, knot_verdicts

__all__ = ["StreamingAdaptor", "FrameResult", "adapt_per_frame", "STREAMING_FORCE_MODELS"]

STREAMING_FORCE_MODELS = ("segment", "com", "measured")
#: who judges each frame (:class:`StreamingAdaptor`'s ``audit``): a worker process, the
#: caller's thread (on the hot path), nobody
AUDIT_MODES = ("worker", "inline", "off")
#: a step that would make any velocity component larger than this [rad/s, m/s] is not taken
#: (the robot coasts: the audit fails those frames)
MAX_SPEED = 100.0
_STATUS = {1: "QP", 2: "QP, relaxed", -99: "coasting"}
#: how a stream given no ``v_demo`` starts (:class:`StreamingAdaptor`'s ``start``):
#: ``"estimate"`` waits for its second frame and starts there, moving with the demonstrator's
#: velocity estimated from the two; ``"rest"`` starts at its first frame at rest
STARTS = ("estimate", "rest")
#: a foot the demonstration puts down starts its stance at the next frame when its sole's
#: highest corner is at most LANDED_GAP [m] above the floor (under the audit's ``contact_gap``
#: tolerance, 1 mm; a swing sole's corners stay 0.5 mm above it, ``receding.FLOOR_MARGIN``)
#: and it moves slower than LANDED_SPEED [m/s]; until then it lands (its resting pose, a hard
#: row). Stance taken at the demonstration's flag instead held a sole that had not landed
#: where it was: Talos joining the shipped walk at rest hovered 3.7 mm up for 46 frames.
LANDED_GAP, LANDED_SPEED = 9e-4, 0.05
#: a stance whose sole is further above the floor than the audit's ``contact_gap`` tolerance
#: [m] is not kept: the foot lands again, and where the other is not down either the robot is
#: in the air until one lands (its stance held it where it was — a live stream's step after a
#: restart, whose gap of dropped frames made it long, left G1's left sole 1.6 mm up for the 68
#: frames of its stance; kept down as the only support, a sole 10.8 mm up for 13 frames)
_TOLERANCES = AuditTolerances()
HOVER_GAP = _TOLERANCES.contact_gap
#: after RECOVER_AFTER lost frames in a row — whose hard rows could not all hold (relaxed,
#: failed or coasting), or whose stance sole slipped past the audit's tolerance — the stream
#: starts again at the next frame, as a stream joined there does: the robot stood where it
#: stands, in the demonstration's pose of that frame, moving with its velocity estimated
#: from the last two frames (:meth:`StreamingAdaptor._recover`; the frame it jumps at fails
#: the audit, and says ``"recovered"``). Without it a relaxed frame was never undone: G1
#: joined 1.0 s into the 3-D walk lost every frame from its 83rd on, its wrenches at 14 kN
#: (76 of 151 frames feasible; 146 after two lost frames, 147 after one)
RECOVER_AFTER = 1


class FrameResult(NamedTuple):
    """One :meth:`StreamingAdaptor.step`: the new frame's ``q`` ``(nq,)`` and ``v`` ``(nv,)``;
    the previous frame, now final (``None`` at the first step): its ``a`` ``(nv,)``,
    ``wrenches`` ``{side: (6,)}`` [N, N·m, sole frames] and ``feasible`` (its verdict if it
    is known at this step: with ``audit="inline"``, except a frame before a restart, whose
    verdict may wait for the next acceleration; ``None`` with the worker, which delivers
    it a few frames later in ``verdicts``, and with ``audit=False``); the step's ``status``
    (``"QP"``: every hard row held; ``"QP, relaxed"``: some could not; ``"rest pose"`` at
    the first frame), ``iterations`` and ``time_s`` [s] (the frame's solve, the verdict's
    bookkeeping left out); ``verdicts`` ``((frame, feasible), ...)``: the verdicts (the
    audit's knot verdict; frames counted from 0 since the last
    :meth:`~StreamingAdaptor.reset`) delivered since the previous step, in frame order;
    ``contact`` ``{side: bool}``: the new frame's stance flags, the robot's own — the
    demonstration's, except that a foot it puts down starts its stance only once its sole
    is on the floor (:data:`LANDED_GAP`), one frame or more later (the audit's and the
    verdicts' contact schedule)."""

    q: np.ndarray
    v: np.ndarray
    previous_a: np.ndarray | None
    previous_wrenches: dict | None
    previous_feasible: bool | None
    status: str
    iterations: int
    time_s: float
    verdicts: tuple[tuple[int, bool], ...] = ()
    contact: dict | None = None


class StreamingAdaptor:
    """Adapt a demonstration frame by frame (module docstring).

    ``demonstrator``, ``imitator``: robots; ``force``: one of
    :data:`STREAMING_FORCE_MODELS`; ``weights``: accepted for the trajectory mode's signature
    (the per-frame QP has its own task weights, :class:`~.receding.Gains`); ``limits``,
    ``contact``: as for :func:`~.solve.adapt_optimal` (the ``"all"`` contact rule only);
    ``contacts``: sole overrides; ``body_map``: a map, a naming family or a JSON file of either
    (:func:`~gdimitate.retarget.bodymap.body_map`); ``dt`` [s]: default frame period; ``ipopt``:
    unused (no NLP runs; a non-default ``weights`` or any ``ipopt`` warns); ``audit``: who
    judges each frame (:data:`AUDIT_MODES`) — ``True``/``"worker"``: a worker process forked
    at construction (:class:`~.verdict_worker.VerdictWorker`; ``"inline"`` where the platform
    cannot fork), fed each committed frame, whose verdicts arrive in later steps'
    ``FrameResult.verdicts`` and in :meth:`verdicts`; ``"inline"``: in :meth:`step` itself
    (the previous frame's, ``FrameResult.previous_feasible``: ~20 ms a frame on Talos);
    ``False``/``"off"``: none (audit the assembled motion afterwards, as
    :func:`adapt_per_frame` does). Both judges run :func:`.verdict_worker.knot_verdicts` and
    give the same verdicts. While open, the adaptor holds NumPy's and CasADi's BLAS to one
    thread (:func:`~gdimitate.retarget.threads.hold_one_thread`: setting it back after each
    frame woke OpenBLAS's threads, which spun on the worker's core). :meth:`close` (or a
    ``with`` block) stops the worker and gives the threads back; so do garbage collection
    and the interpreter's exit. ``start`` (:data:`STARTS`): a stream given
    no ``v_demo`` at its first frame — a live one, or one joined mid-walk — waits for its
    second frame (``"estimate"``: the first frame's result is a preview, the rest pose, with
    ``status="waiting"`` and the verdict False; :attr:`first_frame` is then 1) and starts
    there moving with the demonstrator's velocity estimated from the two frames; or starts at
    rest at its first frame (``"rest"``; from rest a robot cannot catch up with a walk it
    joined: on the shipped walk 1.0 s in, Talos's frames were 56 of 65 feasible so against
    65 of 65).
    """

    def __init__(self, demonstrator: Robot, imitator: Robot, force: str = "segment", *,
                 weights: Weights | None = None, limits: Limits | None = None,
                 contact: Contact | None = None, contacts: dict | None = None,
                 body_map: BodyMap | dict | str | PathLike | None = None, dt: float = 1 / 60,
                 ipopt: dict | None = None, audit: bool | str = True,
                 start: str = "estimate"):
        if force not in STREAMING_FORCE_MODELS:
            raise UnknownNameError("streaming force model", force, STREAMING_FORCE_MODELS)
        if start not in STARTS:
            raise UnknownNameError("stream start", start, STARTS)
        self.start = start
        if not (np.isfinite(dt) and dt > 0):
            raise InvalidInputError(f"dt must be a positive period in seconds; got {dt!r}")
        self.contact = contact or Contact()
        if self.contact.rule != "all":
            raise InvalidInputError("the streaming mode needs contact rule 'all' (the anchor "
                                    "rule looks at the whole stance history)")
        self.demonstrator, self.imitator, self.force, self.dt = (demonstrator, imitator, force,
                                                                 float(dt))
        self.weights, self.limits = weights or Weights(), limits or Limits()
        if self.weights != Weights() or ipopt:  # said, not silently dropped
            warnings.warn(GdimitateWarning(
                "the per-frame mode ignores weights= and ipopt= (its QP has its own task "
                "weights, gdimitate.retarget.receding.Gains; no NLP runs): use "
                "mode='trajectory' for them"), stacklevel=2)
        self.audit_mode = _audit_mode(audit)
        self.audit = self.audit_mode != "off"
        self.contacts: dict[str, SoleContact] = resolve_contacts(imitator, self.contact,
                                                                 contacts)
        bm = body_map if isinstance(body_map, BodyMap) else None
        self.body_map = bm or _body_map(demonstrator, imitator, body_map)
        base, act = base_dofs(imitator)
        self._lim = limits_resolved = limits_mod.resolve(imitator, act, self.limits)
        self._act_names = limits_resolved.names
        self._act = np.array([imitator.idx_v(n) for n in self._act_names], int)
        self._audit_robot = limited_robot(imitator, limits_resolved)
        self._qp = FrameQP(self._audit_robot, self.contacts, base, self._act,
                           self.contact.f_min, self.contact.cop_margin)
        self._fid = {s: imitator.model.getFrameId(self.contacts[s].frame) for s in SIDES}
        self._judge: InlineVerdicts | VerdictWorker | None = None
        #: one BLAS thread while open (:func:`~..threads.hold_one_thread`): released by
        #: close(), garbage collection or the interpreter's exit
        self._one_thread = weakref.finalize(self, hold_one_thread())
        self.reset()
        judge_args = (self._audit_robot, self.contacts, self.contact.cone_half_angle)
        if self.audit_mode == "worker":
            self._judge = VerdictWorker(*judge_args)
        elif self.audit_mode == "inline":
            self._judge = InlineVerdicts(*judge_args)

    def reset(self) -> None:
        """Forget the previous frames."""
        self._ref = FrameReference(self.demonstrator, self.imitator, self.body_map,
                                   self._act_names, self.force)
        self._hist: dict[str, list] = {k: [] for k in ("t", "q", "v", "a", "c", "w")}
        self._anchor: dict[str, pin.SE3] = {}
        self._lift: dict[str, float] = {}  # the demonstration's lift-offs [s]
        self._demo_flags: dict[str, bool] = {}
        self._a_prev = np.zeros(self.imitator.model.nv)
        self._n = 0
        self._turns: tuple[Turn, Turn] | None = None  # into the stream's frame, and back
        self._verdicts: list[bool] = []  # the motion's frames 0, 1, ... judged so far
        #: the first frame while it waits for the second (start="estimate"): (q_demo, flags,
        #: forces)
        self._waiting: tuple[np.ndarray, dict, dict | None] | None = None
        self._skip = 0  # stream frames before the motion's first (the one that waited)
        self._lost = 0  # lost frames in a row (RECOVER_AFTER)
        #: the last restart (:meth:`_recover`): its frame and the demonstration's flags there
        self._restart: tuple[int, dict] = (-1, {})
        #: final()'s verdicts: (first knot, [ok, ...]) of the last two frames
        self._final_verdicts: tuple[int, list[bool]] | None = None
        if self._judge is not None:
            self._judge.reset()

    # ------------------------------------------------------------------ one frame
    def step(self, q_demo: np.ndarray, contact: dict[str, bool], dt: float | None = None,
             forces: dict[str, np.ndarray] | None = None, verbose: bool = False,
             v_demo: np.ndarray | None = None) -> FrameResult:
        """Adapt one demonstrator configuration ``q_demo`` ``(nq_demo,)`` with its stance flags
        ``{"left": bool, "right": bool}``; ``dt`` [s] since the previous frame; ``forces``
        ``{side: (3,)}`` [N] the measured ground force on each foot (``force="measured"``);
        ``v_demo`` ``(nv_demo,)`` [rad/s, m/s]: the demonstrator's velocity, read at the first
        frame only — the robot then starts moving with it (scaled) instead of at rest (a walk
        joined mid-stride cannot be caught from a standstill within a step).

        Nothing assumes a heading: the stream is adapted in the frame of its first
        configuration — the world turned about the vertical through the first base position
        by the base's facing yaw there (:func:`~gdimitate.heading.facing_yaw`) — and each
        ``q`` turned back, so a stream turned about the vertical gives the same motion up to
        that turn (velocities, accelerations and sole wrenches are in local frames)."""
        d = self.demonstrator
        q_demo = np.asarray(q_demo, dtype=float)
        if q_demo.shape != (d.model.nq,):
            raise InvalidInputError(f"q_demo must have shape ({d.model.nq},) for {d.name}; "
                                    f"got {q_demo.shape}")
        if not self._hist["t"] and self._waiting is None:
            yaw, about = stream_frame(d, q_demo)
            self._turns = (Turn(-yaw, about), Turn(yaw, about)) if yaw else None
        turns = self._turns
        if turns is not None:
            q_demo = turns[0].configurations(q_demo)
            R = turns[0].R
            forces = None if forces is None else {s: R @ np.asarray(f, float)
                                                  for s, f in forces.items()}
        r = self._step(q_demo, contact, dt, forces, v_demo)
        if turns is not None and self.imitator.base == "free":  # a planar imitator walks in
            r = r._replace(q=turns[1].configurations(r.q))  # its x–z plane
        return r

    def _step(self, q_demo: np.ndarray, contact: dict[str, bool], dt: float | None,
              forces: dict[str, np.ndarray] | None, v_demo: np.ndarray | None) -> FrameResult:
        """:meth:`step` in the stream's frame."""
        if set(contact) != set(SIDES):
            raise InvalidInputError(f"contact must give 'left' and 'right'; got {list(contact)}")
        if self.force == "measured" and forces is None:
            raise InvalidInputError("force='measured' needs forces={side: (3,)} at each step")
        dt = self.dt if dt is None else float(dt)
        if not (np.isfinite(dt) and dt > 0):
            raise InvalidInputError(f"dt must be a positive period in seconds; got {dt!r}")
        H = self._hist
        t = H["t"][-1] + dt if H["t"] else 0.0
        flags = {s: bool(contact[s]) for s in SIDES}
        t0 = time.perf_counter()
        if not H["t"] and v_demo is None and self.start == "estimate":
            if self._waiting is None:
                return self._wait(q_demo, flags, forces, t0)
            v_demo = pin.difference(self.demonstrator.model, self._waiting[0], q_demo) / dt
            self._waiting, self._skip = None, 1
        self._ref.frames.append(self._ref.features(t, q_demo, flags, forces))
        if not H["t"]:
            return self._first(t, flags, t0, v_demo)
        if self._lost >= RECOVER_AFTER:
            return self._recover(t, flags, t0)
        own = self._own_flags(flags)
        with self._threads():
            a, W, flag = self._solve(len(H["t"]) - 1, own)
        v_next = H["v"][-1] + self._h * a
        if not (np.all(np.isfinite(a)) and all(np.all(np.isfinite(W[s])) for s in SIDES)
                and np.max(np.abs(v_next)) < MAX_SPEED):  # no usable step: coast
            a, W, flag = np.zeros_like(a), {s: np.zeros(6) for s in SIDES}, -99
        q, v = self._commit(t, flags, own, a, W)
        self._lost = self._lost + 1 if flag != 1 or self._slipped(own) else 0
        elapsed = time.perf_counter() - t0
        new, ok = self._judged()
        self._n += 1
        return FrameResult(q.copy(), v.copy(), a.copy(), {s: W[s].copy() for s in SIDES}, ok,
                           _STATUS.get(flag, f"QP failed ({flag})"), 1, elapsed, new,
                           dict(own))

    def _own_flags(self, flags: dict) -> dict:
        """The robot's stance flags for the new frame, from the demonstration's ``flags``: a
        foot already in stance, or one that has landed (:data:`LANDED_GAP`,
        :data:`LANDED_SPEED`), may be down; a foot the demonstration lifts is lifted, unless
        the other has not landed yet (it then stays down: no flight the demonstration does
        not have); a stance sole above the floor (:data:`HOVER_GAP`) lands again."""
        H = self._hist
        was = H["c"][-1]
        prev = dict(was)
        if any(was.values()):
            m, data = self.imitator.model, self._qp.d1
            pin.framesForwardKinematics(m, data, H["q"][-1])
            for s in SIDES:
                if was[s] and self._top(data, s) > HOVER_GAP:
                    prev[s] = False
        out = dict(flags) if all(prev[s] or not flags[s] for s in SIDES) else \
            self._landed(flags, prev)
        for s in SIDES:
            if prev[s] and not out[s] and not any(out.values()) and any(flags.values()):
                out[s] = True
        return out

    def _landed(self, flags: dict, prev: dict) -> dict:
        """:meth:`_own_flags` before its no-flight rule: the demonstration's ``flags`` with a
        foot it puts down kept in swing until its sole is on the floor."""
        m, data = self.imitator.model, self._qp.d1
        H = self._hist
        pin.forwardKinematics(m, data, H["q"][-1], H["v"][-1])
        pin.updateFramePlacements(m, data)
        out = {}
        for s in SIDES:
            if not flags[s] or prev[s]:
                out[s] = flags[s]
                continue
            speed = float(np.linalg.norm(pin.getFrameVelocity(
                m, data, self._fid[s], pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).linear))
            out[s] = self._top(data, s) <= LANDED_GAP and speed <= LANDED_SPEED
        return out

    def _top(self, data, side: str) -> float:
        """The height [m] of sole ``side``'s highest corner, placed by ``data``."""
        oMf = data.oMf[self._fid[side]]
        return float(np.max(oMf.translation[2] + self.contacts[side].corners() @
                            oMf.rotation[2]))

    @property
    def first_frame(self) -> int:
        """The stream frame (counted from 0 since the last :meth:`reset`) that is the motion's
        first: 1 when the first waited for the second (``start="estimate"`` without
        ``v_demo``), else 0."""
        return self._skip

    def _wait(self, q_demo: np.ndarray, flags: dict, forces, t0: float) -> FrameResult:
        """The first frame of a stream without the demonstrator's velocity: kept, and shown
        as the rest pose it would start from (a preview, not a frame of the motion)."""
        f0 = self._ref.features(0.0, q_demo, flags, forces)
        q = initial_pose(self.imitator, self._ref, f0, self._act, None)  # (a preview: no
        # collision rows, which cost ~0.2 s)
        self._waiting = (q_demo.copy(), flags, forces)
        return FrameResult(q, np.zeros(self.imitator.model.nv), None, None, None, "waiting",
                           0, time.perf_counter() - t0, (), dict(flags))

    def _first(self, t: float, flags: dict, t0: float, v_demo) -> FrameResult:
        f0 = self._ref.frames[0]
        moving = v_demo is not None
        if moving:
            v_demo = np.asarray(v_demo, float)
            if v_demo.shape != (self.demonstrator.model.nv,):
                raise InvalidInputError(f"v_demo must have shape "
                                        f"({self.demonstrator.model.nv},); got {v_demo.shape}")
        q, v0 = self._start_state(f0, f0, v_demo)
        self._append(t, q, v0, flags)
        self._demo_flags = dict(flags)
        elapsed = time.perf_counter() - t0
        new, _ = self._judged()
        self._n += 1
        return FrameResult(q.copy(), v0.copy(), None, None, None,
                           "moving start" if moving else "rest pose", 0, elapsed, new,
                           dict(flags))

    def _start_state(self, f0: dict, at: dict, v_demo: np.ndarray | None
                     ) -> tuple[np.ndarray, np.ndarray]:
        """``(q (nq,), v (nv,))`` of a start at the demonstration's frame ``f0`` (its
        features), the soles placed where the demonstrator's of ``at`` are, scaled (``at``
        is ``f0`` moved along the floor: a restart stands where the robot is); moving with
        ``v_demo`` (scaled; None: at rest). The reference, the stance anchors and the
        stance flags start there."""
        moving = v_demo is not None
        cv = None
        if moving:
            # the demonstrator's scratch Data (as the reference's features use it): creating a
            # human's takes ~50 ms (eight nv³ tensors), most of a restart's cost
            dm, dd = self.demonstrator.model, self.demonstrator.data
            pin.centerOfMass(dm, dd, f0["q"], v_demo)
            cv = self._ref.k * dd.vcom[0]
        q = initial_pose(self.imitator, self._ref, at, self._act, cv, collision=self._qp.sc)
        v0 = (initial_velocity(self.imitator, q, self._ref, f0, v_demo, self._act)
              if v_demo is not None else np.zeros(self.imitator.model.nv))
        # scaled down, as a whole (the soles stay still), into the joints' velocity limits
        # (Romeo's hips: 2.1 rad/s, the demonstrator's swing hip moves faster)
        vel = np.asarray(self._audit_robot.model.velocityLimit)[self._act]
        ok = np.isfinite(vel) & (vel > 0)
        peak = np.abs(v0[self._act][ok]) / vel[ok] if ok.any() else np.zeros(1)
        if peak.size and peak.max() > 0.9:
            v0 = v0 * (0.9 / peak.max())
        m, data = self.imitator.model, self.imitator.model.createData()
        pin.framesForwardKinematics(m, data, q)
        feet = {s: data.oMf[self._fid[s]].copy() for s in SIDES}
        from ...model.kinematics import base_joint_id

        self._ref.start(f0, pin.centerOfMass(m, data, q), feet,
                        data.oMi[base_joint_id(self.imitator)].rotation.copy(), moving)
        self._anchor = {s: feet[s] for s in SIDES if f0["contact"][s]}
        return q, v0

    def _recover(self, t: float, flags: dict, t0: float) -> FrameResult:
        """Start again at this frame (:data:`RECOVER_AFTER`): the last knot's ``a`` and
        wrenches are its QP's, the new frame's state a start (:meth:`_start_state`) with the
        demonstrator's velocity estimated from the last two frames, its soles where the
        robot's stance soles are (the demonstration's moved along the floor by the
        difference, unscaled)."""
        H, F = self._hist, self._ref.frames
        f0, f_prev = F[-1], F[-2]
        dt = f0["t"] - f_prev["t"]
        v_demo = pin.difference(self.demonstrator.model, f_prev["q"], f0["q"]) / max(dt, 1e-9)
        m, data = self.imitator.model, self._qp.d1
        pin.framesForwardKinematics(m, data, H["q"][-1])
        down = [s for s in SIDES if H["c"][-1][s]] or list(SIDES)
        here = np.mean([data.oMf[self._fid[s]].translation[:2] for s in down], axis=0)
        there = np.mean([f0["soles"][s].translation[:2] for s in down], axis=0)
        shift = np.r_[here / self._ref.s - there, 0.0]
        at = {**f0, "soles": {s: pin.SE3(p.rotation, p.translation + shift)
                              for s, p in f0["soles"].items()}, "com": f0["com"] + shift}
        a, W, _ = self._solve(len(H["t"]) - 1, H["c"][-1])
        self._ref.lift = {s: None for s in SIDES}
        q, v = self._start_state(f0, at, v_demo)
        H["a"].append(a)
        H["w"].append(W)
        self._a_prev = np.zeros_like(a)
        self._demo_flags = dict(flags)
        # the robot's own flags at the jump: no stance, so that each stance after it begins
        # at the next frame (the audit's slip is measured from a stance's first frame); its
        # QP stands on the demonstration's (:meth:`_solve`)
        lifted = {s: False for s in SIDES}
        self._append(t, q, v, lifted)
        self._restart = (len(H["t"]) - 1, dict(flags))
        self._lost = 0
        new, ok = self._judged()
        self._n += 1
        return FrameResult(q.copy(), v.copy(), a.copy(), {s: W[s].copy() for s in SIDES}, ok,
                           "recovered", 1, time.perf_counter() - t0, new, lifted)

    def _solve(self, j: int, nxt: dict) -> tuple[np.ndarray, dict, int]:
        """Knot ``j``'s QP (the next knot's stance flags ``nxt``)."""
        H = self._hist
        q, v = H["q"][j], H["v"][j]
        F = self._ref.frames
        h = F[j + 1]["t"] - H["t"][j] if j + 1 < len(F) else self.dt
        m, data = self.imitator.model, self._qp.d
        pin.framesForwardKinematics(m, data, q)
        feet = {s: data.oMf[self._fid[s]].copy() for s in SIDES}
        c = pin.centerOfMass(m, data, q, v)
        tk = self._ref.tasks(j, nxt, feet, self._anchor, (c.copy(), data.vcom[0].copy()))
        now = self._restart[1] if self._restart[0] == j else H["c"][j]
        a, W, flag = self._qp.solve(q, v, h, now, nxt, tk, self._a_prev)
        self._h = h
        return a, W, flag

    def _commit(self, t: float, flags: dict, own: dict, a: np.ndarray, W: dict):
        """Knot j's ``a``, wrenches final; knot k's ``q``, ``v`` by exact integration, its
        stance flags ``own`` (the robot's; ``flags``: the demonstration's, whose touch-downs
        time the next swings)."""
        H, m = self._hist, self.imitator.model
        v = H["v"][-1] + self._h * a
        q = pin.integrate(m, H["q"][-1], self._h * v)
        H["a"].append(a)
        H["w"].append(W)
        self._a_prev = a
        prev, demo_prev = H["c"][-1], self._demo_flags
        data = self._qp.d1
        pin.framesForwardKinematics(m, data, q)
        for s in SIDES:
            if own[s] and not prev[s]:  # touch-down: the stance's pose is this one
                self._anchor[s] = data.oMf[self._fid[s]].copy()
            elif not own[s]:
                self._anchor.pop(s, None)
            if flags[s] and not demo_prev[s] and s in self._lift:
                self._ref.touched_down(s, t - self._lift.pop(s), t)
            elif not flags[s] and demo_prev[s]:
                self._lift[s] = t
        self._demo_flags = dict(flags)
        self._append(t, q, v, own)
        return q, v

    def _slipped(self, own: dict) -> bool:
        """Whether a foot in stance since an earlier frame has moved, at the frame just
        committed, further from where its stance began than the audit allows (its ``slip``
        and ``slip_rotation`` tolerances): the frame is lost though its QP held."""
        data, tol = self._qp.d1, _TOLERANCES  # _commit's kinematics of the new frame
        for s, start in self._anchor.items():
            if not own[s]:
                continue
            now = data.oMf[self._fid[s]]
            if (np.linalg.norm(now.translation - start.translation) > tol.slip
                    or np.linalg.norm(pin.log3(start.rotation.T @ now.rotation))
                    > tol.slip_rotation):
                return True
        return False

    def _append(self, t: float, q: np.ndarray, v: np.ndarray, c: dict) -> None:
        """Commit a new frame's time [s], ``q`` ``(nq,)``, ``v`` ``(nv,)`` and the robot's
        own stance flags to the history."""
        for k, x in (("t", t), ("q", q), ("v", v), ("c", c)):
            self._hist[k].append(x)

    def final(self) -> tuple[np.ndarray, dict, bool | None]:
        """``(a (nv,), wrenches {side: (6,)}, feasible)`` of the last frame, from its own
        QP (call after the last :meth:`step`); ``feasible``: its verdict (judged here, on the
        frames it reads: :func:`.verdict_worker.knot_verdicts`), None with ``audit=False``;
        :meth:`verdicts` then includes it and the frame before's."""
        H = self._hist
        if not H["t"] and self._waiting is not None:  # one frame in all: it starts at rest
            q_demo, flags, forces = self._waiting
            self._waiting = None
            self._ref.frames.append(self._ref.features(0.0, q_demo, flags, forces))
            self._first(0.0, flags, time.perf_counter(), None)
        j = len(H["t"]) - 1
        if j < 0:
            raise InvalidInputError("final() needs at least one step()")
        with self._threads():
            a, W, _ = self._solve(j, H["c"][j])
        ok = None
        if self.audit:  # the frame before may have waited for this acceleration
            first = max(j - 1, 0)
            oks = knot_verdicts(self._audit_robot, self.contacts, self.contact.cone_half_angle,
                                H, first, j, tail=(a, W))
            self._final_verdicts = (first, [bool(x) for x in oks])
            ok = bool(oks[-1])
        return a, W, ok

    def _threads(self):
        """A solve's thread context: nothing while the adaptor holds one thread, one for the
        block after :meth:`close`."""
        return nullcontext() if self._one_thread.alive else single_thread()

    # ------------------------------------------------------------------ the verdicts
    def _judged(self) -> tuple[tuple[tuple[int, bool], ...], bool | None]:
        """Hand the judge the frame just committed; ``(verdicts delivered since the last
        step, the previous frame's verdict or None)``."""
        if self._judge is None:
            return (), None
        H = self._hist
        k = len(H["t"]) - 1
        prev = (H["a"][-1], H["w"][-1]) if k else (None, None)
        self._judge.add((H["t"][k], H["q"][k], H["v"][k], H["c"][k], *prev))
        got = tuple(self._judge.collect())
        self._verdicts.extend(ok for _, ok in got)
        new = tuple((f + self._skip, ok) for f, ok in got)
        if k == 0 and self._skip:  # the frame that waited: a preview, not feasible
            new = ((0, False), *new)
        return new, (self._verdicts[k - 1] if 0 < k <= len(self._verdicts) else None)

    def verdicts(self, wait: bool = True, timeout: float | None = None) -> np.ndarray:
        """``(K,)`` bool: the verdicts of frames ``0..K−1`` delivered so far (each the
        audit's knot verdict; a first frame that waited, :attr:`first_frame`: False).
        ``wait``: first wait for every frame's — all but the newest, whose verdict needs the
        next frame, and the one before where it waits for the newest's acceleration
        (:func:`.verdict_worker.knot_verdicts`); :meth:`final` judges both —
        at most ``timeout`` [s] (None: no limit; :class:`~.verdict_worker.VerdictWorkerError`
        when it passes or the worker failed). After :meth:`close`: those delivered before.
        Raises :class:`~gdimitate.errors.InvalidInputError` with ``audit=False``."""
        if not self.audit:
            raise InvalidInputError("no verdicts: this StreamingAdaptor was made with "
                                    "audit=False")
        if self._judge is not None:
            self._verdicts.extend(ok for _, ok in self._judge.collect(wait, timeout))
        out = list(self._verdicts)
        fin = self._final_verdicts
        if fin is not None and fin[0] <= len(out) and fin[0] + len(fin[1]) == len(
                self._hist["t"]):
            out = out[:fin[0]] + fin[1]
        return np.array([False] * self._skip + out, bool)

    def close(self) -> None:
        """Stop the verdict worker, keeping the verdicts delivered so far (:meth:`verdicts`);
        later steps are not judged; give back the BLAS threads (the adaptor holds one while
        open: :func:`~gdimitate.retarget.threads.hold_one_thread`). Idempotent; ``with
        StreamingAdaptor(...) as sa:`` calls it at the block's end."""
        self._one_thread()
        if self._judge is not None:
            judge, self._judge = self._judge, None
            try:
                self._verdicts.extend(ok for _, ok in judge.collect())
            finally:
                judge.close()

    def __enter__(self) -> StreamingAdaptor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _audit_mode(audit: bool | str) -> str:
    """``audit=`` as one of :data:`AUDIT_MODES` (True: ``"worker"``, or ``"inline"`` where
    the platform cannot fork; False: ``"off"``)."""
    if isinstance(audit, (bool, np.bool_)):
        return ("worker" if can_fork() else "inline") if audit else "off"
    if audit not in AUDIT_MODES:
        raise UnknownNameError("audit mode", audit, AUDIT_MODES)
    return str(audit)


def streamed_info(status: str, ok: np.ndarray, time_s: float) -> SolverInfo:
    """The solver record of a streamed motion of ``ok.size`` frames (``ok``: each frame's
    verdict): ``status``, one QP per frame after the first (``iterations``), ``time_s`` [s].
    No goal is listed unmet and nothing is elastic: a frame that fails is said by the audit,
    check by check (the verdict's reasons), and counted by ``frame_feasible`` — not a
    second time as a goal "off by 1"."""
    T = int(ok.size)
    return SolverInfo(status=status, success=bool(ok.all()), iterations=max(T - 1, 0),
                      time_s=float(time_s), build_s=0.0, cached=True, elastic=False, knots=T,
                      variables=0, constraints=0, unmet=())


def stream_frame(demonstrator: Robot, q0: np.ndarray) -> tuple[float, np.ndarray]:
    """``(yaw [rad], about (2,) [m])``: the frame a stream is adapted in
    (:meth:`StreamingAdaptor.step`), from its first configuration ``q0``; ``(0, 0)`` for a
    demonstrator without a free-flyer base."""
    if demonstrator.base != "free":
        return 0.0, np.zeros(2)
    yaw = float(facing_yaw(q0[None, :], demonstrator.base_rotation)[0])
    return yaw, np.array(q0[:2], float)


def _body_map(demonstrator: Robot, imitator: Robot, given) -> BodyMap:
    return body_map(demonstrator, imitator, given)


def adapt_per_frame(demo: Motion, demonstrator: Robot, imitator: Robot, force: str = "segment",
                    forces: ContactForces | None = None, weights: Weights | None = None,
                    limits: Limits | None = None, contact: Contact | None = None,
                    contacts: dict | None = None, body_map=None, tol: float = 1e-6,
                    ipopt: dict | None = None):
    """:class:`StreamingAdaptor` over every frame of ``demo`` (what ``adapt(...,
    method="optimal", mode="per_frame")`` runs). Returns an
    :class:`~gdimitate.adapt.AdaptedMotion` whose ``motion`` has the frames' ``q``, ``v``,
    ``a``, whose ``solver`` is a :class:`~.info.SolverInfo` (frames per second in
    ``time_s``/``knots``) and whose ``frame_feasible`` ``(T,)`` are the per-frame flags —
    the audit of the assembled motion, knot by knot, run once after the frames (also in
    ``solver``'s ``unmet`` when some frames fail); ``audit`` is that whole motion's. The
    motion's stance flags are the imitator's own (:attr:`FrameResult.contact`)."""
    from ...assess.audit import audit

    if demo.base_nq and demo.q.shape[1] != demonstrator.model.nq:
        raise InvalidInputError("the demonstration does not match the demonstrator")
    if force == "measured" and forces is None:
        raise InvalidInputError("force='measured' needs forces= (the measured ground forces)")
    ad = StreamingAdaptor(demonstrator, imitator, force, weights=weights, limits=limits,
                          contact=contact, contacts=contacts, body_map=body_map, dt=demo.dt,
                          ipopt=ipopt, audit=False)
    T = demo.T
    nq, nv = imitator.model.nq, imitator.model.nv
    q, v, a = np.zeros((T, nq)), np.zeros((T, nv)), np.zeros((T, nv))
    W = {s: np.zeros((T, 6)) for s in SIDES}
    contact_used = {s: np.zeros(T, bool) for s in SIDES}  # the imitator's own stance flags
    statuses = []
    v0 = None
    if T > 1:  # the demonstrator's velocity at the first frame: start moving with it
        v0 = pin.difference(demonstrator.model, demo.q[0], demo.q[1]) / (demo.t[1] - demo.t[0])
    t0 = time.perf_counter()
    for k in range(T):
        f_k = None
        if force == "measured" and forces is not None:  # None refused above
            f_k = {s: np.array([np.interp(demo.t[k], forces.t, forces[s].force[:, i])
                                for i in range(3)]) for s in SIDES}
        dt = demo.t[k] - demo.t[k - 1] if k else demo.dt
        r = ad.step(demo.q[k], {s: bool(demo.contact[s][k]) for s in SIDES}, dt, f_k,
                    v_demo=v0 if k == 0 else None)
        q[k], v[k] = r.q, r.v
        assert r.contact is not None  # every step says the robot's stance
        for s in SIDES:
            contact_used[s][k] = r.contact[s]
        if k:
            a[k - 1] = r.previous_a
            assert r.previous_wrenches is not None  # every frame after the first settles one
            for s in SIDES:
                W[s][k - 1] = r.previous_wrenches[s]
        statuses.append(r.status)
    a[-1], wl, _ = ad.final()
    ad.close()
    for s in SIDES:
        W[s][-1] = wl[s]
    elapsed = time.perf_counter() - t0
    motion = robot_motion(imitator, demo.t, q, contact_used).replace(v=v, a=a)
    aud = audit(ad._audit_robot, motion, W, ad.contacts,
                cone_half_angle=ad.contact.cone_half_angle)
    ok = np.asarray(aud.knot_feasible, bool)  # every frame's verdict, off the hot path
    report = compare(demonstrator, demo, imitator, motion, "optimal",
                     {s: ok.copy() for s in SIDES}, force if force != "measured" else "segment")
    info = streamed_info(max(set(statuses), key=statuses.count), ok, elapsed)
    return AdaptedMotion(motion=motion, report=report, robot=imitator, wrenches=W,
                         contacts=dict(ad.contacts), audit=aud, solver=info,
                         force_model=force, frame_feasible=ok)
