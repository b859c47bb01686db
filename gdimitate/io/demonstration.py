"""Any demonstration file → the demonstrator :class:`~gdimitate.Robot`, its
:class:`~gdimitate.Motion` and (where measured) its :class:`~gdimitate.contact.ContactForces`.

One entry point, :func:`load_demonstration`, dispatches on the file's extension:

- ``.mot`` / ``.sto`` (OpenSim coordinates): with ``robot=`` (a Robot converted from the
  subject's ``.osim``, :meth:`Robot.from_osim`) the full-body reader
  :func:`gdimitate.io.opensim.read_coordinates`; without one, the sagittal reader
  :func:`gdimitate.io.gait.read_opensim` (planar human scaled to 1.75 m), which refuses a
  full-body file and says to pass the model;
- ``.osim`` + ``coordinates=`` (a ``.mot``/``.sto``): :meth:`Robot.from_osim` of the model
  and the coordinates read onto it;
- ``.bvh``: :func:`gdimitate.io.bvh.read_bvh` (skeleton → URDF, contacts from the feet);
- ``.npz`` (:meth:`Motion.to_npz`): the motion with its robot rebuilt from the metadata the
  file records (library name, URDF / ``.osim`` / ``.bvh`` path, legs, contacts) and checked
  against the recorded :attr:`Robot.fingerprint` (a mismatch is an error);
- markers: ``.osim`` + ``markers=`` (a ``.trc`` or a gait-lab ``.c3d``), or the ``.trc`` /
  ``.c3d`` itself with ``robot=`` from the ``.osim``: marker-based inverse kinematics
  (:func:`gdimitate.io.opensim.inverse_kinematics`, per-marker residuals in
  :attr:`Demonstration.ik`); a ``.c3d``'s force plates are the forces
  (:meth:`gdimitate.io.c3d.C3DTrial.contact_forces`: plates to feet by proximity) unless
  ``grf=`` is given.

Forces: ``grf=`` (an OpenSim ground-reaction-force ``.mot``/``.sto``) is read with
:func:`gdimitate.io.opensim.read_grf` on the motion's times, with the OpenSim ExternalLoads XML
that assigns its force sets to bodies when one lies beside it (same stem with ``.xml``, or
the only ``.xml`` in that folder naming the file as its ``datafile``); the measured stance
(vertical force > 20 N) becomes the motion's contact schedule. A full-body motion without
forces gets its contacts from the feet's sole corners (height and speed,
:func:`gdimitate.io.bvh.detect_contacts`). ``overground=True`` turns a treadmill trial with
forces overground (:func:`gdimitate.io.opensim.treadmill_to_overground`: the belt speed, estimated
from the stance feet, added to the base x and the centres of pressure).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import DemonstrationFormatError
from ..model.contact import ContactForces
from ..model.motion import Motion
from ..model.robot import Robot

__all__ = ["Demonstration", "DemonstrationFormatError", "SUPPORTED",
           "load_demonstration"]

#: File extensions :func:`load_demonstration` reads, with what each one is.
SUPPORTED: dict[str, str] = {
    ".mot": "OpenSim coordinates (+ grf=; full-body needs robot= from the .osim)",
    ".sto": "OpenSim coordinates, storage format (as .mot)",
    ".osim": "OpenSim model, with coordinates= (.mot/.sto)",
    ".bvh": "BVH motion capture",
    ".npz": "gdimitate motion (Motion.to_npz / AdaptedMotion.save), robot recorded",
    ".trc": "markers (+ robot= from the .osim: marker-based IK; + grf=)",
    ".c3d": "gait-lab C3D, markers and force plates (+ robot= from the .osim: marker-based IK)",
}


@dataclass(frozen=True)
class Demonstration:
    """A demonstration ready for :func:`gdimitate.adapt`.

    ``robot``: the demonstrator; ``motion``: its :class:`Motion` (``q`` ``(T, nq)`` in
    Pinocchio order, ``contact`` ``{side: (T,) bool}``); ``forces``: measured
    :class:`ContactForces` on ``motion.t`` or ``None``; ``source``: the file read;
    ``note``: what was done (reader, contact source, overground shift, ...); ``ik``: the
    :class:`~gdimitate.opensim.IKResult` of a marker demonstration (per-marker residuals),
    else ``None``.
    """

    robot: Robot
    motion: Motion
    forces: ContactForces | None
    source: str
    note: str
    ik: object = None


def load_demonstration(path: str | Path, *, grf: str | Path | None = None,
                       coordinates: str | Path | None = None, robot: Robot | None = None,
                       overground: bool = True, markers: str | Path | None = None,
                       package_dir: str | Path | None = None) -> Demonstration:
    """Read a demonstration file (see the module docstring for each format).

    ``path``: ``.mot``/``.sto``/``.osim``/``.bvh``/``.npz``/``.trc``/``.c3d``; ``grf``:
    OpenSim ground reaction forces (``.mot``/``.sto``); ``coordinates``: the coordinates file
    of an ``.osim`` model; ``markers``: the ``.trc``/``.c3d`` markers of an ``.osim`` model;
    ``robot``: the demonstrator for a full-body ``.mot``/``.sto`` (or to check an ``.npz``
    against); ``overground``: turn a treadmill trial with forces overground;
    ``package_dir``: the mesh package folder of an ``.npz``'s recorded URDF robot, where it
    is not the URDF's own folder or below it (a folder recorded in the file is used only
    there: a file never widens what may be read, docs/security.md).

    Raises :class:`~gdimitate.errors.DemonstrationFormatError` for an unknown
    extension (listing :data:`SUPPORTED`) or arguments the format cannot use, and the readers'
    own errors for malformed files.
    """
    p = _check_arguments(path, grf, coordinates, robot, overground, markers, package_dir)
    suffix = p.suffix.lower()
    if suffix not in SUPPORTED:
        raise DemonstrationFormatError(
            f"{p}: unknown demonstration format {p.suffix or '(no extension)'!r}; supported: "
            + "; ".join(f"{k} ({v})" for k, v in SUPPORTED.items()))
    for name, value in (("coordinates", coordinates), ("markers", markers)):
        if value is not None and suffix != ".osim":
            raise DemonstrationFormatError(f"{name}= goes with an .osim model; {p} is {suffix}")
    if suffix == ".osim":
        if (coordinates is None) == (markers is None):
            raise DemonstrationFormatError(
                f"{p} is an OpenSim model: pass either coordinates= (CLI: --coordinates "
                "FILE.mot), the .mot/.sto of its joint angles, or markers= (CLI: --markers "
                "FILE.trc|FILE.c3d), its measured markers")
        if robot is not None:
            raise DemonstrationFormatError("an .osim demonstration builds its own robot; "
                                           "robot= is for a .mot/.sto/.trc/.c3d")
        if markers is not None:
            return _from_markers(Path(markers).expanduser(), p, grf, overground,
                                 f"{p} (model) + ")
        return _full_body(Path(str(coordinates)).expanduser(), Robot.from_osim(p), grf,
                          overground,
                          f"{p} (model) + ")
    if suffix in (".trc", ".c3d"):
        if robot is None:
            raise DemonstrationFormatError(
                f"{p} holds markers: give the OpenSim model they were placed on "
                "(load_demonstration('model.osim', markers=...), or robot=Robot.from_osim("
                "'model.osim'); CLI: --osim model.osim). Every format: "
                + "; ".join(f"{k} ({v})" for k, v in SUPPORTED.items()))
        return _from_markers(p, robot, grf, overground, "")
    if grf is not None and suffix in (".bvh", ".npz"):
        raise DemonstrationFormatError(f"grf= goes with OpenSim coordinates; {p} is {suffix}")
    if suffix in (".mot", ".sto"):
        if robot is not None:
            return _full_body(p, robot, grf, overground, "")
        return _sagittal(p, grf)
    if suffix == ".bvh":
        if robot is not None:
            raise DemonstrationFormatError("a .bvh demonstration builds its own robot from the "
                                           "skeleton; robot= is for a .mot/.sto or .npz")
        from .bvh import read_bvh

        bot, motion = read_bvh(p)
        info = bot.bvh_info
        return Demonstration(bot, motion, None, str(p),
                             f"BVH ({info.unit}, floor at z = 0: {info.grounded}); contacts "
                             "from the feet's height and speed")
    return _npz(p, robot, package_dir)


def _check_arguments(path, grf, coordinates, robot, overground, markers, package_dir) -> Path:
    """:func:`load_demonstration`'s arguments of the right types (paths, a Robot, a bool) →
    the demonstration's path; :class:`InvalidInputError` naming the argument otherwise."""
    from ..errors import InvalidInputError
    from ..model.inputs import path_arg

    p = path_arg("path", path).expanduser()
    for name, value in (("grf", grf), ("coordinates", coordinates), ("markers", markers),
                        ("package_dir", package_dir)):
        if value is not None:
            path_arg(name, value)
    if robot is not None and not isinstance(robot, Robot):
        raise InvalidInputError(f"robot must be a gdimitate.Robot or None; got "
                                f"{type(robot).__name__}")
    if not isinstance(overground, bool):
        raise InvalidInputError(f"overground must be True or False; got {overground!r:.40}")
    return p


def _sagittal(p: Path, grf) -> Demonstration:
    from ..errors import OpenSimDataError
    from .gait import read_opensim

    try:
        bot, motion = read_opensim(p, grf=grf)
    except OpenSimDataError as e:
        if "full-body" not in str(e):
            raise
        raise DemonstrationFormatError(
            f"{p} is a full-body 3-D coordinates file: give its OpenSim model (robot="
            "Robot.from_osim(model.osim); CLI: --osim model.osim) or read it as model.osim "
            "with coordinates=") from None
    return Demonstration(bot, motion, None, str(p),
                         "OpenSim sagittal coordinates on a planar human (1.75 m); contacts "
                         + ("from the measured vertical GRF" if grf is not None
                            else "from the sole heights"))


def _external_loads(grf: Path) -> Path | None:
    """The ExternalLoads XML beside a GRF file: ``<stem>.xml``, or the only ``.xml`` in its
    folder whose ``datafile`` names the GRF file."""
    same = grf.with_suffix(".xml")
    if same.is_file():
        return same
    hits = []
    for x in sorted(grf.parent.glob("*.xml")):
        try:
            text = x.read_text(errors="replace")[:200_000]
        except OSError:
            continue
        if "ExternalLoads" in text and grf.name in text:
            hits.append(x)
    return hits[0] if len(hits) == 1 else None


def _full_body(coords: Path, robot: Robot, grf, overground: bool, prefix: str
               ) -> Demonstration:
    from .opensim import read_coordinates

    if coords.suffix.lower() not in (".mot", ".sto"):
        raise DemonstrationFormatError(f"coordinates must be a .mot/.sto file; got {coords}")
    motion = read_coordinates(coords, robot)
    return _with_forces(robot, motion, grf, None, overground, f"{prefix}{coords}",
                        "OpenSim full-body coordinates")


def _from_markers(path: Path, robot: Robot | Path, grf, overground: bool, prefix: str
                  ) -> Demonstration:
    """Marker-based inverse kinematics of a ``.trc``/``.c3d`` on ``robot`` (or on the
    ``.osim`` path's model, its soles put on the lab floor below the trial's foot markers),
    then its forces (``grf``, else a C3D's plates, else the feet's kinematics)."""
    import numpy as np

    from .opensim import inverse_kinematics, read_trc

    trial = None
    suffix = path.suffix.lower()
    if suffix == ".c3d":
        from .c3d import read_c3d

        trial = read_c3d(path)
        markers = trial.markers
    elif suffix == ".trc":
        markers = read_trc(path)
    else:
        raise DemonstrationFormatError(f"markers must be a .trc or .c3d file; got {path}")
    if not isinstance(robot, Robot):
        robot = Robot.from_osim(robot, markers=markers)
    motion, ik = inverse_kinematics(robot, markers, return_result=True)
    what = (f"marker-based IK ({len(ik.names)} markers, residual RMS "
            f"{1000 * float(np.sqrt(np.nanmean(ik.residuals ** 2))):.1f} mm)")
    plates = trial if trial is not None and trial.plates and grf is None else None
    demo = _with_forces(robot, motion, grf, plates, overground, f"{prefix}{path}", what)
    return Demonstration(demo.robot, demo.motion, demo.forces, demo.source, demo.note, ik)


def _with_forces(robot: Robot, motion: Motion, grf, trial, overground: bool, source: str,
                 what: str) -> Demonstration:
    """The demonstration of ``motion`` with its forces: an OpenSim ``grf`` file, a C3D
    ``trial``'s plates, or (neither) contacts from the feet's kinematics."""
    from .opensim import read_grf, treadmill_to_overground

    if grf is None and trial is None:
        from .bvh.contacts import kinematic_stance

        contact, how = kinematic_stance(robot, motion.q, motion.t)
        return Demonstration(robot, motion.replace(contact=contact), None, source,
                             f"{what}; contacts from the sole corners' {how} (no forces given)")
    if trial is not None:
        forces = trial.contact_forces(robot, motion)
        note = f"{what}; forces from {len(trial.plates)} force plate(s) of {Path(source).name}"
    else:
        grf = Path(grf).expanduser()
        xml = _external_loads(grf)
        forces = read_grf(grf, robot, xml, t=motion.t)
        note = (f"{what}; forces {grf.name} (ExternalLoads "
                f"{xml.name if xml else 'none: feet from column names'})")
    motion = motion.replace(contact=forces.contact)
    if overground:
        motion, forces = treadmill_to_overground(robot, motion, forces)
        note += "; " + forces.frame_note
    return Demonstration(robot, motion, forces, source, note)


def _recorded_package_dir(p: Path, rec, given: str | Path | None) -> str | None:
    """The package folder to load an ``.npz``'s recorded robot with: ``given`` (the caller's
    own) if any; else the recorded one if it is the URDF's own folder or below it (for a
    library robot: example-robot-data's folder, which the library uses anyway); else
    :class:`~gdimitate.errors.MeshPathError` — a file must never widen what may be read."""
    import os

    from ..errors import MeshPathError

    if given is not None:
        return str(given)
    if rec.kind == "library" or not rec.package_dir:
        return None  # a library robot's meshes come from the library's own folder
    if rec.kind != "urdf":
        return None  # .osim/.bvh robots are rebuilt from their source: no package folder
    recorded = Path(os.path.realpath(rec.package_dir))
    urdf_dir = Path(os.path.realpath(Path(rec.source).parent))
    if recorded.is_relative_to(urdf_dir):
        return str(recorded)
    raise MeshPathError(
        f"{p}: its robot_package_dir {rec.package_dir!r} is not the URDF's folder {urdf_dir} or "
        "below it; a motion file cannot widen the folders its robot's meshes are read from. "
        "If that folder is right, pass it yourself: load_demonstration(..., package_dir=...) "
        "or load the robot with Robot.from_urdf(..., package_dir=...) and pass robot=")


def _recorded_json(p: Path, field: str, text: str) -> object:
    """A JSON option (``robot_legs``/``robot_contacts``) recorded in an ``.npz``, checked
    (:func:`gdimitate.model.inputs.loads_json`): :class:`FileFormatError` naming the file and
    field."""
    from ..errors import FileFormatError
    from ..model.inputs import loads_json

    if not text:
        return None
    value = loads_json(text, f"{p}: robot_{field}", FileFormatError)
    if not isinstance(value, dict):
        raise FileFormatError(f"{p}: robot_{field} must be a JSON object {{\"left\": …, "
                              f"\"right\": …}}; got {type(value).__name__}")
    return value


def _recorded_names(p: Path, text: str) -> tuple[str, ...]:
    """The ``robot_massless`` joint names recorded in an ``.npz`` (a JSON list of str):
    :class:`FileFormatError` naming the file and field otherwise."""
    from ..errors import FileFormatError
    from ..model.inputs import loads_json

    if not text:
        return ()
    value = loads_json(text, f"{p}: robot_massless", FileFormatError)
    if not (isinstance(value, list) and all(isinstance(j, str) for j in value)):
        raise FileFormatError(f"{p}: robot_massless must be a JSON list of joint names; got "
                              f"{text[:80]!r}")
    return tuple(value)


def _npz(p: Path, robot: Robot | None, package_dir: str | Path | None = None
         ) -> Demonstration:
    from ..errors import FileFormatError, RobotMismatchError
    from ..model.library import list_robots
    from ..model.motion import RobotRecord, check_motion_layout

    rec = RobotRecord.from_npz(p)
    motion = Motion.from_npz(p)
    if rec is None:
        if robot is None:
            raise RobotMismatchError(
                f"{p} records no robot (written without Motion.to_npz(path, robot=)); pass "
                "its robot (robot=; CLI: --demonstrator NAME|URDF)")
        note = "gdimitate NPZ (no robot recorded; robot as given)"
    else:
        if robot is None:
            if rec.kind == "memory":
                raise RobotMismatchError(
                    f"{p}: its robot {rec.name!r} was built in memory and cannot be rebuilt "
                    "from the file; pass it (robot=; CLI: --demonstrator)")
            if rec.kind == "library" and rec.source not in list_robots():
                raise FileFormatError(f"{p}: robot_kind 'library' with robot_source "
                                      f"{rec.source[:100]!r}, which is not a library robot "
                                      f"({', '.join(list_robots())})")
            legs = _recorded_json(p, "legs", rec.legs)
            contacts = _recorded_json(p, "contacts", rec.contacts)
            if rec.kind == "bvh":
                from .bvh import read_bvh

                robot = read_bvh(rec.source, name=rec.name)[0]
            else:
                robot = Robot.load(rec.source,
                                   package_dir=_recorded_package_dir(p, rec, package_dir),
                                   legs=legs, contacts=contacts,  # type: ignore[arg-type]
                                   massless_joints=_recorded_names(p, rec.massless))
        if robot.fingerprint != rec.fingerprint:
            raise RobotMismatchError(
                f"{p} was written for robot {rec.name!r} ({rec.kind} {rec.source}, fingerprint "
                f"{rec.fingerprint}); {robot.name!r} has fingerprint {robot.fingerprint}: its "
                "joints, placements, inertias or limits differ (the model file changed?)")
        note = f"gdimitate NPZ of robot {rec.name!r} ({rec.kind}, fingerprint checked)"
    motion = check_motion_layout(robot, motion, p, RobotMismatchError)
    forces = None
    return Demonstration(robot, motion, forces, str(p), note)
