"""gdimitate.model.symbolic checked against Pinocchio's own numbers.

Tolerance: kinematic quantities (positions, rotations, Jacobians, com and its acceleration)
agree to 1e-9 absolute; torques and momentum rates to 1e-9 relative to the largest entry of
Pinocchio's result (at least 1e-9 absolute), since Talos torques reach ~10³ N·m.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdimitate.errors import UnknownNameError, UnsupportedJointError
from gdimitate.model.library import library_entry
from gdimitate.model.symbolic import SUPPORTED_JOINTS, SymbolicModel

TOL = 1e-9
LIBRARY_ROBOTS = ["human", "talos", "g1", "icub", "bolt", "romeo"]
N_STATES = 5
N_FRAMES = 10


def _link(name: str, mass: float, length: float) -> str:
    i = mass * length**2 / 12
    return f"""
  <link name="{name}">
    <inertial><origin xyz="0 0 {-length / 2}"/><mass value="{mass}"/>
      <inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i / 10}"/></inertial>
  </link>"""


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, axis: str) -> str:
    limit = '<limit lower="-3" upper="3" effort="100" velocity="10"/>' if kind != "fixed" else ""
    ax = f'<axis xyz="{axis}"/>' if kind != "fixed" else ""
    return f"""
  <joint name="{name}" type="{kind}">
    <parent link="{parent}"/><child link="{child}"/><origin xyz="{xyz}"/>{ax}{limit}
  </joint>"""


def planar_biped_urdf() -> str:
    """A small planar biped: prismatic x, prismatic z, revolute pitch, then two legs with
    hip/knee/ankle about -y and a fixed sole frame below each ankle."""
    parts = ['<?xml version="1.0"?>\n<robot name="planar_biped">', '  <link name="world"/>',
             _link("base_x_link", 0.0, 0.0), _link("base_z_link", 0.0, 0.0),
             _link("torso", 30.0, 0.6),
             _joint("base_x", "prismatic", "world", "base_x_link", "0 0 0", "1 0 0"),
             _joint("base_z", "prismatic", "base_x_link", "base_z_link", "0 0 1", "0 0 1"),
             _joint("base_pitch", "revolute", "base_z_link", "torso", "0 0 0", "0 1 0")]
    for side, y in (("left", 0.1), ("right", -0.1)):
        parts += [
            _link(f"{side}_thigh", 7.0, 0.4), _link(f"{side}_shank", 3.0, 0.4),
            _link(f"{side}_foot", 1.0, 0.08), f'  <link name="{side}_sole"/>',
            _joint(f"{side}_hip", "revolute", "torso", f"{side}_thigh", f"0 {y} 0", "0 -1 0"),
            _joint(f"{side}_knee", "revolute", f"{side}_thigh", f"{side}_shank", "0 0 -0.4",
                   "0 -1 0"),
            _joint(f"{side}_ankle", "revolute", f"{side}_shank", f"{side}_foot", "0 0 -0.4",
                   "0 -1 0"),
            _joint(f"{side}_sole_joint", "fixed", f"{side}_foot", f"{side}_sole",
                   "0.03 0 -0.08", ""),
        ]
    parts.append("</robot>")
    return "\n".join(parts)


def _random_placement(rng: np.random.Generator) -> pin.SE3:
    return pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3) * 0.3)


def zoo_model(kinds: list[str], seed: int, root: str = "free") -> pin.Model:
    """A random tree with one joint of each type in ``kinds`` (after an optional root),
    random placements, random inertias and one frame per joint."""
    rng = np.random.default_rng(seed)
    makers = {
        "RX": pin.JointModelRX, "RY": pin.JointModelRY, "RZ": pin.JointModelRZ,
        "RUBX": pin.JointModelRUBX, "RUBY": pin.JointModelRUBY, "RUBZ": pin.JointModelRUBZ,
        "PX": pin.JointModelPX, "PY": pin.JointModelPY, "PZ": pin.JointModelPZ,
        "RU": lambda: pin.JointModelRevoluteUnaligned(_unit(rng)),
        "PU": lambda: pin.JointModelPrismaticUnaligned(_unit(rng)),
        "RUBU": pin.JointModelRevoluteUnboundedUnaligned,
        "planar": pin.JointModelPlanar, "free": pin.JointModelFreeFlyer,
        "spherical": pin.JointModelSpherical,
    }
    model = pin.Model()
    parents = [0]
    for k, kind in enumerate(([root] if root else []) + kinds):
        parent = parents[int(rng.integers(len(parents)))] if k > 1 else parents[-1]
        jid = model.addJoint(parent, makers[kind](), _random_placement(rng), f"j{k}_{kind}")
        model.appendBodyToJoint(jid, pin.Inertia.Random(), pin.SE3.Identity())
        model.addFrame(pin.Frame(f"f{k}", jid, 0, _random_placement(rng), pin.FrameType.OP_FRAME))
        parents.append(jid)
    return model


def _unit(rng: np.random.Generator) -> np.ndarray:
    x = rng.normal(size=3)
    return x / np.linalg.norm(x)


@functools.cache
def robot(name: str) -> tuple[pin.Model, SymbolicModel]:
    """(Pinocchio model, its SymbolicModel), built once per test session."""
    if name == "planar":
        model = pin.buildModelFromXML(planar_biped_urdf())
    elif name == "zoo":
        kinds = ["RX", "RY", "RZ", "RU", "RUBX", "RUBY", "RUBZ", "RUBU", "PX", "PY", "PZ",
                 "PU", "planar"]
        model = zoo_model(kinds, seed=7)
    else:
        path, _ = library_entry(name)
        model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    return model, SymbolicModel(model)


def random_state(model: pin.Model, rng: np.random.Generator):
    """Random (q, v, a): finite position bounds, a random unit quaternion for a free-flyer."""
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit  # +-inf or +-DBL_MAX if unset
    lo = np.where(np.abs(lo) < 1e6, lo, -1.0)
    hi = np.where(np.abs(hi) < 1e6, hi, 1.0)
    lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    q = pin.randomConfiguration(model, lo, hi)
    for jm in model.joints[1:]:
        if jm.shortname() == "JointModelFreeFlyer":
            q[jm.idx_q: jm.idx_q + 3] = rng.uniform(-1, 1, 3)
            quat = rng.normal(size=4)
            q[jm.idx_q + 3: jm.idx_q + 7] = quat / np.linalg.norm(quat)
    return q, rng.normal(size=model.nv), rng.normal(size=model.nv)


def _np(x) -> np.ndarray:
    return np.array(x, dtype=float)


def _sample_frames(name: str, sm: SymbolicModel) -> list[str]:
    names = list(sm.frame_names)
    idx = np.linspace(0, len(names) - 1, min(N_FRAMES, len(names))).round().astype(int)
    picked = {names[i] for i in idx} | set(CONTACTS[name])
    return sorted(picked)


CONTACTS = {
    "human": ("left_foot", "right_foot"), "talos": ("left_sole_link", "right_sole_link"),
    "g1": ("left_ankle_roll_link", "right_ankle_roll_link"), "icub": ("l_sole", "r_sole"),
    "bolt": ("FL_FOOT", "FR_FOOT"), "romeo": ("l_sole", "r_sole"),
    "planar": ("left_sole", "right_sole"), "zoo": ("f12", "f13"),
}


def _close_rel(got: np.ndarray, want: np.ndarray) -> float:
    """Error relative to max(1, |want|_inf); returns the absolute error for the report."""
    err = float(np.abs(got - want).max())
    assert err <= TOL * max(1.0, float(np.abs(want).max())), err
    return err


ALL_ROBOTS = [*LIBRARY_ROBOTS, "planar", "zoo"]


@pytest.mark.parametrize("name", ALL_ROBOTS)
def test_sizes_and_names(name: str) -> None:
    model, sm = robot(name)
    assert (sm.nq, sm.nv) == (model.nq, model.nv)
    assert sm.joint_names == tuple(model.names[1:])
    assert set(sm.frame_names) == {f.name for f in model.frames}
    assert sm.mass == pytest.approx(pin.computeTotalMass(model), rel=1e-12)
    np.testing.assert_array_equal(sm.gravity, model.gravity.linear)


@pytest.mark.parametrize("name", ALL_ROBOTS)
def test_frames_match_pinocchio(name: str) -> None:
    model, sm = robot(name)
    data = model.createData()
    rng = np.random.default_rng(1)
    frames = _sample_frames(name, sm)
    for _ in range(N_STATES):
        q, _, _ = random_state(model, rng)
        pin.framesForwardKinematics(model, data, q)
        pin.computeJointJacobians(model, data, q)
        for fn in frames:
            fid = model.getFrameId(fn)
            assert fid == sm.frame_id(fn)
            np.testing.assert_allclose(_np(sm.frame_position(fn)(q)).ravel(),
                                       data.oMf[fid].translation, rtol=0, atol=TOL)
            np.testing.assert_allclose(_np(sm.frame_rotation(fn)(q)), data.oMf[fid].rotation,
                                       rtol=0, atol=TOL)
            jac = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(_np(sm.frame_jacobian(fn)(q)), jac, rtol=0, atol=TOL)


@pytest.mark.parametrize("name", ALL_ROBOTS)
def test_root_placements_match_pinocchio(name: str) -> None:
    """``root_placement``: frames in the root joint's frame, Pinocchio's ``oMi[1]⁻¹ · oMf``
    (the world's placement where several joints hang from the universe), and free of the
    root's own coordinates."""
    model, sm = robot(name)
    data = model.createData()
    rng = np.random.default_rng(2)
    frames = _sample_frames(name, sm)
    one_root = [int(p) for p in model.parents[1:]].count(0) == 1
    for _ in range(N_STATES):
        q, _, _ = random_state(model, rng)
        pin.framesForwardKinematics(model, data, q)
        root = data.oMi[1] if one_root else pin.SE3.Identity()
        for fn in frames:
            want = root.actInv(data.oMf[model.getFrameId(fn)])
            R, p = sm.root_placement(fn)
            got = ca.Function("f", [sm.q], [R, p])(q)
            np.testing.assert_allclose(_np(got[0]), want.rotation, rtol=0, atol=TOL)
            np.testing.assert_allclose(_np(got[1]).ravel(), want.translation, rtol=0, atol=TOL)
    if one_root:
        jm = model.joints[1]
        below = [fn for fn in frames if model.frames[model.getFrameId(fn)].parentJoint > 1]
        R, p = sm.root_placement(below[-1])
        used = set(ca.jacobian(ca.vertcat(ca.vec(R), p), sm.q).sparsity().get_col())
        assert not used & set(range(jm.idx_q, jm.idx_q + jm.nq))


@pytest.mark.parametrize("name", ALL_ROBOTS)
def test_com_and_centroidal_match_pinocchio(name: str) -> None:
    model, sm = robot(name)
    data = model.createData()
    rng = np.random.default_rng(2)
    for _ in range(N_STATES):
        q, v, a = random_state(model, rng)
        pin.centerOfMass(model, data, q, v, a)
        np.testing.assert_allclose(_np(sm.com(q)).ravel(), data.com[0], rtol=0, atol=TOL)
        np.testing.assert_allclose(_np(sm.com_acceleration(q, v, a)).ravel(), data.acom[0],
                                   rtol=0, atol=TOL)
        pin.computeCentroidalMomentumTimeVariation(model, data, q, v, a)
        dhg = _np(sm.centroidal_momentum_rate(q, v, a)).ravel()
        _close_rel(dhg, data.dhg.vector)
        # linear momentum rate = m c_ddot (the contact forces sum to m (c_ddot - g))
        np.testing.assert_allclose(dhg[:3], sm.mass * data.acom[0],
                                   rtol=0, atol=TOL * max(1.0, sm.mass))


@pytest.mark.parametrize("name", ALL_ROBOTS)
def test_rnea_matches_pinocchio(name: str) -> None:
    model, sm = robot(name)
    data = model.createData()
    rng = np.random.default_rng(3)
    contacts = CONTACTS[name]
    rnea_c = sm.rnea_contact(contacts)
    for _ in range(N_STATES):
        q, v, a = random_state(model, rng)
        tau = pin.rnea(model, data, q, v, a)
        _close_rel(_np(sm.rnea(q, v, a)).ravel(), tau)
        # contact wrenches at frame origins, world axes -> Pinocchio's joint-local fext
        wrenches = [rng.normal(size=6) * 100 for _ in contacts]
        pin.framesForwardKinematics(model, data, q)
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        tau_jt = _np(sm.rnea(q, v, a)).ravel()
        for fn, w in zip(contacts, wrenches, strict=True):
            fr = model.frames[model.getFrameId(fn)]
            p = data.oMf[model.getFrameId(fn)].translation
            world = pin.Force(w[:3], w[3:] + np.cross(p, w[:3]))
            fext[fr.parentJoint] += data.oMi[fr.parentJoint].actInv(world)
            tau_jt -= _np(sm.frame_jacobian(fn)(q)).T @ w
        want = pin.rnea(model, data, q, v, a, fext)
        got = _np(rnea_c(q, v, a, *wrenches)).ravel()
        _close_rel(got, want)
        _close_rel(tau_jt, want)


def test_planar_biped_structure() -> None:
    model, sm = robot("planar")
    assert sm.joint_names[:3] == ("base_x", "base_z", "base_pitch")
    q = np.zeros(sm.nq)
    q[0], q[1] = 0.3, 0.05
    sole = _np(sm.frame_position("left_sole")(q)).ravel()
    np.testing.assert_allclose(sole, [0.3 + 0.03, 0.1, 1.05 - 0.8 - 0.08], atol=1e-12)
    # standing still: the net contact force carries the weight
    dhg = _np(sm.centroidal_momentum_rate(q, np.zeros(sm.nv), np.zeros(sm.nv))).ravel()
    np.testing.assert_allclose(dhg, 0, atol=1e-12)
    acom = _np(sm.com_acceleration(q, np.zeros(sm.nv), np.zeros(sm.nv))).ravel()
    np.testing.assert_allclose(sm.mass * (acom - sm.gravity), [0, 0, 9.81 * sm.mass])


def test_functions_accept_symbols() -> None:
    """The optimiser calls the Functions on its own SX/MX variables."""
    _, sm = robot("planar")
    for sym in (ca.SX, ca.MX):
        q, v, a = sym.sym("q", sm.nq), sym.sym("v", sm.nv), sym.sym("a", sm.nv)
        tau = sm.rnea(q, v, a)
        assert tau.shape == (sm.nv, 1)
        assert sm.frame_jacobian("right_sole")(q).shape == (6, sm.nv)
        assert sm.frame_rotation("right_sole")(q).shape == (3, 3)


@settings(max_examples=40, deadline=None)
@given(kinds=st.lists(st.sampled_from(["RX", "RY", "RZ", "RU", "RUBX", "RUBY", "RUBZ", "RUBU",
                                        "PX", "PY", "PZ", "PU", "planar", "free"]),
                      min_size=1, max_size=6),
       root=st.sampled_from(["free", "planar", ""]), seed=st.integers(0, 2**16))
def test_random_trees_match_pinocchio(kinds: list[str], root: str, seed: int) -> None:
    model = zoo_model(kinds, seed, root)
    sm = SymbolicModel(model)
    data = model.createData()
    rng = np.random.default_rng(seed)
    q, v, a = random_state(model, rng)
    _close_rel(_np(sm.rnea(q, v, a)).ravel(), pin.rnea(model, data, q, v, a))
    pin.computeJointJacobians(model, data, q)
    pin.framesForwardKinematics(model, data, q)
    fn = sm.frame_names[-1]
    jac = pin.getFrameJacobian(model, data, model.getFrameId(fn), pin.LOCAL_WORLD_ALIGNED)
    jac = np.reshape(jac, (6, model.nv))  # pin squeezes nv == 1
    np.testing.assert_allclose(_np(sm.frame_jacobian(fn)(q)), jac, rtol=0, atol=TOL)
    pin.centerOfMass(model, data, q, v, a)
    np.testing.assert_allclose(_np(sm.com_acceleration(q, v, a)).ravel(), data.acom[0],
                               rtol=0, atol=TOL)


@pytest.mark.parametrize("kind", ["spherical"])
def test_unsupported_joint_raises(kind: str) -> None:
    model = zoo_model(["RX", kind], seed=0)
    with pytest.raises(UnsupportedJointError, match="JointModelSpherical") as err:
        SymbolicModel(model)
    assert "j2_spherical" in str(err.value)
    assert "JointModelRX" in str(err.value)  # lists what is supported
    assert "JointModelSpherical" not in SUPPORTED_JOINTS


def test_unsupported_composite_and_mimic() -> None:
    model = pin.Model()
    comp = pin.JointModelComposite(pin.JointModelRX())
    comp.addJoint(pin.JointModelRY())
    model.addJoint(0, comp, pin.SE3.Identity(), "comp")
    with pytest.raises(UnsupportedJointError, match="comp.*JointModelComposite"):
        SymbolicModel(model)
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRX(), pin.SE3.Identity(), "leader")
    model.addJoint(j1, pin.JointModelMimic(model.joints[j1], 2.0, 0.1), pin.SE3.Identity(),
                   "follower")
    with pytest.raises(UnsupportedJointError, match="follower.*JointModelMimic"):
        SymbolicModel(model)


def test_unknown_frame_raises() -> None:
    _, sm = robot("planar")
    for call in (sm.frame_position, sm.frame_rotation, sm.frame_jacobian,
                 lambda n: sm.rnea_contact(["left_sole", n])):
        with pytest.raises(UnknownNameError) as err:
            call("left_toe")
        assert err.value.kind == "frame"
        assert "left_sole" in err.value.valid
        assert "left_toe" in str(err.value) and "'right_sole'" in str(err.value)
    with pytest.raises(KeyError):  # UnknownNameError is also a KeyError
        sm.frame_position("nope")


def test_functions_are_cached() -> None:
    _, sm = robot("planar")
    assert sm.frame_position("left_sole") is sm.frame_position("left_sole")
    assert sm.rnea_contact(["left_sole"]) is sm.rnea_contact(("left_sole",))
