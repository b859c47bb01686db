"""Measured ground reaction forces from OpenSim GRF files (``.mot``/``.sto``).

A GRF file holds, per force plate (or per foot), the force the ground applies to the foot
``…ground_force_…v{x,y,z}`` [N], its point of application (centre of pressure)
``…ground_force_…p{x,y,z}`` [m] and the free torque ``…ground_torque_…{x,y,z}`` [N·m], all in
the lab (OpenSim ground) frame. Three naming conventions are common and all are read:

- ``ground_force_vx`` (right) with ``l_ground_force_vx`` (left) — OpenSim's gait2354 example;
- ``ground_force_r_vx`` / ``ground_force_l_vx`` (also ``_R_``/``_L_``, ``_calcn_r_``) — newer
  OpenSim examples and AddBiomechanics;
- ``ground_force_vx`` with ``1_ground_force_vx`` — OpenSim's gait10dof18musc example, where the
  unprefixed set is the right foot and ``1_`` the left.

Which foot each force belongs to comes from an OpenSim ExternalLoads ``.xml`` where given
(its ``ExternalForce``'s ``applied_to_body``, located in the robot's kinematic tree: the body
belongs to the leg whose sole it carries; columns chosen by ``force_identifier``,
``point_identifier``, ``torque_identifier`` as OpenSim does, by prefix). Without one, the
default is by name: a set whose name carries ``r``/``right`` or ``l``/``left`` belongs to that
foot; an unprefixed set next to an ``l_`` or ``1_`` set is the right foot. Numbered plates
(``1_``, ``2_``) with no unprefixed set cannot be assigned by name: pass ``external_loads``.

Frame: the vertical axis is the one along which the summed force is largest on average (the
ground carries the body's weight): Y for OpenSim's Y-up ground (our world: x = X, y = −Z,
z = Y), Z for a Z-up lab (x = X, y = Y, z = Z); X forward in both. What was detected is stated
in :attr:`~gdimitate.contact.ContactForces.frame_note`.

Stance: a foot is in contact where its vertical force exceeds :data:`CONTACT_THRESHOLD` (20 N,
a common force-plate threshold for heel strike and toe-off); the centre of pressure is NaN
elsewhere (the file's value there is noise over a near-zero force). Units are judged on
loaded rows only: a centre of pressure beyond :data:`MAX_COP_M` where the plate carries more
than :data:`CONTACT_THRESHOLD` is refused as not in metres, whatever unloaded rows hold.
Forces and torques are kept as measured everywhere. Resampling onto other times is linear
interpolation of each column.
"""

from __future__ import annotations

import re
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ...errors import (
    CoordinateMismatchWarning,
    ForceDataError,
    OpenSimDataError,
    ResourceLimitError,
    UnitError,
)
from ...model.contact import ContactForces, FootForces
from ...model.osim._table import Table, read_table
from ...model.osim.joints import ground_to_world
from ...model.osim.model import MAX_OSIM_BYTES
from ...safety import parse_xml, read_text_bounded

__all__ = ["CONTACT_THRESHOLD", "ExternalForceSpec", "read_external_loads", "read_grf"]

#: Vertical force above which a foot is in stance [N].
CONTACT_THRESHOLD = 20.0
SIDES = ("left", "right")
_FORCE = re.compile(r"^(?P<pre>.*?)ground_force_(?P<mid>(?:.*_)?)v(?P<ax>[xyz])$", re.I)


@dataclass(frozen=True)
class ExternalForceSpec:
    """One ``<ExternalForce>`` of an OpenSim ExternalLoads file: ``name``; ``body`` (the
    ``applied_to_body``); the column prefixes ``force_identifier``, ``point_identifier``,
    ``torque_identifier`` (``""`` where absent); ``force_expressed_in``,
    ``point_expressed_in`` (body names; ``"ground"`` is the only one read here)."""

    name: str
    body: str
    force_identifier: str
    point_identifier: str
    torque_identifier: str
    force_expressed_in: str = "ground"
    point_expressed_in: str = "ground"


def read_external_loads(path: str | Path) -> tuple[ExternalForceSpec, ...]:
    """The applied ``ExternalForce`` entries of an OpenSim ExternalLoads ``.xml`` (OpenSim 4's
    ``appliesForce`` and 3.x's ``isDisabled`` both honoured). Raises
    :class:`~gdimitate.errors.OpenSimDataError` for a missing/malformed file, a DOCTYPE or
    entity declaration (refused), or no applied force."""
    path = Path(path)
    if not path.is_file():
        raise OpenSimDataError(f"no such ExternalLoads file: {path}")
    # an XML tree: bounded like an OpenSim model (ElementTree holds ~16 bytes per byte)
    text = read_text_bounded(path, MAX_OSIM_BYTES, "ExternalLoads file", OpenSimDataError,
                             ResourceLimitError)
    root = parse_xml(text, path, OpenSimDataError)
    out = []
    for el in root.iter("ExternalForce"):
        def get(tag: str, default: str = "", el: ET.Element = el) -> str:
            node = el.find(tag)
            return (node.text or "").strip() if node is not None else default

        if get("appliesForce", "true").lower() == "false" or get("isDisabled").lower() == "true":
            continue
        name = el.get("name", "")
        body = get("applied_to_body")
        if not body:
            raise OpenSimDataError(f"{path}: ExternalForce {name!r} has no applied_to_body")
        spec = ExternalForceSpec(name, body, get("force_identifier"), get("point_identifier"),
                                 get("torque_identifier"),
                                 get("force_expressed_in_body", "ground") or "ground",
                                 get("point_expressed_in_body", "ground") or "ground")
        for what in ("force_expressed_in", "point_expressed_in"):
            if getattr(spec, what) != "ground":
                raise OpenSimDataError(
                    f"{path}: ExternalForce {name!r} is {what.replace('_', ' ')} body "
                    f"{getattr(spec, what)!r}; only forces expressed in 'ground' are read")
        if not spec.force_identifier:
            raise OpenSimDataError(f"{path}: ExternalForce {name!r} has no force_identifier")
        out.append(spec)
    if not out:
        raise OpenSimDataError(f"{path}: no applied <ExternalForce> entries")
    return tuple(out)


# ---------------------------------------------------------------------- column sets
@dataclass(frozen=True)
class _Set:
    """Column indices of one force set: ``force``, ``point`` (or None), ``torque`` (or None)."""

    label: str
    force: tuple[int, int, int]
    point: tuple[int, int, int] | None
    torque: tuple[int, int, int] | None


def _by_prefix(table: Table, prefix: str, what: str) -> tuple[int, int, int] | None:
    """Indices of the three columns starting with ``prefix`` (OpenSim's identifier rule)."""
    if not prefix:
        return None
    idx = [i for i, n in enumerate(table.names) if n.startswith(prefix)]
    if len(idx) != 3:
        raise ForceDataError(f"{table.path}: {what} identifier {prefix!r} matches {len(idx)} "
                             f"columns {[table.names[i] for i in idx]}; exactly 3 are needed")
    return idx[0], idx[1], idx[2]


def _named_sets(table: Table) -> dict[tuple[str, str], _Set]:
    """Force sets found by the naming conventions, keyed by (prefix, infix)."""
    low = {n.lower(): i for i, n in enumerate(table.names)}
    keys: dict[tuple[str, str], dict[str, int]] = {}
    for n in table.names:
        m = _FORCE.match(n)
        if m:
            keys.setdefault((m["pre"], m["mid"]), {})[m["ax"].lower()] = table.names.index(n)
    sets = {}
    for (pre, mid), axes in keys.items():
        label = f"{pre}ground_force_{mid}v"
        if sorted(axes) != ["x", "y", "z"]:
            raise ForceDataError(f"{table.path}: force set {label!r} has components "
                                 f"{sorted(axes)}; x, y and z are needed")

        def find(stem: str) -> tuple[int, int, int] | None:
            ix, iy, iz = (low.get(f"{stem}{a}".lower()) for a in "xyz")
            return (ix, iy, iz) if ix is not None and iy is not None and iz is not None else None

        point = find(f"{pre}ground_force_{mid}p")
        torque = find(f"{pre}ground_torque_{mid}")
        sets[(pre, mid)] = _Set(label, (axes["x"], axes["y"], axes["z"]), point, torque)
    return sets


def _side_token(pre: str, mid: str) -> str | None:
    tokens = [t.lower() for t in re.split(r"[_\W]+", pre + "_" + mid) if t]
    sides = {("right" if t in ("r", "right") else "left") for t in tokens
             if t in ("r", "right", "l", "left")}
    return sides.pop() if len(sides) == 1 else None


def _default_sides(table: Table) -> tuple[dict[str, list[_Set]], str]:
    sets = _named_sets(table)
    if not sets:
        raise ForceDataError(
            f"{table.path}: no ground-force columns (expected e.g. ground_force_vx/vy/vz, "
            f"ground_force_r_vx or 1_ground_force_vx); columns are {list(table.names)[:12]}")
    side = {k: _side_token(*k) for k in sets}
    unnamed = {k for k, v in side.items() if v is None}
    if unnamed == {("", "")} and len(sets) > 1 and set(side.values()) == {None, "left"}:
        side[("", "")] = "right"  # ground_force_v* + l_ground_force_v*
    elif unnamed == {("", ""), ("1_", "")} and len(sets) == 2:
        side[("", "")], side[("1_", "")] = "right", "left"  # gait10dof18musc convention
    for k, v in side.items():
        if v is None:
            raise ForceDataError(
                f"{table.path}: cannot tell which foot force set {sets[k].label!r} belongs to "
                f"from its name (sets: {[s.label for s in sets.values()]}); pass "
                "external_loads= (an OpenSim ExternalLoads .xml naming each force's "
                "applied_to_body)")
    out: dict[str, list[_Set]] = {"left": [], "right": []}
    for k, fs in sets.items():
        out[str(side[k])].append(fs)
    for foot in SIDES:
        if len(out[foot]) > 1:
            raise ForceDataError(
                f"{table.path}: several force sets name the {foot} foot "
                f"({[x.label for x in out[foot]]}); pass external_loads= to combine them")
    return out, "feet by column names"


def _body_side(robot, body: str, path: Path) -> str:
    """The leg whose sole frame hangs below ``body`` in the robot's kinematic tree."""
    model = robot.model
    if not model.existFrame(body):
        raise ForceDataError(f"{path}: applied_to_body {body!r} is not a frame of robot "
                             f"{robot.name!r}; its bodies are "
                             f"{[f.name for f in model.frames if f.type == pin.BODY][:40]}")
    joint = model.frames[model.getFrameId(body)].parentJoint
    sides = [s for s in SIDES
             if joint in model.supports[model.frames[model.getFrameId(robot.legs[s].sole)]
                                        .parentJoint]]
    if len(sides) != 1:
        raise ForceDataError(f"{path}: body {body!r} carries {'both' if sides else 'neither'} "
                             "of the robot's soles; apply foot forces to a foot body")
    return sides[0]


def _xml_sides(table: Table, robot, xml: Path) -> tuple[dict[str, list[_Set]], str]:
    out: dict[str, list[_Set]] = {"left": [], "right": []}
    notes = []
    for spec in read_external_loads(xml):
        side = _body_side(robot, spec.body, xml)
        force = _by_prefix(table, spec.force_identifier, "force")
        if force is None:
            raise ForceDataError(f"{xml}: external force {spec.name!r} has no "
                                 "force_identifier")
        s = _Set(spec.force_identifier, force,
                 _by_prefix(table, spec.point_identifier, "point"),
                 _by_prefix(table, spec.torque_identifier, "torque"))
        out[side].append(s)
        notes.append(f"{spec.name}→{spec.body}→{side}")
    return out, f"feet from {xml.name} ({', '.join(notes)})"


# ---------------------------------------------------------------------- combining, frames
def _vertical_axis(table: Table, sets: dict[str, list[_Set]]) -> str:
    cols = [i for v in sets.values() for s in v for i in s.force]
    peak = float(np.max(np.abs(table.data[:, cols])))
    if peak <= CONTACT_THRESHOLD:
        said = "are all zero" if peak == 0 else f"never exceed {peak:.3g} N"
        raise ForceDataError(
            f"{table.path}: the forces {said} ({len(cols)} force columns, {table.t.size} rows): "
            "an unloaded or unconnected plate, not a walk; check the plate's channels and "
            "that the file holds the trial's forces")
    total = sum(table.data[:, list(s.force)].mean(axis=0) for v in sets.values() for s in v)
    k = int(np.argmax(np.abs(total)))
    if k == 0 or total[k] <= 0:
        raise ForceDataError(
            f"{table.path}: the mean force {np.round(total, 1).tolist()} N is largest along "
            f"{'XYZ'[k]}{' and negative' if total[k] <= 0 else ''}; expected the ground's push "
            "up along +Y (OpenSim) or +Z. Forces on the plate (the foot's push) must be negated")
    return "XYZ"[k]


def _foot_wrench(table: Table, sets: list[_Set], R: np.ndarray, up: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World force, centre of pressure and free torque ``(N, 3)`` of one foot on the file's
    own rows (several sets on one foot are summed: moments about the origin added, the centre
    of pressure recomputed on the mean plate height)."""
    d = table.data
    for s in sets:
        if s.point is None:
            raise ForceDataError(f"{table.path}: force {s.label!r} has no centre-of-pressure "
                                 "columns (…p{x,y,z}); they are needed to apply it")
    F = [d[:, list(s.force)] for s in sets]
    P = [d[:, list(s.point)] for s in sets if s.point is not None]  # all (checked above)
    Tq = [d[:, list(s.torque)] if s.torque is not None else np.zeros_like(F[0]) for s in sets]
    missing = [s.label for s in sets if s.torque is None]
    if missing:
        warnings.warn(f"{table.path}: no free-torque columns for {missing}; their free torque "
                      "is taken as 0", CoordinateMismatchWarning, stacklevel=4)
    _check_cop_units(table, F, P, up)
    if len(sets) == 1:
        f, p, tq = F[0], P[0], Tq[0]
    else:
        f = sum(F[1:], F[0])
        m = sum(np.cross(p, fi) + ti for p, fi, ti in zip(P, F, Tq))
        h = np.mean([p[:, up] for p in P], axis=0)
        loaded = np.abs(f[:, up]) > 1e-9
        p = P[0].copy()  # where no force acts the point is immaterial
        p[loaded] = _cop_on_plane(f[loaded], m[loaded], h[loaded], up)
        tq = m - np.cross(p, f)
    return f @ R.T, p @ R.T, tq @ R.T


#: Largest |centre of pressure| coordinate [m] of a loaded row: a lab is not 20 m wide.
MAX_COP_M = 20.0


def _check_cop_units(table: Table, F: list[np.ndarray], P: list[np.ndarray], up: int) -> None:
    """Refuse centre-of-pressure columns that are not in metres, judged on loaded rows only
    (vertical force above :data:`CONTACT_THRESHOLD`): where a plate carries no load its centre
    of pressure is a division by ~0 and holds arbitrary numbers (OpenSim's own example
    ``grf_walk.mot`` has 330 and −496 "m" there)."""
    for f, p in zip(F, P):
        loaded = np.abs(f[:, up]) > CONTACT_THRESHOLD
        if not loaded.any():
            continue
        worst = float(np.max(np.abs(p[loaded])))
        if worst > MAX_COP_M:
            row = int(np.flatnonzero(loaded)[np.argmax(np.max(np.abs(p[loaded]), axis=1))])
            raise UnitError(
                f"{table.path}: centre of pressure reaches {worst:g} at t = "
                f"{table.t[row]:g} s where the plate carries {abs(f[row, up]):.0f} N; "
                "positions must be in metres (millimetres? divide by 1000)")


def _cop_on_plane(f: np.ndarray, m: np.ndarray, h: np.ndarray, up: int) -> np.ndarray:
    """Point on the plane ``x[up] = h`` about which the moment ``m`` of force ``f`` (about the
    origin) has no horizontal component."""
    a, b = [i for i in range(3) if i != up]
    p = np.empty_like(f)
    p[:, up] = h
    # m_p = m − p × f must vanish along a and b; solved for p_a, p_b (cyclic index algebra)
    sign = 1.0 if (a, b, up) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0
    p[:, b] = (sign * m[:, a] + h * f[:, b]) / f[:, up]
    p[:, a] = (h * f[:, a] - sign * m[:, b]) / f[:, up]
    return p


def read_grf(path: str | Path, robot, external_loads: str | Path | None = None,
             t: np.ndarray | None = None, *, contact_threshold: float = CONTACT_THRESHOLD
             ) -> ContactForces:
    """Read an OpenSim ground-reaction-force file → :class:`~gdimitate.contact.ContactForces`.

    ``robot``: the :class:`~gdimitate.Robot` the forces act on (its legs locate the
    ExternalLoads bodies). ``external_loads``: an OpenSim ExternalLoads ``.xml`` assigning each
    force to a body; without it, feet are assigned by column names (module docstring).
    ``t`` ``(T,)`` [s]: times to resample onto (linear interpolation; must lie inside the
    file's time range), default the file's own rows.

    Per foot (``"left"``, ``"right"``): ``force`` ``(T, 3)`` [N] the ground applies ON the foot,
    ``cop`` ``(T, 3)`` [m] centre of pressure (NaN out of contact), ``torque`` ``(T, 3)``
    [N·m] free torque, all in our world frame (x forward, y left, z up); ``contact`` ``(T,)``
    where the vertical force exceeds ``contact_threshold`` [N] (default 20 N).

    Raises :class:`~gdimitate.errors.ForceDataError` (no force columns, a foot without a
    force, centre of pressure missing, an unassignable set, force not pointing up),
    :class:`~gdimitate.errors.UnitError` (centre of pressure of a loaded row not in metres),
    :class:`~gdimitate.errors.OpenSimDataError` / :class:`~gdimitate.errors.TimeGridError`
    (malformed table, NaN, time not increasing, ``t`` outside the file).
    """
    table = read_table(path)
    if external_loads is not None:
        sets, who = _xml_sides(table, robot, Path(external_loads))
    else:
        sets, who = _default_sides(table)
    empty = [s for s in SIDES if not sets[s]]
    if empty:
        raise ForceDataError(f"{table.path}: no force for the {empty} foot ({who}); each foot "
                             "needs one force set")
    up = _vertical_axis(table, sets)
    R = ground_to_world(up)
    ft = table.t
    tt = ft.copy() if t is None else np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 1 or not np.all(np.isfinite(tt)):
        raise OpenSimDataError(f"t must be a finite 1-D array of times [s]; got shape {tt.shape}")
    if tt.min() < ft[0] - 1e-9 or tt.max() > ft[-1] + 1e-9:
        raise OpenSimDataError(f"{table.path}: the file covers t = {ft[0]:g}–{ft[-1]:g} s; "
                               f"asked {tt.min():g}–{tt.max():g} s (cut t to the file's range)")
    feet = {}
    for side in SIDES:
        f, p, tq = _foot_wrench(table, sets[side], R, "XYZ".index(up))
        f, p, tq = (np.column_stack([np.interp(tt, ft, x[:, k]) for k in range(3)])
                    for x in (f, p, tq))
        contact = f[:, 2] > contact_threshold
        p[~contact] = np.nan
        feet[side] = FootForces(f, p, tq, contact)
    frame = ("OpenSim ground Y up → world x = X, y = −Z, z = Y" if up == "Y"
             else "lab Z up → world x = X, y = Y, z = Z")
    grid = "file's own rows" if t is None else f"resampled onto {tt.size} times (linear)"
    note = (f"{frame}; {who}; {grid}; stance where vertical force > {contact_threshold:g} N; "
            "positions as measured (not turned overground)")
    return ContactForces(tt, feet, source=str(table.path), frame_note=note)
