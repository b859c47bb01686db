"""What one demonstration frame asks of the imitator in the streaming mode: the references of
the per-frame QP's tasks (:class:`~.receding.Tasks`), from the demonstrator's own kinematics.

Centre of mass. Along the walk, positions map by ``p ↦ k·p + o``: ``k`` the legs' ratio,
cut so that a human step (:data:`STEP_RATIO` of its leg) becomes a step of :func:`max_step`
robot legs (flat feet reach less far than a heel-strike and toe-off); ``o`` follows, with a
:data:`TAU_OFFSET` time constant, where the imitator's stance soles are against the
demonstrator's, so that the centre of mass keeps the demonstrator's place relative to its own
support. Sideways (across the demonstrator's pelvis heading) it keeps the demonstrator's
place between its two soles, scaled by the ratio of the soles' lateral spreads (the weight
shift and sway in time with the steps). Heights: the imitator's starting height plus ``s``
times the demonstrator's change. Velocities and accelerations are central differences over
the frames ``j − 1, j, j + 1`` (the streaming step of frame ``j + 1`` solves knot ``j``: no
extra latency).

Swing soles: a sole that leaves the floor follows a smooth arc (quintic in the horizontal
plane, clearance ``0.08 ·`` leg length at mid-swing) to the capture point ``ξ = c + ċ/ω`` of
the linear inverted pendulum over the stance sole, predicted for the expected touch-down
(the last swing's duration; :data:`FIRST_SWING` before the first), landing within
:data:`LAND` of that duration, and then rests flat on the floor, unloaded, until the
demonstration's contact flag says it is in stance — so that it touches down still and flat.
A sole the demonstration puts down before it has landed (a swing shorter than expected, a
robot catching up with a walk it joined) goes straight to its landing pose, resting; its
stance begins when it is there (:class:`~.streaming.StreamingAdaptor`'s own touch-down).
The landing point keeps at least :data:`SEPARATION` times the narrowest stance's lateral
distance (:func:`least_stance_width`) from the other sole and at most :data:`MAX_STEP` legs
ahead of or behind it.

Joints no demonstrator joint drives rest at the robot's rest pose
(:func:`.parts.self_collision.rest_pose`, the trajectory mode's, with a wider clearance:
:data:`REST_MARGIN`, :data:`REST_CLEARANCE`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from ...model.footsteps import sole_frames
from ...model.heading import yaw_matrix
from ...model.robot import SIDES
from ...model.selfcollision import Proximity
from .receding import Tasks, q_of_v

__all__ = ["FrameReference"]

LAND, FIRST_SWING, TAU_OFFSET, CLEARANCE, SEPARATION, RAMP = 0.95, 0.45, 0.15, 0.08, 1.0, 0.6
KEEP_GOING, MAX_STEP, STEP_RATIO = 0.0, 0.5, 0.75
#: a sole late for its touch-down (the demonstration's foot is down, the robot's not yet)
#: lands where it is, flat, at its own yaw, LATE_LAND of its pose error removed per frame (a
#: resting sole's 0.2, ``receding.Gains.rest``, took G1's 14 mm to 2 mm in 8 frames, while it
#: was still pulled sideways to its step's goal; turned to the step's yaw as it landed,
#: Romeo's hip yaw went past its velocity limit)
LATE_LAND = 0.5
#: the rest pose (:func:`.parts.self_collision.rest_pose`): pairs of collision geometries
#: closer than REST_MARGIN [m] at the neutral pose moved REST_CLEARANCE [m] apart (the
#: trajectory mode's 1 cm / 1.5 cm left Talos's hands against its swinging thighs)
REST_MARGIN, REST_CLEARANCE = 0.02, 0.025
#: the walking speed is cut to STEP_SPEED steps of MAX_STEP legs per step period (the rest
#: of the step's reach is the capture-point feedback's); STEP_PERIOD: the first estimate
#: of the step period, in swing durations
STEP_SPEED, STEP_PERIOD = 0.8, 1.3
#: a robot whose linear inverted pendulum diverges by more than e^DIVERGENCE over a swing of
#: FIRST_SWING seconds takes steps shorter than MAX_STEP legs by the excess factor
DIVERGENCE = 1.7
#: the landing point is fixed from this fraction of the swing on (moved later, a sole low over
#: the floor chased it sideways: iCub's lagged 4 cm, touched the floor and was dragged)
FREEZE = 0.75
#: the least lateral gap [m] between the soles' edges, and the least distance [m] between
#: the two legs' collision geometries, of the narrowest stance (:func:`least_stance_width`).
#: Talos's thighs are 1.2 cm apart at its neutral pose: its legs stay straight down (17 cm). At
#: 1 cm it stood 15.6 cm wide: joined 1.0 s into the 3-D walk, 124 of 151 frames feasible
#: against 102, but 62 of the first 65 against 64; at 3 mm (14.9 cm) its thighs met in the
#: walk (55 of 151)
SOLE_GAP, LEG_CLEARANCE = 0.02, 0.012


class FrameReference:
    """References per frame (module docstring). ``demonstrator``, ``imitator``: robots;
    ``bmap``: the body map; ``act_names``: the imitator's actuated joints (QP order);
    ``force``: the goal's force model (``measured``, ``segment`` or ``com``)."""

    def __init__(self, demonstrator, imitator, bmap, act_names, force: str):
        self.d, self.r, self.force = demonstrator, imitator, force
        self.s = float(np.mean([imitator.legs[x].length for x in SIDES])
                       / np.mean([demonstrator.legs[x].length for x in SIDES]))
        dm = demonstrator.model
        self.sole = {x: dm.getFrameId(f) for x, f in sole_frames(demonstrator).items()}
        self.knee = {x: dm.getJointId(demonstrator.legs[x].knee) for x in SIDES}
        self.ankle = {x: dm.getFrameId(demonstrator.legs[x].ankle or demonstrator.legs[x].sole)
                      for x in SIDES}
        self.pelvis, self.base_off, self.root0 = _pelvis(demonstrator, imitator, bmap)
        n = len(act_names)
        self.neutral = np.array([imitator.neutral[imitator.idx_q(j)] for j in act_names])
        self.jmap = [(demonstrator.idx_q(dj), act_names.index(ij), sc, off)
                     for dj, (ij, sc, off) in bmap.joints.items() if ij in act_names]
        if act_names:  # the joints no demonstrator joint drives: the rest pose, limbs clear
            from ..parts.self_collision import rest_pose

            rest = rest_pose(imitator, REST_MARGIN, REST_CLEARANCE)
            self.neutral = rest[[imitator.idx_q(j) for j in act_names]]
        self.n_act = n
        self.leg = float(np.mean([imitator.legs[x].length for x in SIDES]))
        #: horizontal scale of the centre of mass's path: the legs' ratio, cut so that the
        #: demonstrator's steps (~STEP_RATIO of its leg) become steps of MAX_STEP legs
        self.step = max_step(imitator)
        self.k = min(self.s, self.s * self.step / STEP_RATIO)
        self.clearance = CLEARANCE * self.leg
        # the least lateral distance of the soles' centres: side by side, SOLE_GAP apart. Not
        # the hips' distance (legs straight down): a person's soles pass within a few cm of
        # each other (the CMU walk's are 5-10 cm apart), and the weight shifts from one to the
        # other within a double support of 0.15 s; at the hips' 13 cm, G1's centre of mass,
        # over one sole when the other landed, could move 2 cm of the 6.5 cm it needed by
        # lift-off (its 3-cm-wide centre-of-pressure margin), fell sideways and lost the
        # stream from its first touch-down (69 of 343 frames feasible; 342 of 343 at 8 cm)
        # (:func:`least_stance_width`: G1 8.9 cm, iCub 9.4, Romeo 14.6, Talos 17)
        self.sep = least_stance_width(imitator)
        self.frames: list[dict] = []
        self.heading: np.ndarray | None = None
        self.swing: dict = {x: None for x in SIDES}
        self.t_swing = FIRST_SWING
        #: the step period [s]: between the last two touch-downs (before them, STEP_PERIOD
        #: swing durations)
        self.t_step = STEP_PERIOD * FIRST_SWING
        self._t_down: float | None = None
        self.lift: dict[str, Any] = {x: None for x in SIDES}

    # ------------------------------------------------------------------ one frame
    def features(self, t: float, q_demo: np.ndarray, contact: dict, forces) -> dict:
        """The demonstrator's quantities of one frame (world, its own scale)."""
        m, data = self.d.model, self.d.data
        pin.framesForwardKinematics(m, data, q_demo)
        com = pin.centerOfMass(m, data, q_demo).copy()
        soles = {x: data.oMf[self.sole[x]].copy() for x in SIDES}
        joints = self.neutral.copy()
        for qi, ai, sc, off in self.jmap:
            joints[ai] = sc * q_demo[qi] + off
        rot = data.oMf[self.pelvis].rotation.copy() if self.pelvis is not None else None
        base = rot @ self.base_off if rot is not None else None
        push = {}
        for x in SIDES:
            d = None
            if contact[x]:
                if self.force == "measured" and forces is not None:
                    d = np.asarray(forces[x], float)
                elif self.force == "segment":
                    d = data.oMi[self.knee[x]].translation - data.oMf[self.ankle[x]].translation
                elif self.force == "com":
                    d = com - soles[x].translation
            nd = np.linalg.norm(d) if d is not None else 0.0
            push[x] = d / nd if d is not None and nd > 1e-9 else None
        return {"t": t, "q": q_demo, "com": com, "soles": soles, "joints": joints, "rot": rot,
                "base": base, "push": push, "contact": {x: bool(contact[x]) for x in SIDES}}

    def start(self, f0: dict, com0: np.ndarray, feet0: dict, base_rot0: np.ndarray,
              moving: bool) -> None:
        """Anchor the map on the first frame: the imitator's ``com0`` ``(3,)``, sole poses
        ``feet0`` {side: SE3} and base rotation ``base_rot0``; ``moving``: the imitator starts
        with the demonstrator's velocity (else at rest: the centre of mass is led from where
        it stands to the demonstration's within :data:`RAMP` seconds)."""
        self.ramp = 1e-9 if moving else RAMP
        self.z0, self.zd0 = float(com0[2]), float(f0["com"][2])
        self.off = self._centre(feet0, f0) - self.k * self._centre(f0["soles"], f0)
        self.rot0, self.com0 = base_rot0, np.asarray(com0, float).copy()
        for x in SIDES:  # a foot in swing at the start rests on the floor, waiting
            if not f0["contact"][x]:
                R = feet0[x].rotation
                self.lift[x] = {"t0": -1e9, "p0": feet0[x].translation.copy(), "R0": R.copy(),
                                "goal": (feet0[x].translation[:2].copy(),
                                         float(np.arctan2(R[1, 0], R[0, 0])))}

    def _centre(self, poses: dict, f: dict) -> np.ndarray:
        down = [x for x in SIDES if f["contact"][x]] or list(SIDES)
        return sum(poses[x].translation[:2] for x in down) / len(down)

    def _map(self, p: np.ndarray) -> np.ndarray:
        return self.k * p[:2] + self.off

    # ------------------------------------------------------------------ the tasks
    def tasks(self, j: int, nxt: dict, feet: dict, anchors: dict, robot_com: tuple) -> Tasks:
        """The tasks of knot ``j`` (frames ``j − 1 … j + 1`` must be in :attr:`frames`); ``nxt``
        the stance flags of knot ``j + 1``; ``feet`` {side: SE3} the imitator's soles at ``j``;
        ``anchors`` {side: SE3} the poses the stance feet began their stance with;
        ``robot_com`` ``(position (3,), velocity (3,))`` the imitator's centre of mass at
        ``j``."""
        F = self.frames
        f0, f1, f2 = F[max(j - 1, 0)], F[j], F[min(j + 1, len(F) - 1)]
        h = max(f2["t"] - f0["t"], 1e-9)
        hs = [x for x in SIDES if f1["contact"][x] and x in anchors]
        if hs:
            ctr = sum(anchors[x].translation[:2] for x in hs) / len(hs)  # (np.mean: 10×)
            dem = sum(f1["soles"][x].translation[:2] for x in hs) / len(hs)
            gain = min(1.0, (f2["t"] - f1["t"]) / TAU_OFFSET)
            self.off = self.off + gain * (ctr - self.k * dem - self.off)
        com = [np.append(self._map(f["com"]), self.z0 + self.s * (f["com"][2] - self.zd0))
               for f in (f0, f1, f2)]
        hh = 0.5 * h
        acc = (com[2] - 2 * com[1] + com[0]) / hh**2 if f0 is not f1 and f2 is not f1 else \
            np.zeros(3)
        R = self.ramp
        b, db, ddb = _quintic((f1["t"] - F[0]["t"]) / R)  # from rest to the demonstration
        gap = com[1] - self.com0
        target = self.com0 + b * gap
        cv = b * (com[2] - com[0]) / h + db / R * gap
        cv[:2] = self._cap(cv[:2])
        self._shift(target, cv, nxt, feet, f1, f0, f2)
        tk = Tasks(com=target,
                   com_vel=cv,
                   com_acc=b * acc + ddb / R**2 * gap,
                   base_rot=f1["base"] if f1["base"] is not None else self.rot0, feet={},
                   joints=f1["joints"], joints_vel=(f2["joints"] - f0["joints"]) / h,
                   push=f1["push"], anchor=anchors)
        # foot placement feedback (capture point): a centre of mass ahead of its reference
        # by e (and ė) puts the swing foot ahead by e + ė/ω, ω = √(g/z)
        c, cd = robot_com
        self._cp = (c[:2], cd[:2], np.sqrt(9.81 / max(c[2], 1e-3)))
        self.heading = f1["rot"] if f1["rot"] is not None else self.rot0 @ self.root0.T
        for x in SIDES:
            if nxt[x]:
                self.lift[x] = None
            else:
                tk.feet[x] = self._swing(x, f1, f0, f2, feet, h)
                if f2["contact"][x]:  # late: down where it is, flat, faster than a rest
                    p, R = feet[x].translation, feet[x].rotation
                    yaw = np.arctan2(R[1, 0], R[0, 0])
                    tk.feet[x] = (np.array([p[0], p[1], 0.0]), yaw_matrix(yaw),
                                  *tk.feet[x][2:])
                    tk.land[x] = LATE_LAND
        return tk

    def _swing(self, x: str, f1: dict, f0: dict, f2: dict, feet: dict, h: float) -> tuple:
        """The swing foot's reference ``(position, rotation, velocity (6,), acc (6,), resting)``."""
        t = f1["t"]
        if self.lift[x] is None:
            self.lift[x] = {"t0": t, "p0": feet[x].translation.copy(),
                            "R0": feet[x].rotation.copy(), "goal": None}
        L = self.lift[x]
        T = LAND * self.t_swing
        phi = min((t - L["t0"]) / T, 1.0)
        late = bool(f2["contact"][x])  # the demonstration is down, this sole not yet: land
        if L["goal"] is None or (phi < FREEZE and not late):
            sole = f1["soles"][x]
            # the capture point ξ = c + ċ/ω at the expected touch-down, diverging from the
            # stance sole p as ξ(t + τ) = p + (ξ − p) e^{ωτ} (linear inverted pendulum),
            # less a share of the lead ċ/ω so that the walk goes on
            c, cd, w0 = self._cp
            o = "right" if x == "left" else "left"
            p = feet[o].translation[:2]
            tau = max(L["t0"] + self.t_swing - t, 0.0)
            xi = p + (c + cd / w0 - p) * np.exp(w0 * tau)
            goal = xi - KEEP_GOING * cd / w0
            R = sole.rotation
            yaw = np.arctan2(R[1, 0], R[0, 0])
            L["goal"] = (self._apart(x, goal, feet), yaw)
        goal, yaw = L["goal"]
        Rg = yaw_matrix(yaw)
        sig, dsig, ddsig = _quintic(phi)
        b, db, ddb = _bump(phi)
        p0 = L["p0"]
        dp = np.append(goal - p0[:2], -p0[2])
        up = np.array([0.0, 0.0, self.clearance])
        pos = p0 + sig * dp + b * up
        vel = (dsig * dp + db * up) / T
        acc = (ddsig * dp + ddb * up) / T**2
        w = pin.log3(L["R0"].T @ Rg)
        R = L["R0"] @ pin.exp3(sig * w)
        om = L["R0"] @ w * dsig / T
        al = L["R0"] @ w * ddsig / T**2
        if phi >= 1.0 or late:  # resting on the floor until the touch-down (or going there)
            return np.append(goal, 0.0), Rg, np.zeros(6), np.zeros(6), True
        return pos, R, np.concatenate([vel, om]), np.concatenate([acc, al]), False

    def _shift(self, target: np.ndarray, cv: np.ndarray, nxt: dict, feet: dict,
               f1: dict, f0: dict, f2: dict) -> None:
        """Sideways (across the pelvis heading) the centre of mass keeps the demonstrator's
        place between its two soles — its weight shift and sway — scaled from its soles'
        lateral distance to the imitator's (a sway in time with the demonstrator's steps)."""
        R = (f1["rot"] if f1["rot"] is not None else self.rot0 @ self.root0.T)[:2, 0]
        fwd = R / max(np.linalg.norm(R), 1e-9)
        lat = np.array([-fwd[1], fwd[0]])

        def spread(soles) -> tuple[float, float]:
            y = [float(soles[x].translation[:2] @ lat) for x in SIDES]
            return 0.5 * (y[0] + y[1]), max(abs(y[0] - y[1]), 1e-3)

        dm, dw = spread(f1["soles"])
        rm, rw = spread(feet)
        k = rw / dw
        y = rm + k * (float(f1["com"][:2] @ lat) - dm)
        vy = k * float((f2["com"][:2] - f0["com"][:2]) @ lat) / max(f2["t"] - f0["t"], 1e-9)
        target[:2] += (y - target[:2] @ lat) * lat
        cv[:2] += (vy - cv[:2] @ lat) * lat

    def _cap(self, v: np.ndarray) -> np.ndarray:
        """A horizontal velocity ``v`` ``(2,)`` [m/s] cut to :data:`STEP_SPEED` steps of
        :data:`MAX_STEP` leg lengths per step period (the time between the last two
        touch-downs; flat feet reach less far than a heel-strike and toe-off: the
        demonstrator's scaled stride is out of reach). The period is the demonstration's, the
        leg the robot's: a short robot walks at the human's cadence with short steps (G1's
        first cap, per 1.25 swings, let it run 10 % faster than its steps could follow and it
        fell in the second step)."""
        vmax = STEP_SPEED * self.step * self.leg / self.t_step
        n = float(np.linalg.norm(v))
        return v * (vmax / n) if n > vmax else v

    def _apart(self, x: str, goal: np.ndarray, feet: dict) -> np.ndarray:
        """``goal`` kept at least :data:`SEPARATION` times the narrowest stance's lateral
        distance to its side of the other sole, and at most :data:`MAX_STEP` leg lengths ahead
        or behind it, along the demonstrator's pelvis heading (the soles' own yaw follows its
        toe-out)."""
        o = "right" if x == "left" else "left"
        other = feet[o]
        R = (self.heading if self.heading is not None else other.rotation)[:2, :2]
        fwd = R[:, 0] / max(np.linalg.norm(R[:, 0]), 1e-9)
        lat = np.array([-fwd[1], fwd[0]])
        sign = 1.0 if x == "left" else -1.0
        step = goal - other.translation[:2]
        along = float(np.clip(step @ fwd, -self.step * self.leg, self.step * self.leg))
        side = max(float(step @ lat) * sign, SEPARATION * self.sep)
        return other.translation[:2] + along * fwd + sign * side * lat

    def touched_down(self, x: str, duration: float, t: float | None = None) -> None:
        """A swing of ``duration`` [s] ended at time ``t`` [s] (the next estimates of a
        swing's duration and of the step period)."""
        self.t_swing = float(duration)
        if t is not None:
            if self._t_down is not None and t > self._t_down:
                self.t_step = float(t - self._t_down)
            self._t_down = float(t)


def least_stance_width(robot, step: float = 0.005) -> float:
    """The least lateral distance [m] of the soles' centres that ``robot`` can stand at: from
    its neutral pose both legs turn inwards about their hip roll joints (the ankle roll joints
    turning back, the soles flat) in steps of ``step`` [rad] until the soles' edges come within
    :data:`SOLE_GAP` of each other, the two legs' collision geometries
    (:func:`gdimitate.model.selfcollision.self_collision`) within :data:`LEG_CLEARANCE`, or a
    joint to its position limit. A robot without roll joints in its legs, or without collision
    geometry, takes the soles' rule alone; one whose legs are closer than
    :data:`LEG_CLEARANCE` at the neutral pose already stands with its legs straight down from
    its hips (their lateral distance)."""
    from ...model.selfcollision import self_collision

    m, d = robot.model, robot.model.createData()
    contacts = robot.require_contacts()
    soles = 2 * max(c.half_width for c in contacts.values()) + SOLE_GAP
    fid = {x: m.getFrameId(contacts[x].frame) for x in SIDES}
    from ...model.kinematics import base_joint_id

    above = set(m.supports[base_joint_id(robot)])  # the base joint and the joints above it
    chain = {x: [j for j in m.supports[m.frames[fid[x]].parentJoint] if j not in above]
             for x in SIDES}
    q0 = robot.neutral.copy()
    pin.computeJointJacobians(m, d, q0)
    pin.framesForwardKinematics(m, d, q0)
    moves: dict[int, float] = {}
    for x, sign in (("left", -1.0), ("right", 1.0)):  # the sole's lateral move, inwards
        roll = [j for j in chain[x] if m.joints[j].nv == 1 and abs(pin.getJointJacobian(
            m, d, j, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[3, m.joints[j].idx_v]) > 0.9]
        if len(roll) < 2:
            return soles
        dy = pin.getFrameJacobian(m, d, fid[x], pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[
            1, m.joints[roll[0]].idx_v]
        if abs(dy) < 1e-6:
            return soles
        s = sign * np.sign(dy)
        moves[m.joints[roll[0]].idx_q], moves[m.joints[roll[-1]].idx_q] = s, -s
    sc = self_collision(robot)
    legs = {j: x for x in SIDES for j in chain[x]}
    pairs = [] if sc is None else [
        k for k, p in enumerate(sc.geometry.collisionPairs)
        if {legs.get(sc.geometry.geometryObjects[p.first].parentJoint),
            legs.get(sc.geometry.geometryObjects[p.second].parentJoint)} == set(SIDES)]
    idx = np.array(list(moves), int)
    sgn = np.array(list(moves.values()))

    def width(theta: float) -> float | None:
        q = q0.copy()
        q[idx] += theta * sgn
        if np.any(q[idx] < m.lowerPositionLimit[idx]) or np.any(
                q[idx] > m.upperPositionLimit[idx]):
            return None
        if sc is not None and pairs and np.min(sc.distances(q)[pairs]) < LEG_CLEARANCE:
            return None
        pin.framesForwardKinematics(m, d, q)
        return abs(float(d.oMf[fid["left"]].translation[1] - d.oMf[fid["right"]].translation[1]))

    best = width(0.0)
    if best is None:  # the legs closer than the clearance already: straight down from the hips
        pin.framesForwardKinematics(m, d, q0)
        ys = [d.oMi[m.getJointId(robot.legs[x].hip)].translation[1] for x in SIDES]
        return max(soles, float(abs(ys[0] - ys[1])))
    theta = step
    while (w := width(theta)) is not None and w >= soles and w < best:
        best, theta = w, theta + step
    return max(soles, best)


def max_step(robot) -> float:
    """The longest step [legs] of ``robot`` at the demonstration's cadence: :data:`MAX_STEP`,
    cut by ``exp(DIVERGENCE − ω T)`` where the robot's linear inverted pendulum
    (``ω = √(g / z)``, ``z`` its neutral centre-of-mass height above the soles [m]) diverges by
    more than ``e^DIVERGENCE`` over a swing of ``T`` = :data:`FIRST_SWING` [s]. A small robot
    walking at a human's cadence has more time to fall per step than its size allows: iCub
    (ω T = 2.0) fell in its second step with half-leg steps (40 of 205 frames of the 3-D walk
    feasible; 177 with 0.36-leg ones, the value this gives); Talos (1.5), G1 and Romeo (1.7)
    keep half a leg."""
    m, d = robot.model, robot.model.createData()
    pin.framesForwardKinematics(m, d, robot.neutral)
    c = pin.centerOfMass(m, d, robot.neutral)
    sole = min(d.oMf[m.getFrameId(robot.legs[x].sole)].translation[2] for x in SIDES)
    w = np.sqrt(9.81 / max(float(c[2] - sole), 1e-3))
    step = MAX_STEP * min(1.0, float(np.exp(DIVERGENCE - w * FIRST_SWING)))
    # the swing sole covers two steps in a swing, peaking at 1.875 times its mean speed (the
    # quintic): at most what the slowest sagittal leg joint turns the leg by at its limit
    vel = [float(m.velocityLimit[m.joints[m.getJointId(n)].idx_v]) for x in SIDES
           for n in (robot.legs[x].hip, robot.legs[x].knee, robot.legs[x].ankle)
           if n and m.existJointName(n)]
    vel = [v for v in vel if np.isfinite(v) and 0 < v < 1e30]
    if vel:
        step = min(step, min(vel) * FIRST_SWING / (2 * 1.875))
    return step


def _pelvis(demonstrator, imitator, bmap) -> tuple[int | None, np.ndarray, np.ndarray]:
    """``(demonstrator frame id of the body-map segment on the imitator's base joint — its
    pelvis — or None, the constant rotation (3, 3) from that frame to the imitator's base
    joint, the imitator's base rotation (3, 3) at its neutral pose)``: both neutral poses face
    +x, so the demonstrator's pelvis rotation ``R`` becomes the base rotation ``R @ offset``
    (iCub's base joint is turned by π about z at its neutral pose: its ``root_link`` looks
    back)."""
    from ...model.kinematics import base_joint_id

    im, dm = imitator.model, demonstrator.model
    root = base_joint_id(imitator)
    idata, ddata = im.createData(), dm.createData()
    pin.framesForwardKinematics(im, idata, imitator.neutral)
    root0 = idata.oMi[root].rotation.copy()
    seg = [d for d, i in bmap.segments.items()
           if im.existFrame(i) and im.frames[im.getFrameId(i)].parentJoint == root
           and dm.existFrame(d)]
    if not seg:
        return None, np.eye(3), root0
    fid = dm.getFrameId(seg[0])
    pin.framesForwardKinematics(dm, ddata, demonstrator.neutral)
    return fid, ddata.oMf[fid].rotation.T @ root0, root0


def _quintic(phi: float) -> tuple[float, float, float]:
    """Smooth step ``10φ³ − 15φ⁴ + 6φ⁵`` and its first two derivatives."""
    p = min(max(phi, 0.0), 1.0)
    return (p**3 * (10 - 15 * p + 6 * p * p), 30 * p * p * (1 - p) ** 2,
            60 * p * (1 - p) * (1 - 2 * p))


def _bump(phi: float) -> tuple[float, float, float]:
    """``64 φ³ (1 − φ)³`` (1 at mid-swing, still at both ends) and its derivatives."""
    p = min(max(phi, 0.0), 1.0)
    u = 1 - p
    return 64 * p**3 * u**3, 192 * p * p * u * u * (u - p), 384 * p * u * ((u - p) ** 2 - p * u)


#: the first frame's base height, in the neutral pose's: tried in this order until both soles
#: are on their goals within SOLE_TOL [m] (G1 at the shipped walk's first frame, at rest: at
#: 0.92 both knees stuck at their hyperextension limit with the stance sole 1.5 mm and the
#: resting swing sole 14 mm above the floor, and the stance held them there: 115 of 124 frames
#: failed ``contact_gap``)
BASE_HEIGHTS, SOLE_TOL = (0.92, 0.88, 0.84, 0.80, 0.75, 0.70), 1e-4
#: the least distance [m] of the robot's own collision pairs at the first frame (Talos at the
#: shipped walk's frame 1.0 s: its right gripper 4.4 cm inside its thigh, which the first
#: step's collision rows could not undo within its torque limits)
START_CLEARANCE, CLEARANCE_WEIGHT, NEAR = 3e-3, 1e5, 0.1
#: every REFRESH-th Gauss–Newton step chooses the pairs within NEAR whose rows it may take
REFRESH = 10
#: the first frame's Gauss–Newton steps stop when no coordinate moves more than STILL [rad, m]
STILL = 1e-10


def initial_pose(robot, ref: FrameReference, f0: dict, act_idx: np.ndarray,
                 com_vel: np.ndarray | None, iterations: int = 100,
                 collision=None) -> np.ndarray:
    """The first frame's configuration ``(nq,)`` (the robot at rest): stance soles flat on
    the floor and swing soles flat on it too (resting), both under the demonstrator's
    scaled soles, the centre of mass over the stance soles, the base at 92 % of its neutral
    height (lower, down :data:`BASE_HEIGHTS`, where the soles cannot reach their goals from
    there) with the demonstrator's pelvis orientation, the other joints near their targets —
    damped Gauss–Newton steps on the configuration's Lie group. ``com_vel`` ``(3,)`` [m/s]:
    the demonstrator's scaled centre-of-mass velocity, for a start with its velocity
    (:func:`initial_velocity`): the centre of mass where the demonstrator's is (scaled) and a
    swing sole resting under the capture point ``c + ċ·√(z/g)`` along the walk.
    ``collision``: the robot's :class:`~gdimitate.model.selfcollision.SelfCollision` pairs, kept
    :data:`START_CLEARANCE` apart (a penalty row per pair closer than that)."""
    goals, centre = _start_goals(robot, ref, f0, com_vel)
    best = (np.inf, robot.neutral)
    for height in BASE_HEIGHTS:
        q, err = _pose_at(robot, ref, f0, act_idx, goals, centre, height, iterations,
                          collision)
        if err < best[0]:
            best = (err, q)
        if err <= SOLE_TOL:
            break
    return best[1]


def _start_goals(robot, ref: FrameReference, f0: dict, com_vel: np.ndarray | None
                 ) -> tuple[dict, np.ndarray]:
    """The first frame's sole goals ``{side: SE3}`` and the centre of mass's goal ``(3,)``
    (:func:`initial_pose`)."""
    planar = robot.base == "planar"
    goals = {}
    for x in SIDES:
        sole = f0["soles"][x]
        R = sole.rotation
        yaw = 0.0 if planar else np.arctan2(R[1, 0], R[0, 0])
        p = np.r_[ref.s * sole.translation[:2], 0.0]
        goals[x] = pin.SE3(yaw_matrix(yaw), p)
    down = [x for x in SIDES if f0["contact"][x]] or list(SIDES)
    moving = com_vel is not None
    if len(down) == 1:  # keep the swing sole clear of the stance sole
        o = [x for x in SIDES if x != down[0]][0]
        if com_vel is not None:  # and, moving, put it where it will catch the centre of mass
            dem = f0["soles"][down[0]].translation[:2]
            cp = (goals[down[0]].translation[:2] + ref.k * (f0["com"][:2] - dem)
                  + com_vel[:2] * np.sqrt(f0["com"][2] / 9.81))
            fwd = com_vel[:2] / max(np.linalg.norm(com_vel[:2]), 1e-9)
            g = goals[o].translation[:2]
            goals[o].translation = np.r_[g + fwd * ((cp - g) @ fwd), 0.0]
        g = ref._apart(o, goals[o].translation[:2], goals)
        goals[o].translation = np.r_[g, goals[o].translation[2]]
    centre = np.mean([goals[x].translation for x in down], axis=0)
    if moving:  # where the demonstrator's centre of mass is relative to its soles, scaled
        dem = np.mean([f0["soles"][x].translation[:2] for x in down], axis=0)
        centre = np.r_[centre[:2] + ref.k * (f0["com"][:2] - dem), 0.0]
    return goals, centre


def _pose_at(robot, ref: FrameReference, f0: dict, act_idx: np.ndarray, goals: dict,
             centre: np.ndarray, height: float, iterations: int, collision=None
             ) -> tuple[np.ndarray, float]:
    """:func:`initial_pose`'s Gauss–Newton solve with the base at ``height`` times its neutral
    height: ``(q (nq,), the soles' largest error to their goals (the norm of its log6: m
    and rad))``; ``collision``: as :func:`initial_pose`'s."""
    from ...model.kinematics import base_joint_id

    m, d = robot.model, robot.model.createData()
    planar = robot.base == "planar"
    comp = np.array([0, 2, 4] if planar else range(6))
    root = base_joint_id(robot)
    q = robot.neutral.copy()
    fids = {x: m.getFrameId(robot.require_contacts()[x].frame) for x in SIDES}
    pin.framesForwardKinematics(m, d, q)
    z_root = d.oMi[root].translation[2] - min(d.oMf[f].translation[2] for f in fids.values())
    rot = f0["base"] if f0["base"] is not None else ref.root0
    targets = f0["joints"]
    near = _Near(collision)
    qa, vl = q_of_v(m, act_idx), _leg_dofs(m, fids, act_idx)  # vl: held at their limits
    ql = q_of_v(m, vl)
    lin = [0] if planar else [0, 1]
    ang = [4] if planar else [3, 4, 5]
    Js = np.zeros((act_idx.size, m.nv))  # the posture rows
    Js[np.arange(act_idx.size), act_idx] = 1.0
    damping = 1e-6 * np.eye(m.nv)
    for _ in range(iterations):
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        J, e, w = [], [], []
        for x in SIDES:
            Jf = pin.getFrameJacobian(m, d, fids[x], pin.ReferenceFrame.LOCAL)
            J.append(Jf[comp])
            e.append(pin.log6(d.oMf[fids[x]].actInv(goals[x])).vector[comp])
            w.append(np.full(comp.size, 1e5))
        c = pin.centerOfMass(m, d, q)
        Jc = pin.jacobianCenterOfMass(m, d, q)
        J.append(Jc[lin])
        e.append((centre - c)[lin])
        w.append(np.full(len(lin), 30.0))
        Jr = pin.getJointJacobian(m, d, root, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        J.append(Jr[[2] + ang])
        Rb = d.oMi[root].rotation
        e.append(np.r_[height * z_root - d.oMi[root].translation[2],
                       pin.log3(rot @ Rb.T)[[a - 3 for a in ang]]])
        w.append(np.full(1 + len(ang), 10.0))
        J.append(Js)
        e.append(targets - q[qa])
        w.append(np.full(act_idx.size, 0.1))
        near.rows(q, d, J, e, w)
        Ja, ea, wa = np.vstack(J), np.concatenate(e), np.concatenate(w)
        dq = _bounded_step(Ja.T @ (wa[:, None] * Ja) + damping, Ja.T @ (wa * ea), m, q, vl,
                           ql)
        q = np.clip(pin.integrate(m, q, dq), m.lowerPositionLimit, m.upperPositionLimit)
        if np.max(np.abs(dq)) < STILL:  # converged
            break
    pin.framesForwardKinematics(m, d, q)
    err = max(float(np.linalg.norm(pin.log6(d.oMf[fids[x]].actInv(goals[x])).vector[comp]))
              for x in SIDES)
    return q, err


class _Near:
    """:func:`initial_pose`'s self-collision rows: each pair of ``collision`` (a
    :class:`~gdimitate.model.selfcollision.SelfCollision`, or None: none) closer than
    :data:`START_CLEARANCE` asks, weighted :data:`CLEARANCE_WEIGHT`, to be that far apart —
    among the pairs within :data:`NEAR` at the last of every :data:`REFRESH` steps (a pair
    the Gauss–Newton steps swept into from farther off is left alone until then). These
    steps are sensitive to round-off where the rows fight the soles: at Talos's walk pose
    1.0 s in, a difference of 1e-11 in one row's rate grew to 0.4 m within ten steps and left
    the gripper 4.3 cm inside the thigh instead of 3.7 mm clear (the rates are computed as
    before, pair by pair, for that reason). Damping the steps and weighing the rows 1e6
    instead made the soles stop 2.4 mm short of their goals at a restart of Talos's CMU walk
    (six base heights tried: 0.67 s); a step with the clearance as a hard row (a QP) would
    settle it, not tried."""

    def __init__(self, collision):
        self.c, self.calls = collision, 0
        if collision is not None:
            self.proximity = Proximity(collision)

    def rows(self, q: np.ndarray, d, J: list, e: list, w: list) -> None:
        """Append the rows at ``q`` (``d``: its data, joint Jacobians computed)."""
        if self.c is None:
            return
        _, dist, Jd = self.proximity.tracked(d, q, self.calls % REFRESH == 0, NEAR,
                                             START_CLEARANCE)
        self.calls += 1
        J.append(Jd)
        e.append(START_CLEARANCE - dist)
        w.append(np.full(dist.size, CLEARANCE_WEIGHT))


def _leg_dofs(m, fids: dict, act_idx: np.ndarray) -> np.ndarray:
    """The velocity indices (sorted) of the actuated joints ``act_idx`` that carry the sole
    frames ``fids`` {side: frame id} of model ``m`` (the legs)."""
    act = set(act_idx.tolist())
    return np.array(sorted({m.joints[j].idx_v for x in SIDES
                            for j in m.supports[m.frames[fids[x]].parentJoint]
                            if j > 0 and m.joints[j].idx_v in act}), int)


def _bounded_step(A: np.ndarray, b: np.ndarray, m, q: np.ndarray,
                  act_idx: np.ndarray, qi: np.ndarray) -> np.ndarray:
    """The Gauss–Newton step ``(nv,)`` solving ``A dq = b`` (``A`` ``(nv, nv)``) at the
    configuration ``q`` ``(nq,)`` of model ``m`` with the 1-dof joints ``act_idx`` (velocity
    indices; ``qi``: their configuration indices, :func:`~.receding.q_of_v`) that are at a
    position limit the step would push past held still — an active
    set, so that the other joints take up what they cannot. Clipping the step afterwards
    instead stalls (the rest of the step assumed the held joint's share): iCub's swing sole
    at the CMU walk's first pose stayed 1.9 mm under the floor, tilted 1.1°, its hip roll at
    its 17° limit; it landed so and its stance held it there (penetration > 1 mm at every
    frame). :func:`initial_pose` holds the legs' joints only — they carry the soles, whose
    rows are the hard ones; holding the arms too (Talos's arm_left_2 at its limit) moved
    Talos's start by 4 mm, and its CMU walk then failed from frame 76 instead of 167."""
    qa, lo, up = q[qi], m.lowerPositionLimit[qi], m.upperPositionLimit[qi]
    free = np.ones(b.size, bool)
    dq = np.linalg.solve(A, b)
    for _ in range(4):
        push = dq[act_idx]
        held = ((qa >= up - 1e-9) & (push > 0)) | ((qa <= lo + 1e-9) & (push < 0))
        held &= free[act_idx]
        if not held.any():
            break
        free[act_idx[held]] = False
        sub = np.flatnonzero(free)
        dq = np.zeros(b.size)
        dq[sub] = np.linalg.solve(A[np.ix_(sub, sub)], b[sub])
    return dq


def initial_velocity(robot, q: np.ndarray, ref: FrameReference, f0: dict, v_demo: np.ndarray,
                     act_idx: np.ndarray) -> np.ndarray:
    """The first frame's velocity ``(nv,)``: both soles still, the centre of mass moving with
    the demonstrator's (scaled), the base turning with its pelvis, the other joints with their
    mapped joints (least squares in the null space of the soles' velocity rows)."""
    from ...model.kinematics import base_joint_id

    m, d = robot.model, robot.model.createData()
    dm, dd = ref.d.model, ref.d.data  # a human's new Data would take ~50 ms (eight nv³ tensors)
    planar = robot.base == "planar"
    comp = np.array([0, 2, 4] if planar else range(6))
    pin.computeJointJacobians(m, d, q)
    pin.updateFramePlacements(m, d)
    C = np.vstack([pin.getFrameJacobian(m, d, m.getFrameId(robot.require_contacts()[x].frame),
                                        pin.ReferenceFrame.LOCAL)[comp] for x in SIDES])
    qd = f0["q"]
    pin.computeAllTerms(dm, dd, qd, v_demo)
    lin = [0, 2] if planar else [0, 1, 2]
    J = [pin.jacobianCenterOfMass(m, d, q)[lin]]
    r = [ref.k * dd.vcom[0][lin]]
    wts = [30.0] * len(lin)
    if f0["rot"] is not None and ref.pelvis is not None:
        J.append(pin.getJointJacobian(m, d, base_joint_id(robot),
                                      pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[3:])
        r.append(pin.getFrameVelocity(dm, dd, ref.pelvis,
                                      pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).angular)
        wts += [10.0] * 3
    Js = np.zeros((act_idx.size, m.nv))
    Js[np.arange(act_idx.size), act_idx] = 1.0
    vj = np.zeros(act_idx.size)
    v_of_q = {dm.joints[j].idx_q + k: dm.joints[j].idx_v for j in range(1, dm.njoints)
              for k in range(dm.joints[j].nq)}
    for qi, ai, sc, _ in ref.jmap:
        vj[ai] = sc * v_demo[v_of_q[qi]]
    J.append(Js)
    r.append(vj)
    wts += [0.1] * act_idx.size
    Ja, ra, wa = np.vstack(J), np.concatenate(r), np.sqrt(np.array(wts))
    N = scipy_null(C)
    y = np.linalg.lstsq((wa[:, None] * Ja) @ N, wa * ra, rcond=None)[0]
    return N @ y


def scipy_null(C: np.ndarray) -> np.ndarray:
    """An orthonormal basis ``(n, n − rank)`` of the null space of ``C``."""
    _, sv, Vt = np.linalg.svd(C)
    rank = int(np.sum(sv > 1e-10 * max(sv.max(initial=0.0), 1.0)))
    return Vt[rank:].T
