"""Physical and structural checks of a URDF before Pinocchio reads it (docs/security.md).

:func:`check_urdf_physics` refuses inertial data no body can have; :func:`check_urdf_joints`
refuses what Pinocchio would reject without naming it or accept wrongly, and warns about
effort and velocity limits of 0. Both take the parsed XML root and name the file and the link
or joint at fault in a :class:`~gdimitate.errors.URDFError`.
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Iterable

import numpy as np

from .errors import UnlimitedJointWarning, URDFError
from .kinematics import PLANAR_BASE

__all__ = ["INERTIA_TOL", "check_urdf_joints", "check_urdf_physics"]

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
                    bad = el.find(tag)
                    text = bad.get(key) if bad is not None else None
                    raise URDFError(f"{source}: {what}: <{tag} {key}={text!r}> must be three "
                                    "finite numbers") from None
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
