"""A BVH skeleton whose rest pose splays its legs (CMU's: each hip→ankle line 20° out of the
vertical) is paired with an imitator at its legs-down pose (:func:`legs_down`), not at the
rest pose: otherwise the imitator's hip-roll target is the subject's ~20° of adduction that
brings a splayed leg under the hip (issue 17: G1's hips driven into its waist)."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.io.bvh import read_bvh
from gdimitate.model.robot import Robot
from gdimitate.retarget.bodymap import body_map, legs_down


def _skeleton(path, splay_deg: float) -> None:
    """A Y-up, +Z-facing BVH in metres whose thigh and shank bones lean ``splay_deg`` outward
    in the frontal plane at the zero pose (2 frames, standing still)."""
    a = np.radians(splay_deg)

    def bone(sx, length):  # outward (x = ±lateral) and down (-y)
        return f"{float(sx * length * np.sin(a))!r} {float(-length * np.cos(a))!r} 0.0"

    legs = []
    for side, sx in (("Left", 1.0), ("Right", -1.0)):
        legs.append(f"""  JOINT {side}UpLeg
  {{
    OFFSET {0.09 * sx} -0.05 0.0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT {side}Leg
    {{
      OFFSET {bone(sx, 0.42)}
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT {side}Foot
      {{
        OFFSET {bone(sx, 0.40)}
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT {side}ToeBase
        {{
          OFFSET 0.0 -0.07 0.13
          CHANNELS 3 Zrotation Xrotation Yrotation
          End Site
          {{
            OFFSET 0.0 0.0 0.05
          }}
        }}
      }}
    }}
  }}""")
    spine = """  JOINT Spine
  {
    OFFSET 0.0 0.1 0.0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0.0 0.3 0.0
    }
  }"""
    n = 6 + 3 * 9
    h = 0.05 + 0.82 * np.cos(a) + 0.07
    row = " ".join(["0.0", repr(float(h)), "0.0"] + ["0.0"] * (n - 3))
    text = "\n".join(["HIERARCHY", "ROOT Hips", "{", "  OFFSET 0.0 0.0 0.0",
                      "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                      *legs, spine, "}", "MOTION", "Frames: 2", "Frame Time: 0.01", row, row])
    path.write_text(text + "\n")


@pytest.fixture(scope="module")
def g1():
    return Robot.load("g1")


@pytest.mark.parametrize("splay", [0.0, 12.0, 20.0])
def test_legs_down_hangs_the_legs_and_offsets_the_hip_roll(tmp_path, g1, splay):
    """Independent of the secant search: at :func:`legs_down` Pinocchio puts each ankle
    straight below its hip in the frontal plane (< 1e-9 m sideways), reached by turning the
    hip-roll channel by exactly the splay (closed form, 1e-9 rad); the G1 map's hip-roll
    offset then maps that pose onto G1's neutral pose (``scale · q + offset`` = 0, 1e-9
    rad), and no other leg joint gets an offset."""
    path = tmp_path / "splayed.bvh"
    _skeleton(path, splay)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, _ = read_bvh(path, scale=1.0)
        bm = body_map(robot, g1)
    q = legs_down(robot)
    q[3:7] = pin.Quaternion(np.asarray(robot.base_rotation)).coeffs()
    d = robot.model.createData()
    pin.forwardKinematics(robot.model, d, q)
    for side in ("left", "right"):
        leg = robot.legs[side]
        v = d.oMi[robot.model.getJointId(leg.ankle)].translation - \
            d.oMi[robot.model.getJointId(leg.hip)].translation
        assert abs(v[1]) < 1e-9 and v[2] < 0
        roll = f"{side.capitalize()}UpLeg_Zrotation"
        assert abs(abs(q[robot.idx_q(roll)]) - np.radians(splay)) < 1e-9
        iname, scale, offset = bm.joints[roll]
        assert iname == f"{side}_hip_roll_joint"
        assert scale * q[robot.idx_q(roll)] + offset == pytest.approx(0.0, abs=1e-9)
    others = {k: v for k, v in bm.joints.items() if "Leg" in k or "Foot" in k}
    assert all(v[2] == 0.0 for k, v in others.items() if "UpLeg_Z" not in k), others


def test_cmu_clip_hip_roll_targets_are_near_zero(g1):
    """The shipped CMU clip (rest pose splayed 20°: OFFSET 2.597 -7.136 per thigh): the
    mapped G1 hip-roll targets, averaged over the clip, are within 5° of G1's neutral — the
    subject's legs hang under its hips (before: -23.4° / +21.8°, 23° of adduction)."""
    from gdimitate.io.gait import human_walk_path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, motion = read_bvh(human_walk_path().parents[1] / "cmu_02_01" / "cmu_02_01.bvh")
        bm = body_map(robot, g1)
    for side in ("Left", "Right"):
        dn = f"{side}UpLeg_Zrotation"
        iname, scale, offset = bm.joints[dn]
        target = scale * motion.q[:, robot.idx_q(dn)] + offset
        assert abs(np.degrees(offset)) == pytest.approx(np.degrees(np.arctan2(5.0896, 13.9835)),
                                                        abs=0.2)
        assert abs(np.degrees(target.mean())) < 5.0, (dn, np.degrees(target.mean()))


def test_cmu_soles_flat_in_stance_and_legs_reach():
    """The shipped CMU clip: measured with the legs hanging, each sole frame lies within 6° of
    flat on average over its detected stance frames (Pinocchio FK; at the splayed rest pose
    it stood 23° on edge), and ``Leg.length`` (thigh + shank) is the leg's reach: no frame's
    hip→ankle distance exceeds it (before: 0.790 m against up to 0.838 m), within 1 mm of
    the bones' 3-D lengths (file OFFSETs: |(2.5972, −7.13576)| + |(2.49236, −6.8477)| CMU
    units of 0.056444 m)."""
    from gdimitate.io.gait import human_walk_path
    from gdimitate.model.kinematics import frame_placements

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, motion = read_bvh(human_walk_path().parents[1] / "cmu_02_01" / "cmu_02_01.bvh")
    bones = (np.hypot(2.5972, 7.13576) + np.hypot(2.49236, 6.8477)) * 0.056444
    for side in ("left", "right"):
        f = robot.contacts[side].frame
        R = frame_placements(robot, motion.q, [f])[f].rotation[motion.contact[side]]
        roll = np.degrees(np.arctan2(R[:, 2, 1], R[:, 2, 2]))
        assert abs(roll.mean()) < 6.0, (side, roll.mean())
        leg = robot.legs[side]
        P = frame_placements(robot, motion.q, [leg.hip, leg.ankle])
        span = np.linalg.norm(P[leg.ankle].translation - P[leg.hip].translation, axis=1)
        assert span.max() <= leg.length
        if side == "left":
            assert leg.length == pytest.approx(bones, abs=1e-3)
