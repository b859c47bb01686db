"""Flat-foot contacts: the sole rectangle of each foot and its contact wrench cone.

A :class:`SoleContact` is a Pinocchio frame at the centre of a foot's sole (z along the sole's
outward normal — up when the foot is flat on the floor — x forward), the sole rectangle's
half-length ``X`` (along x) and half-width ``Y`` (along y) [m], and the friction coefficient
``mu``. The contact wrench ``w = [f; τ]`` (6,) that the ground applies to the foot is written at
the frame's origin in the frame's axes.

The wrench cone of a rectangular sole (Caron, Pham, Nakamura, "Stability of surface contacts
for humanoid robots: closed-form formulae of the contact wrench cone for rectangular support
areas", ICRA 2015, arXiv:1501.04719) is the set of wrenches that four corner forces, each in
its Coulomb friction cone, can produce. In closed form, 16 linear inequalities
``A(X, Y, μ) @ w <= 0`` (:func:`wrench_cone`):

    |f_x| ≤ μ f_z,  |f_y| ≤ μ f_z,  |τ_x| ≤ Y f_z,  |τ_y| ≤ X f_z,
    τ_min ≤ τ_z ≤ τ_max,
    τ_min = −μ(X+Y) f_z + |Y f_x − μ τ_x| + |X f_y − μ τ_y|,
    τ_max = +μ(X+Y) f_z − |Y f_x + μ τ_x| − |X f_y + μ τ_y|.

A unilateral minimum ``f_z ≥ f_min`` is kept separate (it is a problem parameter).

Sole rectangles are measured from the foot's geometry (:func:`measure_sole`): the vertices of
the collision and visual geometry attached to the foot's joint that lie within ``depth`` [m] of
the lowest one at the robot's grounded neutral pose, their extent along the world x and y axes.
Users override them with ``Robot(..., contacts=...)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import ContactError, InvalidInputError
from .meshes import ASSIMP_Y_UP_UNDO, collada_y_up

__all__ = [
    "DEFAULT_MU",
    "SoleContact",
    "FootForces",
    "ContactForces",
    "wrench_cone",
    "wrench_cone_rows",
    "PLANAR_CONE_ROWS",
    "cone_margin",
    "centre_of_pressure",
    "geometry_vertices",
    "measure_sole",
    "sole_contacts",
    "sole_frame_name",
]

#: Default Coulomb friction coefficient [-] of a foot on the floor. Rubber soles on a hard floor
#: are 0.8–1.0; human walking needs a friction ratio |f_t|/f_n of at most about 0.3. 0.7 keeps
#: a margin on both sides.
DEFAULT_MU = 0.7


@dataclass(frozen=True)
class SoleContact:
    """A foot's flat contact: ``frame`` (Pinocchio frame name at the sole centre, z normal, x
    forward), ``half_length`` X and ``half_width`` Y [m] of the sole rectangle, friction ``mu``."""

    side: str
    frame: str
    half_length: float
    half_width: float
    mu: float = DEFAULT_MU

    def __post_init__(self) -> None:
        for name in ("half_length", "half_width", "mu"):
            v = getattr(self, name)
            if not isinstance(v, (int, float, np.floating)) or not math.isfinite(v) or v <= 0:
                raise InvalidInputError(
                    f"{self.side} contact: {name} must be a finite number > 0; got {v!r}"
                    + (" (a sole rectangle of zero size cannot carry a moment)"
                       if name != "mu" else " (mu ≤ 0 means no friction: a foot cannot push)"))
            object.__setattr__(self, name, float(v))

    def corners(self) -> np.ndarray:
        """The four sole corners ``(4, 3)`` [m] in the contact frame (z = 0): front-left,
        front-right, back-right, back-left."""
        X, Y = self.half_length, self.half_width
        return np.array([[X, Y, 0.0], [X, -Y, 0.0], [-X, -Y, 0.0], [-X, Y, 0.0]])

    def cone(self) -> np.ndarray:
        """This contact's wrench cone matrix ``(16, 6)``, see :func:`wrench_cone`."""
        return wrench_cone(self.half_length, self.half_width, self.mu)

    def replace(self, **changes) -> SoleContact:
        """A copy with some fields changed (validated again)."""
        d = {k: getattr(self, k) for k in ("side", "frame", "half_length", "half_width", "mu")}
        d.update(changes)
        return SoleContact(**d)


#: The rows of :func:`wrench_cone_rows` that a model moving in the x–z plane keeps (its
#: wrench has f_y = τ_x = τ_z = 0): friction along x (0, 1), centre of pressure along x (6, 7).
PLANAR_CONE_ROWS = (0, 1, 6, 7)


def wrench_cone_rows(w, half_length, half_width, mu, cop_length=None, cop_width=None) -> list:
    """The 16 rows of the contact wrench cone, each ``≤ 0`` inside it (Caron et al. 2015,
    Eq. 4-6): friction (4), centre of pressure (4), yaw moment (8), for a wrench
    ``w = [f_x, f_y, f_z, τ_x, τ_y, τ_z]`` [N, N·m] (at the sole centre, in the sole frame);
    ``half_length``, ``half_width`` [m], ``mu`` [-]. Rows in order:

    0–3 ``±f_x − μ f_z``, ``±f_y − μ f_z``; 4–7 ``±τ_x − Y_c f_z``, ``±τ_y − X_c f_z``;
    8–15 for ``(s1, s2)`` in ``(+,+), (+,−), (−,+), (−,−)`` the pair
    ``τ_min − τ_z`` and ``τ_z − τ_max`` of that corner sign choice.

    Written with ``+``, ``−`` and ``·`` only, so ``w`` and the parameters may be numbers, NumPy
    arrays (``w[i]`` of shape ``(...)``: the rows come out elementwise) or symbolic
    expressions (CasADi): the one formula of the cone in the package — the matrix
    :func:`wrench_cone`, the optimiser's rows (``retarget.parts.cone``) and the audit's margins
    (:func:`cone_margin`) are all taken from it.
    ``cop_length``/``cop_width``: the half-lengths of the centre-of-pressure rows (default the
    sole's; smaller ones keep the centre of pressure a margin inside the sole)."""
    fx, fy, fz, tx, ty, tz = (w[i] for i in range(6))
    X, Y, m = half_length, half_width, mu
    Xc = X if cop_length is None else cop_length
    Yc = Y if cop_width is None else cop_width
    rows = [fx - m * fz, -fx - m * fz, fy - m * fz, -fy - m * fz,
            tx - Yc * fz, -tx - Yc * fz, ty - Xc * fz, -ty - Xc * fz]
    for s1 in (1.0, -1.0):
        for s2 in (1.0, -1.0):
            # τ_z ≥ τ_min:  −τ_z − μ(X+Y) f_z + s1 (Y f_x − μ τ_x) + s2 (X f_y − μ τ_y) ≤ 0
            rows.append(s1 * Y * fx + s2 * X * fy - m * (X + Y) * fz - s1 * m * tx
                        - s2 * m * ty - tz)
            # τ_z ≤ τ_max:  +τ_z − μ(X+Y) f_z + s1 (Y f_x + μ τ_x) + s2 (X f_y + μ τ_y) ≤ 0
            rows.append(s1 * Y * fx + s2 * X * fy - m * (X + Y) * fz + s1 * m * tx
                        + s2 * m * ty + tz)
    return rows


def wrench_cone(half_length: float, half_width: float, mu: float,
                cop_length: float | None = None, cop_width: float | None = None) -> np.ndarray:
    """The contact wrench cone of a rectangular sole, ``A`` ``(16, 6)`` with ``A @ w <= 0``
    exactly when the wrench ``w = [f_x, f_y, f_z, τ_x, τ_y, τ_z]`` (at the sole centre, in the
    sole frame) is produced by four corner forces inside their friction cones (Caron et al.
    2015, Eq. 4-6). Rows: friction (4), centre of pressure (4), yaw moment (8) — the
    coefficients of :func:`wrench_cone_rows` (which are linear in ``w``), ``cop_length``,
    ``cop_width`` [m] as there."""
    return np.array(wrench_cone_rows(np.eye(6), float(half_length), float(half_width),
                                     float(mu), cop_length, cop_width), dtype=float) + 0.0


def cone_margin(contact: SoleContact, w: np.ndarray) -> dict[str, np.ndarray]:
    """Margins of wrenches ``w`` ``(..., 6)`` to the contact's cone, each ``(...,)``, positive
    inside, in physical units:

    - ``normal`` [N]: f_z;
    - ``friction`` [-]: μ − |f_t|/f_z (``-inf`` where f_z ≤ 0);
    - ``cop`` [m]: the centre of pressure's distance inside the rectangle (negative outside);
    - ``yaw`` [N·m]: min(τ_z − τ_min, τ_max − τ_z).
    """
    w = np.asarray(w, dtype=float)
    f, tau = w[..., :3], w[..., 3:]
    fz = f[..., 2]
    X, Y, mu = contact.half_length, contact.half_width, contact.mu
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(fz > 0, np.hypot(f[..., 0], f[..., 1]) / np.where(fz > 0, fz, 1), np.inf)
        px = np.where(fz > 0, -tau[..., 1] / np.where(fz > 0, fz, 1), np.inf)
        py = np.where(fz > 0, tau[..., 0] / np.where(fz > 0, fz, 1), np.inf)
    cop = np.minimum(X - np.abs(px), Y - np.abs(py))
    # min(τ_z − τ_min, τ_max − τ_z): the yaw rows 8–15 of the cone, each ≤ 0 inside
    yaw = -np.max(wrench_cone_rows(np.moveaxis(w, -1, 0), X, Y, mu)[8:], axis=0)
    return {"normal": fz, "friction": mu - ratio, "cop": cop, "yaw": yaw}


def centre_of_pressure(w: np.ndarray) -> np.ndarray:
    """Centre of pressure ``(..., 2)`` [m] in the sole frame of wrenches ``(..., 6)`` at the sole
    centre: ``(−τ_y/f_z, τ_x/f_z)``; NaN where f_z ≤ 0."""
    w = np.asarray(w, dtype=float)
    fz = w[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        safe = np.where(fz > 0, fz, np.nan)
        return np.stack([-w[..., 4] / safe, w[..., 3] / safe], axis=-1)


# ---------------------------------------------------------------------- measured forces
@dataclass(frozen=True)
class FootForces:
    """Forces one foot exchanged with the ground, on a time grid of ``T`` samples, in the world
    frame (x forward, y left, z up): ``force`` ``(T, 3)`` [N] the ground applies to the foot
    (its reverse is the foot's push on the ground); ``cop`` ``(T, 3)`` [m] centre of pressure
    (NaN where the foot is off the ground); ``torque`` ``(T, 3)`` [N·m] free moment about the
    centre of pressure; ``contact`` ``(T,)`` bool, True in stance."""

    force: np.ndarray
    cop: np.ndarray
    torque: np.ndarray
    contact: np.ndarray

    def __post_init__(self) -> None:
        f = np.asarray(self.force, dtype=float)
        T = f.shape[0] if f.ndim == 2 else -1
        for name in ("force", "cop", "torque"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.shape != (T, 3):
                raise InvalidInputError(f"FootForces.{name} must be (T, 3); got {a.shape}")
            object.__setattr__(self, name, a)
        c = np.asarray(self.contact, dtype=bool)
        if c.shape != (T,):
            raise InvalidInputError(f"FootForces.contact must be ({T},); got {c.shape}")
        object.__setattr__(self, "contact", c)


@dataclass(frozen=True)
class ContactForces:
    """Measured (or simulated) contact forces of both feet: ``t`` ``(T,)`` [s] and ``feet``
    ``{"left": FootForces, "right": FootForces}``; ``source`` says where they came from (a
    file path, ``"simulation"`` …) and ``frame_note`` what was done to them (e.g. "treadmill
    trial turned overground: belt speed 1.2 m/s added")."""

    t: np.ndarray
    feet: Mapping[str, FootForces]
    source: str = ""
    frame_note: str = ""

    def __getitem__(self, side: str) -> FootForces:
        return self.feet[side]

    @property
    def contact(self) -> dict[str, np.ndarray]:
        """``{side: (T,) bool}`` stance masks."""
        return {s: f.contact for s, f in self.feet.items()}


# ---------------------------------------------------------------------- measuring soles
def geometry_vertices(geom: object, placement: pin.SE3, mesh_path: str = ""
                      ) -> np.ndarray | None:
    """Vertices ``(n, 3)`` of an hpp-fcl geometry (meshes: their vertices, Y-up Collada files
    turned back as :mod:`gdimitate.model.meshes` explains; boxes: 8 corners; cylinders, capsules,
    spheres: enclosing polygons) mapped by ``placement``; None when the shape has no extent we
    can read."""
    v = None
    if hasattr(geom, "vertices"):
        try:
            v = np.asarray(geom.vertices(), dtype=float)
        except Exception:  # an empty BVH model raises
            v = None
        if v is not None and mesh_path and collada_y_up(mesh_path):
            v = v @ ASSIMP_Y_UP_UNDO.T
    elif hasattr(geom, "halfSide"):
        h = np.asarray(geom.halfSide, dtype=float)
        v = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    elif hasattr(geom, "radius"):
        r = float(geom.radius)
        hl = float(getattr(geom, "halfLength", 0.0))
        ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        ring = np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)
        if type(geom).__name__ == "Sphere":
            v = np.concatenate([np.c_[ring, np.zeros(16)], np.c_[ring[:, :1] * 0, ring[:, :1] * 0,
                                                                  ring[:, 1:2]]])
            v = np.concatenate([v, [[0, 0, r], [0, 0, -r]]])
        else:
            cap = r if type(geom).__name__ == "Capsule" else 0.0
            v = np.concatenate([np.c_[ring, np.full(16, z)] for z in (-hl - cap, hl + cap)])
    if v is None or v.size == 0:
        return None
    return v @ placement.rotation.T + placement.translation


def sole_frame_name(side: str) -> str:
    """Name of the frame gdimitate adds at a measured sole centre: ``<side>_sole_contact``."""
    return f"{side}_sole_contact"


def measure_sole(model: pin.Model, data: pin.Data, geometry: list, q: np.ndarray, side: str,
                 frame: str, mu: float = DEFAULT_MU, depth: float = 0.005,
                 up: np.ndarray | None = None) -> tuple[SoleContact, pin.Frame | None]:
    """Measure the sole rectangle below ``frame`` (a frame on the foot) at configuration ``q``
    ``(nq,)`` (the foot flat on the floor, world z up).

    ``geometry``: ``pin.GeometryModel``\\ s in order of preference (collision, then visual): the
    first that has objects on the foot's parent joint is used; its vertices within ``depth``
    [m] of the lowest one form the sole; its extent along world x/y gives the rectangle.
    Returns the contact and, where the given frame is not already at the rectangle's centre
    with world-aligned axes, a new ``pin.Frame`` named :func:`sole_frame_name` to add to the
    model (the caller adds it).
    Raises :class:`ContactError` when the foot has no geometry.
    """
    fid = model.getFrameId(frame)
    parent = model.frames[fid].parentJoint
    pin.framesForwardKinematics(model, data, q)
    pts = []
    for gm in geometry:
        if gm is None:
            continue
        for g in gm.geometryObjects:
            if g.parentJoint != parent:
                continue
            v = geometry_vertices(g.geometry, data.oMi[parent] * g.placement, g.meshPath)
            if v is not None:
                pts.append(v)
        if pts:
            break
    if not pts:
        raise ContactError(
            f"cannot measure the {side} sole: no collision or visual geometry is attached to "
            f"joint {model.names[parent]!r} (the parent of frame {frame!r}). Pass "
            f"contacts={{'{side}': {{'frame': …, 'half_length': …, 'half_width': …}}, …}}.")
    P = np.concatenate(pts)
    low = P[:, 2].min()
    S = P[P[:, 2] <= low + depth]
    lo, hi = S[:, :2].min(axis=0), S[:, :2].max(axis=0)
    half = (hi - lo) / 2
    if min(half) < 1e-4:
        raise ContactError(
            f"the {side} sole measured from the geometry of joint {model.names[parent]!r} has "
            f"zero size ({2 * half[0]:.4f} × {2 * half[1]:.4f} m): a point or line foot. Pass "
            "contacts= with a sole rectangle.")
    centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, low])
    contact = SoleContact(side, frame, float(half[0]), float(half[1]), mu)
    oMf = data.oMf[fid]
    aligned = np.allclose(oMf.rotation, np.eye(3), atol=1e-6)
    if aligned and np.linalg.norm(oMf.translation - centre) < 1e-4:
        return contact, None
    oMi = data.oMi[parent]
    placement = oMi.actInv(pin.SE3(np.eye(3), centre))
    name = sole_frame_name(side)
    new = pin.Frame(name, parent, fid, placement, pin.FrameType.OP_FRAME)
    return contact.replace(frame=name), new


def _given_contact(robot, s: str, g: Mapping, measured: SoleContact | None) -> SoleContact:
    """A ``contacts=`` mapping for side ``s`` over the measured contact (or none)."""
    g = dict(g)
    unknown = set(g) - {"frame", "half_length", "half_width", "mu"}
    if unknown:
        raise InvalidInputError(
            f"contacts[{s!r}] has unknown keys {sorted(unknown)}; valid: frame, "
            "half_length, half_width, mu")
    frame = g.get("frame") or (measured.frame if measured else robot.legs[s].sole)
    robot.frame_id(frame)
    hl = g.get("half_length", measured.half_length if measured else None)
    hw = g.get("half_width", measured.half_width if measured else None)
    if hl is None or hw is None:
        raise InvalidInputError(
            f"contacts[{s!r}] needs half_length and half_width [m] (the foot has no "
            "geometry to measure them from)")
    return SoleContact(s, frame, hl, hw, g.get("mu", measured.mu if measured else DEFAULT_MU))


def sole_contacts(robot, given: Mapping[str, SoleContact | Mapping] | None = None
                  ) -> tuple[dict[str, SoleContact], dict[str, str]]:
    """``(contacts, problems)`` of a robot under construction (``model``, ``data``, ``legs``,
    ``neutral``, ``collision_model``, ``visual_model``, ``frame_id``): per side the sole
    measured from the feet's geometry at the grounded neutral pose (:func:`measure_sole`; its
    frame ``<side>_sole_contact`` is added to the model where the sole frame is not at the
    rectangle's centre, and ``robot.data`` made anew), then overridden by ``given`` (a
    :class:`SoleContact` or a mapping with ``half_length``, ``half_width`` [m] and optionally
    ``frame`` and ``mu``). Point-footed legs (no ankle) get none; ``problems`` says why a
    foot has no contact. :class:`InvalidInputError` for bad ``given``."""
    given = dict(given or {})
    problems: dict[str, str] = {}
    bad = [k for k in given if k not in ("left", "right")]
    if bad:
        raise InvalidInputError(f"contacts= keys must be 'left'/'right'; got {bad}")
    out: dict[str, SoleContact] = {}
    for s in ("left", "right"):
        g = given.get(s)
        if isinstance(g, SoleContact):
            robot.frame_id(g.frame)
            out[s] = g.replace(side=s)
            continue
        if robot.legs[s].ankle is None and g is None:
            continue  # point foot
        measured = None
        try:
            measured, frame = measure_sole(
                robot.model, robot.data, [robot.collision_model, robot.visual_model],
                robot.neutral, s, robot.legs[s].sole)
            if frame is not None:
                robot.model.addFrame(frame)
                robot.data = robot.model.createData()
        except ContactError as e:
            if g is None:
                problems[s] = str(e)
                continue
        if g is None:
            if measured is not None:
                out[s] = measured
            continue
        out[s] = _given_contact(robot, s, g, measured)
    return out, problems
