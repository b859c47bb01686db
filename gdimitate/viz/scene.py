"""Static meshcat drawing: a robot's visual geometry, a ghost copy, ground, arrows, markers, lines.

Every geometry object of a Pinocchio ``GeometryModel`` becomes two meshcat nodes:
``<root>/<name>`` receives the object's *rigid* placement ``oMg`` (unscaled; this is what the
animation records) and its child ``<root>/<name>/s<k>`` holds the shape with a constant local
transform that carries ``meshScale`` (and the y→z turn of three.js cylinders). Folding a
mirrored scale (Talos's right leg, ``meshScale = (1, -1, 1)``) into the animated transform is
what scrambles Pinocchio's own recorder (docs/design.md §10); the constant child transform is
decomposed
correctly by three.js.

Robots without visual geometry can be drawn as a skeleton: :func:`skeleton_geometry` builds
spheres at the joints and rods between them.
"""

from __future__ import annotations

import functools
import io
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import coal
import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..errors import ViewerError
from ..model.meshes import collada_y_up
from .decimate import decimated_stl

__all__ = [
    "Style",
    "draw_arrow",
    "draw_geometry",
    "draw_ground",
    "draw_marker",
    "draw_polyline",
    "has_visuals",
    "material",
    "node_names",
    "shapes",
    "skeleton_geometry",
]

RGB = tuple[float, float, float]

# three.js cylinders run along local y; Pinocchio/coal cylinders along z: turn y into z.
_Y_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])


@dataclass(frozen=True)
class Style:
    """Colours (RGB in [0, 1]) and sizes of the decorations drawn around robots.

    Sizes of arrows and markers are fractions of each robot's leg length ``L`` (hip to sole in
    the neutral pose, 1 m when unknown), so a 0.3 m robot and a 1.8 m one look alike.

    Attributes:
        ground_color: colour of the ground slab (top face at z = 0).
        ground_margin: how far the ground extends beyond the robots [m].
        arrow_length, arrow_radius: force-direction arrow size [L]; the tip touches the sole.
        arrow_side_offset: arrows are moved this far sideways, away from the body (+y for the
            left foot, -y for the right), so that the leg does not hide them [L].
        arrow_colors: per leg name, the arrow's colour.
        com_radius, com_color: the centre-of-mass marker (a sphere) [L].
        path_colors: per leg name, the colour of the foot-path line.
        ghost_opacity: default opacity of a ghost copy.
    """

    ground_color: RGB = (0.78, 0.80, 0.82)
    ground_margin: float = 0.6
    arrow_length: float = 0.55
    arrow_radius: float = 0.014
    arrow_side_offset: float = 0.18
    arrow_colors: tuple[tuple[str, RGB], ...] = (("left", (0.9, 0.15, 0.1)),
                                                 ("right", (0.1, 0.45, 0.95)))
    com_radius: float = 0.045
    com_color: RGB = (0.95, 0.8, 0.05)
    path_colors: tuple[tuple[str, RGB], ...] = (("left", (0.85, 0.3, 0.1)),
                                                ("right", (0.15, 0.4, 0.85)))
    ghost_opacity: float = 0.35

    def arrow_color(self, leg: str) -> RGB:
        """Colour of ``leg``'s arrow (grey for a leg not listed)."""
        return dict(self.arrow_colors).get(leg, (0.4, 0.4, 0.4))

    def path_color(self, leg: str) -> RGB:
        """Colour of ``leg``'s foot path (grey for a leg not listed)."""
        return dict(self.path_colors).get(leg, (0.4, 0.4, 0.4))


def _hex(rgb: ArrayLike) -> int:
    r, g, b = (int(round(255 * min(max(float(c), 0.0), 1.0))) for c in np.ravel(rgb)[:3])
    return (r << 16) | (g << 8) | b


def material(rgb: ArrayLike, opacity: float = 1.0) -> mg.MeshPhongMaterial:
    """A Phong material of colour ``rgb`` (3 floats in [0, 1]) and ``opacity`` in [0, 1]."""
    opacity = float(opacity)
    if not 0.0 <= opacity <= 1.0:
        raise ViewerError(f"opacity must be in [0, 1], got {opacity}")
    if opacity < 1.0:
        # depthWrite off keeps a ghost from hiding what lies behind it.
        return mg.MeshPhongMaterial(color=_hex(rgb), transparent=True, opacity=opacity,
                                    depthWrite=False)
    return mg.MeshPhongMaterial(color=_hex(rgb))


#: Most triangles of one drawn mesh (:func:`gdimitate.viz.decimate.decimated_stl`): every
#: drawn mesh is embedded in a saved page, once per robot shown; G1's meshes at full detail
#: (14.5 MB of STL) made the demo's page 40 MB. At this budget a G1 takes ~1.2 MB of a page
#: (the viewer's own code ~1.4 MB) and its drawn surface stays within ~1 cm of the original
#: (95th percentile; 3.5 % of the torso's width at worst).
MAX_MESH_FACES = 500


@functools.lru_cache(maxsize=256)
def _mesh_file(path: str) -> mg.MeshGeometry:
    suffix = Path(path).suffix.lower()
    loaders = {".stl": mg.StlMeshGeometry, ".obj": mg.ObjMeshGeometry, ".dae": mg.DaeMeshGeometry}
    if suffix not in loaders:
        raise ViewerError(f"mesh format {suffix!r} of {path} is not supported; "
                          "valid formats: .stl, .obj, .dae")
    try:
        if suffix in (".stl", ".obj"):
            return mg.StlMeshGeometry.from_stream(io.BytesIO(decimated_stl(path,
                                                                           MAX_MESH_FACES)))
        return loaders[suffix].from_file(path)
    except (OSError, ValueError) as e:
        raise ViewerError(f"cannot read mesh {path}: {e}") from e


def shapes(obj: pin.GeometryObject) -> list[tuple[mg.Geometry, np.ndarray]]:
    """meshcat geometries of one Pinocchio geometry object, each with its constant local
    transform ``(4, 4)`` relative to the object's placement (``meshScale`` included).

    Primitives (box, cylinder, sphere, capsule, ellipsoid) come from the coal shape; anything
    else from the mesh file (``.stl``, ``.obj``, ``.dae``). Returns ``[]`` for a geometry that
    cannot be drawn.
    """
    g = obj.geometry
    scale = np.diag([*np.asarray(obj.meshScale, dtype=float).reshape(3), 1.0])
    if isinstance(g, coal.Box):
        return [(mg.Box(tuple(2.0 * np.asarray(g.halfSide))), scale)]
    if isinstance(g, coal.Cylinder):
        return [(mg.Cylinder(2.0 * g.halfLength, g.radius), scale @ _Y_TO_Z)]
    if isinstance(g, coal.Sphere):
        return [(mg.Sphere(g.radius), scale)]
    if isinstance(g, coal.Ellipsoid):
        return [(mg.Ellipsoid(np.asarray(g.radii)), scale)]
    if isinstance(g, coal.Capsule):
        parts: list[tuple[mg.Geometry, np.ndarray]] = [
            (mg.Cylinder(2.0 * g.halfLength, g.radius), scale @ _Y_TO_Z)]
        for sign in (-1.0, 1.0):
            end = np.eye(4)
            end[2, 3] = sign * g.halfLength
            parts.append((mg.Sphere(g.radius), scale @ end))
        return parts
    path = obj.meshPath
    if path and Path(path).suffix.lower() in (".stl", ".obj", ".dae") and Path(path).is_file():
        mesh = _mesh_file(str(Path(path).resolve()))
        if collada_y_up(str(Path(path).resolve())):
            return [(mesh, scale @ _Y_TO_Z)]
        return [(mesh, scale)]
    return []


def has_visuals(visual_model: pin.GeometryModel | None) -> bool:
    """Whether ``visual_model`` exists and holds at least one geometry object."""
    return visual_model is not None and visual_model.ngeoms > 0


def node_names(visual_model: pin.GeometryModel) -> list[str]:
    """meshcat node name of each geometry object, in ``geometryObjects`` order (unique, no
    ``/``)."""
    names = []
    for i, obj in enumerate(visual_model.geometryObjects):
        names.append(f"{i:03d}_{obj.name.replace('/', '_')}")
    return names


def draw_geometry(node: meshcat.Visualizer, visual_model: pin.GeometryModel,
                  color: Sequence[float] | None = None, opacity: float = 1.0) -> list[str]:
    """Draw every object of ``visual_model`` under ``node``; return the node name of each.

    Args:
        node: the meshcat node under which the robot goes (one child per geometry object).
        visual_model: Pinocchio visual geometry (mesh paths already absolute).
        color: one RGB colour for every part (e.g. a ghost), or ``None`` for the URDF colours.
        opacity: in [0, 1]; < 1 makes the parts translucent.

    Raises:
        ViewerError: if no object of the model can be drawn.
    """
    names = node_names(visual_model)
    drawn = 0
    for name, obj in zip(names, visual_model.geometryObjects, strict=True):
        rgba = np.asarray(obj.meshColor, dtype=float)
        rgb = rgba[:3] if color is None else np.asarray(color, dtype=float)
        alpha = float(opacity) * (float(rgba[3]) if color is None else 1.0)
        for k, (geometry, local) in enumerate(shapes(obj)):
            child = node[name][f"s{k}"]
            child.set_object(geometry, material(rgb, alpha))
            child.set_transform(local)
            drawn += 1
    if drawn == 0:
        raise ViewerError(
            "none of the robot's visual geometry objects can be drawn (no primitives, no "
            ".stl/.obj/.dae mesh files found); pass skeleton=True to draw joints and links"
        )
    return names


def skeleton_geometry(model: pin.Model, radius: float = 0.02,
                      color: Sequence[float] = (0.55, 0.55, 0.6)) -> pin.GeometryModel:
    """A stick-figure visual model for a robot without visual geometry.

    A sphere of ``radius`` [m] at every joint and a rod from each joint to each of its child
    joints (fixed to the parent joint, so it moves with it). Joints at the same place as their
    parent (e.g. a planar base's x/z/pitch chain) get no rod.
    """
    geom = pin.GeometryModel()
    rgba = np.array([*color[:3], 1.0])
    for j in range(1, model.njoints):
        ball = pin.GeometryObject(f"joint_{model.names[j]}", j, pin.SE3.Identity(),
                                  coal.Sphere(radius))
        ball.meshColor = rgba
        geom.addGeometryObject(ball)
        parent = model.parents[j]
        offset = np.asarray(model.jointPlacements[j].translation)
        length = float(np.linalg.norm(offset))
        if parent == 0 or length < 1e-6:
            continue
        rot = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), offset / length)
        place = pin.SE3(rot.toRotationMatrix(), offset / 2.0)
        rod = pin.GeometryObject(f"link_{model.names[parent]}_{model.names[j]}", parent,
                                 place, coal.Cylinder(0.6 * radius, length))
        rod.meshColor = rgba
        geom.addGeometryObject(rod)
    return geom


def draw_ground(node: meshcat.Visualizer, xy_min: ArrayLike, xy_max: ArrayLike,
                color: Sequence[float] = (0.78, 0.80, 0.82), thickness: float = 0.02) -> None:
    """A grey slab whose top face is the plane z = 0, covering ``[xy_min, xy_max]`` [m]."""
    lo, hi = np.asarray(xy_min, dtype=float), np.asarray(xy_max, dtype=float)
    size = np.maximum(hi - lo, 0.1)
    node.set_object(mg.Box((float(size[0]), float(size[1]), thickness)), material(color))
    T = np.eye(4)
    T[:2, 3] = (lo + hi) / 2.0
    T[2, 3] = -thickness / 2.0
    node.set_transform(T)


def draw_arrow(node: meshcat.Visualizer, length: float, radius: float,
               color: Sequence[float], opacity: float = 1.0) -> None:
    """An arrow along the node's local +z, tail at its origin, tip at ``(0, 0, length)`` [m]."""
    head = min(0.3 * length, 8.0 * radius)
    mat = material(color, opacity)
    shaft = node["shaft"]
    shaft.set_object(mg.Cylinder(length - head, radius), mat)
    T = _Y_TO_Z.copy()
    T[2, 3] = (length - head) / 2.0
    shaft.set_transform(T)
    tip = node["head"]
    tip.set_object(mg.Cylinder(head, radiusTop=0.0, radiusBottom=2.5 * radius), mat)
    T = _Y_TO_Z.copy()
    T[2, 3] = length - head / 2.0
    tip.set_transform(T)


def draw_marker(node: meshcat.Visualizer, radius: float, color: Sequence[float],
                opacity: float = 1.0) -> None:
    """A sphere of ``radius`` [m] at the node's origin."""
    node.set_object(mg.Sphere(radius), material(color, opacity))


def draw_polyline(node: meshcat.Visualizer, points: np.ndarray, color: Sequence[float],
                  linewidth: float = 2.0) -> None:
    """A line through ``points`` ``(N, 3)`` [m] (non-finite rows are dropped)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) < 2:
        return
    node.set_object(mg.Line(mg.PointsGeometry(pts.T.astype(np.float32)),
                            mg.LineBasicMaterial(color=_hex(color), linewidth=linewidth)))
