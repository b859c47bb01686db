"""``Robot``: a Pinocchio model plus a description of its legs in the sagittal plane.

Each leg is described by its hip-pitch, knee and ankle-pitch joints, its sole frame, the
sagittal segment lengths *measured from the model* at the neutral pose, and the sign/offset that
map a joint angle onto docs/design.md §4's planar angles (from the downward vertical, positive when
the
distal end is in front)::

    planar angle = sign · q + offset

The robot's own "forward/left/up" is measured too (legs point down, left hip is on the left), so
Y-up models such as example-robot-data's ``human`` or iCub (x backwards) are turned to face +x
with z up by a constant base rotation :attr:`Robot.base_rotation`.
"""

from __future__ import annotations

import math
import tempfile
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .contact import DEFAULT_MU, SoleContact, measure_sole
from .errors import (
    ContactError,
    InvalidInputError,
    LegDetectionError,
    MeshPathError,
    UnknownNameError,
    UnknownRobotError,
    UnlimitedJointWarning,
    URDFError,
)
from .legs import SIDES, resolve_leg_names
from .library import LIBRARY, library_entry, list_robots
from .meshes import confine_meshes
from .safety import MAX_URDF_BYTES, check_urdf_bounds, parse_xml, read_text_bounded
from .urdfgen import PLANAR_MODELS, PlanarBipedSpec, planar_biped_urdf

__all__ = ["Leg", "Robot", "PLANAR_BASE"]

#: Joint names of our planar floating base (x, z, pitch), in q order.
PLANAR_BASE = ("base_x", "base_z", "base_pitch")

#: Explicit legs for library robots whose joint names don't say hip/knee/ankle.
LEG_PRESETS: dict[str, dict[str, dict[str, str | None]]] = {
    "talos": {
        s: {"hip": f"leg_{s}_3_joint", "knee": f"leg_{s}_4_joint", "ankle": f"leg_{s}_5_joint",
            "sole": f"{s}_sole_link"} for s in SIDES
    },
    "human": {
        s: {"hip": f"{s}_hip_Z", "knee": f"{s}_knee_Z", "ankle": f"{s}_ankle_Z",
            "sole": f"{s}_foot"} for s in SIDES
    },
    "bolt": {
        s: {"hip": f"F{s[0].upper()}_HFE", "knee": f"F{s[0].upper()}_KFE", "ankle": None,
            "sole": f"F{s[0].upper()}_FOOT"} for s in SIDES
    },
}


@dataclass(frozen=True)
class Leg:
    """One leg in the sagittal plane.

    ``hip``, ``knee``, ``ankle``: joint names (``ankle`` is ``None`` for point-footed robots such
    as Bolt); ``sole``: frame name of the contact point. ``thigh``, ``shank``, ``foot`` [m]:
    sagittal distances hip→knee, knee→ankle and ankle→sole at the neutral pose (``foot`` is
    the vertical ankle-to-sole height). ``signs``/``offsets`` (hip, knee, ankle): planar angle
    = sign·q + offset, with the hip angle relative to the torso and the knee/ankle angles
    relative to their parent segment.
    """

    side: str
    hip: str
    knee: str
    ankle: str | None
    sole: str
    thigh: float
    shank: float
    foot: float
    signs: tuple[float, float, float]
    offsets: tuple[float, float, float]

    @property
    def length(self) -> float:
        """Thigh + shank [m]."""
        return self.thigh + self.shank


#: Joints of library robots whose subtrees are massless on purpose (Romeo's hands: every
#: finger link has mass 0); see :func:`check_urdf_physics`.
MASSLESS_PRESETS: dict[str, tuple[str, ...]] = {
    "romeo": tuple(f"{s}{j}" for s in "LR" for j in ("Hand", "Finger21", "Finger31", "Thumb1")),
}
#: Principal moments of inertia down to −(INERTIA_TOL + 1e-9·trace) [kg·m²] count as zero, and
#: the triangle inequality may fail by INERTIA_TOL + 1e-6·trace (rounding in CAD exports).
INERTIA_TOL = 1e-12


def _inertial(link: ET.Element, source: object) -> tuple[float, np.ndarray]:
    """``(mass [kg], 3×3 rotational inertia [kg·m²])`` of a URDF ``<link>``, checked."""
    name = link.get("name")
    el = link.find("inertial")
    if el is None:
        return 0.0, np.zeros((3, 3))

    def num(node: ET.Element | None, key: str, what: str) -> float:
        try:
            v = float(node.get(key))  # type: ignore[union-attr, arg-type]
        except (AttributeError, TypeError, ValueError):
            raise URDFError(f"{source}: link {name!r}: {what} is missing or not a number"
                            ) from None
        if not math.isfinite(v):
            raise URDFError(f"{source}: link {name!r}: {what} is {v} (must be finite)")
        return v

    m = num(el.find("mass"), "value", "<mass value>")
    if m < 0:
        raise URDFError(f"{source}: link {name!r} has mass {m:g} kg; a mass must be >= 0")
    i = el.find("inertia")
    c = {k: num(i, k, f"<inertia {k}>") for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
    origin = el.find("origin")
    for key in ("xyz", "rpy"):
        text = origin.get(key) if origin is not None else None
        try:
            ok = text is None or all(math.isfinite(float(v)) for v in text.split())
        except ValueError:
            ok = False
        if not ok:
            raise URDFError(f"{source}: link {name!r}: inertial origin {key}={text!r} must be "
                            "three finite numbers")
    inertia = np.array([[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]],
                        [c["ixz"], c["iyz"], c["izz"]]])
    ev = np.linalg.eigvalsh(inertia)
    scale = float(abs(np.trace(inertia)))
    if ev[0] < -(INERTIA_TOL + 1e-9 * scale):
        raise URDFError(f"{source}: link {name!r}: inertia is not positive semi-definite "
                        f"(principal moments {np.round(ev, 12).tolist()} kg·m²)")
    if ev[0] + ev[1] < ev[2] - (INERTIA_TOL + 1e-6 * scale):
        raise URDFError(f"{source}: link {name!r}: principal moments {np.round(ev, 12).tolist()}"
                        " kg·m² break the triangle inequality I1 + I2 >= I3 (no body has them)")
    return m, inertia


def check_urdf_physics(root: ET.Element, source: object,
                       massless_joints: Iterable[str] = ()) -> None:
    """Refuse a URDF whose inertial data no body can have, naming the link: a NaN, infinite
    or negative mass; an inertia that is not positive semi-definite (a point mass, all moments
    zero, is accepted: real models use them for sensors) or breaks the triangle inequality; a
    moving joint whose whole subtree is massless (it moves nothing, so the joint-space inertia
    matrix is singular) unless the joint, or one above it, is in ``massless_joints``; a robot
    of total mass 0. Massless links on fixed joints (frames, soles) are fine."""
    mass = {str(lk.get("name")): _inertial(lk, source)[0] for lk in root.findall("link")}
    children: dict[str, list[tuple[str, str, str]]] = {}
    has_parent = set()
    for j in root.findall("joint"):
        p, c = j.find("parent"), j.find("child")
        if p is None or c is None:
            continue
        children.setdefault(str(p.get("link")), []).append(
            (str(j.get("name")), str(j.get("type")), str(c.get("link"))))
        has_parent.add(str(c.get("link")))
    roots = [lk for lk in mass if lk not in has_parent]
    order: list[str] = []  # links, parents before children (iterative: chains may be deep)
    stack = list(roots)
    while stack:
        lk = stack.pop()
        order.append(lk)
        stack.extend(c for _, _, c in children.get(lk, ()))
    below = dict(mass)
    for lk in reversed(order):
        below[lk] = mass.get(lk, 0.0) + sum(below.get(c, 0.0) for _, _, c in children.get(lk, ()))
    if roots and sum(below.get(r, 0.0) for r in roots) <= 0:
        raise URDFError(f"{source}: the robot's total mass is 0 kg")
    allowed = set(massless_joints)
    exempt: set[str] = set()
    for lk in order:
        for jname, jtype, c in children.get(lk, ()):
            if lk in exempt or jname in allowed:
                exempt.add(c)
            elif jtype != "fixed" and below.get(c, 0.0) <= 0:
                raise URDFError(
                    f"{source}: link {c!r} hangs on the moving joint {jname!r} ({jtype}) with "
                    "no mass on it or below it, so the joint moves nothing; give the link a "
                    "mass and inertia, make the joint fixed, or pass "
                    f"massless_joints=({jname!r},) if that is intended")


def _numbers(el: ET.Element | None, key: str, n: int) -> list[float] | None:
    """The ``n`` numbers of attribute ``key`` of ``el`` (None when absent), or None-free
    ValueError text on NaN/inf/wrong count."""
    text = el.get(key) if el is not None else None
    if text is None:
        return None
    vals = [float(v) for v in text.split()]  # ValueError on junk
    if len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise ValueError(text)
    return vals


def check_urdf_joints(root: ET.Element, source: object) -> None:
    """Refuse what Pinocchio would reject without naming it, or accept wrongly: a duplicate
    link or joint name; an ``<origin>`` (joint, visual, collision) or ``<axis>`` that is not
    three finite numbers; a joint limit that is not a finite number or whose lower limit
    exceeds its upper one (the audit would then check no position of that joint). Warn
    (:class:`~gdimitate.errors.UnlimitedJointWarning`) about moving joints whose effort or
    velocity limit is 0, which many URDFs write for "unknown": they are not checked (the
    audit lists them in ``unlimited``)."""
    for kind in ("link", "joint"):
        names = [str(e.get("name")) for e in root.findall(kind)]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise URDFError(f"{source}: {kind} names must be unique; repeated: {dup[:10]}")
    where = [(f"joint {j.get('name')!r}", j) for j in root.findall("joint")] + [
        (f"link {lk.get('name')!r} <{g.tag}>", g) for lk in root.findall("link")
        for g in lk if g.tag in ("visual", "collision")]
    for what, el in where:
        for tag, keys in (("origin", ("xyz", "rpy")), ("axis", ("xyz",))):
            for key in keys:
                try:
                    _numbers(el.find(tag), key, 3)
                except ValueError:
                    raise URDFError(f"{source}: {what}: <{tag} {key}="
                                    f"{el.find(tag).get(key)!r}> must be three finite numbers"
                                    ) from None
    zero: dict[str, list[str]] = {"effort": [], "velocity": []}
    for j in root.findall("joint"):
        lim, name = j.find("limit"), j.get("name")
        if lim is None or j.get("type") in ("fixed", "floating", "planar"):
            continue
        vals = {}
        for key in ("lower", "upper", "effort", "velocity"):
            try:
                v = _numbers(lim, key, 1)
            except ValueError:
                raise URDFError(f"{source}: joint {name!r}: <limit {key}={lim.get(key)!r}> "
                                "must be a finite number") from None
            vals[key] = None if v is None else v[0]
        lo, hi = vals["lower"], vals["upper"]
        if j.get("type") != "continuous" and lo is not None and hi is not None and lo > hi:
            raise URDFError(f"{source}: joint {name!r} has lower limit {lo:g} > upper limit "
                            f"{hi:g}; swap them (no position could satisfy both)")
        for key in zero:
            if vals[key] == 0 and name not in PLANAR_BASE:  # our planar base: unactuated
                zero[key].append(str(name))
    for key, names in zero.items():
        if names:
            warnings.warn(f"{source}: {len(names)} joints have {key} limit 0, read as 'no "
                          f"limit given' (not checked; the audit lists them in unlimited): "
                          f"{', '.join(names[:12])}{' …' if len(names) > 12 else ''}",
                          UnlimitedJointWarning, stacklevel=3)


class Robot:
    """A robot model (Pinocchio) with its legs described for sagittal imitation.

    Attributes: ``name``; ``model``/``data`` (``pin.Model``/``pin.Data``); ``visual_model``
    (``pin.GeometryModel`` or ``None`` when the URDF has no visual geometry); ``legs``
    (``{"left": Leg, "right": Leg}``); ``base`` (``"planar"``, ``"free"`` or ``"fixed"``);
    ``base_rotation`` (3×3, turns the model to face +x with z up); ``package_dir``;
    ``urdf_path`` (``None`` for in-memory models); ``contacts`` (``{"left": SoleContact,
    "right": SoleContact}``, the flat-foot contacts of :mod:`gdimitate.contact`, measured from
    the feet's geometry unless given; empty for point-footed robots such as Bolt);
    ``collision_model`` (``pin.GeometryModel`` or ``None``).

    ``contacts=`` overrides the measured soles: per side a :class:`~gdimitate.contact.SoleContact`
    or a mapping with ``half_length``, ``half_width`` [m] and optionally ``frame`` (default: the
    measured sole centre) and ``mu`` (default :data:`~gdimitate.contact.DEFAULT_MU`).
    """

    def __init__(self, name: str, model: pin.Model, visual_model: pin.GeometryModel | None,
                 legs: Mapping[str, Mapping[str, str | None]] | None = None,
                 package_dir: Path | None = None, urdf_path: Path | None = None,
                 contacts: Mapping[str, SoleContact | Mapping] | None = None,
                 collision_model: pin.GeometryModel | None = None):
        self.name = name
        self.model = model
        self.data = model.createData()
        has_geometry = visual_model is not None and visual_model.ngeoms > 0
        self.visual_model = visual_model if has_geometry else None
        has_collision = collision_model is not None and collision_model.ngeoms > 0
        self.collision_model = collision_model if has_collision else None
        self.package_dir = package_dir
        self.urdf_path = urdf_path
        names = list(model.names)[1:]
        if all(b in names for b in PLANAR_BASE):
            self.base = "planar"
        elif model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer":
            self.base = "free"
        else:
            self.base = "fixed"
        spec = self._resolve_leg_names(legs)
        self.base_rotation = np.eye(3)
        q0 = pin.neutral(model)
        self.base_rotation = self._measure_orientation(spec, q0)
        for s in SIDES:
            spec[s]["sole"] = self._sole_from_geometry(s, spec[s])
        self.legs: dict[str, Leg] = {s: self._measure_leg(s, spec[s]) for s in SIDES}
        self.neutral = self._grounded_neutral()
        self.contacts: dict[str, SoleContact] = self._make_contacts(contacts)
        if self.contacts:
            self.neutral = self._ground(self.neutral, [c.frame for c in self.contacts.values()])

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_urdf(cls, path: str | Path, legs: Mapping[str, Mapping[str, str | None]] | None = None,
                  *, name: str | None = None,
                  package_dir: str | Path | Sequence[str | Path] | None = None,
                  floating: bool | None = None,
                  contacts: Mapping[str, SoleContact | Mapping] | None = None,
                  massless_joints: Iterable[str] = ()) -> Robot:
        """Load a URDF. ``legs``: ``{"left": {"hip":…, "knee":…, "ankle":…, "sole":…},
        "right": {…}}`` (joint/frame names), auto-detected from names when omitted.

        ``floating``: add a free-flyer root joint (default: yes, unless the URDF already has
        our planar base joints). ``package_dir``: folder (or folders) resolving
        ``package://`` meshes (default: the URDF's folder). ``contacts``: sole rectangles
        overriding the measured ones (see :class:`Robot`). ``massless_joints``: moving joints
        whose subtree may be massless (see :func:`check_urdf_physics`).

        Before Pinocchio reads the file it is checked (``docs/security.md``): its size, link
        count and depth (:mod:`gdimitate.safety`), its inertial data
        (:func:`check_urdf_physics`), and every mesh reference, which must resolve inside the
        URDF's folder or a package directory (:func:`gdimitate.meshes.confine_meshes`).

        Raises:
            URDFError: naming the file and the link or mesh at fault
                (:class:`~gdimitate.errors.MeshPathError`,
                :class:`~gdimitate.errors.URDFLimitError` for the specific cases).
        """
        path = Path(path)
        if not path.is_file():
            raise URDFError(f"URDF file not found: {path}")
        root = parse_xml(read_text_bounded(path, MAX_URDF_BYTES, "URDF"), path)
        check_urdf_bounds(root, path)
        check_urdf_joints(root, path)
        check_urdf_physics(root, path, massless_joints)
        if floating is None:
            joints = {j.get("name") for j in root.findall("joint")}
            floating = not all(b in joints for b in PLANAR_BASE)
        if package_dir is None:
            pkgs = [path.parent]
        elif isinstance(package_dir, str | Path):
            pkgs = [Path(package_dir)]
        else:
            pkgs = [Path(d) for d in package_dir]
        try:
            confine_meshes(root, path, pkgs)
        except MeshPathError as e:
            if "not found" not in str(e):
                raise
            raise MeshPathError(f"{e}; if the URDF names its meshes package://NAME/…, pass "
                                "package_dir= (CLI: --package-dir) the folder that holds NAME/"
                                ) from None
        xml = ET.tostring(root, encoding="unicode")
        try:
            model = (pin.buildModelFromXML(xml, pin.JointModelFreeFlyer()) if floating
                     else pin.buildModelFromXML(xml))
        except Exception as e:  # Pinocchio raises ValueError/RuntimeError on bad files
            raise URDFError(f"cannot read URDF {path}: {e}") from None
        geoms = []
        for kind in (pin.GeometryType.VISUAL, pin.GeometryType.COLLISION):
            try:  # every mesh path is absolute now: Pinocchio searches no folder
                geoms.append(pin.buildGeomFromUrdfString(model, xml, kind, package_dirs=[]))
            except Exception as e:
                raise URDFError(f"{path}: cannot load its {kind.name.lower()} meshes: {e}"
                                ) from None
        return cls(name or model.name or path.stem, model, geoms[0], legs,
                   pkgs[0] if pkgs else None, path, contacts=contacts,
                   collision_model=geoms[1])

    @classmethod
    def from_osim(cls, path: str | Path, *, name: str | None = None,
                  markers=None) -> Robot:
        """An OpenSim model (``.osim``, 3.x or 4.x) converted by
        :func:`gdimitate.opensim.convert_osim` (into a temporary folder that is removed once
        the URDF is loaded: :attr:`urdf_path` is ``None``; write the URDF yourself with
        :func:`gdimitate.opensim.opensim_to_urdf`) and loaded with a free-flyer. Joint names
        are the OpenSim coordinate names; the legs (hip flexion, knee and ankle joints from the
        model's topology, the sole frame under the ankle) and the sole rectangles (the foot
        boxes) are passed explicitly. The conversion report is kept as ``robot.osim``
        (:class:`~gdimitate.opensim.OsimConversion`). ``markers``: a marker trial of the
        subject (``.trc`` path or ``Markers``) that puts the soles on the lab floor below the
        feet's markers (else they lie at the bones; ``robot.osim.sole_height`` says which).
        Raises :class:`~gdimitate.errors.OsimError` for a model that cannot be converted."""
        from .opensim import convert_osim

        with tempfile.TemporaryDirectory(prefix="gdimitate_osim_") as tmp:
            conv = convert_osim(path, Path(tmp) / f"{Path(path).stem}.urdf", markers=markers)
            legs = {s: {k: conv.legs[s][k] for k in ("hip", "knee", "ankle", "sole")}
                    for s in SIDES}
            contacts = {s: {"frame": conv.legs[s]["contact"], "half_length": conv.soles[s][0],
                            "half_width": conv.soles[s][1]} for s in SIDES}
            robot = cls.from_urdf(conv.urdf, legs, name=name or conv.model.name, floating=True,
                                  contacts=contacts)
        robot.urdf_path = None  # the folder is gone: nothing is left in the temp directory
        robot.osim = conv
        return robot

    @classmethod
    def from_spec(cls, spec: PlanarBipedSpec) -> Robot:
        """Build one of our planar bipeds from its spec (the same text ``urdf/`` holds)."""
        xml = planar_biped_urdf(spec)
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / f"{spec.name}.urdf"
            p.write_text(xml)
            model, collision, visual = pin.buildModelsFromUrdf(str(p), [tmp])
        robot = cls(spec.name, model, visual, collision_model=collision)
        robot.spec = spec
        return robot

    @classmethod
    def from_library(cls, name: str) -> Robot:
        """A named robot: our planar models (``hoap2``, ``case1_demonstrator``, …) or an
        example-robot-data model (``human``, ``talos``, ``romeo``, ``icub``, ``g1``, ``bolt``).
        :func:`gdimitate.list_robots` lists the names."""
        if name in PLANAR_MODELS:
            return cls.from_spec(PLANAR_MODELS[name])
        if name not in LIBRARY:
            raise UnknownRobotError(name, list_robots())
        path, pkg = library_entry(name)
        return cls.from_urdf(path, LEG_PRESETS.get(name), name=name, package_dir=pkg,
                             floating=True, massless_joints=MASSLESS_PRESETS.get(name, ()))

    @classmethod
    def load(cls, spec: str | Path, *, package_dir: str | Path | None = None,
             contacts: Mapping[str, SoleContact | Mapping] | None = None,
             legs: Mapping[str, Mapping[str, str | None]] | None = None) -> Robot:
        """A robot from a library name (:func:`gdimitate.list_robots`) or a model file path
        (``.urdf``: :meth:`from_urdf` with ``legs``, ``package_dir`` and ``contacts``;
        ``.osim``: :meth:`from_osim`, whose legs and soles come from the model).

        ``contacts``/``legs`` on a library robot override its presets (its URDF is loaded
        with them). Raises :class:`UnknownRobotError` (listing the names) for a name that is
        neither a library robot nor an existing file, :class:`InvalidInputError` for
        ``legs``/``contacts`` on an ``.osim`` or an unknown extension. The arguments are kept
        as ``robot.load_args`` (motion files record them)."""
        robot = cls._load(str(spec), package_dir, contacts, legs)
        robot.load_args = {"spec": str(spec), "package_dir": package_dir, "legs": legs,
                           "contacts": contacts}
        return robot

    @classmethod
    def _load(cls, text: str, package_dir, contacts, legs) -> Robot:
        p = Path(text).expanduser()
        if text in list_robots() and not p.suffix:
            if legs is None and contacts is None and package_dir is None:
                return cls.from_library(text)
            if text in PLANAR_MODELS:
                raise InvalidInputError(f"{text!r} is one of our planar models: it takes no "
                                        "legs=/contacts=/package_dir=")
            path, pkg = library_entry(text)
            return cls.from_urdf(path, legs or LEG_PRESETS.get(text), name=text,
                                 package_dir=package_dir or pkg, floating=True,
                                 contacts=contacts,
                                 massless_joints=MASSLESS_PRESETS.get(text, ()))
        suffix = p.suffix.lower()
        if suffix == ".urdf":
            return cls.from_urdf(p, legs, package_dir=package_dir, contacts=contacts)
        if suffix == ".osim":
            if legs is not None or contacts is not None:
                raise InvalidInputError(f"{p}: an OpenSim model brings its own legs and soles; "
                                        "legs=/contacts= are for URDFs")
            return cls.from_osim(p)
        if suffix:
            raise InvalidInputError(f"robot {text!r}: a model file must be .urdf or .osim; "
                                    f"library names: {list_robots()}")
        raise UnknownRobotError(text, list_robots())

    @property
    def fingerprint(self) -> str:
        """A short hash (16 hex digits) of the model: joint names and types, joint
        placements, link inertias (mass, centre of mass, rotational inertia) and position,
        velocity and effort limits, rounded to 1e-9 (so a URDF re-read from its text gives the
        same one). Motion files record it to check that they are read with their robot."""
        import hashlib

        m = self.model
        h = hashlib.sha256()
        for j in range(1, m.njoints):
            h.update(f"{m.names[j]}:{m.joints[j].shortname()};".encode())
        arrays = [np.array([X.homogeneous for X in m.jointPlacements]),
                  np.array([[I.mass, *I.lever, *I.inertia.ravel()] for I in m.inertias]),
                  m.lowerPositionLimit, m.upperPositionLimit, m.velocityLimit, m.effortLimit]
        for a in arrays:
            a = np.clip(np.nan_to_num(np.asarray(a, dtype=float)), -1e20, 1e20)
            h.update((np.round(a, 9) + 0.0).tobytes())  # + 0.0: no negative zeros
        return h.hexdigest()[:16]

    # ------------------------------------------------------------------ leg detection
    def _resolve_leg_names(self, legs) -> dict[str, dict[str, str | None]]:
        return resolve_leg_names(self, legs)

    def _joint_axis_world(self, joint: str, q: np.ndarray) -> np.ndarray:
        jid = self.model.getJointId(joint)
        pin.computeJointJacobians(self.model, self.data, q)
        J = pin.getJointJacobian(self.model, self.data, jid, pin.LOCAL_WORLD_ALIGNED)
        return J[3:, self.model.joints[jid].idx_v]

    # ------------------------------------------------------------------ measurements
    def _pos(self, joint: str | None = None, frame: str | None = None) -> np.ndarray:
        if joint is not None:
            return self.data.oMi[self.model.getJointId(joint)].translation.copy()
        return self.data.oMf[self.model.getFrameId(frame)].translation.copy()

    def _measure_orientation(self, spec, q0) -> np.ndarray:
        pin.framesForwardKinematics(self.model, self.data, q0)
        up = np.mean([self._pos(spec[s]["hip"]) - self._pos(frame=spec[s]["sole"]) for s in SIDES],
                     axis=0)
        up /= np.linalg.norm(up)
        left = self._pos(spec["left"]["hip"]) - self._pos(spec["right"]["hip"])
        left -= (left @ up) * up
        if np.linalg.norm(left) < 1e-6:
            raise LegDetectionError(f"{self.name}: the left and right hips coincide; "
                                    "cannot tell the sagittal plane")
        left /= np.linalg.norm(left)
        fwd = np.cross(left, up)
        R0 = np.vstack([fwd, left, up])  # rows: world x, y, z expressed in model coordinates
        if self.base != "free" and not np.allclose(R0, np.eye(3), atol=1e-6):
            raise LegDetectionError(
                f"{self.name}: a non-floating model must face +x with z up (found forward "
                f"{np.round(fwd, 3)}, up {np.round(up, 3)})")
        return R0 if self.base == "free" else np.eye(3)

    def _sole_from_geometry(self, side: str, names, min_gap: float = 0.01) -> str:
        """If the foot's visual geometry reaches more than ``min_gap`` [m] below the named sole
        frame (e.g. example-robot-data's ``human``, whose "foot" frame sits at the ankle), add
        a frame ``<side>_sole_auto`` directly below the sole frame at the geometry's lowest
        point (neutral pose) and use it. Legs without an ankle (point feet) keep their frame.
        Returns the sole frame name to use."""
        if self.visual_model is None or names["ankle"] is None:  # point feet: keep the frame
            return names["sole"]
        m = self.model
        fid = m.getFrameId(names["sole"])
        parent = m.frames[fid].parentJoint
        q0 = pin.neutral(m)
        if self.base == "free":
            q0[3:7] = pin.Quaternion(self.base_rotation).coeffs()
        pin.framesForwardKinematics(m, self.data, q0)
        sole = self.data.oMf[fid].translation
        low = sole[2]
        for g in self.visual_model.geometryObjects:
            if g.parentJoint != parent or not hasattr(g.geometry, "vertices"):
                continue
            v = np.asarray(g.geometry.vertices())
            if v.size == 0:
                continue
            M = self.data.oMi[parent] * g.placement
            world = v @ M.rotation.T + M.translation
            low = min(low, float(world[:, 2].min()))
        if sole[2] - low <= min_gap:
            return names["sole"]
        target = sole - np.array([0.0, 0.0, sole[2] - low])
        placement = pin.SE3(np.eye(3), self.data.oMi[parent].actInv(target))
        name = f"{side}_sole_auto"
        m.addFrame(pin.Frame(name, parent, fid, placement, pin.FrameType.OP_FRAME))
        self.data = m.createData()
        return name

    def _measure_leg(self, side: str, names) -> Leg:
        q0 = pin.neutral(self.model)
        if self.base == "free":
            q0[3:7] = pin.Quaternion(self.base_rotation).coeffs()
        pin.framesForwardKinematics(self.model, self.data, q0)
        hip, knee = self._pos(names["hip"]), self._pos(names["knee"])
        sole = self._pos(frame=names["sole"])
        ankle = self._pos(names["ankle"]) if names["ankle"] else sole

        def ang(v):  # planar angle of vector v from the downward vertical, + forward
            return math.atan2(v[0], -v[2])

        th_off = ang(knee - hip)
        sh_off = ang(ankle - knee)
        signs = []
        for role in ("hip", "knee", "ankle"):
            j = names[role]
            if j is None:
                signs.append(1.0)
                continue
            a = self._joint_axis_world(j, q0)
            if abs(a[1]) < 0.9:
                raise LegDetectionError(
                    f"{self.name}: {side} {role} joint {j!r} turns about {np.round(a, 3)}, not "
                    "about the lateral axis; pass the pitch joint in legs=")
            signs.append(-float(np.sign(a[1])))
        return Leg(
            side=side, hip=names["hip"], knee=names["knee"], ankle=names["ankle"],
            sole=names["sole"],
            thigh=float(np.hypot(*(knee - hip)[[0, 2]])),
            shank=float(np.hypot(*(ankle - knee)[[0, 2]])),
            foot=float(ankle[2] - sole[2]),
            signs=(signs[0], signs[1], signs[2]),
            offsets=(th_off, sh_off - th_off, 0.0),
        )

    def _make_contacts(self, given) -> dict[str, SoleContact]:
        """Sole contacts: measured from the feet's geometry at the grounded neutral pose (a
        frame ``<side>_sole_contact`` is added where the sole frame is not at the rectangle's
        centre), then overridden by ``given``. Point-footed legs (no ankle) get none."""
        given = dict(given or {})
        self.contact_problems: dict[str, str] = {}
        bad = [k for k in given if k not in SIDES]
        if bad:
            raise InvalidInputError(f"contacts= keys must be 'left'/'right'; got {bad}")
        out: dict[str, SoleContact] = {}
        for s in SIDES:
            g = given.get(s)
            if isinstance(g, SoleContact):
                self.frame_id(g.frame)
                out[s] = g.replace(side=s)
                continue
            if self.legs[s].ankle is None and g is None:
                continue  # point foot
            measured = None
            try:
                measured, frame = measure_sole(
                    self.model, self.data, [self.collision_model, self.visual_model],
                    self.neutral, s, self.legs[s].sole)
                if frame is not None:
                    self.model.addFrame(frame)
                    self.data = self.model.createData()
            except ContactError as e:
                if g is None:
                    self.contact_problems[s] = str(e)
                    continue
            if g is None:
                out[s] = measured
                continue
            g = dict(g)
            unknown = set(g) - {"frame", "half_length", "half_width", "mu"}
            if unknown:
                raise InvalidInputError(
                    f"contacts[{s!r}] has unknown keys {sorted(unknown)}; valid: frame, "
                    "half_length, half_width, mu")
            frame = g.get("frame") or (measured.frame if measured else self.legs[s].sole)
            self.frame_id(frame)
            hl = g.get("half_length", measured.half_length if measured else None)
            hw = g.get("half_width", measured.half_width if measured else None)
            if hl is None or hw is None:
                raise InvalidInputError(
                    f"contacts[{s!r}] needs half_length and half_width [m] (the foot has no "
                    "geometry to measure them from)")
            out[s] = SoleContact(s, frame, hl, hw, g.get("mu", measured.mu if measured
                                                         else DEFAULT_MU))
        return out

    def require_contacts(self) -> dict[str, SoleContact]:
        """:attr:`contacts` of both feet, or :class:`ContactError` saying why a foot has none
        and how to pass ``contacts=``."""
        missing = [s for s in SIDES if s not in self.contacts]
        if missing:
            why = "; ".join(self.contact_problems.get(s, f"the {s} leg has no ankle (point foot)")
                            for s in missing)
            raise ContactError(f"{self.name}: no flat-foot contact for {missing}: {why}")
        return self.contacts

    def _ground(self, q: np.ndarray, frames: list[str]) -> np.ndarray:
        """``q`` with the base lowered (or raised) so that the lowest of ``frames`` is at z = 0."""
        q = q.copy()
        pin.framesForwardKinematics(self.model, self.data, q)
        zmin = min(self._pos(frame=f)[2] for f in frames)
        if self.base == "free":
            q[2] -= zmin
        elif self.base == "planar":
            q[self.idx_q("base_z")] -= zmin
        return q

    def _grounded_neutral(self) -> np.ndarray:
        """Pinocchio's neutral pose with 1-DoF joints moved inside their position limits
        (e.g. iCub's elbows, whose range excludes 0), base turned and lowered onto z = 0."""
        m = self.model
        q = pin.neutral(m)
        for j in range(1, m.njoints):
            jm = m.joints[j]
            if jm.nq == 1 and m.names[j] not in PLANAR_BASE:
                lo, hi = m.lowerPositionLimit[jm.idx_q], m.upperPositionLimit[jm.idx_q]
                if np.isfinite(lo) and np.isfinite(hi) and lo <= hi:
                    q[jm.idx_q] = min(max(q[jm.idx_q], lo), hi)
        if self.base == "free":
            q[3:7] = pin.Quaternion(self.base_rotation).coeffs()
        return self._ground(q, [self.legs[s].sole for s in SIDES])

    # ------------------------------------------------------------------ queries
    @property
    def joint_names(self) -> tuple[str, ...]:
        """Model joint names in Pinocchio order (without ``universe``)."""
        return tuple(self.model.names)[1:]

    @property
    def mass(self) -> float:
        """Total mass [kg] (Pinocchio)."""
        return float(pin.computeTotalMass(self.model))

    def idx_q(self, joint: str) -> int:
        """Index in q of a 1-DoF joint (the first index for multi-DoF joints)."""
        if not self.model.existJointName(joint):
            raise UnknownNameError("joint", joint, self.joint_names)
        return int(self.model.joints[self.model.getJointId(joint)].idx_q)

    def idx_v(self, joint: str) -> int:
        """Index in v of a joint (the first for multi-DoF joints)."""
        if not self.model.existJointName(joint):
            raise UnknownNameError("joint", joint, self.joint_names)
        return int(self.model.joints[self.model.getJointId(joint)].idx_v)

    def frame_id(self, frame: str) -> int:
        """Pinocchio frame id; :class:`UnknownNameError` lists the valid names."""
        if not self.model.existFrame(frame):
            raise UnknownNameError("frame", frame, [f.name for f in self.model.frames])
        return int(self.model.getFrameId(frame))

    def com(self, q: np.ndarray) -> np.ndarray:
        """Whole-body centre of mass [m] for q ``(nq,)`` → ``(3,)`` or ``(T, nq)`` → ``(T, 3)``."""
        q = np.asarray(q, dtype=float)
        if q.ndim == 1:
            return pin.centerOfMass(self.model, self.data, q).copy()
        return np.array([pin.centerOfMass(self.model, self.data, qi) for qi in q])

    def __repr__(self) -> str:
        L = self.legs["left"]
        return (f"Robot({self.name!r}, base={self.base}, nq={self.model.nq}, "
                f"mass={self.mass:.2f} kg, "
                f"thigh={L.thigh:.4f} m, shank={L.shank:.4f} m, foot={L.foot:.4f} m)")
