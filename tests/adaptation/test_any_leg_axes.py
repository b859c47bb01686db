"""A robot whose knee is not a pitch joint (issue 19): it loads, adapts and audits in 3-D.

The robot is written here as a URDF: a pelvis and two legs (hip roll, hip pitch, knee, ankle
pitch, ankle roll, a box foot), 0.3 m thigh and shank, the knee turning about an axis tilted
30° from the lateral one towards the outside (|cos| = 0.866 with the lateral axis: not a pitch
joint by the sagittal measurement's rule, |cos| ≥ 0.9) or about the forward (roll) axis. Its
twin with pitch knees walks (:func:`gdimitate.walking_motion`); the optimal adaptor carries
that walk over to the tilted knees. The paper's planar tools refuse the robot by name
(:func:`gdimitate.planar.sagittal_leg`, ``method="analytic"``); nothing else asks for them.

References are independent of gdimitate's loading and of the optimiser: Pinocchio's own
model of the same file (``pin.buildModelFromUrdf``), closed forms of the box feet, and the
output's inverse dynamics, integration and stance poses recomputed with Pinocchio.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.model.robot import SIDES
from gdimitate.planar import sagittal_leg
from gdimitate.retarget import Contact

TILT = np.radians(30.0)
LEG = 0.3  # thigh = shank [m]
FOOT = (0.2, 0.08, 0.04)  # box foot [m]: length, width, height


def _link(name: str, mass: float, size, xyz, collision: bool = False) -> str:
    x, y, z = size
    ixx, iyy, izz = (mass * (y * y + z * z) / 12, mass * (x * x + z * z) / 12,
                     mass * (x * x + y * y) / 12)
    geo = f'<geometry><box size="{x} {y} {z}"/></geometry>'
    o = f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="0 0 0"/>'
    col = f"<collision>{o}{geo}</collision>" if collision else ""
    return (f'<link name="{name}"><inertial>{o}<mass value="{mass}"/><inertia ixx="{ixx}" '
            f'ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>'
            f"<visual>{o}{geo}</visual>{col}</link>")


def _joint(name: str, parent: str, child: str, xyz, axis, lo: float, hi: float) -> str:
    return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="0 0 0"/>'
            f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
            f'<limit lower="{lo}" upper="{hi}" effort="150" velocity="12"/></joint>')


def biped_urdf(knee: str) -> str:
    """The robot with its knees about the lateral axis (``"pitch"``), the axis tilted 30°
    outwards in the horizontal plane (``"tilted"``: knee flexion moves each foot backwards
    and out) or the forward axis (``"roll"``)."""
    links = [_link("pelvis", 12.0, (0.2, 0.3, 0.3), (0, 0, 0.1))]
    joints = []
    for s, y in (("left", 0.1), ("right", -0.1)):
        axis = {"pitch": (0.0, 1.0, 0.0), "roll": (1.0, 0.0, 0.0),
                "tilted": (np.sign(y) * np.sin(TILT), np.cos(TILT), 0.0)}[knee]
        links += [_link(f"{s}_hip_roll_link", 0.5, (0.05, 0.05, 0.05), (0, 0, 0)),
                  _link(f"{s}_thigh", 2.0, (0.06, 0.06, LEG), (0, 0, -LEG / 2)),
                  _link(f"{s}_shank", 1.5, (0.05, 0.05, LEG), (0, 0, -LEG / 2)),
                  _link(f"{s}_ankle_link", 0.2, (0.03, 0.03, 0.03), (0, 0, 0)),
                  _link(f"{s}_foot", 0.6, FOOT, (0, 0, -FOOT[2]), collision=True),
                  f'<link name="{s}_sole"/>']
        joints += [
            _joint(f"{s}_hip_roll", "pelvis", f"{s}_hip_roll_link", (0, y, 0), (1, 0, 0),
                   -0.5, 0.5),
            _joint(f"{s}_hip", f"{s}_hip_roll_link", f"{s}_thigh", (0, 0, 0), (0, 1, 0),
                   -1.5, 1.5),
            _joint(f"{s}_knee", f"{s}_thigh", f"{s}_shank", (0, 0, -LEG), axis, -0.1, 2.4),
            _joint(f"{s}_ankle", f"{s}_shank", f"{s}_ankle_link", (0, 0, -LEG), (0, 1, 0),
                   -1.0, 1.0),
            _joint(f"{s}_ankle_roll", f"{s}_ankle_link", f"{s}_foot", (0, 0, 0), (1, 0, 0),
                   -0.5, 0.5),
            f'<joint name="{s}_sole_joint" type="fixed"><parent link="{s}_foot"/>'
            f'<child link="{s}_sole"/><origin xyz="0 0 {-1.5 * FOOT[2]}"/></joint>']
    return f'<robot name="knee_{knee}">{"".join(links)}{"".join(joints)}</robot>'


def _load(tmp_path: Path, knee: str) -> tuple[gd.Robot, pin.Model]:
    path = tmp_path / f"knee_{knee}.urdf"
    path.write_text(biped_urdf(knee))
    # the name carries the knee: the adaptor's compiled problems are cached by robot
    robot = gd.Robot.from_urdf(path, name=f"test_knee_{knee}_30deg")
    return robot, pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())


@pytest.mark.parametrize("knee", ["tilted", "roll"])
def test_a_robot_whose_knee_is_not_a_pitch_joint_loads(tmp_path, knee):
    robot, ref = _load(tmp_path, knee)
    assert robot.base == "free" and robot.floating
    assert tuple(ref.names)[1:] == robot.joint_names
    data = ref.createData()
    q0 = robot.neutral
    pin.framesForwardKinematics(ref, data, q0)
    for s in SIDES:
        leg = robot.legs[s]
        assert (leg.hip, leg.knee, leg.ankle, leg.sole) == (f"{s}_hip", f"{s}_knee",
                                                             f"{s}_ankle", f"{s}_sole")
        # the knee's world axis (Pinocchio's Jacobian): 30° off the lateral axis, or forward
        jid = ref.getJointId(leg.knee)
        pin.computeJointJacobians(ref, data, q0)
        axis = pin.getJointJacobian(ref, data, jid, pin.LOCAL_WORLD_ALIGNED)[3:, ref.joints[
            jid].idx_v]
        assert abs(axis[1]) == pytest.approx(np.cos(TILT) if knee == "tilted" else 0.0,
                                             abs=1e-12)
        # 3-D segment lengths and the foot height, against Pinocchio's joint placements
        p = {j: data.oMi[ref.getJointId(j)].translation for j in (leg.hip, leg.knee,
                                                                   leg.ankle)}
        sole = data.oMf[ref.getFrameId(leg.sole)].translation
        assert leg.segments == pytest.approx((np.linalg.norm(p[leg.knee] - p[leg.hip]),
                                              np.linalg.norm(p[leg.ankle] - p[leg.knee])),
                                             abs=1e-12)
        assert leg.segments == pytest.approx((LEG, LEG), abs=1e-12)
        assert leg.foot == pytest.approx(p[leg.ankle][2] - sole[2], abs=1e-12)
        assert sole[2] == pytest.approx(0.0, abs=1e-12)  # the neutral pose stands on z = 0
        # the sole rectangle: the box foot's bottom face
        c = robot.contacts[s]
        assert (c.half_length, c.half_width) == pytest.approx((FOOT[0] / 2, FOOT[1] / 2),
                                                              abs=1e-9)
        # the paper's planar tools refuse the leg, naming the joint
        with pytest.raises(gd.LegDetectionError, match=f"{s} knee joint '{s}_knee'"):
            sagittal_leg(robot, s)
    twin, _ = _load(tmp_path, "pitch")
    with pytest.raises(gd.LegDetectionError, match="not about the lateral axis"):
        gd.adapt(gd.walking_motion(twin, gd.GaitSpec(cycles=1)), twin, robot, "analytic")


@pytest.mark.slow
def test_a_robot_whose_knee_is_not_a_pitch_joint_adapts_and_audits(tmp_path):
    """The pitch-knee twin's walk (one stride, 35 % single support, steps of 0.4 leg
    lengths) adapted to the tilted knees at 20 knots/s, the push within 0.35 rad of the
    twin's shank direction: measured feasible (39 iterations), the tilted knees flexing up
    to 0.59 rad. Checked with Pinocchio: the output's integration, the base rows of its
    inverse dynamics with its wrenches as external forces (RNEA), torques within the effort
    limits, the stance feet holding their poses on the floor."""
    twin, _ = _load(tmp_path, "pitch")
    robot, ref = _load(tmp_path, "tilted")
    demo = gd.walking_motion(twin, gd.GaitSpec(cycles=1, single_support=0.35,
                                               step_length=0.4, period=1.2))
    r = gd.adapt(demo, twin, robot, method="optimal", force="segment", rate=20,
                 contact=Contact(cone_half_angle=0.35), verbose=False)
    assert r.solver.success and not r.solver.unmet
    assert r.audit.feasible and not r.audit.binding
    M, data = r.motion, ref.createData()
    knee = M.q[:, [robot.idx_q(f"{s}_knee") for s in SIDES]]
    assert knee.max() > 0.3  # the tilted knees do the flexing
    h = np.diff(M.t)
    for k in range(M.T - 1):
        np.testing.assert_allclose(pin.integrate(ref, M.q[k], h[k] * M.v[k + 1]), M.q[k + 1],
                                   atol=1e-8)
        np.testing.assert_allclose(M.v[k] + h[k] * M.a[k], M.v[k + 1], atol=1e-8)
    mg = robot.mass * 9.81
    frames = [ref.frames[ref.getFrameId(r.contacts[s].frame)] for s in SIDES]
    for k in range(M.T):  # Pinocchio's RNEA with the wrenches as external forces
        fext = [pin.Force.Zero() for _ in range(ref.njoints)]
        for s, fr in zip(SIDES, frames):
            fext[fr.parentJoint] = fext[fr.parentJoint] + fr.placement.act(
                pin.Force(r.wrenches[s][k]))
        tau = pin.rnea(ref, data, M.q[k], M.v[k], M.a[k], fext)
        assert np.abs(tau[:6]).max() <= 1e-6 * mg
        assert np.all(np.abs(tau[6:]) <= ref.effortLimit[6:] * (1 + 1e-6))
    for s in SIDES:
        fid = ref.getFrameId(r.contacts[s].frame)
        stance = np.flatnonzero(M.contact[s])
        runs = np.split(stance, np.flatnonzero(np.diff(stance) > 1) + 1)
        for run in runs:
            poses = []
            for k in run:
                pin.framesForwardKinematics(ref, data, M.q[k])
                poses.append(data.oMf[fid].homogeneous.copy())
            poses = np.array(poses)
            assert np.abs(poses - poses[0]).max() <= 1e-3  # held (the audit's slip tolerance)
            assert np.abs(poses[:, 2, 3]).max() <= 1e-3  # on the floor


def test_the_compiled_problem_cache_tells_knee_axes_apart(tmp_path):
    """Two robots of one name whose knees differ only in the axis (30° vs 35° tilt, both
    Pinocchio RevoluteUnaligned joints) must not share compiled derivatives: the adaptor's
    cache key covers joint axes (it did not, and the second robot got the first's solution)."""
    from gdimitate.retarget.trajectory.problem import fingerprint

    text = biped_urdf("tilted")
    other = text
    for sign in (1.0, -1.0):
        a = f'axis xyz="{sign * np.sin(TILT)} {np.cos(TILT)} 0.0"'
        b = f'axis xyz="{sign * np.sin(np.radians(35))} {np.cos(np.radians(35))} 0.0"'
        assert a in other
        other = other.replace(a, b)
    keys = []
    for i, t in enumerate((text, other, text)):
        path = tmp_path / f"r{i}.urdf"
        path.write_text(t)
        keys.append(fingerprint(gd.Robot.from_urdf(path, name="same_name")))
    assert keys[0] != keys[1]
    assert keys[0] == keys[2]
