"""Where robot models come from: example-robot-data's URDFs and our own planar models.

example-robot-data (PyPI) installs URDFs and meshes under
``<site-packages>/cmeel.prefix/share/example-robot-data/robots`` but, in its current release,
has no Python loader. We find that folder through the distribution's list of installed files
(``importlib.metadata``), never through a hard-coded path, and hand its parent to Pinocchio as
the package directory so that ``package://example-robot-data/...`` mesh paths resolve.
"""

from __future__ import annotations

import functools
import importlib.metadata
from dataclasses import dataclass
from pathlib import Path

from ..errors import UnknownRobotError, URDFError

__all__ = ["LibraryEntry", "LIBRARY", "MASSLESS_PRESETS", "erd_robots_dir", "library_entry",
           "list_robots"]


@dataclass(frozen=True)
class LibraryEntry:
    """One example-robot-data model: its URDF path relative to ``robots/`` and a note."""

    name: str
    urdf: str
    note: str = ""


LIBRARY: dict[str, LibraryEntry] = {
    e.name: e
    for e in [
        LibraryEntry("human", "human_description/robots/human.urdf",
                     "Y-up human model; flexion about Z"),
        LibraryEntry("talos", "talos_data/robots/talos_reduced.urdf", "PAL Talos, 1.75 m"),
        LibraryEntry("romeo", "romeo_description/urdf/romeo.urdf", "Aldebaran Romeo, 1.4 m"),
        LibraryEntry("icub", "icub_description/robots/icub_reduced.urdf", "IIT iCub, 1.0 m"),
        LibraryEntry("g1", "g1_description/urdf/g1_29dof_rev_1_0.urdf", "Unitree G1, 29 DoF"),
        LibraryEntry("bolt", "bolt_description/robots/bolt.urdf",
                     "ODRI Bolt biped, point feet, no ankle"),
        LibraryEntry("simple_humanoid",
                     "simple_humanoid_description/urdf/simple_humanoid.urdf",
                     "no visual geometry"),
        LibraryEntry("alexander", "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf",
                     "Boardwalk Robotics Alexander, lower body (legs and pelvis), 49 kg"),
        LibraryEntry("icub_full", "icub_description/robots/icub.urdf",
                     "IIT iCub with every joint (eyes, hands), 1.0 m"),
        LibraryEntry("g1_hands", "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
                     "Unitree G1, 29 DoF with three-finger hands"),
    ]
}

#: Joints of library robots whose subtrees are massless on purpose (Romeo's hands: every
#: finger link has mass 0); see :func:`gdimitate.model.urdfcheck.check_urdf_physics`.
MASSLESS_PRESETS: dict[str, tuple[str, ...]] = {
    "romeo": tuple(f"{s}{j}" for s in "LR" for j in ("Hand", "Finger21", "Finger31", "Thumb1")),
}


@functools.cache
def erd_robots_dir() -> Path:
    """The ``robots/`` folder of the installed example-robot-data distribution.

    Raises :class:`URDFError` if the distribution is not installed or holds no ``robots/``.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as e:
        raise URDFError(
            "example-robot-data is not installed; `pip install example-robot-data`"
        ) from e
    for f in dist.files or ():
        parts = Path(str(f)).parts
        if "example-robot-data" in parts and "robots" in parts:
            i = parts.index("robots")
            if i > 0 and parts[i - 1] == "example-robot-data":
                return Path(str(dist.locate_file(Path(*parts[: i + 1])))).resolve()
    raise URDFError("example-robot-data is installed but ships no robots/ folder")


def library_entry(name: str) -> tuple[Path, Path]:
    """``(urdf_path, package_dir)`` of an example-robot-data robot named in :data:`LIBRARY`.

    ``package_dir`` is the folder that contains ``example-robot-data/`` (pass it to Pinocchio).
    """
    if name not in LIBRARY:
        raise UnknownRobotError(name, list_robots())
    robots = erd_robots_dir()
    path = robots / LIBRARY[name].urdf
    if not path.is_file():
        raise URDFError(f"example-robot-data has no {LIBRARY[name].urdf} (robot {name!r})")
    return path, robots.parent.parent


def list_robots() -> list[str]:
    """Names accepted by :meth:`gdimitate.Robot.from_library`: our planar models, then
    example-robot-data's bipeds and humanoids that Pinocchio loads (not listed: ``alex``,
    upper body only; ``talos_full_v2``, whose ``package:///`` mesh paths point outside the
    package; ``romeo_small``, whose inertias break the triangle inequality; Cassie, SDF only)."""
    from .urdfgen import PLANAR_MODELS

    return [*PLANAR_MODELS, *LIBRARY]
