"""OpenSim joints as chains of URDF joints, with the approximation of coupled motions measured.

An OpenSim joint moves its child body B relative to its parent P as (see :mod:`.model`)::

    X_P_B(q) = X_P_F · Trans(Σ tᵢ(q)·aᵢ) · R₁(r₁(q)) · R₂(r₂(q)) · R₃(r₃(q)) · X_B_M⁻¹

Each transform axis is classified:

* **exact**: ``LinearFunction`` (or degree-1 ``Polynomial``) of one coordinate with slope ±1 —
  one URDF revolute (rotation) or prismatic (translation) joint *named after the coordinate*,
  its axis flipped for slope −1 and its intercept a fixed offset about/along the same axis
  (both exact, so the URDF joint value equals the OpenSim coordinate value);
* **constant**: a fixed rotation or offset;
* **coupled**: any other function (splines such as the gait2354 knee translation, the walker
  knee's spline rotations, patella coordinates, slopes ≠ ±1) — not representable in a URDF.

Coupled axes are approximated, keeping every URDF joint value equal to its coordinate:

* coupled *rotations* of the coordinate q of the joint's one exact rotation (a walker knee,
  whose ab/adduction and axial rotation — and translations — are splines of the flexion
  angle): every coupled axis of the joint becomes its own *spline-driven* URDF joint
  (revolute about / prismatic along the OpenSim axis, in OpenSim's order) named
  ``<coordinate>__<axis name>`` (e.g. ``knee_angle_r__rotation2``), whose value is
  ``f(q) − f(q_default)`` (:attr:`Step.follows`; readers fill it from q,
  :func:`follow_coordinates`). The chain is then OpenSim's transform exactly (no fixed axis
  follows a rotation that grows along a spline: the least-squares fixed axis it replaces was
  5.5 mm / 0.9° off on the synthetic walker knee over its range, 10.5 mm on a Rajagopal
  model's walk);
* coupled *translations* of a coordinate that drives an exact rotation of the joint (a knee
  whose centre of rotation slides with flexion) are replaced by the best fixed centre of
  rotation: the child origin is modelled as ``p + R(q)·d`` with constant ``p``, ``d`` [m]
  fitted by least squares to the true path over the coordinates' ranges;
* everything else (functions of a coordinate with no exact axis in the joint, slopes ≠ ±1,
  coupled rotations in joints with several exact rotations) is held at its value at the
  coordinates' default values.

:class:`Approximation` records, per joint, the largest error of the child body origin [m] and
orientation [rad] over the coordinates' whole ranges (the tests compare both against OpenSim).

Measured (tests/io/test_opensim_model.py, OpenSim 4.6 as reference):

* gait2354-family knee (subject01, translation splines of ``knee_angle``): the fixed hinge is
  within 3.2 mm of the spline knee over its whole range (−120°…+10°), and within 1.6 mm at
  every frame of the subject's 211-frame walking IK; orientations are exact. The whole-body
  centre of mass stays within 0.17 mm. (A translation held at the default knee angle would be
  17 mm off at 70° of flexion.)
* Rajagopal-style walker knee (the synthetic test model's knee: ab/adduction 0.05·sin(q/1.3)
  and axial rotation 0.1·q/2.09 rad, translation splines): spline-driven joints, every body
  origin within 1 µm of OpenSim's over −10°…120° of flexion (a fixed axis and centre: 0.9°
  and 5.5 mm; holding the coupled rotations at their default-angle values: 6.4°).
* Coordinates with no exact axis (a patella's ``knee_angle_r_beta``, a slope-0.5 rotation):
  the body is welded at the default value; the error is reported, the coordinate has no URDF
  joint.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ...errors import OsimError, UnitError
from .functions import Function
from .model import OsimJoint, OsimModel, read_osim

__all__ = ["WORLD_FROM_OPENSIM", "ground_to_world", "Step", "Approximation", "JointPlan",
           "plan_joint",
           "joint_transform", "pelvis_to_freeflyer", "root_joint", "follow_coordinates"]

#: Rotation turning OpenSim's ground axes (X forward, Y up, Z right) into ours (x forward,
#: y left, z up): v_ours = WORLD_FROM_OPENSIM @ v_osim, i.e. x = X, y = −Z, z = Y.
WORLD_FROM_OPENSIM = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def ground_to_world(up: str) -> np.ndarray:
    """Rotation ``(3, 3)`` from a lab frame with X forward and ``up`` (``"Y"``: OpenSim's
    ground, Z to the right; ``"Z"``: Y to the left) to our world (x forward, y left, z up)."""
    if up.upper() == "Y":
        return WORLD_FROM_OPENSIM.copy()
    if up.upper() == "Z":
        return np.eye(3)
    raise UnitError(f"up axis must be 'Y' or 'Z'; got {up!r}")


def rotations(axis: np.ndarray, angle: np.ndarray | float) -> np.ndarray:
    """Rotation matrices (*angle.shape, 3, 3) about unit ``axis`` (3,) by ``angle`` [rad]."""
    a = np.asarray(angle, dtype=float)[..., None, None]
    k = np.asarray(axis, dtype=float)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * (K @ K)


@dataclass(frozen=True)
class Step:
    """One URDF joint of a chain: ``kind`` ``"revolute"``/``"prismatic"``; ``coordinate``
    (the URDF joint's name); ``origin`` (R (3, 3), p (3,)) placing the joint frame in the
    previous link (OpenSim axes); unit ``axis`` (3,) in the joint frame; ``follows``: for a
    spline-driven joint (a coupled axis of a walker knee) ``(coordinate, function, f0)``: its
    value is ``function(q_coordinate) − f0`` (``f0``: the function at the coordinate's default,
    built into ``origin``), else ``None`` (the joint value IS the coordinate)."""

    kind: str
    coordinate: str
    origin: tuple[np.ndarray, np.ndarray]
    axis: np.ndarray
    follows: tuple[str, Function, float] | None = None

    def value(self, values: Mapping[str, np.ndarray], n: int) -> np.ndarray:
        """The joint's value ``(n,)`` [rad, m] for coordinate ``values`` (missing ones at 0 —
        the URDF's neutral; a spline-driven joint at 0 when its coordinate is missing)."""
        if self.follows is None:
            return _values(values, self.coordinate, n, 0.0)
        driver, f, f0 = self.follows
        if driver not in values:
            return np.zeros(n)
        return f(_values(values, driver, n, 0.0)) - f0


@dataclass(frozen=True)
class Approximation:
    """How a joint's coupled axes were approximated and how far off that is.

    ``coupled``: the transform-axis names approximated; ``coordinates``: the coordinates
    swept to measure the error; ``method``: ``"spline-driven joints"`` (exact up to
    round-off), ``"fixed-centre fit"`` or ``"held at default"``;
    ``max_position_error`` [m] of the child body origin and ``max_rotation_error`` [rad] of
    its orientation, over the coordinates' ranges.
    """

    joint: str
    coupled: tuple[str, ...]
    coordinates: tuple[str, ...]
    method: str
    max_position_error: float
    max_rotation_error: float


@dataclass(frozen=True)
class JointPlan:
    """An OpenSim joint as URDF joints: ``steps`` (possibly none: a fixed joint), then the
    fixed ``tail`` (R, p) from the last moving joint's frame to the child body's frame."""

    joint: str
    parent: str
    child: str
    steps: tuple[Step, ...]
    tail: tuple[np.ndarray, np.ndarray]
    approximation: Approximation | None


def _compose(A, B):
    """(R, p)·(R, p), batched over leading axes."""
    RA, pA = A
    RB, pB = B
    return RA @ RB, pA + (RA @ pB[..., None])[..., 0]


def _inverse(X):
    R, p = X
    Rt = np.swapaxes(R, -1, -2)
    return Rt, -(Rt @ p[..., None])[..., 0]


def _values(values: Mapping[str, np.ndarray], name: str, n: int, default: float) -> np.ndarray:
    v = values.get(name)
    return np.full(n, default) if v is None else np.broadcast_to(np.asarray(v, float), (n,))


def joint_transform(joint: OsimJoint, values: Mapping[str, np.ndarray], n: int):
    """OpenSim's X_P_B(q) for ``n`` samples: (R (n, 3, 3), p (n, 3)). ``values``: coordinate
    name → (n,) values [rad, m]; missing coordinates take their default values."""
    defaults = {c.name: c.default for c in joint.coordinates}
    R = np.broadcast_to(np.eye(3), (n, 3, 3))
    t = np.zeros((n, 3))
    for a in joint.axes:
        q = _values(values, a.coordinate, n, defaults.get(a.coordinate, 0.0)) \
            if a.coordinate else np.zeros(n)
        v = a.function(q)
        if a.kind == "rotation":
            R = R @ rotations(a.axis, v)
        else:
            t = t + v[:, None] * a.axis
    X = _compose(_compose(joint.parent_offset, (R, t)), _inverse(joint.child_offset))
    return X


def _classify(joint: OsimJoint, claimed: set[str]):
    """Per axis: ("exact", sign, intercept) | ("constant", value) | ("coupled",)."""
    out: list[tuple] = []
    for a in joint.axes:
        if a.coordinate is None:
            out.append(("constant", float(a.function(0.0))))
            continue
        lin = a.function.linear()
        if lin is not None and abs(abs(lin[0]) - 1.0) < 1e-12 and a.coordinate not in claimed:
            claimed.add(a.coordinate)
            out.append(("exact", float(np.sign(lin[0])), float(lin[1])))
        else:
            out.append(("coupled",))
    return out


def _build(joint: OsimJoint, kinds, held: Mapping[str, float], p_fit, d_fit,
           follow: bool = False):
    """Steps and tail of the approximating chain; coupled axes at their ``held`` values, or,
    with ``follow``, each coupled axis a spline-driven joint (``Step.follows``) — the chain is
    then OpenSim's transform exactly."""
    pending = joint.parent_offset
    tvec = np.asarray(p_fit, float).copy()
    steps: list[Step] = []
    trans = [(a, k) for a, k in zip(joint.axes, kinds) if a.kind == "translation"]
    rots = [(a, k) for a, k in zip(joint.axes, kinds) if a.kind == "rotation"]
    for a, k in trans:
        if k[0] == "constant":
            tvec = tvec + k[1] * a.axis
        elif k[0] == "exact":
            tvec = tvec + k[2] * a.axis
        else:  # coupled: held (a fit's p then corrects it) or followed from there
            tvec = tvec + held[a.name] * a.axis
    pending = _compose(pending, (np.eye(3), tvec))
    for a, k in trans:
        if k[0] == "exact" or (follow and k[0] == "coupled"):
            steps.append(_step("prismatic", a, k, held, pending))
            pending = (np.eye(3), np.zeros(3))
    for a, k in rots:
        if k[0] == "constant":
            pending = _compose(pending, (rotations(a.axis, k[1]), np.zeros(3)))
        elif k[0] == "coupled" and not follow:
            pending = _compose(pending, (rotations(a.axis, held[a.name]), np.zeros(3)))
        else:
            at = k[2] if k[0] == "exact" else held[a.name]
            pending = _compose(pending, (rotations(a.axis, at), np.zeros(3)))
            steps.append(_step("revolute", a, k, held, pending))
            pending = (np.eye(3), np.zeros(3))
    tail = _compose(_compose(pending, (np.eye(3), np.asarray(d_fit, float))),
                    _inverse(joint.child_offset))
    return tuple(steps), tail


def _step(kind: str, a, k, held: Mapping[str, float], origin) -> Step:
    """The URDF joint of one exact axis (named after its coordinate, axis flipped for slope
    −1) or one followed coupled axis (named ``<coordinate>__<axis name>``)."""
    if k[0] == "exact":
        return Step(kind, a.coordinate, origin, k[1] * a.axis)
    return Step(kind, f"{a.coordinate}__{a.name}", origin, a.axis,
                (a.coordinate, a.function, held[a.name]))


def chain_transform(steps, tail, values: Mapping[str, np.ndarray], n: int):
    """X_P_B of an approximating chain for ``n`` samples (R (n,3,3), p (n,3))."""
    X = (np.broadcast_to(np.eye(3), (n, 3, 3)), np.zeros((n, 3)))
    for s in steps:
        q = s.value(values, n)
        if s.kind == "revolute":
            M = (rotations(s.axis, q), np.zeros((n, 3)))
        else:
            M = (np.broadcast_to(np.eye(3), (n, 3, 3)), q[:, None] * s.axis)
        X = _compose(_compose(X, s.origin), M)
    return _compose(X, tail)


def _grid(coords, n_total: int = 4000) -> dict[str, np.ndarray]:
    k = len(coords)
    if k == 0:
        return {}
    m = int(np.clip(round(n_total ** (1.0 / k)), 3, 201))
    axes = [np.linspace(c.range[0], c.range[1], m) for c in coords]
    mesh = np.meshgrid(*axes, indexing="ij")
    return {c.name: g.ravel() for c, g in zip(coords, mesh)}


def _rotation_angle(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Angle [rad] of Raᵀ·Rb, precise for small angles: ‖Ra − Rb‖_F = 2√2·sin(θ/2)."""
    f = np.linalg.norm(Ra - Rb, axis=(-2, -1))
    return 2.0 * np.arcsin(np.clip(f / (2.0 * np.sqrt(2.0)), 0.0, 1.0))


def _walker(joint: OsimJoint, kinds) -> bool:
    """True for a joint whose one exact rotation's coordinate q also drives coupled rotations
    (a walker knee): its coupled axes of q become spline-driven joints. (A fixed axis fitted
    by least squares was 5.5 mm / 0.9° off on the synthetic walker knee, 10.5 mm on a
    Rajagopal model's: no fixed axis follows a rotation that grows along a spline.)"""
    rots = [(a, k) for a, k in zip(joint.axes, kinds) if a.kind == "rotation"]
    exact = [a.coordinate for a, k in rots if k[0] == "exact"]
    coupled = [a for a, k in zip(joint.axes, kinds) if k[0] == "coupled"]
    return (len(exact) == 1 and any(a.kind == "rotation" for a in coupled)
            and all(a.coordinate == exact[0] for a in coupled))


def plan_joint(joint: OsimJoint, claimed: set[str]) -> JointPlan:
    """Classify ``joint``'s axes (claiming exact coordinates in ``claimed``), approximate the
    coupled ones and measure the error over the coordinates' ranges."""
    kinds = _classify(joint, claimed)
    coupled = [a for a, k in zip(joint.axes, kinds) if k[0] == "coupled"]
    defaults = {c.name: c.default for c in joint.coordinates}
    held = {a.name: float(a.function(defaults[str(a.coordinate)])) for a in coupled}
    zero = np.zeros(3)
    if not coupled:
        steps, tail = _build(joint, kinds, held, zero, zero)
        return JointPlan(joint.name, joint.parent, joint.child, steps, tail, None)
    exact = {a.coordinate for a, k in zip(joint.axes, kinds) if k[0] == "exact"}
    riding = [a for a in coupled if a.kind == "translation" and a.coordinate in exact]
    swept = [c for c in joint.coordinates]
    grid = _grid(swept)
    n = len(next(iter(grid.values())))
    R_true, p_true = joint_transform(joint, grid, n)
    p_fit, d_fit, methods = zero, zero, []
    follow = _walker(joint, kinds)
    if follow:
        methods.append("spline-driven joints")
    elif riding:
        # fit p, d in  p + T_exact(q) + R(q)·d  ≈  true child origin (F frame), over the sweep
        steps0, tail0 = _build(joint, kinds, held, zero, zero)
        Xf = _inverse(joint.parent_offset)
        Rt_F, pt_F = _compose((np.broadcast_to(Xf[0], (n, 3, 3)),
                               np.broadcast_to(Xf[1], (n, 3))), (R_true, p_true))
        R0, p0 = _compose((np.broadcast_to(Xf[0], (n, 3, 3)), np.broadcast_to(Xf[1], (n, 3))),
                          chain_transform(steps0, tail0, grid, n))
        # without p, d: origin p0 = T_exact + R_apx·o ; with: + p + R_apx_pre·d, where
        # R_apx_pre = orientation of the frame before the tail's child offset
        R_pre = R0 @ joint.child_offset[0]
        A = np.concatenate([np.broadcast_to(np.eye(3), (n, 3, 3)), R_pre], axis=2)
        sol, *_ = np.linalg.lstsq(A.reshape(-1, 6), (pt_F - p0).reshape(-1), rcond=None)
        p_fit, d_fit = sol[:3], sol[3:]
        methods.append("fixed-centre fit")
    method = " + ".join(methods) or "held at default"
    steps, tail = _build(joint, kinds, held, p_fit, d_fit, follow)
    R_apx, p_apx = chain_transform(steps, tail, grid, n)
    approx = Approximation(
        joint.name, tuple(a.name for a in coupled), tuple(c.name for c in swept), method,
        float(np.max(np.linalg.norm(p_apx - p_true, axis=1))),
        float(np.max(_rotation_angle(R_apx, R_true))))
    return JointPlan(joint.name, joint.parent, joint.child, steps, tail, approx)


def root_joint(model: OsimModel) -> OsimJoint:
    """The single joint from the ground; it must be a 6-DoF free joint (3 exact rotations and
    3 exact translations), which becomes Pinocchio's free-flyer."""
    roots = [j for j in model.joints if j.parent == model.ground]
    if len(roots) != 1:
        raise OsimError(f"{model.name}: {len(roots)} joints hang from the ground "
                        f"({[j.name for j in roots]}); exactly one (ground→pelvis, 6 DoF) is "
                        "supported — weld the others to the pelvis or remove them")
    j = roots[0]
    kinds = _classify(j, set())
    n_rot = sum(k[0] == "exact" and a.kind == "rotation" for a, k in zip(j.axes, kinds))
    n_tr = sum(k[0] == "exact" and a.kind == "translation" for a, k in zip(j.axes, kinds))
    if n_rot != 3 or n_tr != 3 or any(k[0] == "coupled" for k in kinds):
        raise OsimError(f"{model.name}: the ground joint {j.name!r} must have 3 rotational and "
                        "3 translational coordinates, each a LinearFunction with slope ±1 (a "
                        f"free joint); it has {n_rot} and {n_tr}")
    return j


def pelvis_to_freeflyer(values: Mapping[str, np.ndarray],
                        model: OsimModel | str | Path) -> np.ndarray:
    """Pinocchio free-flyer configurations of the root body (pelvis) in OUR world frame.

    ``values``: root-joint coordinate name → (T,) values in radians and metres (e.g.
    ``pelvis_tilt``, ``pelvis_list``, ``pelvis_rotation``, ``pelvis_tx``, ``pelvis_ty``,
    ``pelvis_tz``; convert degrees first); missing ones take their default values.
    ``model``: the :class:`~gdimitate.model.osim.model.OsimModel` or ``.osim`` path whose root
    joint defines the coordinates (its axes, order, offsets). Returns ``(T, 7)``
    ``[x, y, z, qx, qy, qz, qw]``: the pose of the URDF root link written by
    :func:`~gdimitate.opensim.opensim_to_urdf`, position = C·p, rotation = C·R·Cᵀ with
    C = :data:`WORLD_FROM_OPENSIM` (x = X, y = −Z, z = Y).
    """
    m = model if isinstance(model, OsimModel) else read_osim(model)
    j = root_joint(m)
    lens = {np.asarray(v).shape for v in values.values()}
    if len(lens) > 1:
        raise OsimError(f"pelvis_to_freeflyer: coordinate arrays differ in shape {lens}")
    unknown = set(values) - {c.name for c in j.coordinates}
    if unknown:
        raise OsimError(f"pelvis_to_freeflyer: {sorted(unknown)} are not coordinates of the "
                        f"root joint {j.name!r} ({[c.name for c in j.coordinates]})")
    arr = [np.atleast_1d(np.asarray(v, float)) for v in values.values()]
    n = arr[0].shape[0] if arr else 1
    if any(not np.all(np.isfinite(a)) for a in arr):
        raise OsimError("pelvis_to_freeflyer: NaN/inf coordinate values")
    R, p = joint_transform(j, {k: np.atleast_1d(np.asarray(v, float))
                               for k, v in values.items()}, n)
    C = WORLD_FROM_OPENSIM
    Rw = C @ R @ C.T
    pw = p @ C.T
    quat = Rotation.from_matrix(Rw).as_quat()  # x, y, z, w
    return np.concatenate([pw, quat], axis=1)


def follow_coordinates(plans, q: np.ndarray, idx_q) -> np.ndarray:
    """Fill the spline-driven joints of ``q`` ``(T, nq)`` from their coordinates' columns, in
    place, and return it. ``plans``: the conversion's :class:`JointPlan` s; ``idx_q``: joint
    name → column (e.g. ``Robot.idx_q``)."""
    for pl in plans:
        for s in pl.steps:
            if s.follows is not None:
                driver, f, f0 = s.follows
                q[:, idx_q(s.coordinate)] = f(q[:, idx_q(driver)]) - f0
    return q
