"""The exception hierarchy: every error gdimitate raises derives from :class:`GdimitateError`.

Each class names *what* was wrong; messages say what to fix and, where there is a finite set
of valid choices (robot names, joint names, frame names), list them.
"""

from __future__ import annotations

from collections.abc import Iterable


class GdimitateError(Exception):
    """Base class of all gdimitate errors."""


class URDFError(GdimitateError):
    """A URDF file is missing, unreadable or malformed."""


class UnknownNameError(GdimitateError, KeyError):
    """A robot, joint, frame or option name that does not exist.

    The message lists the valid names.
    """

    def __init__(self, kind: str, name: object, valid: Iterable[str]):
        self.kind = kind
        self.name = name
        self.valid = tuple(valid)
        shown = ", ".join(repr(v) for v in self.valid[:60])
        more = f" (and {len(self.valid) - 60} more)" if len(self.valid) > 60 else ""
        super().__init__(f"unknown {kind} {name!r}; valid {kind}s: {shown}{more}")

    def __str__(self) -> str:  # KeyError would repr() the message otherwise
        return str(self.args[0])


class UnknownRobotError(UnknownNameError):
    """A robot name that is neither in example-robot-data's list nor among our URDFs."""

    def __init__(self, name: object, valid: Iterable[str]):
        super().__init__("robot", name, valid)


class LegDetectionError(GdimitateError):
    """The legs of a robot could not be found from its joint names; pass ``legs=`` explicitly."""


class InvalidInputError(GdimitateError, ValueError):
    """An array with the wrong shape, NaN/inf values, or a value out of its valid range."""


class BodyMapError(InvalidInputError):
    """A body map or a body-map family file (``gdimitate/data/bodymaps/*.json``, or a user's
    passed as ``body_map=``) that is malformed: a missing or unknown key, an unknown role or
    joint name, a scale or offset that is not a finite number, a duplicate entry. The message
    names the file and the entry and lists the valid choices."""


class TimeGridError(InvalidInputError):
    """A time vector that is not one-dimensional, finite and strictly increasing."""


class LegMatchError(GdimitateError):
    """Demonstrator and imitator legs cannot be matched (e.g. different leg names)."""


class UnsupportedJointError(GdimitateError):
    """A joint type the symbolic model does not implement."""


class OscillatorError(InvalidInputError):
    """Matsuoka parameters that cannot oscillate or cannot be integrated as asked."""


class SolverError(GdimitateError):
    """The optimiser could not be set up (not: could not find a feasible point, which is a
    result reported in :class:`~gdimitate.AdaptedMotion.report`)."""


class ViewerError(GdimitateError):
    """The meshcat viewer could not show what was asked (no geometry, port in use, ...)."""


class ContactError(GdimitateError):
    """A robot's feet cannot be found or measured (no sole geometry, point feet): pass
    ``contacts=`` explicitly."""


class OsimError(URDFError):
    """An OpenSim model (``.osim``) that cannot be converted to a URDF: malformed XML, a
    missing body, a joint whose parent is unknown, an unsupported joint or function type, a
    NaN mass, a coordinate that no joint uses. The message names the element and what to fix."""


class OpenSimDataError(InvalidInputError):
    """An OpenSim data file (``.mot``/``.sto`` coordinates or forces, ``.trc`` markers, an
    ExternalLoads ``.xml``) that is malformed or inconsistent; the message names the file and
    what to fix."""


class CoordinateMismatchError(OpenSimDataError):
    """A coordinates file whose columns name none of the model's joints (wrong model or file)."""


class UnitError(OpenSimDataError):
    """A unit flag that contradicts the values (e.g. ``inDegrees=no`` with angles of 60) or a
    unit that is not recognised."""


class ForceDataError(OpenSimDataError):
    """A ground-reaction-force file without recognisable force columns, or forces that cannot
    be assigned to the feet."""


class CoordinateMismatchWarning(UserWarning):
    """File columns the model lacks, or model coordinates the file lacks (listed by name)."""


class BVHError(GdimitateError, ValueError):
    """A BVH motion-capture file that is missing or malformed (the message gives the line
    number and what to fix), or a skeleton :func:`gdimitate.io.bvh.read_bvh` cannot convert."""


class MarkerGapWarning(UserWarning):
    """Markers missing in some frames of a marker file (kept as NaN there, listed by name)."""


class FileFormatError(InvalidInputError):
    """A data file that is not what its name says (an ``.npz`` that is not a NumPy archive or
    lacks keys, a binary ``.mot``, an empty file); the message names the file and what is
    wrong with it."""


class C3DFormatError(FileFormatError):
    """A C3D file whose header, parameter section or data section is truncated or corrupt
    (checked against the file's length before ``ezc3d`` reads it); the message names the
    file, the section, the expected and the actual size."""


class OpenSimFormatError(OpenSimDataError, FileFormatError):
    """An OpenSim ``.mot``/``.sto`` file that is not a table at all (not UTF-8 text, no column
    names, repeated column names): both an :class:`OpenSimDataError` and a
    :class:`FileFormatError`, whichever reader it came through."""


class ResourceLimitError(InvalidInputError):
    """An input whose size would exhaust memory or time (a URDF too large or too deep, a
    motion whose time axis is implausible, too many harmonics or cycles); the message states
    the limit (see :mod:`gdimitate.safety`)."""


class OsimLimitError(OsimError, ResourceLimitError):
    """An ``.osim`` file over the size a model may have
    (:data:`gdimitate.model.osim.model.MAX_OSIM_BYTES`)."""


class URDFLimitError(URDFError, ResourceLimitError):
    """A URDF too large, with too many links or a kinematic chain too deep to parse safely
    (Pinocchio's parser crashes on a 5000-deep chain); the message states the limit."""


class OutputError(GdimitateError):
    """An output path that cannot be written (a folder that is a file, no permission)."""


class MeshPathError(URDFError):
    """A URDF mesh reference that points outside the folders it may read (the URDF's own
    folder and the declared package directories), or a mesh file that is missing."""


class GdimitateWarning(UserWarning):
    """Base class of gdimitate's warnings."""


class UnitsWarning(GdimitateWarning):
    """A unit flag that the values seem to contradict (e.g. ``inDegrees=no`` with 60 rad)."""


class UnlimitedJointWarning(GdimitateWarning):
    """URDF joints whose effort or velocity limit is 0 (many URDFs write 0 for "unknown"):
    read as no limit, so not checked; the audit lists them in ``unlimited``."""


class SimulationError(GdimitateError):
    """The physics check (:mod:`gdimitate.sim`) could not run as asked."""


class SimModelError(SimulationError):
    """A robot that cannot be turned into a MuJoCo model (unsupported joint, massless moving
    link, no flat-foot contacts, bad model options)."""


class PlanError(SimulationError, InvalidInputError):
    """A plan handed to :func:`gdimitate.sim.simulate` that does not fit the robot or the plan
    contract (shapes, time grid, stance schedule, wrenches)."""


class DemonstrationFormatError(InvalidInputError):
    """A demonstration file of a kind :func:`gdimitate.io.demonstration.load_demonstration`
    cannot read (the message lists the supported extensions), or arguments that format cannot
    use (e.g. ``coordinates=`` without an ``.osim``)."""


class RobotMismatchError(InvalidInputError):
    """A motion file whose recorded robot (name, fingerprint) differs from the robot it is
    read with, or whose robot cannot be rebuilt from what it records."""


class ExportError(InvalidInputError):
    """An export that cannot be written as asked (unknown format, a motion without the
    velocities or wrenches the format needs, a robot the format cannot describe)."""


class BatchError(InvalidInputError):
    """A batch that cannot start: an input folder that is missing or holds no demonstration
    files, an output folder that is the input folder, a Dask scheduler out of reach or not
    installed."""
