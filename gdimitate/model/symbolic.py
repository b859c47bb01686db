"""CasADi (SX) kinematics and dynamics of a Pinocchio model.

The PyPI ``pin`` wheel has no CasADi bindings, so this module rebuilds, from a ``pin.Model``'s
joint placements, joint axes, inertias and frames, the expressions the optimiser needs:

- world placement of any frame (position ``(3,)``, rotation ``(3, 3)``) and its ``(6, nv)``
  Jacobian in Pinocchio's ``LOCAL_WORLD_ALIGNED`` convention (rows: linear, angular);
- centre of mass ``(3,)``, its acceleration ``(3,)`` and the centroidal momentum rate ``(6,)``;
- inverse dynamics (recursive Newton-Euler) ``(nv,)``, with or without contact wrenches at
  named frames;
- the configuration update ``q ⊕ dv`` (Pinocchio's ``integrate``): additive for 1-DoF joints,
  a rotation of ``[cos, sin]`` for continuous joints, the SE(3) exponential map for the
  free-flyer (quaternion product) and the SE(2) one for planar joints.

Conventions are Pinocchio's, exactly: ``q`` of a free-flyer is ``[x, y, z, qx, qy, qz, qw]``,
its ``v`` and ``a`` are the spatial velocity and acceleration of the base in the base's LOCAL
frame (linear first); continuous joints (``RUB*``) take ``q = [cos, sin]``; gravity is
``model.gravity``. Everything is built once, in the constructor, on shared SX symbols, so that
subexpressions (joint placements, body velocities) are reused by every function.

Spatial algebra (written here, Featherstone/Pinocchio convention): motions and forces are pairs
``(linear, angular)`` of 3-vectors expressed in a body frame; a placement ``M = (R, p)`` maps
child coordinates to parent coordinates.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence

import casadi as ca
import numpy as np
import pinocchio as pin

from ..errors import UnknownNameError, UnsupportedJointError

__all__ = ["SymbolicModel", "SUPPORTED_JOINTS"]

_REVOLUTE = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2,
             "JointModelRevoluteUnaligned": None}
_REVOLUTE_UB = {"JointModelRUBX": 0, "JointModelRUBY": 1, "JointModelRUBZ": 2,
                "JointModelRevoluteUnboundedUnaligned": None}
_PRISMATIC = {"JointModelPX": 0, "JointModelPY": 1, "JointModelPZ": 2,
              "JointModelPrismaticUnaligned": None}
SUPPORTED_JOINTS: tuple[str, ...] = (
    *_REVOLUTE, *_REVOLUTE_UB, *_PRISMATIC, "JointModelFreeFlyer", "JointModelPlanar",
)
"""Pinocchio joint types (``shortname()``) that :class:`SymbolicModel` implements."""

Motion = tuple[ca.SX, ca.SX]  # (linear (3,), angular (3,))
Placement = tuple[ca.SX, ca.SX]  # (R (3, 3), p (3,))


def _cross(a: ca.SX, b: ca.SX) -> ca.SX:
    return ca.vertcat(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                      a[0] * b[1] - a[1] * b[0])


def _compose(m1: Placement, m2: Placement) -> Placement:
    return ca.mtimes(m1[0], m2[0]), m1[1] + ca.mtimes(m1[0], m2[1])


def _act_inv_motion(m: Placement, x: Motion) -> Motion:
    """Parent-frame motion ``x`` expressed in the child frame of ``m``."""
    rt = m[0].T
    return ca.mtimes(rt, x[0] - _cross(m[1], x[1])), ca.mtimes(rt, x[1])


def _act_force(m: Placement, f: Motion) -> Motion:
    """Child-frame force ``f`` expressed in the parent frame of ``m``."""
    lin = ca.mtimes(m[0], f[0])
    return lin, ca.mtimes(m[0], f[1]) + _cross(m[1], lin)


def _rotation(axis: np.ndarray, c: ca.SX, s: ca.SX) -> ca.SX:
    """Rotation about a unit ``axis`` with ``cos = c``, ``sin = s`` (Rodrigues), entry-wise so
    that zero coefficients vanish from the graph."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    aa = np.outer(axis, axis)
    rows = []
    for i in range(3):
        row = []
        for j in range(3):
            e = ca.SX(aa[i, j])
            if (i == j) - aa[i, j] != 0.0:
                e = e + ((i == j) - aa[i, j]) * c
            if k[i, j] != 0.0:
                e = e + k[i, j] * s
            row.append(e)
        rows.append(ca.horzcat(*row))
    return ca.vertcat(*rows)


def _quat_rotation(x: ca.SX, y: ca.SX, z: ca.SX, w: ca.SX) -> ca.SX:
    """Rotation matrix of quaternion ``(x, y, z, w)`` (Eigen's formula; unit norm assumed)."""
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
        ca.horzcat(2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
        ca.horzcat(2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
    )


def _series(th2: ca.SX, exact: Callable[[ca.SX], ca.SX], taylor: Sequence[float],
            eps: float = 1e-6) -> ca.SX:
    """A smooth function of ``θ²``: ``exact(θ²)`` away from 0, its Taylor polynomial
    (coefficients of 1, θ², θ⁴, ...) below ``eps``; the exact branch sees a safe argument there so
    that neither branch nor its derivative produces NaN."""
    safe = ca.if_else(th2 < eps, ca.SX(1.0), th2)
    poly = sum(c * th2**i for i, c in enumerate(taylor))
    return ca.if_else(th2 < eps, poly, exact(safe))


def _quat_mul(a: ca.SX, b: ca.SX) -> ca.SX:
    """Hamilton product of quaternions ``(x, y, z, w)``."""
    av, aw, bv, bw = a[:3], a[3], b[:3], b[3]
    return ca.vertcat(aw * bv + bw * av + _cross(av, bv), aw * bw - ca.dot(av, bv))


def _skew(w: ca.SX) -> ca.SX:
    z = ca.SX(0)
    return ca.vertcat(ca.horzcat(z, -w[2], w[1]), ca.horzcat(w[2], z, -w[0]),
                      ca.horzcat(-w[1], w[0], z))


def _se3_integrate(q: ca.SX, dv: ca.SX) -> ca.SX:
    """Free-flyer ``q ⊕ dv``: ``M · exp6(dv)`` with ``dv = [v; ω]`` in the local frame; the
    quaternion part ``quat ⊗ exp3(ω)`` (Pinocchio, ``JointModelFreeFlyer::integrate``)."""
    v, w = dv[:3], dv[3:]
    th2 = ca.dot(w, w)
    # exp3 as a quaternion: (sin(θ/2)/θ · ω, cos(θ/2))
    sh = _series(th2, lambda x: ca.sin(ca.sqrt(x) / 2) / ca.sqrt(x), (0.5, -1 / 48, 1 / 3840))
    ch = _series(th2, lambda x: ca.cos(ca.sqrt(x) / 2), (1.0, -1 / 8, 1 / 384))
    quat = _quat_mul(q[3:7], ca.vertcat(sh * w, ch))
    # V(ω) = I + (1 − cos θ)/θ² [ω]× + (θ − sin θ)/θ³ [ω]×²
    b = _series(th2, lambda x: (1 - ca.cos(ca.sqrt(x))) / x, (0.5, -1 / 24, 1 / 720))
    c = _series(th2, lambda x: (ca.sqrt(x) - ca.sin(ca.sqrt(x))) / (x * ca.sqrt(x)),
                (1 / 6, -1 / 120, 1 / 5040))
    W = _skew(w)
    step = v + b * ca.mtimes(W, v) + c * ca.mtimes(W, ca.mtimes(W, v))
    R = _quat_rotation(q[3], q[4], q[5], q[6])
    return ca.vertcat(q[:3] + ca.mtimes(R, step), quat)


def _se2_integrate(q: ca.SX, dv: ca.SX) -> ca.SX:
    """Planar joint ``q = [x, y, cos, sin] ⊕ dv = [vx, vy, ω]`` (local): SE(2) exponential."""
    vx, vy, w = dv[0], dv[1], dv[2]
    th2 = w * w
    s_over = _series(th2, lambda x: ca.sin(ca.sqrt(x)) / ca.sqrt(x), (1.0, -1 / 6, 1 / 120))
    c_over = _series(th2, lambda x: (1 - ca.cos(ca.sqrt(x))) / x, (0.5, -1 / 24, 1 / 720))
    lx = s_over * vx - c_over * w * vy
    ly = c_over * w * vx + s_over * vy
    c0, s0 = q[2], q[3]
    cw, sw = ca.cos(w), ca.sin(w)
    return ca.vertcat(q[0] + c0 * lx - s0 * ly, q[1] + s0 * lx + c0 * ly,
                      c0 * cw - s0 * sw, s0 * cw + c0 * sw)


def _fname(prefix: str, name: str) -> str:
    """A valid CasADi function name built from a frame name."""
    return prefix + "_" + re.sub(r"\W", "_", name)


def _unit_axis(jmodel: pin.JointModel, part: slice) -> np.ndarray:
    """Axis of a one-DoF joint, read from its motion subspace (angular or linear part)."""
    jdata = jmodel.createData()
    nq = jmodel.nq
    q0 = np.array([1.0, 0.0]) if nq == 2 else np.zeros(nq)
    jmodel.calc(jdata, q0)
    return np.asarray(jdata.S).reshape(6)[part].copy()


class SymbolicModel:
    """CasADi SX kinematics and dynamics of a ``pin.Model`` (see the module docstring).

    Attributes:
        nq, nv: configuration and velocity sizes.
        mass: total mass (kg) of the bodies attached to moving joints.
        gravity: ``(3,)`` linear gravity (m/s²).
        frame_names: unique frame names, in model order.
        joint_names: joint names without ``"universe"``.
        q, v, a: the SX symbols ``(nq,)``, ``(nv,)``, ``(nv,)`` every expression depends on.
        rnea: ``casadi.Function`` ``(q, v, a) -> tau (nv,)`` (N, N·m): inverse dynamics.
        com: ``casadi.Function`` ``q -> (3,)`` (m): centre of mass in the world frame.
        com_acceleration: ``casadi.Function`` ``(q, v, a) -> (3,)`` (m/s²): c̈ in the world.
        centroidal_momentum_rate: ``casadi.Function`` ``(q, v, a) -> (6,)``: time derivative
            of the centroidal momentum (N; N·m), linear first, at the centre of mass with world
            axes (Pinocchio's ``data.dhg``). Its linear part equals ``mass * com_acceleration``;
            the net external (contact) force is ``mass * (c̈ - gravity)``.

    Raises:
        UnsupportedJointError: for a joint type outside :data:`SUPPORTED_JOINTS`.
    """

    def __init__(self, model: pin.Model):
        self.model = model
        self.nq: int = int(model.nq)
        self.nv: int = int(model.nv)
        self.joint_names: tuple[str, ...] = tuple(model.names[1:])
        self._frame_ids: dict[str, int] = {}
        for fid, frame in enumerate(model.frames):
            self._frame_ids.setdefault(frame.name, fid)
        self.frame_names: tuple[str, ...] = tuple(self._frame_ids)
        self.gravity: np.ndarray = np.array(model.gravity.linear, dtype=float)
        self.q = ca.SX.sym("q", self.nq)
        self.v = ca.SX.sym("v", self.nv)
        self.a = ca.SX.sym("a", self.nv)
        self._build()
        self._cache: dict[tuple, ca.Function] = {}
        self.rnea = ca.Function("rnea", [self.q, self.v, self.a], [self._backward({})],
                                ["q", "v", "a"], ["tau"])
        self.com = ca.Function("com", [self.q], [self._com], ["q"], ["com"])
        self.com_acceleration = ca.Function(
            "com_acceleration", [self.q, self.v, self.a], [self._acom], ["q", "v", "a"],
            ["acom"])
        self.centroidal_momentum_rate = ca.Function(
            "centroidal_momentum_rate", [self.q, self.v, self.a], [self._dhg],
            ["q", "v", "a"], ["dhg"])
        self.integrate = ca.Function("integrate", [self.q, self.v], [self._integrate()],
                                     ["q", "dv"], ["q_next"])
        """``casadi.Function`` ``(q (nq,), dv (nv,)) -> (nq,)``: ``q ⊕ dv`` exactly as
        Pinocchio's ``integrate`` (a free-flyer's ``dv`` is a twist in the base's LOCAL frame,
        linear first)."""

    # ------------------------------------------------------------------ construction
    def _joint(self, jid: int) -> tuple[Placement, ca.SX, ca.SX, ca.SX]:
        """``(M_J, S (6, nv_j), q_dot_j, a_j)`` of joint ``jid``; its bias ``c_J`` is zero for
        every supported type (constant motion subspace in the joint frame)."""
        jm = self.model.joints[jid]
        kind = jm.shortname()
        if kind not in SUPPORTED_JOINTS:
            raise UnsupportedJointError(
                f"joint {self.model.names[jid]!r} has type {kind}, which the symbolic model "
                f"does not implement; supported types: {', '.join(SUPPORTED_JOINTS)}")
        q = self.q[jm.idx_q: jm.idx_q + jm.nq]
        vj = self.v[jm.idx_v: jm.idx_v + jm.nv]
        aj = self.a[jm.idx_v: jm.idx_v + jm.nv]
        zero3 = ca.SX.zeros(3)
        if kind in _REVOLUTE or kind in _REVOLUTE_UB:
            k = {**_REVOLUTE, **_REVOLUTE_UB}[kind]
            axis = np.eye(3)[k] if k is not None else _unit_axis(jm, slice(3, 6))
            c, s = (ca.cos(q[0]), ca.sin(q[0])) if kind in _REVOLUTE else (q[0], q[1])
            m = (_rotation(axis, c, s), zero3)
            sub = np.concatenate([np.zeros(3), axis])[:, None]
        elif kind in _PRISMATIC:
            k = _PRISMATIC[kind]
            axis = np.eye(3)[k] if k is not None else _unit_axis(jm, slice(0, 3))
            m = (ca.SX.eye(3), ca.SX(axis) * q[0])
            sub = np.concatenate([axis, np.zeros(3)])[:, None]
        elif kind == "JointModelFreeFlyer":
            m = (_quat_rotation(q[3], q[4], q[5], q[6]), q[:3])
            sub = np.eye(6)
        else:  # JointModelPlanar: q = [x, y, cos, sin], v = [vx, vy, wz] (local)
            m = (_rotation(np.array([0.0, 0.0, 1.0]), q[2], q[3]), ca.vertcat(q[0], q[1], 0))
            sub = np.zeros((6, 3))
            sub[0, 0] = sub[1, 1] = sub[5, 2] = 1.0
        return m, ca.SX(sub), vj, aj

    def _build(self) -> None:
        """Forward pass: placements, velocities, accelerations and body forces of all joints."""
        model = self.model
        n = model.njoints
        zero = ca.SX.zeros(3)
        self._omi: list[Placement] = [(ca.SX.eye(3), zero)]
        self._limi: list[Placement] = [(ca.SX.eye(3), zero)]
        self._sub: list[ca.SX] = [ca.SX.zeros(6, 0)]
        vel: list[Motion] = [(zero, zero)]
        acc: list[Motion] = [(zero, zero)]
        g = model.gravity
        acc_gf: list[Motion] = [(ca.SX(-g.linear), ca.SX(-g.angular))]
        self._f: list[Motion] = [(zero, zero)]
        mass_total = 0.0
        com_sum = ca.SX.zeros(3)
        acom_sum = ca.SX.zeros(3)
        for i in range(1, n):
            par = model.parents[i]
            mj, sub, vj, aj = self._joint(i)
            jp = model.jointPlacements[i]
            limi = _compose((ca.SX(jp.rotation), ca.SX(jp.translation)), mj)
            omi = _compose(self._omi[par], limi)
            s_v = ca.mtimes(sub, vj)
            vJ = (s_v[:3], s_v[3:])
            s_a = ca.mtimes(sub, aj)
            vp = _act_inv_motion(limi, vel[par])
            vi = (vp[0] + vJ[0], vp[1] + vJ[1])
            # a_i = X a_parent + S a_j + v_i x vJ   (c_J = 0)
            bias = (_cross(vi[1], vJ[0]) + _cross(vi[0], vJ[1]), _cross(vi[1], vJ[1]))
            ap = _act_inv_motion(limi, acc[par])
            ai = (ap[0] + s_a[:3] + bias[0], ap[1] + s_a[3:] + bias[1])
            agp = _act_inv_motion(limi, acc_gf[par])
            agi = (agp[0] + s_a[:3] + bias[0], agp[1] + s_a[3:] + bias[1])
            # body force f_i = I a_gf + v x* (I v)
            inertia = model.inertias[i]
            mi, ci, ic = float(inertia.mass), ca.SX(inertia.lever), ca.SX(inertia.inertia)
            h = self._inertia_times(mi, ci, ic, vi)
            ia = self._inertia_times(mi, ci, ic, agi)
            fi = (ia[0] + _cross(vi[1], h[0]),
                  ia[1] + _cross(vi[1], h[1]) + _cross(vi[0], h[0]))
            self._omi.append(omi)
            self._limi.append(limi)
            self._sub.append(sub)
            vel.append(vi)
            acc.append(ai)
            acc_gf.append(agi)
            self._f.append(fi)
            if mi != 0.0:
                mass_total += mi
                com_sum += mi * (omi[1] + ca.mtimes(omi[0], ci))
                # classical acceleration of the body's com point, in world axes
                acl = (ai[0] + _cross(ai[1], ci)
                       + _cross(vi[1], vi[0] + _cross(vi[1], ci)))
                acom_sum += mi * ca.mtimes(omi[0], acl)
        self.mass: float = mass_total
        inv_m = 1.0 / mass_total if mass_total > 0 else 0.0
        self._com = com_sum * inv_m
        self._acom = acom_sum * inv_m
        # centroidal momentum rate from the net body-force wrench at the world origin, shifted
        # to the com and with the gravity wrench added back (f_i contains -m g).
        f0 = self._root_wrench()
        mg = mass_total * ca.SX(self.gravity)
        lin = f0[0] + mg
        ang = f0[1] + _cross(self._com, mg) - _cross(self._com, lin)
        self._dhg = ca.vertcat(lin, ang)

    @staticmethod
    def _inertia_times(m: float, c: ca.SX, ic: ca.SX, x: Motion) -> Motion:
        """Spatial inertia (mass ``m``, com ``c``, rotational inertia at com ``ic``) times the
        motion ``x``: ``f = m (v - c x w)``, ``n = Ic w + c x f``."""
        f = m * (x[0] - _cross(c, x[1]))
        return f, ca.mtimes(ic, x[1]) + _cross(c, f)

    def _root_wrench(self) -> Motion:
        """Sum of all body forces ``f_i`` in world axes about the world origin."""
        lin, ang = ca.SX.zeros(3), ca.SX.zeros(3)
        for i in range(1, self.model.njoints):
            fl, fa = _act_force(self._omi[i], self._f[i])
            lin, ang = lin + fl, ang + fa
        return lin, ang

    def _backward(self, extra: dict[int, list[Motion]]) -> ca.SX:
        """RNEA backward pass; ``extra[jid]`` lists external forces (joint-local) to subtract."""
        n = self.model.njoints
        f = list(self._f)
        for jid, forces in extra.items():
            for fe in forces:
                f[jid] = (f[jid][0] - fe[0], f[jid][1] - fe[1])
        tau: list[ca.SX] = [ca.SX()] * n
        for i in range(n - 1, 0, -1):
            tau[i] = ca.mtimes(self._sub[i].T, ca.vertcat(*f[i]))
            par = self.model.parents[i]
            if par > 0:
                fl, fa = _act_force(self._limi[i], f[i])
                f[par] = (f[par][0] + fl, f[par][1] + fa)
        out = ca.SX.zeros(self.nv)
        for i in range(1, n):
            jm = self.model.joints[i]
            out[jm.idx_v: jm.idx_v + jm.nv] = tau[i]
        return out

    # ------------------------------------------------------------------ integration
    def _integrate(self) -> ca.SX:
        """``q ⊕ v`` per joint (the symbols ``self.q``, ``self.v`` read as ``q`` and ``dv``)."""
        out = []
        for jid in range(1, self.model.njoints):
            jm = self.model.joints[jid]
            kind = jm.shortname()
            q = self.q[jm.idx_q: jm.idx_q + jm.nq]
            dv = self.v[jm.idx_v: jm.idx_v + jm.nv]
            if kind in _REVOLUTE or kind in _PRISMATIC:
                out.append(q + dv)
            elif kind in _REVOLUTE_UB:
                c, s_ = ca.cos(dv[0]), ca.sin(dv[0])
                out.append(ca.vertcat(q[0] * c - q[1] * s_, q[1] * c + q[0] * s_))
            elif kind == "JointModelFreeFlyer":
                out.append(_se3_integrate(q, dv))
            elif kind == "JointModelPlanar":
                out.append(_se2_integrate(q, dv))
            else:  # pragma: no cover - _joint() rejected it already
                raise UnsupportedJointError(kind)
        return ca.vertcat(*out)

    # ------------------------------------------------------------------ frames
    def frame_id(self, name: str) -> int:
        """Index in ``model.frames`` of the first frame called ``name``.

        Raises:
            UnknownNameError: if no frame has that name (the message lists them).
        """
        try:
            return self._frame_ids[name]
        except (KeyError, TypeError):
            raise UnknownNameError("frame", name, self.frame_names) from None

    def _frame_placement(self, name: str) -> tuple[int, Placement]:
        fr = self.model.frames[self.frame_id(name)]
        pl = fr.placement
        jid = int(fr.parentJoint)
        return jid, _compose(self._omi[jid], (ca.SX(pl.rotation), ca.SX(pl.translation)))

    def _cached(self, key: tuple, make: Callable[[], ca.Function]) -> ca.Function:
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    def frame_position(self, name: str) -> ca.Function:
        """``casadi.Function`` ``q -> (3,)``: world position (m) of frame ``name``'s origin."""
        return self._cached(("pos", name), lambda: ca.Function(
            _fname("pos", name), [self.q], [self._frame_placement(name)[1][1]], ["q"], ["p"]))

    def frame_rotation(self, name: str) -> ca.Function:
        """``casadi.Function`` ``q -> (3, 3)``: rotation of frame ``name`` (columns: the
        frame's axes in world coordinates)."""
        return self._cached(("rot", name), lambda: ca.Function(
            _fname("rot", name), [self.q], [self._frame_placement(name)[1][0]], ["q"], ["R"]))

    def frame_jacobian(self, name: str) -> ca.Function:
        """``casadi.Function`` ``q -> (6, nv)``: Jacobian of frame ``name`` in Pinocchio's
        ``LOCAL_WORLD_ALIGNED`` convention: rows 0-2 map ``v`` to the velocity (m/s) of the
        frame's origin, rows 3-5 to its angular velocity (rad/s), both in world axes."""

        def make() -> ca.Function:
            jid, (_, pf) = self._frame_placement(name)
            jac = ca.SX.zeros(6, self.nv)
            k = jid
            while k > 0:
                rk, pk = self._omi[k]
                jm = self.model.joints[k]
                sub = self._sub[k]
                for c in range(jm.nv):
                    w = ca.mtimes(rk, sub[3:, c])
                    lin = ca.mtimes(rk, sub[:3, c]) + _cross(w, pf - pk)
                    jac[:, jm.idx_v + c] = ca.vertcat(lin, w)
                k = self.model.parents[k]
            return ca.Function(_fname("jac", name), [self.q], [jac], ["q"], ["J"])

        return self._cached(("jac", name), make)

    def placement(self, name: str) -> Placement:
        """World ``(R (3, 3), p (3,))`` of frame ``name`` as SX expressions in :attr:`q` (they
        share the forward pass with every other expression of this model)."""
        return self._frame_placement(name)[1]

    def root_placement(self, name: str) -> Placement:
        """``(R (3, 3), p (3,))`` of frame ``name`` in the root joint's frame (the base's, for
        a floating or planar base; the world's where several joints hang from the universe):
        SX expressions in the joint coordinates below the root only, so that a quantity the
        base's motion leaves unchanged (a distance between two bodies) does not depend,
        structurally, on the base's ``q``."""
        fr = self.model.frames[self.frame_id(name)]
        pl = fr.placement
        return _compose(self._in_root(int(fr.parentJoint)),
                        (ca.SX(pl.rotation), ca.SX(pl.translation)))

    def _in_root(self, jid: int) -> Placement:
        memo = self.__dict__.setdefault("_in_root_memo", {})
        if jid not in memo:
            model = self.model
            root = 1 if [int(p) for p in model.parents[1:]].count(0) == 1 else 0
            if jid == root:
                memo[jid] = (ca.SX.eye(3), ca.SX.zeros(3))
            elif jid == 0:  # the world, seen from the root
                r, p = self._omi[root]
                memo[jid] = (r.T, -ca.mtimes(r.T, p))
            else:
                memo[jid] = _compose(self._in_root(int(model.parents[jid])), self._limi[jid])
        return memo[jid]

    def rnea_contact_expr(self, frames: Sequence[str], wrenches: Sequence[ca.SX]) -> ca.SX:
        """The expression of :meth:`rnea_contact` in :attr:`q`, :attr:`v`, :attr:`a` and the
        given world-aligned ``(6,)`` wrench expressions (shares the forward pass)."""
        extra: dict[int, list[Motion]] = {}
        for name, w in zip(frames, wrenches):
            jid, (_, pf) = self._frame_placement(name)
            rj, pj = self._omi[jid]
            fl = ca.mtimes(rj.T, w[:3])
            fa = ca.mtimes(rj.T, w[3:] + _cross(pf - pj, w[:3]))
            extra.setdefault(jid, []).append((fl, fa))
        return self._backward(extra)

    @property
    def com_expr(self) -> ca.SX:
        """Centre of mass ``(3,)`` as an SX expression in :attr:`q`."""
        return self._com

    def rnea_contact(self, frames: Sequence[str]) -> ca.Function:
        """Inverse dynamics with contact wrenches at the named frames.

        Returns a ``casadi.Function`` ``(q, v, a, w_1, ..., w_k) -> tau (nv,)`` where each
        ``w_c`` is a ``(6,)`` wrench ``[force (N); torque (N·m)]`` that the environment applies
        at the origin of ``frames[c]``, in world axes. Equivalent to
        ``rnea(q, v, a) - sum_c frame_jacobian(frames[c])(q).T @ w_c``, computed inside the
        recursion.
        """
        frames = tuple(frames)

        def make() -> ca.Function:
            wrenches: list = []
            extra: dict = {}
            for c, name in enumerate(frames):
                jid, (_, pf) = self._frame_placement(name)
                w = ca.SX.sym(f"w{c}", 6)
                wrenches.append(w)
                rj, pj = self._omi[jid]
                # world-aligned wrench at p_f -> joint-local wrench about the joint origin
                fl = ca.mtimes(rj.T, w[:3])
                fa = ca.mtimes(rj.T, w[3:] + _cross(pf - pj, w[:3]))
                extra.setdefault(jid, []).append((fl, fa))
            return ca.Function(
                "rnea_contact", [self.q, self.v, self.a, *wrenches], [self._backward(extra)],
                ["q", "v", "a", *[f"w{c}" for c in range(len(frames))]], ["tau"])

        for name in frames:
            self.frame_id(name)
        return self._cached(("rnea_contact", frames), make)
