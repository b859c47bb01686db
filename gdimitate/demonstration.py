"""Any demonstration file → the demonstrator :class:`~gdimitate.Robot`, its
:class:`~gdimitate.Motion` and (where measured) its :class:`~gdimitate.contact.ContactForces`.

One entry point, :func:`load_demonstration`, dispatches on the file's extension:

- ``.mot`` / ``.sto`` (OpenSim coordinates): with ``robot=`` (a Robot converted from the
  subject's ``.osim``, :meth:`Robot.from_osim`) the full-body reader
  :func:`gdimitate.opensim.read_coordinates`; without one, the sagittal reader
  :func:`gdimitate.gait.read_opensim` (planar human scaled to 1.75 m), which refuses a
  full-body file and says to pass the model;
- ``.osim`` + ``coordinates=`` (a ``.mot``/``.sto``): :meth:`Robot.from_osim` of the model
  and the coordinates read onto it;
- ``.bvh``: :func:`gdimitate.bvh.read_bvh` (skeleton → URDF, contacts from the feet);
- ``.npz`` (:meth:`Motion.to_npz`): the motion with its robot rebuilt from the metadata the
  file records (library name, URDF / ``.osim`` / ``.bvh`` path, legs, contacts) and checked
  against the recorded :attr:`Robot.fingerprint` (a mismatch is an error).

Forces: ``grf=`` (an OpenSim ground-reaction-force ``.mot``/``.sto``) is read with
:func:`gdimitate.opensim.read_grf` on the motion's times, with the OpenSim ExternalLoads XML
that assigns its force sets to bodies when one lies beside it (same stem with ``.xml``, or
the only ``.xml`` in that folder naming the file as its ``datafile``); the measured stance
(vertical force > 20 N) becomes the motion's contact schedule. A full-body motion without
forces gets its contacts from the feet's sole corners (height and speed,
:func:`gdimitate.bvh.detect_contacts`). ``overground=True`` turns a treadmill trial with
forces overground (:func:`gdimitate.opensim.treadmill_to_overground`: the belt speed, estimated
from the stance feet, added to the base x and the centres of pressure).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .contact import ContactForces
from .errors import DemonstrationFormatError
from .motion import Motion
from .robot import Robot

__all__ = ["Demonstration", "DemonstrationFormatError", "SUPPORTED",
           "load_demonstration"]

#: File extensions :func:`load_demonstration` reads, with what each one is.
SUPPORTED: dict[str, str] = {
    ".mot": "OpenSim coordinates (+ grf=; full-body needs robot= from the .osim)",
    ".sto": "OpenSim coordinates, storage format (as .mot)",
    ".osim": "OpenSim model, with coordinates= (.mot/.sto)",
    ".bvh": "BVH motion capture",
    ".npz": "gdimitate motion (Motion.to_npz / AdaptedMotion.save), robot recorded",
}


@dataclass(frozen=True)
class Demonstration:
    """A demonstration ready for :func:`gdimitate.adapt`.

    ``robot``: the demonstrator; ``motion``: its :class:`Motion` (``q`` ``(T, nq)`` in
    Pinocchio order, ``contact`` ``{side: (T,) bool}``); ``forces``: measured
    :class:`ContactForces` on ``motion.t`` or ``None``; ``source``: the file read;
    ``note``: what was done (reader, contact source, overground shift, ...).
    """

    robot: Robot
    motion: Motion
    forces: ContactForces | None
    source: str
    note: str


def load_demonstration(path: str | Path, *, grf: str | Path | None = None,
                       coordinates: str | Path | None = None, robot: Robot | None = None,
                       overground: bool = True) -> Demonstration:
    """Read a demonstration file (see the module docstring for each format).

    ``path``: ``.mot``/``.sto``/``.osim``/``.bvh``/``.npz``; ``grf``: OpenSim ground reaction
    forces (``.mot``/``.sto``); ``coordinates``: the coordinates file of an ``.osim`` model;
    ``robot``: the demonstrator for a full-body ``.mot``/``.sto`` (or to check an ``.npz``
    against); ``overground``: turn a treadmill trial with forces overground.

    Raises :class:`~gdimitate.errors.DemonstrationFormatError` for an unknown
    extension (listing :data:`SUPPORTED`) or arguments the format cannot use, and the readers'
    own errors for malformed files.
    """
    raise NotImplementedError  # implemented below in the next commit
