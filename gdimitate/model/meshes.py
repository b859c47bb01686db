"""Mesh files: which ones a URDF may open (confinement), and Collada facts shared by the
geometry users (sole measurement, viewer).

Confinement: :func:`confine_meshes` resolves every mesh and texture reference of a URDF
(``package://``, ``file://``, relative and absolute names, symlinks followed) and refuses any
that lands outside the URDF's own folder and the declared package directories, before
Pinocchio parses the file; the accepted references are rewritten to absolute paths, so the
loader opens exactly the checked files (it would otherwise also search ``ROS_PACKAGE_PATH``).

Collada files may declare ``<up_axis>Y_UP</up_axis>``. URDF authors place such meshes with
``<origin rpy=…>`` written for the file's raw vertices, but Pinocchio's loader (assimp) turns
Y-up Collada vertices to z-up first, so the vertices Pinocchio holds are rotated against what
the URDF meant (iCub's feet: a sole 0.16 m long ends up along y). :data:`ASSIMP_Y_UP_UNDO`
maps Pinocchio's vertices of such a file back to the raw ones (checked on iCub: the corrected
foot is 0.156 m long along x and 0.060 m wide, flat on the sole frame).
"""

from __future__ import annotations

import functools
import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

__all__ = ["ASSIMP_Y_UP_UNDO", "MeshReference", "collada_y_up", "confine_meshes",
           "resolve_mesh"]

#: Rotation taking Pinocchio's (assimp-turned) vertices of a Y_UP Collada file back to the
#: file's raw coordinates: (x, y, z) → (x, −z, y).
ASSIMP_Y_UP_UNDO = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@functools.lru_cache(maxsize=256)
def collada_y_up(path: str) -> bool:
    """Whether ``path`` is a Collada (``.dae``) file that declares ``<up_axis>Y_UP``."""
    if Path(path).suffix.lower() != ".dae" or not Path(path).is_file():
        return False
    with open(path, encoding="utf-8", errors="replace") as f:
        head = f.read(4096)
    return "<up_axis>Y_UP</up_axis>" in head.replace(" ", "")


# ---------------------------------------------------------------------------------- confinement
#: URDF elements whose ``filename`` attribute makes a loader open a file.
MESH_TAGS = ("mesh", "texture")
#: The package name example-robot-data's URDFs use (``package://example-robot-data/...``).
ERD_PACKAGE = "example-robot-data"


class MeshReference(NamedTuple):
    """One file a URDF asks a loader to open: ``link`` (name of the link holding it),
    ``tag`` (``mesh`` or ``texture``), ``filename`` (as written) and ``path`` (resolved,
    absolute, symlinks followed)."""

    link: str
    tag: str
    filename: str
    path: Path


def _erd_package_dir() -> Path | None:
    from ..errors import URDFError
    from .library import erd_robots_dir

    try:
        return erd_robots_dir().parent.parent
    except URDFError:
        return None


def resolve_mesh(filename: str, urdf_dir: Path, package_dirs: Sequence[Path]
                 ) -> tuple[Path, list[Path]]:
    """Where a URDF ``filename`` points, and the folders it may point into.

    ``package://NAME/REST`` (and ``model://``) → ``<dir>/NAME/REST`` in the first declared
    package directory holding it (example-robot-data's own folder as a last resort for
    ``NAME = example-robot-data``); ``file://P`` and plain names → ``P`` (relative to
    ``urdf_dir`` if relative). Returns ``(path, allowed_roots)``; nothing is opened.

    Raises:
        MeshPathError: another URL scheme.
    """
    from ..errors import MeshPathError

    roots = [urdf_dir, *package_dirs]
    scheme, sep, rest = filename.partition("://")
    if not sep:
        scheme, rest = "", filename
    scheme = scheme.lower()
    if scheme in ("package", "model"):
        rest = rest.lstrip("/")  # package:///NAME/... (Talos full v2) reads as package://NAME/
        name = rest.split("/", 1)[0]
        dirs = list(package_dirs)
        if name == ERD_PACKAGE:
            erd = _erd_package_dir()
            if erd is not None:
                dirs.append(erd)
                roots.append(erd / ERD_PACKAGE)
        cands = [Path(d) / rest for d in dirs] or [urdf_dir / rest]
        path = next((c for c in cands if c.exists()), cands[0])
    elif scheme in ("file", ""):
        path = Path(rest)
        if not path.is_absolute():  # the URDF's folder, then (as Pinocchio) the package dirs
            cands = [urdf_dir / path, *(Path(d) / path for d in package_dirs)]
            path = next((c for c in cands if c.exists()), cands[0])
    else:
        raise MeshPathError(f"mesh {filename!r}: URL scheme {scheme!r} is not supported "
                            "(use package://, file:// or a file name)")
    return Path(os.path.realpath(path)), [Path(os.path.realpath(r)) for r in roots]


def confine_meshes(root: ET.Element, urdf_path: Path, package_dirs: Sequence[Path]
                   ) -> list[MeshReference]:
    """Check every ``<mesh>``/``<texture>`` file of a parsed URDF ``root`` and point it at its
    resolved absolute path (``root`` is modified in place, so that Pinocchio opens exactly the
    files checked here and searches nowhere else).

    A reference must resolve inside the URDF's own folder or one of ``package_dirs``
    (example-robot-data's folder for ``package://example-robot-data/``) and the file must
    exist. Nothing is opened. Returns the references (a texture without a file name is skipped).

    Raises:
        MeshPathError: naming the link and the reference, for a path outside those folders
            (``package://../..``, an absolute path, ``file://`` elsewhere, a symlink out) or
            a missing file.
    """
    from ..errors import MeshPathError

    urdf_dir = Path(os.path.realpath(urdf_path.parent))
    owner = {c: p for p in root.iter() for c in p}
    refs: list[MeshReference] = []
    for el in root.iter():
        if el.tag not in MESH_TAGS:
            continue
        up: ET.Element | None = el
        while up is not None and up.tag != "link":
            up = owner.get(up)
        where = f"link {up.get('name')!r}" if up is not None else "a top-level material"
        filename = el.get("filename")
        if filename is None or not filename.strip():
            if el.tag == "mesh":
                raise MeshPathError(f"{urdf_path}: {where} has a <mesh> without a filename")
            continue
        shown = filename if len(filename) <= 200 else f"{filename[:200]}… ({len(filename):,} chars)"
        try:
            path, roots = resolve_mesh(filename.strip(), urdf_dir, package_dirs)
            found = path.is_file()
        except (OSError, ValueError) as e:  # a name too long for the file system, a NUL byte
            raise MeshPathError(f"{urdf_path}: {where}: {el.tag} {shown!r} cannot be looked up "
                                f"({getattr(e, 'strerror', None) or e}); give a valid file "
                                "name") from None
        if not any(path.is_relative_to(r) for r in roots):
            raise MeshPathError(
                f"{urdf_path}: {where}: {el.tag} {shown!r} resolves to {path}, outside the "
                f"folders a URDF may read ({', '.join(map(str, roots))}); move the file there "
                "or pass its package folder as package_dir=")
        if not found:
            raise MeshPathError(f"{urdf_path}: {where}: {el.tag} file {shown!r} not found "
                                f"(looked for {path})")
        el.set("filename", str(path))
        refs.append(MeshReference(str(up.get("name")) if up is not None else "", el.tag,
                                  filename, path))
    return refs
