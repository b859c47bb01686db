"""Read an OpenSim model (``.osim``, OpenSim 3.x and 4.x formats) into plain frozen values.

What is read: bodies (mass, centre of mass, inertia about the centre of mass), joints (parent
and child bodies, the parent and child offset frames, and the joint's motion as an ordered list
of :class:`TransformAxis`), coordinates (motion type, default value, range) and markers. Muscles,
constraints, contact geometry and display meshes are not read.

Formats:

* 4.x: ``<BodySet><objects><Body>`` with ``mass``, ``mass_center``, ``inertia`` (Ixx Iyy Izz
  Ixy Ixz Iyz); ``<JointSet>`` with ``socket_parent_frame``/``socket_child_frame`` naming a
  ``PhysicalOffsetFrame`` of the joint (``translation``, ``orientation``) or a body.
* 3.x: the joint inside its child body (``<Body><Joint><CustomJoint>``) with ``parent_body``,
  ``location_in_parent``, ``orientation_in_parent``, ``location``, ``orientation``;
  ``inertia_xx`` … ``inertia_yz``.

Orientations are body-fixed X-Y-Z Euler angles [rad]. Every joint type becomes the same
representation OpenSim's ``CustomJoint`` uses: X_F_M(q) = Trans(Σ tᵢ(q)·aᵢ) · R₁(r₁(q)) ·
R₂(r₂(q)) · R₃(r₃(q)), translations expressed in the parent offset frame F, rotations applied
body-fixed (each about its axis in the frame left by the previous ones) — checked against
OpenSim itself in the tests. ``PinJoint``: one rotation about z; ``UniversalJoint``: x then y;
``BallJoint``/``GimbalJoint``: x, y, z; ``SliderJoint``: translation along x; ``PlanarJoint``:
rotation z, translations x, y; ``FreeJoint``: rotations x, y, z and translations x, y, z;
``WeldJoint``: none.

The XML is parsed with the standard library; files declaring a DOCTYPE or entities are refused.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import OsimError, OsimLimitError
from ...safety import parse_xml
from .functions import Function, parse_function

__all__ = ["OsimBody", "OsimCoordinate", "TransformAxis", "OsimJoint", "OsimMarker",
           "OsimModel", "read_osim", "euler_xyz"]


def euler_xyz(angles) -> np.ndarray:
    """Rotation matrix (3, 3) of body-fixed X-Y-Z Euler angles [rad]: Rx(a)·Ry(b)·Rz(c)."""
    a, b, c = (float(v) for v in angles)
    return _rot([1, 0, 0], a) @ _rot([0, 1, 0], b) @ _rot([0, 0, 1], c)


def _rot(axis, angle: float) -> np.ndarray:
    """Rodrigues: rotation by ``angle`` [rad] about unit ``axis`` (3,)."""
    k = np.asarray(axis, dtype=float)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


@dataclass(frozen=True)
class OsimBody:
    """A rigid body: ``mass`` [kg], ``com`` (3,) [m] and ``inertia`` (3, 3) [kg·m²] about the
    centre of mass, both in the body frame (OpenSim axes)."""

    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class OsimCoordinate:
    """A generalised coordinate: ``motion_type`` ``"rotational"`` [rad], ``"translational"``
    [m] or ``"coupled"`` (from the file, or, where a 4.x file omits it, translational when
    the coordinate drives only translations); ``default`` value; ``range`` (lower, upper);
    the ``joint`` defining it."""

    name: str
    joint: str
    motion_type: str
    default: float
    range: tuple[float, float]
    locked: bool = False
    explicit_type: bool = True


@dataclass(frozen=True)
class TransformAxis:
    """One axis of a joint's spatial transform: ``kind`` ``"rotation"`` or ``"translation"``,
    unit ``axis`` (3,), the ``coordinate`` driving it (``None`` for a constant) through
    ``function`` (value [rad] or [m] as a function of the coordinate's value)."""

    name: str
    kind: str
    axis: np.ndarray
    coordinate: str | None
    function: Function

    def value(self, q: float | np.ndarray) -> np.ndarray:
        return self.function(q)


@dataclass(frozen=True)
class OsimJoint:
    """A joint: ``type`` (OpenSim class name), ``parent``/``child`` body names (the ground's
    name for the root), ``parent_offset`` X_P_F and ``child_offset`` X_B_M as (R (3, 3),
    p (3,)) pairs, the ordered ``axes`` (rotations first, then translations) and the
    ``coordinates`` it defines."""

    name: str
    type: str
    parent: str
    child: str
    parent_offset: tuple[np.ndarray, np.ndarray]
    child_offset: tuple[np.ndarray, np.ndarray]
    axes: tuple[TransformAxis, ...]
    coordinates: tuple[OsimCoordinate, ...]


@dataclass(frozen=True)
class OsimMarker:
    """A marker fixed on ``body`` at ``location`` (3,) [m] (body frame, OpenSim axes)."""

    name: str
    body: str
    location: np.ndarray


@dataclass(frozen=True)
class OsimModel:
    """A parsed ``.osim`` model. ``ground``: the ground's name; ``version``: the file's
    ``OpenSimDocument Version``. Look things up with :meth:`body`, :meth:`joint`,
    :meth:`coordinate`."""

    name: str
    path: Path | None
    version: int
    ground: str
    bodies: tuple[OsimBody, ...]
    joints: tuple[OsimJoint, ...]
    markers: tuple[OsimMarker, ...]

    @property
    def coordinates(self) -> tuple[OsimCoordinate, ...]:
        return tuple(c for j in self.joints for c in j.coordinates)

    @property
    def mass(self) -> float:
        """Total mass [kg]."""
        return float(sum(b.mass for b in self.bodies))

    def body(self, name: str) -> OsimBody:
        for b in self.bodies:
            if b.name == name:
                return b
        raise OsimError(f"{self.name}: no body {name!r}; bodies: {[b.name for b in self.bodies]}")

    def joint(self, name: str) -> OsimJoint:
        for j in self.joints:
            if j.name == name:
                return j
        raise OsimError(f"{self.name}: no joint {name!r}; joints: {[j.name for j in self.joints]}")

    def joint_of(self, child: str) -> OsimJoint:
        """The joint whose child is body ``child``."""
        for j in self.joints:
            if j.child == child:
                return j
        raise OsimError(f"{self.name}: body {child!r} has no joint")

    def coordinate(self, name: str) -> OsimCoordinate:
        for c in self.coordinates:
            if c.name == name:
                return c
        raise OsimError(f"{self.name}: no coordinate {name!r}; coordinates: "
                        f"{[c.name for c in self.coordinates]}")

    def children(self, body: str) -> tuple[OsimJoint, ...]:
        return tuple(j for j in self.joints if j.parent == body)


# ---------------------------------------------------------------------- XML helpers
JOINT_TYPES = ("CustomJoint", "PinJoint", "WeldJoint", "BallJoint", "UniversalJoint",
               "GimbalJoint", "SliderJoint", "PlanarJoint", "FreeJoint")
_STANDARD_AXES = {  # joint type → ((kind, axis), ...) each driven by the next coordinate
    "PinJoint": (("rotation", (0, 0, 1)),),
    "UniversalJoint": (("rotation", (1, 0, 0)), ("rotation", (0, 1, 0))),
    "BallJoint": (("rotation", (1, 0, 0)), ("rotation", (0, 1, 0)), ("rotation", (0, 0, 1))),
    "GimbalJoint": (("rotation", (1, 0, 0)), ("rotation", (0, 1, 0)), ("rotation", (0, 0, 1))),
    "SliderJoint": (("translation", (1, 0, 0)),),
    "PlanarJoint": (("rotation", (0, 0, 1)), ("translation", (1, 0, 0)),
                    ("translation", (0, 1, 0))),
    "FreeJoint": (("rotation", (1, 0, 0)), ("rotation", (0, 1, 0)), ("rotation", (0, 0, 1)),
                  ("translation", (1, 0, 0)), ("translation", (0, 1, 0)),
                  ("translation", (0, 0, 1))),
    "WeldJoint": (),
}
_IDENTITY = Function("LinearFunction", coefficients=(1.0, 0.0))


def _text(el: ET.Element | None, tag: str, default: str | None = None) -> str | None:
    sub = None if el is None else el.find(tag)
    if sub is None or sub.text is None:
        return default
    return sub.text.strip()


def _name(el: ET.Element, where: str) -> str:
    """The ``name`` attribute of an element; OsimError where it has none."""
    name = el.get("name")
    if name is None:
        raise OsimError(f"{where}: a <{el.tag}> without a name attribute; give it one")
    return name


def _vec(el: ET.Element, tag: str, n: int, where: str, default=None) -> np.ndarray:
    t = _text(el, tag)
    if t is None:
        if default is not None:
            return np.asarray(default, dtype=float)
        raise OsimError(f"{where}: missing <{tag}> ({n} numbers)")
    try:
        v = np.array([float(x) for x in t.split()])
    except ValueError:
        raise OsimError(f"{where}: <{tag}> {t!r} is not {n} numbers") from None
    if v.shape != (n,):
        raise OsimError(f"{where}: <{tag}> needs {n} numbers, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise OsimError(f"{where}: <{tag}> has NaN/inf values {v}; give finite numbers")
    return v


#: Largest ``.osim`` read [bytes]. The largest real OpenSim models (full-body models with
#: hundreds of muscles and their display paths, e.g. Rajagopal 2016 or the 2392-muscle
#: gait models) are a few MB; ElementTree holds 16 bytes per byte of XML (measured on a
#: 6 MB model), so 64 MiB stays within about 1.1 GB, ten times the largest model's size.
MAX_OSIM_BYTES = 64 * 2**20


def _load_xml(path: Path) -> ET.Element:
    if not path.is_file():
        raise OsimError(f"OpenSim model not found: {path}")
    size = path.stat().st_size
    if size > MAX_OSIM_BYTES:
        raise OsimLimitError(f"{path}: {size:,} bytes is over the {MAX_OSIM_BYTES:,} bytes an "
                             "OpenSim model may have (gdimitate.model.osim.model.MAX_OSIM_BYTES; "
                             "real models are a few MB): is it a model file?")
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise OsimError(f"cannot read OpenSim model {path}: {e.strerror or e}") from None
    # bytes: the parser follows the encoding the file declares (a DTD in a UTF-16 model is
    # refused as one in UTF-8 is)
    return parse_xml(raw, path, OsimError)


# ---------------------------------------------------------------------- parsing
def _body(el: ET.Element, where: str) -> OsimBody:
    name = _name(el, where)
    m = _text(el, "mass")
    try:
        mass = float(m) if m is not None else math.nan
    except ValueError:
        mass = math.nan
    if not math.isfinite(mass) or mass < 0:
        raise OsimError(f"{where}: body {name!r} has mass {m!r}; give a finite mass >= 0 [kg]")
    com = _vec(el, "mass_center", 3, f"{where} body {name!r}", default=(0, 0, 0))
    if el.find("inertia") is not None:
        i = _vec(el, "inertia", 6, f"{where} body {name!r}")
    else:
        i = np.array([float(str(_text(el, f"inertia_{k}", "0"))) for k in
                      ("xx", "yy", "zz", "xy", "xz", "yz")])
    if not np.all(np.isfinite(i)):
        raise OsimError(f"{where}: body {name!r} has a NaN/inf inertia {i}")
    inertia = np.array([[i[0], i[3], i[4]], [i[3], i[1], i[5]], [i[4], i[5], i[2]]])
    return OsimBody(name, mass, com, inertia)


def _coordinates(joint_el: ET.Element, joint: str, where: str) -> list[OsimCoordinate]:
    els = joint_el.findall("coordinates/Coordinate") + joint_el.findall(
        "CoordinateSet/objects/Coordinate")
    out = []
    for c in els:
        name = _name(c, where)
        rng = _vec(c, "range", 2, f"{where} coordinate {name!r}", default=(-math.pi, math.pi))
        mt = (_text(c, "motion_type") or "").lower()
        default = float(str(_text(c, "default_value", "0")))
        if not math.isfinite(default):
            raise OsimError(f"{where}: coordinate {name!r} has default_value {default}")
        out.append(OsimCoordinate(name, joint, mt or "rotational", default,
                                  (float(rng[0]), float(rng[1])),
                                  (_text(c, "locked", "false") or "").lower() == "true", bool(mt)))
    return out


def _custom_axes(joint_el: ET.Element, where: str) -> list[TransformAxis]:
    st = joint_el.find("SpatialTransform")
    if st is None:
        raise OsimError(f"{where}: CustomJoint without a <SpatialTransform>")
    out = []
    for name in ("rotation1", "rotation2", "rotation3",
                 "translation1", "translation2", "translation3"):
        ta = st.find(f"TransformAxis[@name='{name}']")
        if ta is None:
            continue
        coords = (_text(ta, "coordinates") or "").split()
        if len(coords) > 1:
            raise OsimError(f"{where} {name}: functions of several coordinates {coords} are "
                            "not supported; use one coordinate per TransformAxis")
        holder = ta.find("function")
        if holder is None:  # OpenSim 3.x also wrote the function directly under the axis
            holder = next((c for c in ta if c.tag not in ("coordinates", "axis")), None)
            fel = holder
        else:
            fel = next(iter(holder), None)
        if fel is None:
            func = Function("Constant", coefficients=(0.0,))
        else:
            func = parse_function(fel, f"{where} {name}")
        axis = _vec(ta, "axis", 3, f"{where} {name}")
        norm = float(np.linalg.norm(axis))
        if norm < 1e-12:
            raise OsimError(f"{where} {name}: zero axis; give a unit vector")
        coord = coords[0] if coords else None
        if coord is None and not func.is_constant:
            func = Function("Constant", coefficients=(float(func(0.0)),))
        kind = "rotation" if name.startswith("rotation") else "translation"
        out.append(TransformAxis(name, kind, axis / norm, coord, func))
    return out


def _offset(frame_el: ET.Element | None, where: str) -> tuple[np.ndarray, np.ndarray]:
    if frame_el is None:
        return np.eye(3), np.zeros(3)
    p = _vec(frame_el, "translation", 3, where, default=(0, 0, 0))
    o = _vec(frame_el, "orientation", 3, where, default=(0, 0, 0))
    return euler_xyz(o), p


def _body_of_path(path: str) -> str:
    """'/bodyset/femur_r' → 'femur_r'; '/ground' → 'ground'; 'femur_r' → 'femur_r'."""
    return path.rstrip("/").split("/")[-1]


def _resolve_frame(joint_el: ET.Element, socket: str, where: str):
    """(body name, (R, p) of the joint frame in that body) for a 4.x joint socket."""
    name = _text(joint_el, socket) or _text(joint_el, f"{socket}_connectee_name")
    if name is None:
        raise OsimError(f"{where}: missing <{socket}>")
    R, p = np.eye(3), np.zeros(3)
    frames = {f.get("name"): f for f in joint_el.findall("frames/PhysicalOffsetFrame")}
    seen = 0
    target = _body_of_path(name)
    while target in frames and seen < 20:
        f = frames[target]
        Rf, pf = _offset(f, f"{where} frame {target!r}")
        R, p = Rf @ R, Rf @ p + pf
        parent = _text(f, "socket_parent") or _text(f, "socket_parent_connectee_name")
        if parent is None:
            raise OsimError(f"{where}: frame {target!r} has no <socket_parent>")
        target = _body_of_path(parent)
        seen += 1
    return target, (R, p)


def _joint(el: ET.Element, where: str, child: str | None, v3: bool):
    jtype = el.tag
    name = _name(el, where)
    w = f"{where} joint {name!r}"
    if jtype not in JOINT_TYPES:
        raise OsimError(f"{w}: unsupported joint type <{jtype}>; supported: "
                        f"{', '.join(JOINT_TYPES)}")
    if (_text(el, "reverse", "false") or "").lower() == "true":
        raise OsimError(f"{w}: reversed joints (<reverse>true) are not supported; re-define "
                        "the joint from parent to child")
    if v3:
        parent = _text(el, "parent_body")
        if parent is None or child is None:
            raise OsimError(f"{w}: missing <parent_body>")
        po = (euler_xyz(_vec(el, "orientation_in_parent", 3, w, default=(0, 0, 0))),
              _vec(el, "location_in_parent", 3, w, default=(0, 0, 0)))
        co = (euler_xyz(_vec(el, "orientation", 3, w, default=(0, 0, 0))),
              _vec(el, "location", 3, w, default=(0, 0, 0)))
    else:
        parent, po = _resolve_frame(el, "socket_parent_frame", w)
        child, co = _resolve_frame(el, "socket_child_frame", w)
    coords = _coordinates(el, name, w)
    if jtype == "CustomJoint":
        axes = _custom_axes(el, w)
    else:
        std = _STANDARD_AXES[jtype]
        if len(coords) != len(std):
            raise OsimError(f"{w}: a {jtype} needs {len(std)} coordinates, the file gives "
                            f"{len(coords)}")
        axes = [TransformAxis(f"{k}{i + 1}", k, np.asarray(a, dtype=float), c.name, _IDENTITY)
                for i, ((k, a), c) in enumerate(zip(std, coords))]
    kinds: dict[str | None, set[str]] = {}
    for a in axes:  # OpenSim 4 files omit motion_type: a coordinate driving only
        kinds.setdefault(a.coordinate, set()).add(a.kind)  # translations is translational
    coords = [c if c.explicit_type or kinds.get(c.name) != {"translation"} else
              OsimCoordinate(c.name, c.joint, "translational", c.default, c.range, c.locked)
              for c in coords]
    names = {c.name for c in coords}
    for a in axes:
        if a.coordinate is not None and a.coordinate not in names:
            raise OsimError(f"{w} {a.name}: refers to coordinate {a.coordinate!r}, which the "
                            f"joint does not define (it defines {sorted(names)})")
    used = {a.coordinate for a in axes}
    for c in coords:
        if c.name not in used:
            raise OsimError(f"{w}: coordinate {c.name!r} is referenced by no TransformAxis of "
                            "the joint; remove it or give it an axis")
    return OsimJoint(name, jtype, parent, child, po, co, tuple(axes), tuple(coords))


def read_osim(path: str | Path) -> OsimModel:
    """Parse an ``.osim`` file → :class:`OsimModel`.

    Raises :class:`~gdimitate.errors.OsimError` naming the element and what to fix: no
    bodies, a joint whose parent or child body is unknown, a body without a joint, two joints
    on one body, an unsupported joint or function type, a NaN/negative mass, a coordinate no
    axis uses.
    """
    path = Path(path)
    root = _load_xml(path)
    where = path.name
    model_el = root.find("Model") if root.tag == "OpenSimDocument" else root
    if model_el is None or model_el.tag != "Model":
        raise OsimError(f"{where}: no <Model> element; is this an OpenSim model file?")
    try:
        version = int(root.get("Version", "40000"))
    except ValueError:
        version = 40000
    v3 = version < 40000
    ground_el = model_el.find("Ground")
    ground = ground_el.get("name", "ground") if ground_el is not None else "ground"
    body_els = model_el.findall("BodySet/objects/Body")
    bodies, joints = [], []
    for b in body_els:
        if v3 and b.get("name") == ground:
            continue
        bodies.append(_body(b, where))
        if v3:
            holder = b.find("Joint")
            jel = next(iter(holder), None) if holder is not None else None
            if jel is not None:
                joints.append(_joint(jel, where, _name(b, where), True))
    if not bodies:
        raise OsimError(f"{where}: no bodies (<BodySet><objects><Body>); the model needs at "
                        "least one body")
    if not v3:
        for jel in list(model_el.find("JointSet/objects") or []):
            joints.append(_joint(jel, where, None, False))
    names = [b.name for b in bodies]
    if len(set(names)) != len(names):
        raise OsimError(f"{where}: duplicate body names {names}")
    known = set(names) | {ground}
    for j in joints:
        if j.parent not in known:
            raise OsimError(f"{where}: joint {j.name!r} has parent {j.parent!r}, which is no "
                            f"body of the model (bodies: {names}, ground {ground!r}); fix its "
                            "parent frame or add the body")
        if j.child not in names:
            raise OsimError(f"{where}: joint {j.name!r} has child {j.child!r}, which is no "
                            f"body of the model (bodies: {names}); add the body or fix the joint")
    for body in names:
        n = sum(j.child == body for j in joints)
        if n == 0:
            raise OsimError(f"{where}: body {body!r} has no joint connecting it to the model; "
                            "add one (a WeldJoint if it is fixed)")
        if n > 1:
            raise OsimError(f"{where}: body {body!r} is the child of {n} joints (closed loops are "
                            "not supported); keep one and use a constraint for the others")
    cnames = [c.name for j in joints for c in j.coordinates]
    if len(set(cnames)) != len(cnames):
        raise OsimError(f"{where}: duplicate coordinate names {cnames}")
    markers = []
    for m in model_el.findall("MarkerSet/objects/Marker"):
        mb = _text(m, "body") or _text(m, "socket_parent_frame") or \
            _text(m, "socket_parent_frame_connectee_name")
        if mb is None or _body_of_path(mb) not in known:
            raise OsimError(f"{where}: marker {m.get('name')!r} is on {mb!r}, which is no body")
        markers.append(OsimMarker(_name(m, where), _body_of_path(mb),
                                  _vec(m, "location", 3, f"{where} marker {m.get('name')!r}")))
    return OsimModel(model_el.get("name", path.stem), path, version, ground, tuple(bodies),
                     tuple(_sort_joints(joints, ground)), tuple(markers))


def _sort_joints(joints: list[OsimJoint], ground: str) -> list[OsimJoint]:
    """Joints in tree order (every parent before its children); OsimError on cycles."""
    out, placed = [], {ground}
    rest = list(joints)
    while rest:
        ready = [j for j in rest if j.parent in placed]
        if not ready:
            raise OsimError(f"joints {[j.name for j in rest]} form a loop or hang from bodies "
                            "not connected to the ground")
        for j in ready:
            out.append(j)
            placed.add(j.child)
            rest.remove(j)
    return out
