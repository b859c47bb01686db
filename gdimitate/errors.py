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
    result reported in :class:`~gdimitate.adapt.AdaptedMotion.report`)."""


class ViewerError(GdimitateError):
    """The meshcat viewer could not show what was asked (no geometry, port in use, ...)."""


class ContactError(GdimitateError):
    """A robot's feet cannot be found or measured (no sole geometry, point feet): pass
    ``contacts=`` explicitly."""


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


class MarkerGapWarning(UserWarning):
    """Markers missing in some frames of a marker file (kept as NaN there, listed by name)."""
