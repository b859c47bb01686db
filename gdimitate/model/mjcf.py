"""A MuJoCo model built from a :class:`~gdimitate.model.robot.Robot`'s Pinocchio model.

The :class:`mujoco.MjSpec` is assembled programmatically from the ``pin.Model`` — bodies,
joint axes, placements, masses and inertias in Pinocchio's joint order — so it works for any
Robot (library URDFs, generated planar models, OpenSim/BVH URDFs) and the joints match by
construction:

- a free-flyer root becomes a MuJoCo free joint; every 1-DoF revolute/prismatic joint a
  hinge/slide with the same axis; an unbounded revolute (``RUB*``, q = (cos, sin)) a hinge
  without range;
- a massless body carrying one joint whose only child is another joint (our planar base's
  ``base_x`` → ``base_z`` → ``base_pitch``) is merged into that child: MuJoCo composes the
  joints of one body in order, which is Pinocchio's chain;
- a joint whose whole subtree carries no mass (example-robot-data's Romeo: 24 finger, thumb
  and hand joints) moves nothing and cannot be integrated (MuJoCo needs positive inertia on
  a moving body): it is left out of the MuJoCo model with its subtree
  (:attr:`SimModel.frozen`). Pinocchio's dynamics of every other joint do not depend on it
  (its rows and columns of the mass matrix are zero), the sole frames are never on it, and
  :meth:`SimModel.q_from_qpos` reports it at Pinocchio's neutral configuration;
- each body's mass, centre of mass and rotational inertia are Pinocchio's (``model.inertias``,
  in the joint frame); Pinocchio's ``armature`` is copied (zero for URDFs); URDF damping and
  friction are *not* copied (Pinocchio's ``rnea`` ignores them too), so neither side has
  hidden passive forces;
- each foot gets a collision box equal to its sole rectangle (``robot.contacts[side]``): half
  sizes (X, Y, ``box_height``/2) under the sole frame, its bottom face on the frame's z = 0
  plane, friction ``mu``; the ground is a plane at z = 0 with the same ``mu``; nothing else
  collides;
- position limits become joint ranges; effort limits become motor actuators (gear 1) with
  ``ctrlrange`` = ``forcerange`` = ±effort. Joints with effort limit 0 (our planar base) are
  passive.

Coordinates: MuJoCo's free joint holds (position, quaternion w, x, y, z) and a velocity of
(world-frame linear velocity of the body origin, body-frame angular velocity); Pinocchio's
free-flyer holds (position, quaternion x, y, z, w) and a LOCAL twist (linear, angular).
:class:`SimModel` converts configurations, velocities, accelerations and generalised forces
exactly both ways.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import pinocchio as pin

from ..errors import SimModelError
from .contact import SoleContact
from .robot import PLANAR_BASE, SIDES, Robot

__all__ = ["ModelOptions", "SimModel", "build_model"]

_HINGE = {"RX": (1, 0, 0), "RY": (0, 1, 0), "RZ": (0, 0, 1)}
_SLIDE = {"PX": (1, 0, 0), "PY": (0, 1, 0), "PZ": (0, 0, 1)}
_UNBOUNDED = {"RUBX": (1, 0, 0), "RUBY": (0, 1, 0), "RUBZ": (0, 0, 1)}


@dataclass(frozen=True)
class ModelOptions:
    """How the MuJoCo model is set up.

    ``timestep`` [s]: the simulation step; ``box_height`` [m]: height of each foot's collision
    box (only its bottom face touches the floor); ``cone``: ``"elliptic"`` (exact Coulomb
    cone) or ``"pyramidal"``; ``impratio``: MuJoCo's frictional-to-normal impedance ratio
    (> 1 makes friction stiffer: less creep of a loaded foot); ``integrator``: MuJoCo
    integrator name (``"implicitfast"``, ``"euler"``, ``"rk4"``); ``contact_timeconst`` [s]
    and ``contact_dampratio``: the contacts' ``solref`` (MuJoCo's default is 0.02, 1);
    ``min_inertia`` [kg·m²]: MuJoCo rejects rotational inertias that are not positive definite,
    so principal moments below this are raised to it (e.g. example-robot-data's iCub has point
    masses on its right leg and wrists); :attr:`SimModel.inertia_changes` lists each change.
    """

    timestep: float = 0.001
    box_height: float = 0.02
    cone: str = "elliptic"
    impratio: float = 10.0
    integrator: str = "implicitfast"
    contact_timeconst: float = 0.01
    contact_dampratio: float = 1.0
    min_inertia: float = 1e-9

    def __post_init__(self) -> None:
        if not (0 < self.timestep <= 0.01):
            raise SimModelError(f"timestep must be in (0, 0.01] s; got {self.timestep!r}")
        if not (self.box_height > 0):
            raise SimModelError(f"box_height must be > 0 m; got {self.box_height!r}")
        if self.cone not in ("elliptic", "pyramidal"):
            raise SimModelError(f"cone must be 'elliptic' or 'pyramidal'; got {self.cone!r}")
        if self.integrator not in ("implicitfast", "euler", "rk4", "implicit"):
            raise SimModelError(f"unknown integrator {self.integrator!r}; valid: "
                                "'implicitfast', 'euler', 'rk4', 'implicit'")
        if not (0 < self.min_inertia < 1e-3):
            raise SimModelError(f"min_inertia must be in (0, 1e-3) kg·m²; got "
                                f"{self.min_inertia!r}")
        if not (self.impratio >= 1):
            raise SimModelError(f"impratio must be ≥ 1; got {self.impratio!r}")
        if not (self.contact_timeconst >= 2 * self.timestep):
            raise SimModelError(
                f"contact_timeconst {self.contact_timeconst!r} s must be at least twice the "
                f"timestep {self.timestep!r} s (MuJoCo's stability rule)")


def _kind(jmodel: pin.JointModel) -> str:
    return jmodel.shortname().replace("JointModel", "")


def _axis(jmodel: pin.JointModel) -> np.ndarray:
    k = _kind(jmodel)
    for table in (_HINGE, _SLIDE, _UNBOUNDED):
        if k in table:
            return np.asarray(table[k], dtype=float)
    if k in ("RevoluteUnaligned", "PrismaticUnaligned", "RevoluteUnboundedUnaligned"):
        return np.asarray(jmodel.extract().axis, dtype=float)
    raise SimModelError(f"joint type {k} is not supported by gdimitate.sim (supported: free "
                        "flyer, revolute, prismatic, unbounded revolute)")


def _is_hinge(jmodel: pin.JointModel) -> bool:
    k = _kind(jmodel)
    return k.startswith("R")


def _quat_wxyz(R: np.ndarray) -> np.ndarray:
    x, y, z, w = pin.Quaternion(R).coeffs()
    return np.array([w, x, y, z])


def _is_base(model: pin.Model, j: int) -> bool:
    return _kind(model.joints[j]) == "FreeFlyer" or model.names[j] in PLANAR_BASE


class _Builder:
    """Walks the Pinocchio tree and adds MuJoCo bodies (see the module docstring)."""

    def __init__(self, robot: Robot, spec: mujoco.MjSpec, min_inertia: float):
        self.robot, self.model, self.spec = robot, robot.model, spec
        self.min_inertia = min_inertia
        self.inertia_changes: dict[str, float] = {}
        m = self.model
        self.children: dict[int, list[int]] = {i: [] for i in range(m.njoints)}
        for i in range(1, m.njoints):
            self.children[m.parents[i]].append(i)
        self.body_of: dict[int, mujoco.MjsBody] = {0: spec.worldbody}
        self.merged: set[int] = set()
        self.frozen: set[int] = set()

    def _massless(self, j: int) -> bool:
        Y = self.model.inertias[j]
        return Y.mass <= 0 and np.allclose(Y.inertia, 0)

    def _subtree(self, j: int) -> list[int]:
        out = [j]
        for k in self.children[j]:
            out += self._subtree(k)
        return out

    def add(self, j: int, parent: mujoco.MjsBody, chain: list[tuple[int, pin.SE3]]) -> None:
        m = self.model
        jm = m.joints[j]
        sub = self._subtree(j)
        if _kind(jm) != "FreeFlyer" and not chain and all(self._massless(k) for k in sub):
            self.frozen.update(sub)  # moves nothing: left out (module docstring)
            return
        F = (chain[-1][1] if chain else pin.SE3.Identity()) * m.jointPlacements[j]
        kids = self.children[j]
        if (self._massless(j) and len(kids) == 1 and _kind(jm) != "FreeFlyer"
                and _kind(m.joints[kids[0]]) != "FreeFlyer"):
            self.merged.add(j)
            self.add(kids[0], parent, chain + [(j, F)])
            return
        if self._massless(j):
            raise SimModelError(
                f"{self.robot.name}: the body of joint {m.names[j]!r} has no mass and no "
                "inertia, and it is not a link between two joints that could be merged; "
                "MuJoCo needs positive masses on moving bodies. Give that link an <inertial> "
                "in the URDF.")
        body = parent.add_body(name=m.names[j], pos=F.translation, quat=_quat_wxyz(F.rotation))
        for cj, Fc in chain:  # merged massless joints, in chain order, in this body's frame
            X = F.inverse() * Fc
            self._joint(body, cj, X.translation, X.rotation @ _axis(m.joints[cj]))
        if _kind(jm) == "FreeFlyer":
            if chain or parent is not self.spec.worldbody:
                raise SimModelError(f"{self.robot.name}: a free-flyer joint must be the root")
            body.add_freejoint(name=m.names[j])
        else:
            self._joint(body, j, np.zeros(3), _axis(jm))
        Y = m.inertias[j]
        I = self._positive(m.names[j], Y.inertia)
        body.explicitinertial = True
        body.mass = float(Y.mass)
        body.ipos = Y.lever
        body.fullinertia = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        self.body_of[j] = body
        for k in kids:
            self.add(k, body, [])

    def _positive(self, name: str, inertia: np.ndarray) -> np.ndarray:
        """``inertia`` (3, 3) with principal moments raised to ``min_inertia`` (recorded)."""
        I = 0.5 * (inertia + inertia.T)
        ev, V = np.linalg.eigh(I)
        if ev.min() >= self.min_inertia:
            return I
        ev2 = np.maximum(ev, self.min_inertia)
        self.inertia_changes[name] = float(np.max(ev2 - ev))
        return (V * ev2) @ V.T

    def _joint(self, body: mujoco.MjsBody, j: int, pos: np.ndarray, axis: np.ndarray) -> None:
        m = self.model
        jm = m.joints[j]
        typ = mujoco.mjtJoint.mjJNT_HINGE if _is_hinge(jm) else mujoco.mjtJoint.mjJNT_SLIDE
        mj = body.add_joint(name=m.names[j], type=typ, pos=pos, axis=axis)
        mj.armature = float(m.armature[jm.idx_v])
        lo, hi = m.lowerPositionLimit[jm.idx_q], m.upperPositionLimit[jm.idx_q]
        bounded = jm.nq == 1 and np.isfinite(lo) and np.isfinite(hi) and lo < hi
        bounded = bounded and abs(lo) < 1e100 and abs(hi) < 1e100 and not _is_base(m, j)
        if bounded:
            mj.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            mj.range = [float(lo), float(hi)]
        else:
            mj.limited = mujoco.mjtLimited.mjLIMITED_FALSE


def _effort(model: pin.Model, j: int) -> float:
    e = float(model.effortLimit[model.joints[j].idx_v])
    return e if np.isfinite(e) and e < 1e100 else np.inf


def build_model(robot: Robot, options: ModelOptions = ModelOptions(),
                contacts: dict[str, SoleContact] | None = None) -> SimModel:
    """The MuJoCo model of ``robot`` with feet, floor and actuators (module docstring).

    ``contacts``: the sole rectangles {side: SoleContact} to give the feet (default: the
    robot's own, ``robot.contacts``; a plan's ``contacts`` where it brings its own).

    Raises :class:`~gdimitate.errors.SimModelError` for a robot without flat-foot contacts,
    an unsupported joint type, a massless moving link or inertias MuJoCo rejects.
    """
    if contacts is None:
        contacts = (robot.require_contacts() if hasattr(robot, "require_contacts")
                    else robot.contacts)
    if set(contacts) != set(SIDES) or not all(isinstance(c, SoleContact)
                                              for c in contacts.values()):
        raise SimModelError(f"{robot.name}: simulation needs flat-foot contacts on both feet")
    spec, mu, solref = _world_spec(robot, options, contacts)
    b = _Builder(robot, spec, options.min_inertia)
    for k in b.children[0]:
        b.add(k, spec.worldbody, [])
    _add_soles(robot, b, options, contacts, mu, solref)
    actuated = _add_actuators(robot.model, spec, b)
    try:
        mjm = spec.compile()
    except ValueError as e:
        raise SimModelError(f"{robot.name}: MuJoCo rejected the model built from its "
                            f"Pinocchio model: {e}") from None
    sim = SimModel(robot, spec, mjm, {s: contacts[s] for s in SIDES}, actuated, options,
                   frozen=sorted(b.frozen))
    sim.inertia_changes = dict(b.inertia_changes)
    return sim


def _world_spec(robot: Robot, options: ModelOptions,
                contacts: dict[str, SoleContact]) -> tuple[mujoco.MjSpec, float, list[float]]:
    """A new spec with the simulation options and the floor; returns it, the floor's
    friction ``mu`` (the soles' one) and the contacts' ``solref``."""
    m = robot.model
    spec = mujoco.MjSpec()
    spec.modelname = str(robot.name)
    spec.compiler.degree = False
    spec.compiler.autolimits = False
    spec.compiler.balanceinertia = False
    spec.compiler.boundmass = 0.0
    spec.compiler.boundinertia = 0.0
    spec.compiler.alignfree = False
    opt = spec.option
    opt.timestep = options.timestep
    opt.gravity = np.asarray(m.gravity.linear, dtype=float)
    opt.cone = (mujoco.mjtCone.mjCONE_ELLIPTIC if options.cone == "elliptic"
                else mujoco.mjtCone.mjCONE_PYRAMIDAL)
    opt.impratio = options.impratio
    opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{options.integrator.upper()}")
    solref = [options.contact_timeconst, options.contact_dampratio]
    mus = {contacts[s].mu for s in SIDES}
    if len(mus) != 1:
        raise SimModelError(f"{robot.name}: the feet have different friction {sorted(mus)}; "
                            "one floor needs one mu")
    mu = mus.pop()
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                            friction=[mu, 0.0, 0.0], contype=1, conaffinity=2, condim=3,
                            solref=solref)
    return spec, mu, solref


def _add_soles(robot: Robot, b: _Builder, options: ModelOptions,
               contacts: dict[str, SoleContact], mu: float, solref: list[float]) -> None:
    """Each foot's collision box (the sole rectangle, ``box_height`` thick, above the sole
    frame) and a site at the sole frame."""
    m = robot.model
    for s in SIDES:
        c = contacts[s]
        fr = m.frames[robot.frame_id(c.frame)]
        if fr.parentJoint in b.merged | b.frozen or fr.parentJoint == 0:
            raise SimModelError(f"{robot.name}: the {s} sole frame {c.frame!r} is not on a "
                                "moving body with mass")
        h = options.box_height / 2
        P = fr.placement
        body = b.body_of[fr.parentJoint]
        body.add_geom(name=f"{s}_sole", type=mujoco.mjtGeom.mjGEOM_BOX,
                      size=[c.half_length, c.half_width, h],
                      pos=P.translation + P.rotation @ np.array([0.0, 0.0, h]),
                      quat=_quat_wxyz(P.rotation), friction=[mu, 0.0, 0.0], contype=2,
                      conaffinity=1, condim=3, solref=solref, mass=0.0, density=0.0)
        body.add_site(name=f"{s}_sole", pos=P.translation, quat=_quat_wxyz(P.rotation))


def _add_actuators(m: pin.Model, spec: mujoco.MjSpec, b: _Builder) -> list[int]:
    """A motor on every 1-DoF joint with a positive effort limit (ctrl and force ranges ±
    the limit where finite); returns their Pinocchio joint ids in actuator order."""
    actuated = []
    for j in range(1, m.njoints):
        if _is_base(m, j) or m.joints[j].nv != 1 or j in b.frozen:
            continue
        e = _effort(m, j)
        if e <= 0:
            continue
        act = spec.add_actuator(name=m.names[j], target=m.names[j],
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_motor()
        if np.isfinite(e):
            act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.ctrlrange = [-e, e]
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.forcerange = [-e, e]
        else:
            act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        actuated.append(j)
    return actuated


class SimModel:
    """A compiled MuJoCo model of a robot, with the index maps between its coordinates and
    Pinocchio's. Attributes: ``robot``; ``spec`` (``mujoco.MjSpec``); ``mj`` (``MjModel``);
    ``contacts`` (``{"left": SoleContact, "right": …}``); ``actuated`` (Pinocchio joint ids
    that have a motor, in actuator order); ``idx_v_act`` ``(nu,)`` their indices in v;
    ``effort`` ``(nu,)`` [N·m or N] their limits (inf where unlimited); ``options``;
    ``inertia_changes`` (body name → largest principal moment added [kg·m²], see
    :attr:`ModelOptions.min_inertia`); ``frozen`` (Pinocchio joint ids of massless subtrees
    left out of the MuJoCo model, see the module docstring) and ``idx_v_frozen`` their
    indices in v."""

    def __init__(self, robot: Robot, spec: mujoco.MjSpec, mj: mujoco.MjModel,
                 contacts: dict[str, SoleContact], actuated: list[int], options: ModelOptions,
                 frozen: Sequence[int] = ()):
        self.robot, self.spec, self.mj, self.contacts = robot, spec, mj, contacts
        self.options = options
        #: body name -> largest principal moment added [kg·m²] (set by build_model)
        self.inertia_changes: dict[str, float] = {}
        m = robot.model
        self.frozen = tuple(frozen)
        self.idx_v_frozen = np.array([i for j in self.frozen for i in
                                      range(m.joints[j].idx_v, m.joints[j].idx_v
                                            + m.joints[j].nv)], dtype=int)
        self._neutral = pin.neutral(m)
        self.actuated = tuple(actuated)
        self.idx_v_act = np.array([m.joints[j].idx_v for j in actuated], dtype=int)
        self.effort = np.array([_effort(m, j) for j in actuated])
        self.free = m.njoints > 1 and _kind(m.joints[1]) == "FreeFlyer"
        self.free_placement = m.jointPlacements[1] if self.free else pin.SE3.Identity()
        # 1-DoF joints: (pin idx_q, pin idx_v, mj qposadr, mj dofadr, unbounded?)
        rows = []
        for j in range(1, m.njoints):
            jm = m.joints[j]
            if _kind(jm) == "FreeFlyer" or j in self.frozen:
                continue
            jid = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, m.names[j])
            rows.append((jm.idx_q, jm.idx_v, mj.jnt_qposadr[jid], mj.jnt_dofadr[jid],
                         jm.nq == 2))
        r = np.array(rows, dtype=int).reshape(-1, 5)
        self._q1, self._v1, self._p1, self._d1 = r[:, 0], r[:, 1], r[:, 2], r[:, 3]
        self._rub = r[:, 4].astype(bool)
        if self.free:
            jid = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, m.names[1])
            self._fp, self._fd = int(mj.jnt_qposadr[jid]), int(mj.jnt_dofadr[jid])
        self.foot_geom = {s: mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_GEOM, f"{s}_sole")
                          for s in SIDES}
        self.foot_body = {s: int(mj.geom_bodyid[self.foot_geom[s]]) for s in SIDES}
        self.sole_site = {s: mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_SITE, f"{s}_sole")
                          for s in SIDES}
        self.floor_geom = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        self.base_body = 1 if self.free else int(mj.jnt_bodyid[self._joint_id_last_base()])

    def _joint_id_last_base(self) -> int:
        names = [n for n in PLANAR_BASE if self.robot.model.existJointName(n)]
        if not names:  # fixed base: the first body
            return 0
        return mujoco.mj_name2id(self.mj, mujoco.mjtObj.mjOBJ_JOINT, names[-1])

    # ------------------------------------------------------------------ conversions
    def _base_rotation(self, q: np.ndarray) -> np.ndarray:
        R = pin.Quaternion(q[6], q[3], q[4], q[5]).normalized().matrix()
        return self.free_placement.rotation @ R

    def qpos_from_q(self, q: np.ndarray) -> np.ndarray:
        """MuJoCo ``qpos`` ``(nq_mj,)`` of a Pinocchio configuration ``q`` ``(nq,)``."""
        q = np.asarray(q, dtype=float)
        out = np.zeros(self.mj.nq)
        if self.free and self.free_placement.isIdentity():
            out[self._fp:self._fp + 3] = q[:3]
            out[self._fp + 3] = q[6]
            out[self._fp + 4:self._fp + 7] = q[3:6]
        elif self.free:
            M = self.free_placement * pin.XYZQUATToSE3(q[:7])
            out[self._fp:self._fp + 3] = M.translation
            out[self._fp + 3:self._fp + 7] = _quat_wxyz(M.rotation)
        out[self._p1] = np.where(self._rub, np.arctan2(q[np.minimum(self._q1 + 1, q.size - 1)],
                                                       q[self._q1]), q[self._q1])
        return out

    def q_from_qpos(self, qpos: np.ndarray) -> np.ndarray:
        """Pinocchio ``q`` ``(nq,)`` of a MuJoCo ``qpos`` (frozen joints: neutral)."""
        qpos = np.asarray(qpos, dtype=float)
        q = self._neutral.copy()
        if self.free:
            quat = qpos[self._fp + 3:self._fp + 7] / np.linalg.norm(qpos[self._fp + 3:self._fp + 7])
            if self.free_placement.isIdentity():
                q[:3] = qpos[self._fp:self._fp + 3]
                q[3:6], q[6] = quat[1:], quat[0]
            else:
                w, x, y, z = quat
                M = pin.SE3(pin.Quaternion(w, x, y, z).matrix(), qpos[self._fp:self._fp + 3].copy())
                q[:7] = pin.SE3ToXYZQUAT(self.free_placement.inverse() * M)
        th = qpos[self._p1]
        q[self._q1] = np.where(self._rub, np.cos(th), th)
        rub = self._q1[self._rub]
        q[rub + 1] = np.sin(th[self._rub])
        return q

    def _lin_rotation(self, q: np.ndarray) -> np.ndarray:
        """World rotation of the free-flyer body; identity without a free flyer."""
        return self._base_rotation(q) if self.free else np.eye(3)

    def qvel_from_v(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """MuJoCo ``qvel`` ``(nv,)`` of Pinocchio's ``v`` at configuration ``q``."""
        v = np.asarray(v, dtype=float)
        out = np.zeros(self.mj.nv)
        if self.free:
            R = self._lin_rotation(q)
            out[self._fd:self._fd + 3] = R @ v[:3]
            out[self._fd + 3:self._fd + 6] = v[3:6]
        out[self._d1] = v[self._v1]
        return out

    def v_from_qvel(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """Pinocchio ``v`` ``(nv,)`` of MuJoCo's ``qvel`` at ``qpos``."""
        qvel = np.asarray(qvel, dtype=float)
        v = np.zeros(self.robot.model.nv)
        if self.free:
            R = self._lin_rotation(self.q_from_qpos(qpos))
            v[:3] = R.T @ qvel[self._fd:self._fd + 3]
            v[3:6] = qvel[self._fd + 3:self._fd + 6]
        v[self._v1] = qvel[self._d1]
        return v

    def qacc_from_a(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """MuJoCo ``qacc`` of Pinocchio's ``a`` = dv/dt: the free joint's world linear
        acceleration is R (a_lin + ω × v_lin)."""
        a = np.asarray(a, dtype=float)
        v = np.asarray(v, dtype=float)
        out = np.zeros(self.mj.nv)
        if self.free:
            R = self._lin_rotation(q)
            out[self._fd:self._fd + 3] = R @ (a[:3] + np.cross(v[3:6], v[:3]))
            out[self._fd + 3:self._fd + 6] = a[3:6]
        out[self._d1] = a[self._v1]
        return out

    def tau_from_qfrc(self, q: np.ndarray, qfrc: np.ndarray) -> np.ndarray:
        """Pinocchio generalised force ``(nv,)`` dual to ``v`` of a MuJoCo one dual to
        ``qvel`` (the same power: τ·v = f·qvel)."""
        qfrc = np.asarray(qfrc, dtype=float)
        tau = np.zeros(self.robot.model.nv)
        if self.free:
            R = self._lin_rotation(q)
            tau[:3] = R.T @ qfrc[self._fd:self._fd + 3]
            tau[3:6] = qfrc[self._fd + 3:self._fd + 6]
        tau[self._v1] = qfrc[self._d1]
        return tau

    def velocity_map(self, q: np.ndarray) -> np.ndarray:
        """``T`` ``(nv_mj, nv)`` with qvel = T v at configuration ``q``."""
        nv = self.robot.model.nv
        return np.column_stack([self.qvel_from_v(q, e) for e in np.eye(nv)])

    # ------------------------------------------------------------------ helpers
    def new_data(self) -> mujoco.MjData:
        """A fresh ``MjData``."""
        return mujoco.MjData(self.mj)

    def set_state(self, data: mujoco.MjData, q: np.ndarray, v: np.ndarray) -> None:
        """Write a Pinocchio state into ``data`` and run ``mj_forward``."""
        data.qpos[:] = self.qpos_from_q(q)
        data.qvel[:] = self.qvel_from_v(q, v)
        mujoco.mj_forward(self.mj, data)

    def state(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Pinocchio ``(q, v)`` of ``data``."""
        q = self.q_from_qpos(data.qpos)
        return q, self.v_from_qvel(data.qpos, data.qvel)
