"""Body maps: presets pair joints whose axes agree (checked against Pinocchio's joint axes
and the robots' own leg sign conventions), user maps from dicts and JSON files, unknown names
listed, unmapped joints warned about."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.errors import InvalidInputError, UnknownNameError
from gdimitate.planar import sagittal_leg
from gdimitate.retarget import BodyMap, UnmappedJointsWarning, body_map
from tests.helpers import TESTS


def _axis(robot, joint):
    m = robot.model
    jid = m.getJointId(joint)
    pin.computeJointJacobians(m, robot.data, robot.neutral)
    J = pin.getJointJacobian(m, robot.data, jid, pin.LOCAL_WORLD_ALIGNED)
    return J[3:, m.joints[jid].idx_v]


@pytest.mark.parametrize("name", ["talos", "g1", "icub", "hoap2"])
def test_planar_preset_signs_follow_the_leg_conventions(robot, name):
    d, i = robot("case1_demonstrator"), robot(name)
    with _nowarn():  # the planar demonstrator has legs only: the arms have nothing to follow
        bm = body_map(d, i)
    for s in ("left", "right"):
        dl, il = d.legs[s], i.legs[s]
        dsag, isag = sagittal_leg(d, s), sagittal_leg(i, s)
        for k, (dj, ij) in enumerate(zip((dl.hip, dl.knee, dl.ankle), (il.hip, il.knee,
                                                                          il.ankle))):
            target, scale, offset = bm.joints[dj]
            assert target == ij and offset == 0.0
            # the planar angle sign·q is the same physical angle on both robots
            assert scale == dsag.signs[k] * isag.signs[k]
            a, b = _axis(d, dj), _axis(i, ij)
            assert np.sign(a @ b) == scale


class _nowarn:
    def __enter__(self):
        import warnings

        self._c = warnings.catch_warnings()
        self._c.__enter__()
        warnings.simplefilter("error", UnmappedJointsWarning)

    def __exit__(self, *exc):
        self._c.__exit__(*exc)
        return False


def test_preset_warns_only_where_the_demonstrator_has_joints_left_over(robot):
    """Issue 34: every G1 run warned about its 14 arm joints, which the shipped walk's model
    (no arms) cannot drive. A preset now warns about an imitator joint only where the
    demonstrator has a joint the preset left unmapped in the same body region (legs, each
    side's arm, the middle): G1 and iCub none; Talos its head (the model's lumbar bending and
    rotation are left over in the middle); every held joint is still listed by held()."""
    from gdimitate import gait

    human = gait.human_walk_3d()[0]
    for name, warned in (("g1", None), ("icub", None),
                         ("talos", {"head_1_joint", "head_2_joint"})):
        imit = robot(name)
        import warnings

        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always", UnmappedJointsWarning)
            bm = body_map(human, imit)
        msgs = [str(w.message) for w in got if issubclass(w.category, UnmappedJointsWarning)]
        if warned is None:
            assert not msgs, msgs
        else:
            assert len(msgs) == 1
            assert set(msgs[0].rsplit(": ", 1)[1].split(", ")) == warned
        held = bm.held(imit)
        mapped = {b for b, _, _ in bm.joints.values()}
        assert not set(held) & mapped
        assert len(held) + len(mapped) == len([j for j in imit.joint_names
                                               if imit.model.joints[
                                                   imit.model.getJointId(j)].nq == 1])
    assert len(body_map(human, robot("g1")).held(robot("g1"))) == 14


def test_user_maps_dict_and_json(robot, tmp_path):
    d, i = robot("case1_demonstrator"), robot("hoap2")
    spec = {"joints": {"left_knee": "left_knee", "right_knee": ["right_knee", -1.0, 0.1]},
            "segments": {"torso": "torso"}}
    with pytest.warns(UnmappedJointsWarning, match="left_hip"):
        bm = body_map(d, i, spec)
    assert bm.joints["right_knee"] == ("right_knee", -1.0, 0.1)
    p = tmp_path / "map.json"
    p.write_text(json.dumps(spec))
    with pytest.warns(UnmappedJointsWarning):
        assert body_map(d, i, p).joints == bm.joints


def test_unknown_names_are_listed(robot):
    d, i = robot("case1_demonstrator"), robot("hoap2")
    with pytest.raises(UnknownNameError, match="left_knee"):
        body_map(d, i, {"joints": {"left_knee": "nope"}})
    with pytest.raises(UnknownNameError, match="torso"):
        body_map(d, i, {"segments": {"nope": "torso"}})
    with pytest.raises(InvalidInputError):
        BodyMap.from_dict({"bones": {}})


# ------------------------------------------------------------------ arms (issue 20)
_ELBOW = {"g1": "{s}_elbow_joint", "talos": "arm_{s}_4_joint", "icub": "{s}_elbow",
          "romeo": "{s}ElbowYaw"}
_SIDE = {"g1": {"left": "left", "right": "right"}, "talos": {"left": "left", "right": "right"},
         "icub": {"left": "l", "right": "r"}, "romeo": {"left": "L", "right": "R"}}


@pytest.fixture(scope="module")
def armed():
    """The synthetic full-body OpenSim model (subject01 with Rajagopal-style arms)."""
    import sys
    import tempfile
    import warnings
    from pathlib import Path

    import gdimitate as gd

    sys.path.insert(0, str(TESTS / "opensim_ref"))
    from with_arms import write_model

    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = write_model(gd.gait.human_walk_3d_folder() / "subject01.osim",
                        Path(tmp) / "armed.osim")
        return gd.Robot.from_osim(p)


@pytest.fixture(scope="module")
def cmu():
    from gdimitate.io.bvh.reader import read_bvh
    from gdimitate.io.gait import human_walk_path

    return read_bvh(human_walk_path().parents[1] / "cmu_02_01" / "cmu_02_01.bvh")[0]


def _elbow_shift(robot, q, frame: str, joint: str, dq: float) -> np.ndarray:
    """World displacement of ``frame``'s origin when ``joint`` turns by ``dq`` from ``q``."""
    m, d = robot.model, robot.model.createData()
    fid = m.getFrameId(frame)
    pin.framesForwardKinematics(m, d, q)
    p0 = d.oMf[fid].translation.copy()
    q2 = q.copy()
    q2[robot.idx_q(joint)] += dq
    pin.framesForwardKinematics(m, d, q2)
    return d.oMf[fid].translation - p0


@pytest.mark.parametrize("name", ["g1", "talos", "icub", "romeo"])
@pytest.mark.parametrize("demo", ["opensim", "bvh"])
def test_arm_presets_move_the_elbows_alike(robot, armed, cmu, name, demo):
    """Issue 20: the arm presets (OpenSim ``arm_flex/arm_add/arm_rot/elbow_flex``, BVH
    ``Arm``/``ForeArm`` rotations) onto each humanoid. Independent of the axes the presets
    compare: from both robots' arms-down poses, a mapped shoulder joint turned by 0.2 rad
    (the imitator's by ``scale``·0.2) moves the demonstrator's elbow and the imitator's the
    same way (cosine of the two displacements > 0.5), or, for the upper arm's twist, leaves
    both nearly in place. The arms-down pose of each imitator is
    its zero pose (Romeo: shoulder pitch +90°), which the offsets map the demonstrator's onto.
    OpenSim's arm flexion is forward: the imitator's elbow moves forward (+x)."""
    from gdimitate.retarget.bodymap import arms_down

    d = armed if demo == "opensim" else cmu
    i = robot(name)
    bm = body_map(d, i)
    qd, qi = arms_down(d), arms_down(i)
    shoulders = {k: v for k, v in bm.joints.items() if "shoulder" in v[0].lower()
                 or v[0].startswith(("arm_left_1", "arm_left_2", "arm_left_3", "arm_right_1",
                                     "arm_right_2", "arm_right_3"))}
    expect = {"g1": 6, "talos": 4, "icub": 6, "romeo": 4}[name]
    assert len(shoulders) >= expect, shoulders
    for dn, (iname, scale, offset) in shoulders.items():
        side = "left" if dn.lower().startswith("left") or dn.endswith("_l") else "right"
        df = (f"elbow_flex_{side[0]}" if demo == "opensim" else f"{side.capitalize()}ForeArm")
        fi = _ELBOW[name].format(s=_SIDE[name][side])
        assert scale * qd[d.idx_q(dn)] + offset == pytest.approx(qi[i.idx_q(iname)])
        a = _elbow_shift(d, qd, df, dn, 0.2)
        b = _elbow_shift(i, qi, fi, iname, scale * 0.2)
        if np.linalg.norm(a) < 1e-3:  # the upper arm's own twist: the elbow stays put
            assert np.linalg.norm(b) < 0.2 * 0.2 * 0.1, (dn, iname, b)
            continue
        assert a @ b > 0.5 * np.linalg.norm(a) * np.linalg.norm(b), (dn, iname, a, b)
        if demo == "opensim" and dn.startswith("arm_flex"):
            assert a[0] > 0 and b[0] > 0
    elbows = [v[0] for k, v in bm.joints.items() if "ForeArm" in k or "elbow_flex" in k]
    assert len(elbows) == (0 if name == "romeo" else 2)


def test_following_report(armed):
    """``following``: per mapped joint, the correlation of the two angle histories and the
    ranges (the demonstrator's mapped and clipped to the imitator's limits), against NumPy on
    a synthetic pair of motions."""
    import gdimitate as gd
    from gdimitate.model.kinematics import robot_motion
    from gdimitate.retarget.bodymap import following

    g1 = gd.Robot.from_library("g1")
    bm = body_map(armed, g1)
    t = np.linspace(0, 1, 41)
    qd = np.tile(armed.neutral, (t.size, 1))
    qd[:, armed.idx_q("arm_flex_r")] = 0.4 * np.sin(2 * np.pi * t)
    qi = np.tile(g1.neutral, (t.size, 1))
    qi[:, g1.idx_q("right_shoulder_pitch_joint")] = -0.1 * np.sin(2 * np.pi * t) + 0.01 * t
    rep = following(bm, robot_motion(armed, t, qd, {}), armed, robot_motion(g1, t, qi, {}), g1)
    f = rep["right_shoulder_pitch_joint"]
    assert f.demonstrator == "arm_flex_r"
    assert f.r == pytest.approx(np.corrcoef(qd[:, armed.idx_q("arm_flex_r")],
                                            qi[:, g1.idx_q("right_shoulder_pitch_joint")])[0, 1])
    assert f.r < -0.99 and f.demonstrator_range == pytest.approx(0.8, abs=1e-3)
    assert f.ratio == pytest.approx(f.imitator_range / 0.8, rel=1e-3)
    assert np.isnan(rep["left_shoulder_pitch_joint"].r)  # constant: no correlation


@pytest.mark.slow
def test_g1_swings_its_arms_like_the_demonstrator(armed):
    """Issue 20, done when: the shipped 3-D walk on the synthetic full-body model (subject01
    with arms swinging against the legs, ±0.23 rad), one stride adapted to G1 at 10 knots/s.
    Each G1 shoulder pitch correlates with the demonstrator's arm flexion (|r| ≥ 0.8) over at
    least half its range (mapped and clipped to G1's limits); no unmapped joint (wrists)
    leaves its rest pose by more than HOLD_RANGE; the audit's self-collision check
    passes. Measured: r = −0.882 / −0.980 (left/right; the map's scale is −1), range ratio
    0.90 / 0.83, wrists within 0.100 rad, 13.2 mm clear (20 knots/s: 0.89 / 0.85, 13.5 mm)."""
    import sys
    import warnings

    import gdimitate as gd
    from gdimitate.io.opensim import read_coordinates, read_grf
    from gdimitate.retarget.bodymap import HOLD_RANGE, following
    from gdimitate.retarget.parts.self_collision import rest_pose

    sys.path.insert(0, str(TESTS / "opensim_ref"))
    from with_arms import arm_swing

    folder = gd.gait.human_walk_3d_folder()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        motion = arm_swing(armed, read_coordinates(folder / "subject01_walk1_ik.mot", armed))
        forces = read_grf(folder / "subject01_walk1_grf.mot", armed,
                          folder / "subject01_walk1_grf.xml", t=motion.t)
        g1 = gd.Robot.from_library("g1")
    demo, fs = gd.gait.one_stride(motion.replace(contact=forces.contact), forces, "left")
    r = gd.adapt(demo, armed, g1, method="optimal", force="measured", forces=fs, rate=10,
                 verbose=False)
    bm = body_map(armed, g1)
    rep = following(bm, demo, armed, r.motion, g1)
    for s in ("left", "right"):
        f = rep[f"{s}_shoulder_pitch_joint"]
        print(f"\n{s} shoulder pitch: r = {f.r:.3f}, range {f.imitator_range:.3f} rad of "
              f"{f.demonstrator_range:.3f} (ratio {f.ratio:.2f})")
        assert abs(f.r) >= 0.8 and f.ratio >= 0.5, f
    mapped = {v[0] for v in bm.joints.values()}
    held = [j for j in g1.joint_names if j not in mapped and g1.model.joints[
        g1.model.getJointId(j)].nq == 1]
    rest = rest_pose(g1)
    moved = max(np.max(np.abs(r.motion.q[:, g1.idx_q(j)] - rest[g1.idx_q(j)])) for j in held)
    print(f"unmapped joints ({len(held)}): largest excursion {moved:.3f} rad")
    assert moved <= HOLD_RANGE + 1e-6
    sc = r.audit.check("self_collision")
    print(f"self-collision: closest {sc.value * 1e3:.1f} mm at knot {sc.knot}")
    assert sc.passed


@pytest.mark.slow
def test_g1_holds_its_arms_under_an_armless_demonstrator():
    """Issue 20, done when, on the shipped subject01 walk (gait2354: no arms): one stride on G1
    at 30 knots/s (10 until the steps cost made G1 walk the scaled stride, 2.3 times as far: at
    10 knots/s the one-step scheme's stance-foot velocity, 2.2e-3 m/s, then exceeds the audit's
    1e-3; 20 until the body-over-feet cost carried the body further: at 20 the left stance's
    velocity exceeds it again) — G1's 14 arm and wrist joints (unmapped) stay within HOLD_RANGE
    of their rest pose (the neutral one with the shoulders rolled out of the torso's margin; a
    weak posture cost let them sweep 1.9–2.5 rad), and the audit, its self-collision check
    included, finds the plan feasible."""
    import warnings

    import gdimitate as gd
    from gdimitate.retarget.bodymap import HOLD_RANGE
    from gdimitate.retarget.parts.self_collision import rest_pose

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h, m, f = gd.gait.human_walk_3d()
        g1 = gd.Robot.from_library("g1")
        demo, fs = gd.gait.one_stride(m, f, "left")
        r = gd.adapt(demo, h, g1, method="optimal", force="measured", forces=fs, rate=30,
                     verbose=False)
        mapped = {v[0] for v in body_map(h, g1).joints.values()}
    held = [j for j in g1.joint_names if j not in mapped
            and g1.model.joints[g1.model.getJointId(j)].nq == 1]
    assert len(held) == 14
    rest = rest_pose(g1)
    moved = max(np.max(np.abs(r.motion.q[:, g1.idx_q(j)] - rest[g1.idx_q(j)])) for j in held)
    print(f"\nsubject01 → G1: unmapped excursion {moved:.3f} rad, self-collision "
          f"{r.audit.self_collision.distance * 1e3:.1f} mm, feasible {r.audit.feasible}")
    assert moved <= HOLD_RANGE + 1e-6
    assert r.audit.check("self_collision").passed and r.audit.feasible, r.audit.binding


def _turned(robot, dR: np.ndarray) -> np.ndarray:
    """``robot``'s neutral pose with its free-flyer base turned by the world rotation ``dR``."""
    q = robot.neutral.copy()
    R = pin.Quaternion(q[3:7]).toRotationMatrix()
    q[3:7] = pin.Quaternion(dR @ R).coeffs()
    return q


@pytest.mark.parametrize("name", ["icub", "g1"])
@pytest.mark.parametrize("demo", ["opensim", "bvh"])
def test_segment_targets_turn_the_imitators_own_frames(robot, armed, cmu, name, demo):
    """The adaptor's segment targets (pelvis, torso; :func:`segment_rotations`) are the
    demonstrator's rotation since its neutral pose applied to the imitator's frames, whatever
    axes each file gives them: iCub's ``root_link`` looks back (π about z from the OpenSim
    pelvis), the CMU skeleton's ``Spine`` has its axes permuted (120° from G1's
    ``torso_link``). Reference: Pinocchio's placements of the imitator's segment frames at its
    neutral pose with its base turned by the same world rotation as the demonstrator's.
    Copying the world rotation itself (the adaptor before) misses by up to 180°."""
    from gdimitate.model.kinematics import frame_placements
    from gdimitate.retarget.targets import segment_rotations

    d, i = (armed if demo == "opensim" else cmu), robot(name)
    bmap = body_map(d, i)
    assert len(bmap.segments) == 2
    dR = pin.rpy.rpyToMatrix(0.1, -0.2, 0.5)
    qd = _turned(d, dR)
    rot = {f: p.rotation for f, p in frame_placements(d, qd[None], list(bmap.segments)).items()}
    got = segment_rotations(d, i, bmap, rot)
    ref = frame_placements(i, _turned(i, dR)[None], list(bmap.segments.values()))
    for n, f in enumerate(bmap.segments.values()):
        np.testing.assert_allclose(got[0, n], ref[f].rotation[0], atol=1e-12)
