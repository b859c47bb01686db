"""Self-collision geometry placed as the URDF means it, and which bodies are neighbours
(gdimitate.model.selfcollision, issue 17).

iCub's collision meshes are Collada files that declare ``<up_axis>Y_UP</up_axis>``; its URDF's
``<collision><origin>`` is written for the file's vertices turned to z-up by the COLLADA
rule (y → z, z → −y). Pinocchio's loader keeps the raw vertices, so as loaded every iCub
link's mesh lay 90° off its link (thighs horizontal, the chest in front of the torso, feet
across the legs) and the self-collision pairs, the audit's check and the adaptor's sphere
rows measured shapes the robot does not have. The checks here re-derive the geometry without
gdimitate: the Collada file read with ElementTree, the URDF's collision origin, Pinocchio's
link frames, coal's distances. Neighbours: a chain of joints turning about one point (a ball
joint written as single-axis joints) counts as one joint, checked against Pinocchio's joint
origins at random configurations and coal's mesh contact.
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.model.selfcollision import self_collision
from tests.helpers import shared

#: The COLLADA specification's change of axes from a Y_UP asset to a Z_UP world:
#: right +x stays x, up +y becomes z, "in" +z becomes −y.
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def _robot(name: str) -> gd.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return shared.library_robot(name)


def _collada_positions(path: str) -> tuple[np.ndarray, str]:
    """The raw vertex positions ``(n, 3)`` of a Collada file's first mesh and its up axis,
    read with ElementTree (no transform node: iCub's files have none)."""
    root = ET.parse(path).getroot()
    ns = {"c": root.tag.split("}")[0].strip("{")}
    assert root.find(".//c:node/c:matrix", ns) is None
    up = root.find(".//c:asset/c:up_axis", ns)
    mesh = root.find(".//c:mesh", ns)
    src = mesh.find("c:vertices/c:input[@semantic='POSITION']", ns).get("source").lstrip("#")
    arr = mesh.find(f"c:source[@id='{src}']/c:float_array", ns)
    return np.array(arr.text.split(), float).reshape(-1, 3), up.text.strip()


def _apply(M: pin.SE3, points: np.ndarray) -> np.ndarray:
    """``points`` ``(n, 3)`` mapped by the rigid transform ``M``."""
    return points @ M.rotation.T + M.translation


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    """The symmetric Hausdorff distance [m] between two point sets (the loader may reorder
    or merge a file's vertices)."""
    d = np.linalg.norm(a[:, None] - b[None], axis=2)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def _urdf_collision_origins(path) -> dict[str, tuple[np.ndarray, np.ndarray, str]]:
    """``{link: (xyz, rotation, mesh file name)}`` of each link's (single) collision mesh."""
    out = {}
    for link in ET.parse(path).getroot().iter("link"):
        col = link.find("collision")
        if col is None or col.find("geometry/mesh") is None:
            continue
        o = col.find("origin")
        xyz = np.array((o.get("xyz") if o is not None else "0 0 0").split(), float)
        rpy = np.array((o.get("rpy") if o is not None else "0 0 0").split(), float)
        out[link.get("name")] = (xyz, pin.rpy.rpyToMatrix(*rpy),
                                 col.find("geometry/mesh").get("filename").rsplit("/", 1)[1])
    return out


def test_icub_meshes_sit_where_the_urdf_and_collada_put_them():
    """Every iCub collision mesh as the self-collision check places it (its geometry model's
    placement applied to the vertices Pinocchio loaded), at the neutral pose, equals the
    Collada file's raw vertices turned to z-up by the COLLADA rule, placed by the URDF's
    collision origin on Pinocchio's link frame — the same point sets to 1e-6 m (the loader
    keeps single precision: 5e-9 m seen), all 28 meshes. As loaded (without the turn) they
    are centimetres off (the thighs: 0.25 m)."""
    robot = _robot("icub")
    sc = self_collision(robot)
    model, data = robot.model, robot.model.createData()
    pin.framesForwardKinematics(model, data, robot.neutral)
    origins = _urdf_collision_origins(robot.urdf_path)
    placed = 0
    for i, g in enumerate(robot.collision_model.geometryObjects):
        link = model.frames[g.parentFrame].name
        xyz, R, fname = origins[link]
        assert g.meshPath.endswith(fname)
        raw, up = _collada_positions(g.meshPath)
        assert up == "Y_UP"
        ref = _apply(data.oMf[g.parentFrame], (xyz[:, None] + R @ Y_UP_TO_Z_UP @ raw.T).T)
        loaded = np.asarray(g.geometry.vertices())
        ours = _apply(data.oMi[g.parentJoint] * sc.geometry.geometryObjects[i].placement, loaded)
        assert _gap(ours, ref) <= 1e-6, g.name  # assimp keeps single precision
        as_loaded = _apply(data.oMi[g.parentJoint] * g.placement, loaded)
        if np.abs(raw).max() > 0.05:  # a mesh larger than 5 cm: turning it moves it
            assert _gap(as_loaded, ref) > 0.02, g.name
        placed += 1
    assert placed == 28


@pytest.mark.parametrize("name", ["talos", "g1", "romeo", "icub"])
def test_each_thigh_hull_spans_its_hip_and_knee(name):
    """Model-relative sanity of the placed geometry on every library humanoid: each leg's
    thigh (the collision geometry on the knee's parent joint) holds the hip and knee joint
    origins — Pinocchio's kinematics — inside its convex hull or within 1 cm of it (coal's
    signed point distance). Measured: knee 2.3–2.9 cm inside on all four; iCub's loaded
    (unturned) thigh left the knee 16–18 cm outside."""
    import coal

    robot = _robot(name)
    sc = self_collision(robot)
    model, data = robot.model, robot.model.createData()
    pin.forwardKinematics(model, data, robot.neutral)
    for side, leg in robot.legs.items():
        knee = model.getJointId(leg.knee)
        thigh = model.parents[knee]
        for j in (thigh, knee):
            p = data.oMi[j].translation
            d = []
            for g in sc.geometry.geometryObjects:
                if g.parentJoint != thigh:
                    continue
                M = data.oMi[thigh] * g.placement
                res = coal.DistanceResult()
                coal.distance(g.geometry, coal.Transform3s(M.rotation, M.translation),
                              coal.Sphere(1e-9), coal.Transform3s(np.eye(3), p),
                              coal.DistanceRequest(), res)
                d.append(res.min_distance)
            assert d and min(d) <= 0.01, (side, model.names[j], d)


# ------------------------------------------------------------------ neighbours through a ball
@pytest.mark.parametrize("name", ["talos", "g1", "romeo", "icub"])
def test_a_chain_of_joints_at_one_point_is_one_joint(name):
    """The neighbour rule's balls against Pinocchio's kinematics at 20 random configurations
    (every joint uniform within its limits):
    joints the rule puts in one ball have the same world origin (1e-9 m) at every one, and
    each child joint whose origin stays on its parent's at every one is in its parent's
    ball."""
    from gdimitate.model.selfcollision import _balls

    robot = _robot(name)
    model, data = robot.model, robot.model.createData()
    ball = _balls(model)
    rng = np.random.default_rng(0)
    lo, hi = model.lowerPositionLimit[7:], model.upperPositionLimit[7:]
    same = np.ones(model.njoints, bool)
    for _ in range(20):
        q = robot.neutral.copy()  # the free-flyer root at neutral, every joint within limits
        q[7:] = rng.uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi))
        pin.forwardKinematics(model, data, q)
        for j in range(2, model.njoints):
            p = model.parents[j]
            gap = np.linalg.norm(data.oMi[j].translation - data.oMi[p].translation)
            same[j] &= bool(gap < 1e-9)
            if ball[j] == ball[p]:
                assert gap < 1e-9, (model.names[j], gap)
    for j in range(2, model.njoints):
        if same[j] and model.parents[j] > 1:
            assert ball[j] == ball[model.parents[j]], model.names[j]


def test_icubs_thigh_and_root_link_are_neighbours_whose_meshes_touch():
    """iCub's thigh hangs from its root link by a three-axis hip at one point: the pair is
    left out as neighbours (distance NaN in :attr:`SelfCollision.excluded`), and rightly —
    coal finds the two meshes themselves (not only their hulls) in contact from 0.4 rad of hip
    extension with no hip roll; the hulls, 0.5 mm apart at the neutral pose, overlap already
    at 0.4 rad of flexion (1.4 mm; the meshes 5.7 mm apart there) — the hip's own clearance,
    not a collision a motion could avoid."""
    import coal

    from gdimitate.model.selfcollision import placement

    robot = _robot("icub")
    sc = self_collision(robot)
    pairs = {(a, b) for a, b, d in sc.excluded if np.isnan(d)}
    assert {("root_link_0", "l_upper_leg_0"), ("root_link_0", "r_upper_leg_0"),
            ("l_hip_1_0", "torso_1_0")} <= pairs
    assert not pairs & set(sc.pairs)
    model, cm = robot.model, robot.collision_model
    a, b = (cm.geometryObjects[cm.getGeometryId(n)] for n in ("root_link_0", "l_upper_leg_0"))
    for pitch in (-0.4, -0.5):  # iCub's hip pitch: positive flexes
        q = robot.neutral.copy()
        q[model.joints[model.getJointId("l_hip_pitch")].idx_q] = pitch
        data = model.createData()
        pin.forwardKinematics(model, data, q)
        T = [data.oMi[g.parentJoint] * placement(g) for g in (a, b)]
        res = coal.CollisionResult()
        coal.collide(a.geometry, coal.Transform3s(T[0].rotation, T[0].translation), b.geometry,
                     coal.Transform3s(T[1].rotation, T[1].translation),
                     coal.CollisionRequest(), res)
        assert res.isCollision(), pitch
