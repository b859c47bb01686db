"""Where a :class:`~gdimitate.Robot` comes from: a URDF, an OpenSim model, one of our planar
specs, a library name — and the dispatch on a name or a file's type (:func:`load`).

Each loader builds Pinocchio models from its source and hands them to the class it is given
(``cls``, :class:`~gdimitate.Robot` or a subclass), whose constructor detects and measures the
legs and soles. The ``Robot.from_urdf``/``from_osim``/``from_spec``/``from_library``/``load``
class methods are these functions with ``cls`` bound. This module imports
:mod:`gdimitate.model.robot` for type annotations only, so the model class does not depend on the
file formats it can be read from (OpenSim is imported when an ``.osim`` is loaded).
"""

from __future__ import annotations

import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

import pinocchio as pin

from ..errors import InvalidInputError, MeshPathError, UnknownRobotError, URDFError, URDFLimitError
from ..safety import MAX_URDF_BYTES, check_urdf_bounds, parse_xml, read_text_bounded
from ..types import SIDES
from .inputs import check_contacts, check_legs, path_arg
from .legs import LEG_PRESETS
from .library import LIBRARY, MASSLESS_PRESETS, library_entry, list_robots
from .meshes import confine_meshes
from .urdfcheck import (
    check_urdf_joints,
    check_urdf_physics,
    check_urdf_size,
    check_urdf_structure,
)
from .urdfgen import PLANAR_BASE, PLANAR_MODELS, PlanarBipedSpec, planar_biped_urdf

if TYPE_CHECKING:
    from .contact import SoleContact

__all__ = ["from_library", "from_osim", "from_spec", "from_urdf", "load", "read_urdf"]

LegNames = Mapping[str, Mapping[str, str | None]]
Contacts = Mapping[str, "SoleContact | Mapping"]


class Built(Protocol):
    """The class a loader is given (:class:`~gdimitate.Robot` or a subclass): its constructor's
    arguments and the attributes the loaders set. A protocol, so that this module does not
    import :mod:`.robot`, whose class methods are these loaders."""

    urdf_path: Path | None
    osim: Any
    spec: PlanarBipedSpec
    load_args: dict[str, Any]

    def __init__(self, name: str, model: pin.Model, visual_model: pin.GeometryModel | None,
                 legs: LegNames | None = None, package_dir: Path | None = None,
                 urdf_path: Path | None = None, contacts: Contacts | None = None,
                 collision_model: pin.GeometryModel | None = None) -> None: ...


#: the class a loader builds, and returns an instance of
R = TypeVar("R", bound=Built)


def _package_dirs(path: Path, package_dir: str | Path | Sequence[str | Path] | None
                  ) -> list[Path]:
    if package_dir is None:
        return [path.parent]
    if isinstance(package_dir, str | Path):
        return [path_arg("package_dir", package_dir)]
    if isinstance(package_dir, bytes) or not isinstance(package_dir, Sequence):
        raise InvalidInputError(f"package_dir must be a folder path or a list of them; got "
                                f"{type(package_dir).__name__} {package_dir!r:.80}")
    return [path_arg("package_dir", d) for d in package_dir]


def read_urdf(path: str | Path, *, package_dir: str | Path | Sequence[str | Path] | None = None,
              floating: bool | None = None, massless_joints: Iterable[str] = ()
              ) -> tuple[pin.Model, pin.GeometryModel, pin.GeometryModel, list[Path]]:
    """``(model, visual model, collision model, package dirs)`` of a URDF file, checked before
    Pinocchio reads it (size, link count and depth, inertial data, joints, mesh paths confined
    to the URDF's folder or a package directory: docs/security.md). ``floating``: add a
    free-flyer root (default: unless the URDF has our planar base joints).
    :class:`~gdimitate.errors.URDFError` (or a subclass) naming the file and what is wrong."""
    path = path_arg("path", path)
    if floating is not None and not isinstance(floating, bool):
        raise InvalidInputError(f"floating must be True, False or None; got {floating!r:.80}")
    massless_joints = _joint_names(massless_joints)
    try:
        if not path.is_file():
            raise URDFError(f"URDF file not found: {path}")
    except OSError as e:  # a name too long for the file system
        raise URDFError(f"cannot open URDF {str(path)[:200]}: {e.strerror or e}") from None
    root = parse_xml(read_text_bounded(path, MAX_URDF_BYTES, "URDF"), path)
    try:
        return _read_checked(path, root, package_dir, floating, massless_joints)
    except RecursionError:  # the stdlib serialiser recurses once per nesting level
        raise URDFLimitError(f"{path}: its XML elements are nested too deeply to process; "
                             "a URDF is nested a few levels deep (robot > link > visual > "
                             "geometry > box)") from None


def _read_checked(path: Path, root: ET.Element,
                  package_dir: str | Path | Sequence[str | Path] | None,
                  floating: bool | None, massless_joints: Iterable[str]
                  ) -> tuple[pin.Model, pin.GeometryModel, pin.GeometryModel, list[Path]]:
    check_urdf_bounds(root, path)
    check_urdf_size(root, path)
    check_urdf_structure(root, path)
    check_urdf_joints(root, path)
    check_urdf_physics(root, path, massless_joints)
    if floating is None:
        joints = {j.get("name") for j in root.findall("joint")}
        floating = not all(b in joints for b in PLANAR_BASE)
    pkgs = _package_dirs(path, package_dir)
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
    return model, geoms[0], geoms[1], pkgs


def from_urdf(cls: type[R], path: str | Path, legs: LegNames | None = None, *,
              name: str | None = None,
              package_dir: str | Path | Sequence[str | Path] | None = None,
              floating: bool | None = None, contacts: Contacts | None = None,
              massless_joints: Iterable[str] = ()) -> R:
    """:meth:`gdimitate.Robot.from_urdf` (its docstring): :func:`read_urdf`, then ``cls``.
    The arguments' types are checked first (:class:`InvalidInputError` naming the argument)."""
    path = path_arg("path", path)
    if name is not None and not isinstance(name, str):
        raise InvalidInputError(f"name must be a str; got {type(name).__name__} {name!r:.80}")
    check_legs(legs)
    check_contacts(contacts)
    model, visual, collision, pkgs = read_urdf(path, package_dir=package_dir,
                                               floating=floating,
                                               massless_joints=massless_joints)
    return cls(name or model.name or path.stem, model, visual, legs, pkgs[0] if pkgs else None,
               path, contacts=contacts, collision_model=collision)


def from_osim(cls: type[R], path: str | Path, *, name: str | None = None,
              markers: Any = None) -> R:
    """:meth:`gdimitate.Robot.from_osim` (its docstring): the model converted into a temporary
    folder by :func:`gdimitate.io.opensim.convert_osim`, loaded with its legs and sole boxes."""
    from .osim.urdf import convert_osim

    with tempfile.TemporaryDirectory(prefix="gdimitate_osim_") as tmp:
        conv = convert_osim(path, Path(tmp) / f"{Path(path).stem}.urdf", markers=markers)
        legs = {s: {k: conv.legs[s][k] for k in ("hip", "knee", "ankle", "sole")}
                for s in SIDES}
        contacts = {s: {"frame": conv.legs[s]["contact"], "half_length": conv.soles[s][0],
                        "half_width": conv.soles[s][1]} for s in SIDES}
        robot = from_urdf(cls, conv.urdf, legs, name=name or conv.model.name, floating=True,
                          contacts=contacts)
    robot.urdf_path = None  # the folder is gone: nothing is left in the temp directory
    robot.osim = conv
    return robot


def from_spec(cls: type[R], spec: PlanarBipedSpec) -> R:
    """:meth:`gdimitate.Robot.from_spec`: one of our planar bipeds from its spec (the same text
    ``urdf/`` holds)."""
    xml = planar_biped_urdf(spec)
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / f"{spec.name}.urdf"
        p.write_text(xml)
        model, collision, visual = pin.buildModelsFromUrdf(str(p), [tmp])
    robot = cls(spec.name, model, visual, collision_model=collision)
    robot.spec = spec
    return robot


def from_library(cls: type[R], name: str) -> R:
    """:meth:`gdimitate.Robot.from_library`: our planar models or an example-robot-data model
    with its presets (:data:`gdimitate.model.legs.LEG_PRESETS`,
    :data:`gdimitate.model.library.MASSLESS_PRESETS`)."""
    if not isinstance(name, str):
        raise InvalidInputError(f"robot name must be a str; got {type(name).__name__} "
                                f"{name!r:.80}; library names: {list_robots()}")
    if name in PLANAR_MODELS:
        return from_spec(cls, PLANAR_MODELS[name])
    if name not in LIBRARY:
        raise UnknownRobotError(name, list_robots())
    path, pkg = library_entry(name)
    return from_urdf(cls, path, LEG_PRESETS.get(name), name=name, package_dir=pkg,
                     floating=True, massless_joints=MASSLESS_PRESETS.get(name, ()))


def load(cls: type[R], spec: str | Path, *, package_dir: str | Path | None = None,
         contacts: Contacts | None = None, legs: LegNames | None = None,
         massless_joints: Iterable[str] = ()) -> R:
    """:meth:`gdimitate.Robot.load` (its docstring): a library name or a ``.urdf``/``.osim``
    path; the arguments kept as ``robot.load_args``."""
    if isinstance(spec, bytes) or not isinstance(spec, str | Path):
        raise InvalidInputError(f"robot spec must be a library name or a model file path (str "
                                f"or Path); got {type(spec).__name__} {spec!r:.80}")
    check_legs(legs)
    check_contacts(contacts)
    massless = _joint_names(massless_joints)
    robot = _dispatch(cls, str(spec), package_dir, contacts, legs, massless)
    robot.load_args = {"spec": str(spec), "package_dir": package_dir, "legs": legs,
                       "contacts": contacts, "massless_joints": massless}
    return robot


def _joint_names(names: Iterable[str]) -> tuple[str, ...]:
    """``massless_joints=`` checked: a list of joint names (not one str) → a tuple."""
    if isinstance(names, str | bytes) or not all(isinstance(j, str) for j in names):
        raise InvalidInputError("massless_joints must be a list of joint names (str); got "
                                f"{names!r:.80}")
    return tuple(names)


def _dispatch(cls: type[R], text: str, package_dir: str | Path | None,
              contacts: Contacts | None, legs: LegNames | None,
              massless: tuple[str, ...] = ()) -> R:
    p = Path(text).expanduser()
    if text in list_robots() and not p.suffix:
        if legs is None and contacts is None and package_dir is None and not massless:
            return from_library(cls, text)
        if text in PLANAR_MODELS:
            raise InvalidInputError(f"{text!r} is one of our planar models: it takes no "
                                    "legs=/contacts=/package_dir=/massless_joints=")
        path, pkg = library_entry(text)
        presets = MASSLESS_PRESETS.get(text, ())
        return from_urdf(cls, path, legs or LEG_PRESETS.get(text), name=text,
                         package_dir=package_dir or pkg, floating=True, contacts=contacts,
                         massless_joints=presets + tuple(j for j in massless
                                                         if j not in presets))
    suffix = p.suffix.lower()
    if suffix == ".urdf":
        return from_urdf(cls, p, legs, package_dir=package_dir, contacts=contacts,
                         massless_joints=massless)
    if suffix == ".osim":
        if legs is not None or contacts is not None or massless:
            raise InvalidInputError(f"{p}: an OpenSim model brings its own legs and soles and "
                                    "its bodies' masses; legs=/contacts=/massless_joints= are "
                                    "for URDFs")
        return from_osim(cls, p)
    if suffix:
        raise InvalidInputError(f"robot {text!r}: a model file must be .urdf or .osim; "
                                f"library names: {list_robots()}")
    raise UnknownRobotError(text, list_robots())
