"""Robots: our generated URDFs, library models, measured legs, bad input."""

import functools

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

import gdimitate
from gdimitate import LegDetectionError, UnknownNameError, UnknownRobotError, URDFError
from gdimitate.model.kinematics import frame_paths, joint_paths
from gdimitate.model.library import library_entry
from gdimitate.model.robot import Robot
from gdimitate.model.sagittal import compose_q, leg_angles
from gdimitate.model.urdfgen import PLANAR_MODELS, planar_biped_urdf
from tests.helpers import ROOT

LIBRARY = ["human", "talos", "romeo", "icub", "g1", "bolt"]


@pytest.mark.parametrize("name", list(PLANAR_MODELS))
def test_committed_urdf_matches_generator(name):
    committed = (ROOT / "urdf" / f"{name}.urdf").read_text()
    assert committed == planar_biped_urdf(PLANAR_MODELS[name]), (
        f"urdf/{name}.urdf differs from the generator: run "
        "`python -m gdimitate.model.urdfgen urdf`")


@pytest.mark.parametrize("name", list(PLANAR_MODELS))
def test_planar_model_lengths_mass_and_fk_against_pinocchio(name, robot):
    r = robot(name)
    spec = PLANAR_MODELS[name]
    assert r.mass == pytest.approx(spec.mass, rel=1e-12)  # Pinocchio's total mass
    for leg in r.legs.values():
        assert (leg.thigh, leg.shank, leg.foot) == pytest.approx(
            (spec.thigh, spec.shank, spec.foot), abs=1e-12)
    # docs/design.md §4 closed-form FK vs Pinocchio FK at random planar angles
    rng = np.random.default_rng(0)
    T = 20
    torso = rng.uniform(-0.3, 0.3, T)
    angles = {s: np.column_stack([rng.uniform(-0.8, 0.8, T), rng.uniform(-1.5, 0, T),
                                  rng.uniform(-0.5, 0.5, T)]) for s in ("left", "right")}
    q = compose_q(r, torso, angles)
    for s in ("left", "right"):
        leg = r.legs[s]
        hip = joint_paths(r, q, [leg.hip])[leg.hip][:, [0, 2]]
        knee = joint_paths(r, q, [leg.knee])[leg.knee][:, [0, 2]]
        ankle = joint_paths(r, q, [leg.ankle])[leg.ankle][:, [0, 2]]
        sole = frame_paths(r, q, [leg.sole])[leg.sole][:, [0, 2]]
        t1, t2, t3 = angles[s].T
        exp_knee = hip + spec.thigh * np.column_stack([np.sin(t1), -np.cos(t1)])
        exp_ankle = exp_knee + spec.shank * np.column_stack([np.sin(t1 + t2), -np.cos(t1 + t2)])
        foot = t1 + t2 + t3  # foot's absolute angle; sole is 'foot' below the ankle in the foot
        exp_sole = exp_ankle + spec.foot * np.column_stack([np.sin(foot), -np.cos(foot)])
        np.testing.assert_allclose(knee, exp_knee, atol=1e-12)
        np.testing.assert_allclose(ankle, exp_ankle, atol=1e-12)
        np.testing.assert_allclose(sole, exp_sole, atol=1e-12)
    # and the planar angles read back
    torso2, angles2 = leg_angles(r, q)
    np.testing.assert_allclose(torso2, torso, atol=1e-14)
    for s in angles:
        np.testing.assert_allclose(angles2[s], angles[s], atol=1e-14)


@pytest.mark.parametrize("name", LIBRARY)
def test_library_segment_lengths_against_yourdfpy(name, robot):
    """Thigh/shank measured by Robot (Pinocchio) vs the same joint origins from yourdfpy's
    independent URDF forward kinematics, projected onto the sagittal plane."""
    r = robot(name)
    path, _ = library_entry(name)
    u = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False,
                           build_collision_scene_graph=False, load_collision_meshes=False)

    def origin(joint):
        return u.get_transform(u.joint_map[joint].child, u.base_link)[:3, 3]

    lat = origin(r.legs["left"].hip) - origin(r.legs["right"].hip)
    lat /= np.linalg.norm(lat)
    for leg in r.legs.values():
        ends = [origin(leg.hip), origin(leg.knee)]
        if leg.ankle:
            ends.append(origin(leg.ankle))
        else:
            sole_link = leg.sole
            ends.append(u.get_transform(sole_link, u.base_link)[:3, 3])

        def sag(v):
            return np.linalg.norm(v - (v @ lat) * lat)

        assert leg.thigh == pytest.approx(sag(ends[1] - ends[0]), abs=1e-9)
        assert leg.shank == pytest.approx(sag(ends[2] - ends[1]), abs=1e-9)
        assert 0.1 < leg.thigh < 0.6 and 0.1 < leg.shank < 0.6


def test_known_lengths_and_masses(robot):
    # Talos: hip pitch → knee 0.38 m, knee → ankle 0.325 m, ankle → sole 0.107 m (URDF)
    talos = robot("talos")
    assert (talos.legs["left"].thigh, talos.legs["left"].shank, talos.legs["left"].foot) == \
        pytest.approx((0.38, 0.325, 0.107), abs=1e-9)
    m = pin.buildModelFromUrdf(str(library_entry("talos")[0]), pin.JointModelFreeFlyer())
    assert talos.mass == pytest.approx(pin.computeTotalMass(m), rel=1e-12)
    assert robot("bolt").legs["left"].ankle is None


@pytest.mark.parametrize("name", LIBRARY + ["hoap2"])
def test_neutral_pose_stands_on_ground_facing_forward(name, robot):
    r = robot(name)
    soles = frame_paths(r, r.neutral[None], [r.legs[s].sole for s in ("left", "right")])
    zl, zr = (soles[r.legs[s].sole][0, 2] for s in ("left", "right"))
    # the neutral pose stands on the measured soles (tests/model/test_contact.py checks those at
    # z = 0 to 1e-5); the URDFs' own sole frames sit within 1.2 mm of that geometry
    assert min(zl, zr) == pytest.approx(0.0, abs=1.5e-3 if r.contacts else 1e-12)
    hips = joint_paths(r, r.neutral[None], [r.legs[s].hip for s in ("left", "right")])
    left, right = (hips[r.legs[s].hip][0] for s in ("left", "right"))
    assert left[1] - right[1] > 0.05  # left hip on +y
    assert left[2] > zl + 0.3 * r.legs["left"].length  # hips above the feet (z up)
    # a positive planar thigh angle moves the knee forward (+x)
    torso, angles = leg_angles(r, r.neutral[None])
    angles["left"][0, 0] += 0.3
    q = compose_q(r, torso, angles, template=r.neutral)
    knee0 = joint_paths(r, r.neutral[None], [r.legs["left"].knee])[r.legs["left"].knee][0]
    knee1 = joint_paths(r, q, [r.legs["left"].knee])[r.legs["left"].knee][0]
    assert knee1[0] - knee0[0] > 0.05 * r.legs["left"].thigh


def test_list_robots():
    names = gdimitate.list_robots()
    for n in ["human", "talos", "romeo", "icub", "g1", "bolt", "hoap2", "case1_demonstrator"]:
        assert n in names


def test_unknown_robot_lists_names():
    with pytest.raises(UnknownRobotError, match="talos") as e:
        Robot.from_library("tallos")
    assert "hoap2" in str(e.value)


def test_missing_and_malformed_urdf(tmp_path):
    with pytest.raises(URDFError, match="not found"):
        Robot.from_urdf(tmp_path / "nope.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot")
    with pytest.raises(URDFError, match="cannot read"):
        Robot.from_urdf(bad)


def _two_leg_urdf(names):
    joints = []
    links = ['<link name="base"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" '
             'iyy="1" iyz="0" izz="1"/></inertial></link>']
    for side, y in (("a", 0.1), ("b", -0.1)):
        parent = "base"
        for k, n in enumerate(names):
            child = f"{side}{n}_link"
            z = 0 if k == 0 else -0.3
            joints.append(f'<joint name="{side}{n}" type="revolute"><parent link="{parent}"/>'
                          f'<child link="{child}"/><origin xyz="0 {y if k == 0 else 0} {z}"/>'
                          '<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" '
                          'velocity="1"/></joint>')
            links.append(f'<link name="{child}"><inertial><mass value="1"/><inertia ixx="1" '
                         'ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>')
            parent = child
    return f'<robot name="x">{"".join(links)}{"".join(joints)}</robot>'


def test_undetectable_legs_say_what_was_tried(tmp_path):
    p = tmp_path / "x.urdf"
    p.write_text(_two_leg_urdf(["j1", "j2", "j3"]))
    with pytest.raises(LegDetectionError, match="hip.*legs=") as e:
        Robot.from_urdf(p)
    assert "aj1" in str(e.value)  # lists the joints it saw
    # explicit legs work
    legs = {"left": {"hip": "aj1", "knee": "aj2", "ankle": "aj3", "sole": "aj3_link"},
            "right": {"hip": "bj1", "knee": "bj2", "ankle": "bj3", "sole": "bj3_link"}}
    r = Robot.from_urdf(p, legs=legs)
    assert r.legs["left"].thigh == pytest.approx(0.3)
    with pytest.raises(UnknownNameError, match="valid joints"):
        Robot.from_urdf(p, legs={**legs, "left": {**legs["left"], "knee": "nope"}})


@pytest.mark.parametrize("name", ["human", "g1"])
def test_sole_at_the_bottom_of_the_foot_mesh(name, robot):
    """Models without a sole frame under the ankle get one at the foot mesh's lowest point: at
    the grounded neutral pose the lowest vertex of the foot mesh (read with trimesh, placed by
    Pinocchio's geometry placements) touches z = 0 (1 mm)."""
    import trimesh

    r = robot(name)
    assert r.legs["left"].sole == "left_sole_auto"
    gm = r.visual_model
    gd = pin.GeometryData(gm)
    pin.forwardKinematics(r.model, r.data, r.neutral)
    pin.updateGeometryPlacements(r.model, r.data, gm, gd)
    sole_joint = r.model.frames[r.frame_id(r.legs["left"].sole)].parentJoint
    lows = []
    for i, g in enumerate(gm.geometryObjects):
        if g.parentJoint == sole_joint and g.meshPath.lower().endswith((".stl", ".dae", ".obj")):
            mesh = trimesh.load(g.meshPath, force="mesh")
            v = np.asarray(mesh.vertices) * np.asarray(g.meshScale)
            M = gd.oMg[i]
            lows.append((v @ M.rotation.T + M.translation)[:, 2].min())
    assert lows and min(lows) == pytest.approx(0.0, abs=1e-3)


# ---------------------------------------------------------------------- every ERD biped
#: Every biped/humanoid URDF example-robot-data ships (folders below), with what loading it
#: gives: "legs" (legs and soles detected, sole rectangles measured), "point feet" (legs
#: detected, no ankle: Bolt), "no geometry" (legs and sole frames detected; no mesh to
#: measure a sole rectangle from: pass contacts=), or the error and why.
ERD_BIPED_DIRS = ("talos_data", "icub_description", "g1_description", "romeo_description",
                  "bolt_description", "human_description", "simple_humanoid_description",
                  "alexander_description", "alex_description", "cassie_description")
ERD_BIPEDS = {
    "talos_data/robots/talos_reduced.urdf": "legs",
    "talos_data/robots/talos_reduced_box.urdf": "legs",
    "talos_data/robots/talos_reduced_corrected.urdf": "legs",
    "talos_data/robots/talos_full_v2.urdf": "legs",
    "talos_data/robots/talos_full_v2_box.urdf": "legs",
    "talos_data/robots/talos_left_arm.urdf": (LegDetectionError, "an arm alone: no legs"),
    "icub_description/robots/icub.urdf": "legs",
    "icub_description/robots/icub_reduced.urdf": "legs",
    "g1_description/urdf/g1_29dof_rev_1_0.urdf": "legs",
    "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf": "legs",
    "romeo_description/urdf/romeo.urdf": "legs",  # with its massless hands named (library)
    "romeo_description/urdf/romeo_small.urdf": (
        URDFError, "inertias that no body has (triangle inequality): refused"),
    "romeo_description/urdf/romeo_laas_small.urdf": (
        URDFError, "inertias that no body has (triangle inequality): refused"),
    "bolt_description/robots/bolt.urdf": "point feet",
    "human_description/robots/human.urdf": "legs",
    "simple_humanoid_description/urdf/simple_humanoid.urdf": "no geometry",
    "simple_humanoid_description/urdf/simple_humanoid_classical.urdf": "no geometry",
    "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf": "legs",
    "alex_description/urdf/alex_nub_hands.urdf": (LegDetectionError, "upper body: no legs"),
    "alex_description/urdf/alex_sake_hands.urdf": (LegDetectionError, "upper body: no legs"),
    "alex_description/urdf/alex_psyonic_hands.urdf": (
        URDFError, "hand inertias that no body has (triangle inequality): refused"),
}
#: Cassie ships SDF only, which this Pinocchio build cannot read (docs/design.md §10).


def test_every_erd_biped_is_listed():
    from gdimitate.model.library import erd_robots_dir

    R = erd_robots_dir()
    shipped = {str(p.relative_to(R)) for d in ERD_BIPED_DIRS for p in (R / d).rglob("*.urdf")}
    assert shipped == set(ERD_BIPEDS), shipped ^ set(ERD_BIPEDS)
    assert not list((R / "cassie_description").rglob("*.urdf"))


@pytest.mark.slow
@pytest.mark.parametrize("rel", sorted(ERD_BIPEDS))
def test_every_erd_biped_loads_or_says_why(rel):
    """Each file loads by path (no presets): legs detected — checked against the hand-written
    Talos preset, and for every robot geometrically (hip above knee above ankle, the sole not
    above the ankle, at the grounded neutral pose; left leg on the left) — and soles
    measured; or it is
    refused with its reason, and a leg-detection error carries a --legs example in the
    robot's own joint names."""
    import json
    import re
    import warnings

    from gdimitate.model.library import erd_robots_dir
    from gdimitate.model.robot import LEG_PRESETS, MASSLESS_PRESETS

    R = erd_robots_dir()
    expect = ERD_BIPEDS[rel]
    massless = MASSLESS_PRESETS["romeo"] if rel.endswith("romeo.urdf") else ()
    load = functools.partial(Robot.from_urdf, R / rel, package_dir=R.parent.parent,
                             massless_joints=massless)
    if isinstance(expect, tuple):
        with pytest.raises(expect[0]) as e:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                load()
        if expect[0] is LegDetectionError:
            text = str(e.value)
            assert "--legs FILE.json" in text
            example = json.loads(text[text.index("\n{"):])
            m_names = re.findall(r"'([^']+)'", text[text.index("Joints:"):text.index("]")])
            for s in ("left", "right"):
                named = {example[s][k] for k in ("hip", "knee", "ankle")} - {None}
                assert len(named) >= 2 and named <= set(m_names)  # ankle null: a point foot
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = load()
    if rel.startswith("talos_data"):
        for s in ("left", "right"):
            leg = r.legs[s]
            assert (leg.hip, leg.knee, leg.ankle, leg.sole) == tuple(
                LEG_PRESETS["talos"][s][k] for k in ("hip", "knee", "ankle", "sole"))
    pin.framesForwardKinematics(r.model, r.data, r.neutral)
    for s in ("left", "right"):
        leg = r.legs[s]
        z = [r.data.oMi[r.model.getJointId(j)].translation[2] for j in (leg.hip, leg.knee)]
        z += [r.data.oMi[r.model.getJointId(leg.ankle)].translation[2]] if leg.ankle else []
        z += [r.data.oMf[r.frame_id(leg.sole)].translation[2]]
        assert all(a > b for a, b in zip(z[:-2], z[1:-1])) and z[-2] >= z[-1], (s, z)
        assert leg.thigh > 0.05 and leg.shank > 0.05
    y = {s: r.data.oMi[r.model.getJointId(r.legs[s].hip)].translation[1] for s in ("left",
                                                                                  "right")}
    assert y["left"] > y["right"]
    if expect == "legs":
        assert set(r.contacts) == {"left", "right"}
    elif expect == "point feet":
        assert r.legs["left"].ankle is None and not r.contacts
    else:
        assert not r.contacts and "no collision or visual geometry" in r.contact_problems["left"]
