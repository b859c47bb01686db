"""Physical and structural checks of a URDF before Pinocchio reads it (docs/security.md).

:func:`check_urdf_size` refuses a model too large for what every loaded robot builds
(:data:`~gdimitate.safety.MAX_URDF_DOF` degrees of freedom,
:data:`~gdimitate.safety.MAX_URDF_GEOMETRIES` shapes); :func:`check_urdf_structure` names the
faults for which Pinocchio only says "not a valid URDF model" (or which it accepts silently:
a link with two parents, a malformed shape that drops the link's collision geometry);
:func:`check_urdf_physics` refuses inertial data no body can have; :func:`check_urdf_joints`
refuses what Pinocchio would reject without naming it or accept wrongly, and warns about
effort and velocity limits of 0. All take the parsed XML root and name the file and the link
or joint at fault in a :class:`~gdimitate.errors.URDFError`.

Magnitudes (beyond them a number is a unit slip or a corrupt file, and the dynamics' products
— mass × length², inertia × velocity² — leave float64's useful range):
:data:`MAX_LINK_MASS_KG`, :data:`MAX_LINK_INERTIA`, :data:`MAX_URDF_LENGTH_M`.
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from typing import cast

import numpy as np

from ..errors import UnlimitedJointWarning, URDFError, URDFLimitError
from ..safety import MAX_URDF_DOF, MAX_URDF_GEOMETRIES
from .urdfgen import PLANAR_BASE

__all__ = ["INERTIA_TOL", "JOINT_DOF", "MAX_LINK_INERTIA", "MAX_LINK_MASS_KG",
           "MAX_URDF_LENGTH_M", "check_urdf_joints", "check_urdf_physics", "check_urdf_size",
           "check_urdf_structure"]

#: Degrees of freedom of each URDF joint type (the types URDF defines).
JOINT_DOF = {"revolute": 1, "continuous": 1, "prismatic": 1, "fixed": 0, "floating": 6,
             "planar": 3}
#: Heaviest link [kg]: 100 t, a thousand times a humanoid (a 1e308 kg link overflows the
#: dynamics; grams written as kilograms stay far below it).
MAX_LINK_MASS_KG = 1e5
#: Largest principal moment of inertia of a link [kg·m²] (100 t at 10 m).
MAX_LINK_INERTIA = 1e7
#: Largest length in a URDF [m]: an ``<origin xyz>`` coordinate, a box side, a radius, a
#: cylinder length (1 km; no robot part is farther from its parent).
MAX_URDF_LENGTH_M = 1e3
#: Largest ``<mesh scale>`` factor (a mesh in micrometres scaled to metres is 1e-6; the
#: inverse 1e6).
MAX_MESH_SCALE = 1e6

#: Principal moments of inertia down to −(INERTIA_TOL + 1e-9·trace) [kg·m²] count as zero, and
#: the triangle inequality may fail by INERTIA_TOL + 1e-6·trace (rounding in CAD exports).
INERTIA_TOL = 1e-12


def _float(text: str) -> float:
    """``float(text)`` for ASCII number text only: Python's ``float`` also takes unicode digits
    (``"١"``) and underscores (``"1_0"``), which Pinocchio's parser does not read the same."""
    if not text.isascii() or "_" in text:
        raise ValueError(text)
    return float(text)


def _inertial(link: ET.Element, source: object) -> tuple[float, np.ndarray]:
    """``(mass [kg], 3×3 rotational inertia [kg·m²])`` of a URDF ``<link>``, checked."""
    name = link.get("name")
    el = link.find("inertial")
    if el is None:
        return 0.0, np.zeros((3, 3))

    def num(node: ET.Element | None, key: str, what: str) -> float:
        try:
            v = _float(node.get(key))  # type: ignore[union-attr, arg-type]
        except (AttributeError, TypeError, ValueError):
            raise URDFError(f"{source}: link {name!r}: {what} is missing or not a number"
                            ) from None
        if not math.isfinite(v):
            raise URDFError(f"{source}: link {name!r}: {what} is {v} (must be finite)")
        return v

    m = num(el.find("mass"), "value", "<mass value>")
    if m < 0:
        raise URDFError(f"{source}: link {name!r} has mass {m:g} kg; a mass must be >= 0")
    if m > MAX_LINK_MASS_KG:
        raise URDFError(f"{source}: link {name!r} has mass {m:g} kg; the limit is "
                        f"{MAX_LINK_MASS_KG:g} kg (gdimitate.model.urdfcheck.MAX_LINK_MASS_KG): is "
                        "the unit right?")
    i = el.find("inertia")
    c = {k: num(i, k, f"<inertia {k}>") for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
    big = [k for k, v in c.items() if abs(v) > MAX_LINK_INERTIA]
    if big:
        raise URDFError(f"{source}: link {name!r}: <inertia {big[0]}={c[big[0]]:g}> kg·m² "
                        f"exceeds {MAX_LINK_INERTIA:g} kg·m² (gdimitate.model.urdfcheck."
                        "MAX_LINK_INERTIA): is the unit right?")
    origin = el.find("origin")
    for key in ("xyz", "rpy"):
        text = origin.get(key) if origin is not None else None
        try:
            vals = [] if text is None else [_float(v) for v in text.split()]
            ok = text is None or (len(vals) == 3 and all(math.isfinite(v) for v in vals))
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
        parent, child = j.find("parent"), j.find("child")
        if parent is None or child is None:
            continue
        children.setdefault(str(parent.get("link")), []).append(
            (str(j.get("name")), str(j.get("type")), str(child.get("link"))))
        has_parent.add(str(child.get("link")))
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
    bad: list[tuple[str, str, str]] = []  # (joint, type, link), every one of them
    for lk in order:
        for jname, jtype, c in children.get(lk, ()):
            if lk in exempt or jname in allowed:
                exempt.add(c)
            elif jtype != "fixed" and below.get(c, 0.0) <= 0:
                bad.append((jname, jtype, c))
                exempt.add(c)  # the joints below it are covered by naming this one
    if bad:
        which = "; ".join(f"link {c!r} on joint {j!r} ({t})" for j, t, c in bad[:20])
        more = f" and {len(bad) - 20} more" if len(bad) > 20 else ""
        names = ", ".join(repr(j) for j, _, _ in bad)
        raise URDFError(
            f"{source}: {len(bad)} moving joint(s) carry no mass on their link or below it, so "
            f"they move nothing: {which}{more}; give the links a mass and inertia, make the "
            f"joints fixed, or pass massless_joints=({names},) if that is intended")


def _numbers(el: ET.Element | None, key: str, n: int) -> list[float] | None:
    """The ``n`` numbers of attribute ``key`` of ``el`` (None when absent), or None-free
    ValueError text on NaN/inf/wrong count."""
    text = el.get(key) if el is not None else None
    if text is None:
        return None
    vals = [_float(v) for v in text.split()]  # ValueError on junk
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
        for g in lk if g.tag in ("visual", "collision", "inertial")]
    for what, el in where:
        for tag, keys in (("origin", ("xyz", "rpy")), ("axis", ("xyz",))):
            for key in keys:
                try:
                    vals = _numbers(el.find(tag), key, 3)
                except ValueError:
                    bad = el.find(tag)
                    text = bad.get(key) if bad is not None else None
                    raise URDFError(f"{source}: {what}: <{tag} {key}={text!r}> must be three "
                                    "finite numbers") from None
                if vals is None or key == "rpy":
                    continue
                given = cast(ET.Element, el.find(tag)).get(key)  # found: it gave numbers
                if tag == "origin" and max(map(abs, vals)) > MAX_URDF_LENGTH_M:
                    raise URDFError(f"{source}: {what}: <origin xyz={given!r}>"
                                    f" is more than {MAX_URDF_LENGTH_M:g} m from its parent "
                                    "(gdimitate.model.urdfcheck.MAX_URDF_LENGTH_M): is the unit "
                                    "right?")
                if tag == "axis" and math.hypot(*vals) < 1e-9 and el.tag == "joint" and \
                        el.get("type") != "fixed":
                    raise URDFError(f"{source}: {what}: <axis xyz={given!r}> is "
                                    "the zero vector; a joint needs a direction to turn or "
                                    "slide about (e.g. xyz=\"0 1 0\")")
    zero: dict[str, list[str]] = {"effort": [], "velocity": []}
    for j in root.findall("joint"):
        lim, name = j.find("limit"), j.get("name")
        if lim is None or j.get("type") in ("fixed", "floating", "planar"):
            continue
        lim_vals: dict[str, float | None] = {}
        for key in ("lower", "upper", "effort", "velocity"):
            try:
                v = _numbers(lim, key, 1)
            except ValueError:
                raise URDFError(f"{source}: joint {name!r}: <limit {key}={lim.get(key)!r}> "
                                "must be a finite number") from None
            lim_vals[key] = None if v is None else v[0]
        lo, hi = lim_vals["lower"], lim_vals["upper"]
        if j.get("type") != "continuous" and lo is not None and hi is not None and lo > hi:
            raise URDFError(f"{source}: joint {name!r} has lower limit {lo:g} > upper limit "
                            f"{hi:g}; swap them (no position could satisfy both)")
        for key in zero:
            if lim_vals[key] == 0 and name not in PLANAR_BASE:  # our planar base: unactuated
                zero[key].append(str(name))
    for key, names in zero.items():
        if names:
            warnings.warn(f"{source}: {len(names)} joints have {key} limit 0, read as 'no "
                          f"limit given' (not checked; the audit lists them in unlimited): "
                          f"{', '.join(names[:12])}{' …' if len(names) > 12 else ''}",
                          UnlimitedJointWarning, stacklevel=3)


def _dof(joint: ET.Element) -> int:
    """Degrees of freedom of a URDF ``<joint>`` (0 for an unknown type, refused elsewhere)."""
    return JOINT_DOF.get(str(joint.get("type")), 0)


def check_urdf_size(root: ET.Element, source: object) -> None:
    """Refuse a URDF with more than :data:`~gdimitate.safety.MAX_URDF_DOF` degrees of freedom
    or :data:`~gdimitate.safety.MAX_URDF_GEOMETRIES` ``<visual>``/``<collision>`` elements
    (:class:`~gdimitate.errors.URDFLimitError` stating the count and the limit), before
    Pinocchio parses it: ``pin.Data`` of a model of nv degrees of freedom needs about 64·nv³
    bytes, and Pinocchio's geometry parser takes time cubic in the number of shapes (the
    measurements are in :mod:`gdimitate.safety`)."""
    dof = sum(_dof(j) for j in root.findall("joint"))
    if dof > MAX_URDF_DOF:
        raise URDFLimitError(
            f"{source} has {dof:,} degrees of freedom (moving joints); the limit is "
            f"{MAX_URDF_DOF:,} (gdimitate.safety.MAX_URDF_DOF: Pinocchio's data for a model of "
            f"nv degrees of freedom takes about 64·nv³ bytes, {64 * (dof + 6) ** 3 / 2**30:.1f} "
            "GiB here); make the joints that need not move fixed")
    shapes = sum(1 for lk in root.findall("link") for g in lk if g.tag in ("visual",
                                                                        "collision"))
    if shapes > MAX_URDF_GEOMETRIES:
        raise URDFLimitError(
            f"{source} has {shapes:,} <visual>/<collision> elements; the limit is "
            f"{MAX_URDF_GEOMETRIES:,} (gdimitate.safety.MAX_URDF_GEOMETRIES: Pinocchio's "
            "geometry parser takes time cubic in their number); merge shapes into meshes")


def _geometry(what: str, geo: ET.Element, source: object) -> None:
    """Refuse a ``<geometry>`` shape Pinocchio would drop (with its whole link's visual or
    collision geometry) or compute on overflowing numbers."""
    def nums(el: ET.Element, key: str, n: int, lo: float, hi: float, unit: str,
             signed: bool = False, bound: str = "MAX_URDF_LENGTH_M") -> None:
        text = el.get(key)
        try:
            vals = [_float(v) for v in str(text).split()]
        except ValueError:
            vals = []
        if text is None or len(vals) != n or not all(math.isfinite(v) for v in vals):
            raise URDFError(f"{source}: {what}: <{el.tag} {key}={text!r}> must be {n} finite "
                            f"number{'s' if n > 1 else ''}")
        bad = [v for v in vals if not lo <= abs(v) <= hi or (v < 0 and not signed)]
        if bad:
            what_range = f"±({lo:g}…{hi:g})" if signed else f"{lo:g}…{hi:g}{unit}"
            raise URDFError(f"{source}: {what}: <{el.tag} {key}={text!r}>: {bad[0]:g} is outside "
                            f"{what_range} (gdimitate.model.urdfcheck.{bound}): is the unit right?")

    for shape in geo:
        if shape.tag == "box":
            nums(shape, "size", 3, 0.0, MAX_URDF_LENGTH_M, " m")
        elif shape.tag == "sphere":
            nums(shape, "radius", 1, 0.0, MAX_URDF_LENGTH_M, " m")
        elif shape.tag in ("cylinder", "capsule"):
            nums(shape, "radius", 1, 0.0, MAX_URDF_LENGTH_M, " m")
            nums(shape, "length", 1, 0.0, MAX_URDF_LENGTH_M, " m")
        elif shape.tag == "mesh" and shape.get("scale") is not None:
            nums(shape, "scale", 3, 1.0 / MAX_MESH_SCALE, MAX_MESH_SCALE, "", signed=True,
                 bound="MAX_MESH_SCALE")


def check_urdf_structure(root: ET.Element, source: object) -> None:
    """Name the URDF faults Pinocchio reports only as "The XML stream does not contain a valid
    URDF model" or accepts silently, before it parses the file
    (:class:`~gdimitate.errors.URDFError` naming the link or joint): a link or joint without
    a name; a joint without a type or of a type URDF does not define; a joint without
    ``<parent link>`` or ``<child link>``, or naming a link that is not defined; a link that is
    the child of two joints (Pinocchio kept one silently); more than one root link (a link no
    joint holds: two separate bodies); a ``revolute``/``prismatic`` joint without
    ``<limit>``, or a ``<limit>`` without ``effort`` or ``velocity``; a ``<box>``,
    ``<sphere>``, ``<cylinder>`` or ``<mesh scale>`` that is not the right count of finite
    numbers within :data:`MAX_URDF_LENGTH_M` (Pinocchio dropped the link's whole geometry)."""
    links = root.findall("link")
    joints = root.findall("joint")
    for kind, items in (("link", links), ("joint", joints)):
        for k, el in enumerate(items):
            if not (el.get("name") or "").strip():
                raise URDFError(f"{source}: <{kind}> number {k + 1} has no name; every link and "
                                "joint needs a unique name=")
    defined = {str(lk.get("name")) for lk in links}
    parent_of: dict[str, str] = {}
    for j in joints:
        name, jtype = j.get("name"), j.get("type")
        if jtype not in JOINT_DOF:
            raise URDFError(f"{source}: joint {name!r} has type {jtype!r}; URDF joint types: "
                            f"{', '.join(JOINT_DOF)}")
        ends = {}
        for tag in ("parent", "child"):
            end = j.find(tag)
            link = end.get("link") if end is not None else None
            if not link:
                raise URDFError(f"{source}: joint {name!r} has no <{tag} link=\"…\"/>; a joint "
                                "connects a parent link to a child link")
            if link not in defined:
                raise URDFError(f"{source}: joint {name!r}: {tag} link {link!r} is not defined "
                                f"(add <link name=\"{link}\"/> or fix the name)")
            ends[tag] = link
        if ends["child"] in parent_of:
            raise URDFError(f"{source}: link {ends['child']!r} is the child of two joints "
                            f"({parent_of[ends['child']]!r} and {name!r}); a link hangs on one "
                            "joint (URDF describes a tree)")
        parent_of[ends["child"]] = str(name)
        lim = j.find("limit")
        if jtype in ("revolute", "prismatic") and lim is None:
            raise URDFError(f"{source}: joint {name!r} ({jtype}) has no <limit>; give <limit "
                            "lower=… upper=… effort=… velocity=…/> (or make it continuous)")
        if lim is not None and jtype not in ("fixed", "floating", "planar"):
            missing = [k for k in ("effort", "velocity") if lim.get(k) is None]
            if missing:
                raise URDFError(f"{source}: joint {name!r}: <limit> has no {missing[0]}=; URDF "
                                "requires effort and velocity (0 means unknown)")
    roots = [str(lk.get("name")) for lk in links if lk.get("name") not in parent_of]
    if len(roots) > 1:
        raise URDFError(f"{source}: {len(roots)} root links (held by no joint): "
                        f"{roots[:10]}; a robot is one tree: connect them by joints")
    if links and not roots:
        raise URDFError(f"{source}: every link is the child of a joint, so there is no root "
                        "link (the joints form a loop)")
    for lk in links:
        for g in lk:
            if g.tag in ("visual", "collision"):
                geo = g.find("geometry")
                if geo is not None:
                    _geometry(f"link {lk.get('name')!r} <{g.tag}>", geo, source)
