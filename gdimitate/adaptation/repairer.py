"""Repair a robot motion from any retargeter on its own robot: the whole-body adaptor with the
same robot as demonstrator and imitator (docs/guide/datasets.md; docs/design.md §6, §12).

:func:`repair` takes a robot motion (GMR's, holosoma's, a joint-angle copy: any
:class:`~gdimitate.Motion` of ``robot``, e.g. read by ``gdimitate audit``'s readers) and makes it
dynamically consistent while keeping, as far as the robot's limits and the physics of contact
allow, what the motion shows:

- **audit before** — :func:`gdimitate.audit_motion` of the motion as given (stance from its
  ``contact`` or the soles' height and speed, wrenches by
  :func:`gdimitate.wrenches.estimate_wrenches` inside each sole's cone, the audit);
- **the demonstration** — the same motion with a *flat-foot* stance schedule
  (:func:`repair_schedule`: the audit's stance where the whole sole is near the floor; the
  adaptor's contact is a flat foot, so a heel-off or toe-off frame is swing for it) and the
  contact wrenches of the same estimate on that schedule, turned into world-frame
  :class:`~gdimitate.contact.ContactForces` (:func:`wrench_forces`) — the "measured" forces
  whose direction is the adaptor's goal (``force="measured"``);
- **the adaptor** — :func:`gdimitate.adapt` (``method="optimal"``) from the robot to itself with
  an identity body map of every 1-DoF joint (:func:`identity_map`: every joint's angle is a
  target, none is held at rest) and :data:`REPAIR_WEIGHTS` (the keypoints' placement and the
  thigh direction weighed up: the motion's own keypoints are the reference);
- **placed** — the adaptor's motion moved along the floor to where the input is
  (:func:`placed`: the mean horizontal offset of the keypoints; a horizontal shift changes no
  force, torque or contact on a flat floor);
- **audit after** — :func:`gdimitate.audit_motion` of the repaired motion (its q, v, a and
  stance; its wrenches estimated anew, not the optimiser's): the verdict.

The result (:class:`RepairResult`) also measures what was kept: the keypoints (hip, knee,
ankle and sole frame of each leg, the ones the adaptor's body map targets) against the input's
at the repaired motion's times (:func:`keypoint_error`), and each foot's push direction
against the input's estimated one (the adaptor's audit, ``force_direction``).
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..assess.audit.dataset import MotionAudit
from ..assess.result import AdaptedMotion
from ..errors import InvalidInputError
from ..model.contact import ContactForces, FootForces
from ..model.legs import hip_height
from ..model.motion import Motion
from ..model.robot import SIDES, Robot
from ..retarget.targets import configurations_at

__all__ = ["REPAIR_WEIGHTS", "FLAT_HEIGHT", "RepairResult", "repair", "repair_schedule",
           "wrench_forces", "identity_map", "keypoint_frames", "keypoint_error", "placed",
           "repair_rate", "MAX_FLIGHT"]

#: Cost weights of the repair (:class:`gdimitate.retarget.Weights` fields changed from the
#: adaptor's defaults): the horizontal ankle-to-hip placement and the thigh direction weighed
#: as the hip height and shank (3), the feet's places in double support 5 × the default (500),
#: every squared acceleration at a tenth of the default (1e-5 s⁴). Measured on the joint
#: copy of the shipped walk onto G1, keypoints' RMS from the input: one stride 7.6 cm with the
#: defaults, 4.4 cm with placement and thigh 3, 4.0 cm with steps 300 too. The smoothness is
#: what kept the whole walk (3.5 s) at 6.1 cm: its pull on every acceleration shortens every
#: step — a repair of that repair (an input already feasible, feet flat and still) came back
#: with each step 1 cm short (travel 0.97) — and the copy's steps came out 2–3 cm short
#: (travel 0.92), the keypoints 8 cm ahead at the start and 16 cm behind at the end; no
#: joint, velocity or torque limit bound. Smoothness 3e-5 / 1e-5 / 5e-6 / 3e-6 at the knot
#: rate of :func:`repair_rate`, placed by a shift alone: the whole walk 4.3 / 3.2 / 2.8 / 2.6
#: cm, GMR's G1 output of the CMU walk 6.8 / 5.6 / 5.1 / 4.8 cm (before 8.8). With
#: :func:`placed`'s turn too, at 1e-5 and steps 300 / 500 / 700 / 1000 (benchmarks/peers.md):
#: the whole walk 3.2 / 3.1 / 3.0 / 3.0 cm, the stride 2.4 cm, GMR's 5.0 / 4.9 / 4.8 / 4.8
#: cm, every one audited feasible and walked by MuJoCo but the whole walk at 1000 (fell at
#: 2.9 s); smoothness 8e-6 / 5e-6 (steps 300): the whole walk fell at 3.0 / 2.0 s, and a
#: differential-IK output's repair stopped short (16 % of knots feasible at 5e-6, 95 % at
#: 1e-4). At 30 knots/s the stride's stance foot moved 1.3–1.6 mm/s at one knot (the audit
#: allows 1).
REPAIR_WEIGHTS: dict[str, float] = {"placement": 3.0, "thigh": 3.0, "steps": 500.0,
                                    "smoothness": 1e-5}

#: A stance frame of the audit's schedule stays stance for the repair only while the sole's
#: highest corner is within this height above the floor [hip heights] (G1: 5.8 cm): the
#: adaptor's contact is a flat foot. On the joint copy above: 0.057 (4 cm) 8.4 cm keypoint
#: RMS, 0.086 (6 cm) 7.6 cm, 0.114 (8 cm) 8.8 cm; the audit's schedule alone (toe-off frames
#: in stance, the sole centre up to 11 cm high) 10.8 cm and a push 19° RMS off.
FLAT_HEIGHT = 0.085


@dataclass(frozen=True, eq=False)
class RepairResult:
    """What :func:`repair` returns.

    - ``adapted``: the :class:`~gdimitate.AdaptedMotion` of the adaptor (its ``motion`` is
      the repaired motion: ``q`` ``(K, nq)``, ``v``/``a`` ``(K, nv)``, ``contact``; its
      ``wrenches`` ``{side: (K, 6)}`` in each sole frame; its ``audit`` checks the push
      against the input's as a target too);
    - ``before``, ``after``: :class:`~gdimitate.audit.dataset.MotionAudit` of the input as
      given and of the repaired motion (the same function on both: wrenches estimated from
      each motion's own inverse dynamics);
    - ``keypoint_rms``, ``keypoint_max`` [m]: RMS and largest distance of the keypoints
      (:func:`keypoint_frames`) from the input's at the repaired motion's times;
    - ``push_error_rms`` ``{side: rad}``: RMS angle of each foot's push from the input's
      estimated one (NaN where no knot has both);
    - ``schedule``: the stance ``{side: (T,) bool}`` on the input's frames the adaptor was
      given; ``seconds``: wall time of the whole repair [s].
    """

    adapted: AdaptedMotion
    before: MotionAudit
    after: MotionAudit
    keypoint_rms: float
    keypoint_max: float
    push_error_rms: Mapping[str, float]
    schedule: Mapping[str, np.ndarray]
    seconds: float

    @property
    def motion(self) -> Motion:
        """The repaired motion (``adapted.motion``)."""
        return self.adapted.motion

    @property
    def feasible(self) -> bool:
        """The verdict: the audit of the repaired motion (:attr:`after`)."""
        return self.after.feasible

    def comparison(self) -> list[tuple[str, str, str]]:
        """``(quantity, before, after)`` rows of the two audits, as printed."""
        b, a = self.before, self.after

        def f(x: float, fmt: str) -> str:
            return "-" if x is None or not math.isfinite(x) else format(x, fmt)

        rows = [("feasible", "yes" if b.feasible else "NO", "yes" if a.feasible else "NO"),
                ("frames", str(b.frames), str(a.frames)),
                ("knots feasible [%]", f(100 * b.share_feasible, ".1f"),
                 f(100 * a.share_feasible, ".1f")),
                ("torque/limit max", f(b.torque_ratio, ".3g"), f(a.torque_ratio, ".3g")),
                ("slip [m]", f(b.slip, ".3g"), f(a.slip, ".3g")),
                ("penetration [m]", f(b.penetration, ".3g"), f(a.penetration, ".3g")),
                ("stance hover [m]", f(b.hover, ".3g"), f(a.hover, ".3g")),
                ("CoP margin [m]", f(b.cop_margin, ".3g"), f(a.cop_margin, ".3g")),
                ("friction |f_t|/f_z", f(b.friction, ".3g"), f(a.friction, ".3g")),
                ("self-collision [m]", "-" if b.self_collision is None
                 else f(b.self_collision, ".3g"),
                 "-" if a.self_collision is None else f(a.self_collision, ".3g")),
                ("failed checks", str(len(b.report.binding)), str(len(a.report.binding)))]
        return rows

    def lines(self) -> list[str]:
        """The console table: the audits side by side, then what was kept."""
        out = [f"{'':<22} {'before':>12} {'after':>12}"]
        out += [f"{q:<22} {b:>12} {a:>12}" for q, b, a in self.comparison()]
        push = ", ".join(f"{s} {math.degrees(e):.1f}°" for s, e in self.push_error_rms.items())
        out.append(f"keypoints from the input: RMS {100 * self.keypoint_rms:.1f} cm, max "
                   f"{100 * self.keypoint_max:.1f} cm; push from the input's RMS {push}")
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``feasible``, ``before`` and ``after`` (each
        :meth:`MotionAudit.summary_dict` with its failed checks), the kept keypoints [m] and
        push [rad], ``seconds``."""
        from ..jsonable import jsonable

        return jsonable({
            "feasible": self.feasible,
            "before": {**self.before.summary_dict(), "failed": self.before.failed()},
            "after": {**self.after.summary_dict(), "failed": self.after.failed()},
            "keypoint_rms_m": self.keypoint_rms, "keypoint_max_m": self.keypoint_max,
            "push_error_rms_rad": dict(self.push_error_rms), "seconds": self.seconds})


def repair_rate(t: np.ndarray, least: float = 40.0) -> float:
    """The knot rate [knots/s] of a repair of a motion on times ``t`` ``(T,)`` [s]: the
    coarsest grid of at least ``least`` knots/s whose knots are input frames — the input's
    frame rate divided by the largest whole number that keeps it at ``least`` or above (60 Hz
    → 60, 120 Hz → 40, 50 Hz → 50, 200 Hz → 40; an input slower than ``least``: its own
    rate). At 30 knots/s the repaired stride's stance foot moved 1.3–1.6 mm/s at one knot
    (a one-step scheme's error, second order in the knot spacing; the audit allows 1 mm/s)
    with :data:`REPAIR_WEIGHTS`' light smoothing; at 40 and 60 it did not."""
    fps = round(1.0 / float(np.median(np.diff(t))), 6)  # 60, not 59.99999999
    return fps / max(1, math.floor(fps / least + 1e-9))


def repair_schedule(robot: Robot, motion: Motion, flat: float = FLAT_HEIGHT
                    ) -> dict[str, np.ndarray]:
    """The stance ``{side: (T,) bool}`` a repair adapts with: the motion's own ``contact``
    where it has both feet; else the audit's (:func:`gdimitate.audit.dataset.stance_schedule`:
    the lowest sole corner's height and speed) where also the sole's highest corner is within
    ``flat`` hip heights of the floor (:func:`gdimitate.bvh.contacts.estimate_floor`), the
    flat foot the adaptor's contact is."""
    from ..assess.audit.dataset import stance_schedule

    stance, _ = stance_schedule(robot, motion)
    if all(s in motion.contact for s in SIDES):
        return stance
    from ..io.bvh.contacts import estimate_floor, sole_corners

    hip = hip_height(robot)
    corners = sole_corners(robot, motion.q)
    floor = estimate_floor(corners)
    return {s: stance[s] & (corners[s][..., 2].max(axis=1) - floor < flat * hip)
            for s in SIDES}


def wrench_forces(robot: Robot, motion: Motion, wrenches: Mapping[str, np.ndarray],
                  source: str = "estimated from the motion's inverse dynamics"
                  ) -> ContactForces:
    """Contact wrenches ``{side: (T, 6)}`` (``[f; τ]`` [N, N·m] on each foot in its contact
    frame at the frame's origin, :func:`gdimitate.wrenches.estimate_wrenches`'s convention) as
    world-frame :class:`ContactForces` on ``motion.t``: the force ``R f``, the centre of
    pressure ``p + R (−τ_y/f_z, τ_x/f_z, 0)`` and the free moment about it ``R (0, 0, τ_z −
    c_x f_y + c_y f_x)``; in contact where ``motion.contact`` says stance and f_z > 0.
    :func:`gdimitate.wrenches.measured_wrenches` turns them back (within round-off)."""
    from ..model.kinematics import frame_placements

    contacts = robot.require_contacts()
    P = frame_placements(robot, motion.q, [contacts[s].frame for s in SIDES])
    feet = {}
    for s in SIDES:
        pl = P[contacts[s].frame]
        R, p = pl.rotation, pl.translation
        w = np.asarray(wrenches[s], float)
        f, tau = w[:, :3], w[:, 3:]
        on = np.asarray(motion.contact[s], bool) & (f[:, 2] > 0)
        fz = np.where(on, f[:, 2], 1.0)
        c = np.where(on[:, None], np.stack([-tau[:, 1] / fz, tau[:, 0] / fz,
                                            np.zeros_like(fz)], axis=1), 0.0)
        free = np.zeros_like(tau)
        free[:, 2] = tau[:, 2] - (c[:, 0] * f[:, 1] - c[:, 1] * f[:, 0])
        cop = p + np.einsum("tij,tj->ti", R, c)
        cop[~on] = np.nan
        feet[s] = FootForces(np.where(on[:, None], np.einsum("tij,tj->ti", R, f), 0.0), cop,
                             np.where(on[:, None], np.einsum("tij,tj->ti", R, free), 0.0), on)
    return ContactForces(np.asarray(motion.t, float).copy(), feet, source)


def identity_map(robot: Robot) -> dict[str, dict]:
    """The body map of ``robot`` onto itself: every 1-DoF joint (not a planar base's) onto
    itself (scale 1, offset 0) and the preset's segments (pelvis, torso) onto themselves."""
    from ..retarget.bodymap import UnmappedJointsWarning, body_map

    m = robot.model
    joints = {j: [j, 1.0, 0.0] for j in robot.joint_names
              if m.joints[m.getJointId(j)].nq == 1 and not j.startswith("base_")}
    try:
        with warnings.catch_warnings():  # the preset's joints are not used: no warning
            warnings.simplefilter("ignore", UnmappedJointsWarning)
            segments = {f: f for f in body_map(robot, robot).segments}
    except InvalidInputError:  # no preset for the robot's naming: joints alone
        segments = {}
    return {"joints": joints, "segments": segments}


def keypoint_frames(robot: Robot) -> list[str]:
    """The keypoints the adaptor's body map targets, per leg: hip, knee, ankle (joints) and
    the sole frame."""
    out = []
    for s in SIDES:
        leg = robot.legs[s]
        out += [f for f in (leg.hip, leg.knee, leg.ankle, leg.sole) if f]
    return out


def _keypoints(robot: Robot, q: np.ndarray) -> np.ndarray:
    """World positions ``(T, n, 3)`` [m] of :func:`keypoint_frames` for ``q`` ``(T, nq)``
    (joints: their origin; frames: theirs)."""
    import pinocchio as pin

    m = robot.model
    d = m.createData()
    names = keypoint_frames(robot)
    out = np.empty((len(q), len(names), 3))
    for k, x in enumerate(q):
        pin.framesForwardKinematics(m, d, x)
        for i, n in enumerate(names):
            out[k, i] = (d.oMf[m.getFrameId(n)].translation if m.existFrame(n)
                         else d.oMi[m.getJointId(n)].translation)
    return out


def placed(robot: Robot, reference: Motion, motion: Motion) -> Motion:
    """``motion`` moved on the floor — turned about the vertical and shifted along it — to
    where ``reference`` is: the turn and shift that bring its keypoints closest to
    ``reference``'s at its times (least squares over every knot and keypoint, horizontal
    coordinates: the 2-D Kabsch fit). The adaptor writes a motion in the demonstration's
    heading frame turned back by its heading estimate; on a flat floor such a turn and shift
    change no force, torque, contact or collision (the audit gives the same numbers), and
    they put the repaired motion where the input was. ``q``'s base position and yaw change;
    ``v`` and ``a`` (a free base's twist in its own frame) do not."""
    import pinocchio as pin

    ref = _keypoints(robot, configurations_at(robot, reference, motion.t))[..., :2]
    own = _keypoints(robot, motion.q)[..., :2]
    ref, own = ref.reshape(-1, 2), own.reshape(-1, 2)
    cr, co = ref.mean(axis=0), own.mean(axis=0)
    h = (own - co).T @ (ref - cr)  # Σ own ⊗ ref, centred
    yaw = math.atan2(h[0, 1] - h[1, 0], h[0, 0] + h[1, 1])
    c, s = math.cos(yaw), math.sin(yaw)
    R2 = np.array([[c, -s], [s, c]])
    q = motion.q.copy()
    q[:, :2] = (q[:, :2] - co) @ R2.T + cr
    turn = pin.Quaternion(pin.rpy.rpyToMatrix(0.0, 0.0, yaw))
    for k in range(len(q)):  # the base quaternion (x, y, z, w) turned about the world's z
        b = turn * pin.Quaternion(q[k, 6], q[k, 3], q[k, 4], q[k, 5])
        q[k, 3:7] = (b.x, b.y, b.z, b.w)
    return motion.replace(q=q)


def keypoint_error(robot: Robot, reference: Motion, motion: Motion) -> np.ndarray:
    """Distances ``(K, n)`` [m] of ``motion``'s keypoints (:func:`keypoint_frames`) from
    ``reference``'s at ``motion.t`` (``reference``'s q there by
    :func:`gdimitate.retarget.targets.configurations_at`)."""
    ref = configurations_at(robot, reference, motion.t)
    return np.linalg.norm(_keypoints(robot, motion.q) - _keypoints(robot, ref), axis=2)


#: The longest time [s] both soles may be off the floor in a motion to repair: a walk has
#: none, a run's flight lasts about 0.1 s; longer is a jump or a motion that left the floor
#: (holosoma's G1 output of the shipped walk has both soles 0.2–0.6 m up for its last 2 s).
MAX_FLIGHT = 0.3


def _check_flight(t: np.ndarray, stance: Mapping[str, np.ndarray]) -> None:
    """Raise :class:`InvalidInputError` naming the frames where no sole is on the floor for
    longer than :data:`MAX_FLIGHT` (``t`` ``(T,)`` [s], ``stance`` ``{side: (T,) bool}``)."""
    air = ~np.logical_or.reduce([np.asarray(stance[s], bool) for s in SIDES])
    edges = np.flatnonzero(np.diff(np.r_[0, air.astype(int), 0]))
    for a, b in zip(edges[::2], edges[1::2]):  # runs [a, b) of frames in the air
        if t[b - 1] - t[max(a - 1, 0)] > MAX_FLIGHT:
            raise InvalidInputError(
                f"both soles are off the floor for {t[b - 1] - t[max(a - 1, 0)]:.2f} s (frames "
                f"{a}–{b - 1}, {t[a]:.2f}–{t[b - 1]:.2f} s; more than {MAX_FLIGHT} s): repair "
                "keeps a walk on the floor — trim the clip to the frames where a foot is down, "
                "or check that the floor is at z = 0")


def repair(robot: Robot, motion: Motion, *, rate: float | None = None,
           weights: Any = None, flat: float = FLAT_HEIGHT, verbose: bool = False,
           **options: Any) -> RepairResult:
    """Make ``motion`` (a motion of ``robot`` from any source) physically consistent on
    ``robot`` itself (module docstring).

    ``robot``: a free-flyer :class:`~gdimitate.Robot` with soles; ``motion``: its
    :class:`~gdimitate.Motion` (``t`` ``(T,)`` [s], ``q`` ``(T, nq)``; ``v``/``a``
    differenced where absent; ``contact`` used where it has both feet); ``rate``
    [knots/s]: the adaptor's grid (default :func:`repair_rate`); ``weights``: a
    :class:`gdimitate.retarget.Weights` (default: the adaptor's with :data:`REPAIR_WEIGHTS`);
    ``flat`` [hip heights]: :func:`repair_schedule`'s sole-flatness bound; ``verbose``: the
    solver's progress on stderr; ``options``: more :func:`gdimitate.retarget.adapt_optimal`
    options (``limits``, ``contact``, ``stop``, ``ipopt`` …; not ``forces``, ``body_map``,
    ``force``).

    Returns a :class:`RepairResult`; :attr:`RepairResult.feasible` is the audit of the
    repaired motion. Raises :class:`~gdimitate.errors.InvalidInputError` for a motion that is
    not the robot's, too short, a robot without a free base, or options the repair sets itself.
    """
    from ..assess.audit.dataset import audit_motion
    from ..assess.wrenches import estimate_wrenches
    from ..model.motion import differentiate
    from ..retarget import Weights
    from .adaptor import adapt

    t0 = time.perf_counter()
    if not isinstance(robot, Robot):
        raise InvalidInputError(f"robot must be a gdimitate.Robot; got {type(robot).__name__}")
    if robot.base != "free":
        raise InvalidInputError(f"repair needs a free-floating robot; {robot.name!r} has a "
                                f"{robot.base} base")
    taken = sorted(set(options) & {"forces", "body_map", "force", "method"})
    if taken:
        raise InvalidInputError(f"repair sets {taken} itself (the input's own estimated "
                                "forces, the identity body map, force='measured'); leave them out")
    if not (isinstance(flat, (int, float)) and math.isfinite(flat) and flat > 0):
        raise InvalidInputError(f"flat must be a positive number of hip heights; got {flat!r}")
    before = audit_motion(robot, motion)  # checks the motion against the robot
    stance = repair_schedule(robot, motion, flat)
    if not any(stance[s].any() for s in SIDES):
        raise InvalidInputError("no frame of the motion has a sole flat on the floor (within "
                                f"{flat:g} hip heights): nothing to stand on; is the floor at "
                                "z = 0 and the motion the robot's?")
    _check_flight(motion.t, stance)
    demo = motion.replace(contact=stance)
    if demo.v is None or demo.a is None:
        demo = differentiate(robot.model, demo)
    forces = wrench_forces(robot, demo, estimate_wrenches(robot, demo).wrenches)
    if weights is None:
        weights = Weights(**REPAIR_WEIGHTS)
    adapted = adapt(demo, robot, robot, method="optimal", force="measured", forces=forces,
                    rate=repair_rate(demo.t) if rate is None else rate,
                    body_map=identity_map(robot), weights=weights, verbose=verbose, **options)
    adapted = dataclasses.replace(adapted, motion=placed(robot, motion, adapted.motion))
    after = audit_motion(robot, adapted.motion)
    err = keypoint_error(robot, motion, adapted.motion)
    push = {}
    fde = adapted.audit.force_direction_error if adapted.audit is not None else {}
    for s in SIDES:
        e = fde.get(s)
        push[s] = float("nan") if e is None else float(e.error_rms)
    return RepairResult(adapted, before, after, float(np.sqrt(np.mean(err ** 2))),
                        float(err.max()), push, stance, time.perf_counter() - t0)
