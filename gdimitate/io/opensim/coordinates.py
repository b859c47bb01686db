"""OpenSim coordinate trajectories (``.mot``/``.sto``) onto a robot's joints → :class:`Motion`.

Columns are matched to the robot's joints by coordinate name: a column is either the plain
coordinate name (``hip_flexion_r``, as OpenSim's inverse kinematics writes it) or a state path
``/jointset/<joint>/<coordinate>/value`` (OpenSim 4 states and Moco solutions, in radians);
``…/speed`` and other state columns (``/forceset/…``) are not coordinates and are listed as
ignored. A URDF converted from the ``.osim`` (:func:`gdimitate.io.opensim.opensim_to_urdf`) names
each 1-DoF joint after its coordinate, so its columns map one to one.

Units: rotational coordinates are in degrees where the header says ``inDegrees=yes`` (or the
older sentence "Angles are in degrees."), else in radians (OpenSim's rule); translations in
metres either way. A file read as radians whose angles exceed 2π is refused with
:class:`~gdimitate.errors.UnitError` (e.g. ``inDegrees=no`` with angles of 60: set
``inDegrees=yes``); a file with no unit flag is read as radians with a warning.

The six ground→pelvis coordinates of an OpenSim model become the free-flyer of the converted
robot (``pelvis_tilt/list/rotation``, ``pelvis_tx/ty/tz`` in gait2354, gait2392 and Rajagopal
2016 models) through the converter's own mapping; on a robot without a free-flyer they are
matched like any other column.

Columns the model lacks and model coordinates the file lacks are listed in a
:class:`~gdimitate.errors.CoordinateMismatchWarning` (the latter keep the robot's neutral
value); a file that names none of the model's coordinates raises
:class:`~gdimitate.errors.CoordinateMismatchError`.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from ...errors import (
    CoordinateMismatchError,
    CoordinateMismatchWarning,
    OpenSimDataError,
    UnitError,
)
from ...model.kinematics import robot_motion
from ...model.motion import Motion
from ...model.osim._table import Table, read_table

__all__ = ["read_coordinates", "coordinate_columns", "robot_coordinates"]

_REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
_PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")
_UNBOUNDED = ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ",
              "JointModelRevoluteUnboundedUnaligned")


def coordinate_columns(table: Table) -> tuple[dict[str, int], list[str]]:
    """``({coordinate: column index}, [ignored state columns])`` of a table: plain names and
    ``/jointset/<joint>/<coordinate>/value`` paths are coordinates; other ``/…`` paths
    (speeds, activations …) are ignored. A coordinate named twice raises
    :class:`~gdimitate.errors.OpenSimDataError`."""
    coords: dict[str, int] = {}
    ignored = []
    for i, name in enumerate(table.names[1:], start=1):
        if name.startswith("/"):
            parts = name.strip("/").split("/")
            if len(parts) == 4 and parts[0] == "jointset" and parts[3] == "value":
                coord = parts[2]
            else:
                ignored.append(name)
                continue
        else:
            coord = name
        if coord in coords:
            raise OpenSimDataError(f"{table.path}: coordinate {coord!r} appears twice (columns "
                                   f"{table.names[coords[coord]]!r} and {name!r}); keep one")
        coords[coord] = i
    return coords, ignored


def robot_coordinates(robot) -> dict[str, str]:
    """``{joint name: "rotational" | "translational" | "unbounded"}`` for the robot's 1-DoF
    joints (revolute, prismatic, unbounded revolute), the joints a coordinate can drive."""
    out = {}
    m = robot.model
    for j in range(1, m.njoints):
        kind = m.joints[j].shortname()
        if kind in _REVOLUTE:
            out[m.names[j]] = "rotational"
        elif kind in _PRISMATIC:
            out[m.names[j]] = "translational"
        elif kind in _UNBOUNDED:
            out[m.names[j]] = "unbounded"
    return out


def _angle_scale(table: Table, values: np.ndarray, names: list[str]) -> float:
    """Degrees→radians factor for the rotational columns ``values`` ``(T, k)``."""
    if table.in_degrees:
        return math.pi / 180.0
    if values.size:
        k = int(np.argmax(np.max(np.abs(values), axis=0)))
        big = float(np.max(np.abs(values[:, k])))
        if big > 2 * math.pi:
            flag = "inDegrees=no" if table.in_degrees is False else "no inDegrees flag"
            raise UnitError(
                f"{table.path}: {flag} (radians) but {names[k]!r} reaches {big:g}, more than "
                "2π: the angles look like degrees; set inDegrees=yes in the header")
    if table.in_degrees is None:
        warnings.warn(f"{table.path}: the header has no inDegrees flag; angles read as "
                      "radians (OpenSim's default). Add inDegrees=yes|no to be explicit",
                      CoordinateMismatchWarning, stacklevel=3)
    return 1.0


def read_coordinates(path: str | Path, robot, *, osim=None) -> Motion:
    """Read an OpenSim coordinates file (``.mot``/``.sto``) onto ``robot``'s joints.

    ``robot``: a :class:`~gdimitate.Robot` whose 1-DoF joints are named after the coordinates
    (e.g. from :meth:`~gdimitate.Robot.from_osim`). ``osim``: the OpenSim model (``OsimModel``
    or ``.osim`` path) whose ground joint the robot's free-flyer replaces — by default the one
    ``Robot.from_osim`` read; without one (a robot from a plain URDF) the ground→pelvis
    columns are listed as columns the model lacks and the base keeps its neutral pose.

    Returns a :class:`~gdimitate.Motion`: ``t`` ``(T,)`` [s] (the file's times), ``q``
    ``(T, nq)`` [rad, m] in Pinocchio order (free-flyer ``[x, y, z, qx, qy, qz, qw]`` in our
    world frame from the ground→pelvis coordinates; the spline-driven joints of a converted
    walker knee from their coordinate), and an empty contact schedule (fill it
    from measured forces, :func:`gdimitate.io.opensim.read_grf`).

    Raises :class:`~gdimitate.errors.CoordinateMismatchError` (no column matches the model),
    :class:`~gdimitate.errors.UnitError` (unit flag contradicting the values),
    :class:`~gdimitate.errors.OpenSimDataError` (malformed file, NaN, a coordinate twice) and
    :class:`~gdimitate.errors.TimeGridError` (time not strictly increasing).
    """
    table = read_table(path)
    cols, ignored = coordinate_columns(table)
    plans = getattr(getattr(robot, "osim", None), "plans", ())
    followed = {s.coordinate for pl in plans for s in pl.steps if s.follows is not None}
    joints = {j: k for j, k in robot_coordinates(robot).items() if j not in followed}
    root = _root_joint(robot, osim)
    root_kind = {c.name: c.motion_type for c in root[0].coordinates} if root else {}
    root_in = [c for c in root_kind if c in cols]
    matched = [c for c in cols if c in joints and c not in root_kind]
    if not matched and not root_in:
        raise CoordinateMismatchError(
            f"{table.path}: none of its coordinates {sorted(cols)[:20]} is a joint of robot "
            f"{robot.name!r} (joints {sorted(joints)[:20]}); read it with the model it was "
            "made for (e.g. Robot.from_osim of the same .osim)")
    extra = sorted(c for c in cols if c not in joints and c not in root_kind)
    absent = sorted(j for j in joints if j not in cols) + [c for c in root_kind if c not in cols]
    if extra or absent or ignored:
        warnings.warn(
            f"{table.path} on robot {robot.name!r}: file columns the model lacks (not used): "
            f"{extra}; model coordinates the file lacks (kept at the neutral pose): {absent}"
            + (f"; ignored non-coordinate state columns: {len(ignored)} ({ignored[:5]}…)"
               if ignored else ""), CoordinateMismatchWarning, stacklevel=2)
    rot = ([c for c in matched if joints[c] != "translational"]
           + [c for c in root_in if root_kind[c] == "rotational"])
    scale = _angle_scale(table, table.data[:, [cols[c] for c in rot]], rot)
    q = np.tile(robot.neutral, (table.t.size, 1))
    for c in matched:
        x = table.data[:, cols[c]] * (scale if joints[c] != "translational" else 1.0)
        i = robot.idx_q(c)
        if joints[c] == "unbounded":
            q[:, i], q[:, i + 1] = np.cos(x), np.sin(x)
        else:
            q[:, i] = x
    if followed:  # spline-driven joints (a walker knee's coupled axes) follow their coordinate
        from ...model.osim.joints import follow_coordinates

        follow_coordinates(plans, q, robot.idx_q)
    if root_in:
        from ...model.osim.joints import pelvis_to_freeflyer

        values = {c: table.data[:, cols[c]] * (scale if root_kind[c] == "rotational" else 1.0)
                  for c in root_in}
        q[:, :7] = pelvis_to_freeflyer(values, root[1])
    return robot_motion(robot, table.t.copy(), q, {})


# ---------------------------------------------------------------------- the free-flyer
def _root_joint(robot, osim):
    """``(OpenSim ground joint, OsimModel)`` the robot's free-flyer replaces, or ``None``."""
    if robot.base != "free":
        return None
    if osim is None:
        osim = _robot_osim(robot)
        if osim is None:
            return None
    from ...model.osim.joints import root_joint
    from ...model.osim.model import OsimModel, read_osim

    model = osim if isinstance(osim, OsimModel) else read_osim(osim)
    return root_joint(model), model


def _robot_osim(robot):
    """The OpenSim model a robot was converted from (``Robot.from_osim`` keeps the conversion
    report as ``robot.osim``), or None."""
    conv = getattr(robot, "osim", None)
    return getattr(conv, "model", None)
