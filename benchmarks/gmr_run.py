"""Run GMR (General Motion Retargeting, github.com/YanjieZe/GMR; not on PyPI) on a BVH walk →
its Unitree G1, in the Python that has GMR's dependencies (a venv of its own: ``pip install
mink mujoco 'qpsolvers[proxqp]' loop_rate_limiters rich tqdm natsort scipy``) with GMR's
repository checked out at ``REPO``. ``benchmarks/peers.py --gmr-python --gmr-repo`` calls this
script; nothing of gdimitate is imported here.

Usage: ``python gmr_run.py REPO IN.bvh OUT.npz``

GMR's own pieces do the work: its BVH reader and forward kinematics
(``utils.lafan_vendor``), its Y-up → Z-up turn (``utils.lafan1.load_lafan1_file``'s matrix),
``GeneralMotionRetargeting(src_human="bvh", tgt_robot="unitree_g1")`` with its IK config
``ik_configs/bvh_to_g1.json`` (weights, scale table, the two mink IK passes, the daqp solver,
its damping) frame by frame, as its ``scripts/bvh_to_robot.py`` does. Its package
``__init__`` imports a MuJoCo viewer (``robot_motion_viewer``) and torch
(``kinematics_model``) that retargeting never uses: stand-in modules are put in their place.

Its BVH reader and IK config are LAFAN1's; a CMU BVH (``gdimitate/data/gait/cmu_02_01``)
needs, and gets, only:

- **renames**: CMU's ``LeftToeBase``/``RightToeBase`` as LAFAN1's ``LeftToe``/``RightToe``
  (whose orientations make GMR's ``LeftFootMod``/``RightFootMod``), CMU's ``Spine1`` (the
  upper spine) as LAFAN1's ``Spine2``;
- **units**: CMU's length unit × 0.056444 m (GMR's loader divides LAFAN1's centimetres by
  100); the clip's own frame time (GMR's script labels every BVH 30 Hz); frame 0, CMU's
  calibration pose, not retargeted;
- **the human's height**: head joint over the lowest toe in the calibration frame + 0.10 m
  (GMR's loader fixes 1.75 m, LAFAN1's actor) — GMR scales by it;
- **a per-body frame correction** in place of the config's rotation offsets (which map
  LAFAN1's bone frames onto the robot's): each body's offset is taken from the calibration
  frame, where the CMU actor stands with straight legs, flat feet and arms out, so that the
  robot body's target is its own orientation at q = 0 turned to the actor's facing and to the
  limb's direction there (``_frame_offsets``). Position offsets stay GMR's (all zero).

Writes ``OUT.npz``: ``qpos`` ``(T, 36)`` in GMR's MuJoCo G1 order (x y z, quaternion w x y z,
29 joints), ``joint_names`` (that order), ``fps`` (the BVH's), ``seconds`` (the retargeting's
wall time, frame loop only), ``height`` (the human height given to GMR) and ``scale`` (GMR's
root scale: ``human_scale_table['Hips']`` × height / its assumed 1.8 m).
"""

import sys
import time
import types
from pathlib import Path

import numpy as np

#: CMU BVH joint → the LAFAN1 name GMR's G1 config uses.
RENAMES = {"LeftToeBase": "LeftToe", "RightToeBase": "RightToe", "Spine1": "Spine2"}
#: CMU's length unit [m].
CMU_UNIT = 0.056444
#: Head joint to the top of the head [m], added to the calibration frame's head height.
HEAD_TOP = 0.10


def _stand_ins(repo: Path) -> None:
    """GMR's package imports a viewer (mujoco.viewer, imageio) and torch at import time; the
    retargeter uses neither. Put empty modules in their place, then import the package."""
    sys.path.insert(0, str(repo))
    viewer = types.ModuleType("general_motion_retargeting.robot_motion_viewer")
    viewer.RobotMotionViewer = None
    kin = types.ModuleType("general_motion_retargeting.kinematics_model")
    kin.KinematicsModel = None
    loader = types.ModuleType("general_motion_retargeting.data_loader")
    loader.load_robot_motion = None
    for mod in (viewer, kin, loader):
        sys.modules[mod.__name__] = mod


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x)


def _min_rotation(a: np.ndarray, b: np.ndarray):
    """The smallest rotation taking direction ``a`` to ``b`` (scipy Rotation)."""
    from scipy.spatial.transform import Rotation as R

    a, b = _unit(a), _unit(b)
    axis = np.cross(a, b)
    s, c = np.linalg.norm(axis), float(a @ b)
    if s < 1e-12:
        return R.identity()
    return R.from_rotvec(axis / s * np.arctan2(s, c))


def _frame_offsets(model, table: dict, pose: dict) -> dict:
    """Per human body of ``table`` (GMR's ik_match_table: robot body → [human body, …]) the
    rotation offset ``O`` with ``R_human(calibration) · O = R_face · D · R_robot(q = 0)``:
    ``R_face`` the yaw that turns the robot's +x to the actor's facing, ``D`` the smallest
    rotation that turns the robot limb's direction at q = 0 (in its facing frame) into the
    actor's in the calibration frame (thigh: hip → knee, shank: knee → ankle, foot: ankle →
    toe, arm: shoulder → elbow, forearm and hand: elbow → wrist; pelvis and torso: none)."""
    import mujoco as mj
    from scipy.spatial.transform import Rotation as R

    d = mj.MjData(model)
    mj.mj_forward(model, d)

    def rpos(name):
        return d.xpos[model.body(name).id].copy()

    def hpos(name):
        return np.asarray(pose[name][0], float)

    left = hpos("LeftUpLeg") - hpos("RightUpLeg")
    left[2] = 0.0
    face = _unit(np.cross(left, [0.0, 0.0, 1.0]))
    R_face = R.from_rotvec([0.0, 0.0, np.arctan2(face[1], face[0])])
    dirs = {}  # robot body → (robot direction at q = 0, human direction in the calibration)
    for s, S in (("left", "Left"), ("right", "Right")):
        dirs[f"{s}_hip_yaw_link"] = (rpos(f"{s}_knee_link") - rpos(f"{s}_hip_pitch_link"),
                                     hpos(f"{S}Leg") - hpos(f"{S}UpLeg"))
        dirs[f"{s}_knee_link"] = (rpos(f"{s}_ankle_roll_link") - rpos(f"{s}_knee_link"),
                                  hpos(f"{S}Foot") - hpos(f"{S}Leg"))
        dirs[f"{s}_ankle_roll_link"] = (rpos(f"{s}_toe_link") - rpos(f"{s}_ankle_roll_link"),
                                        hpos(f"{S}Toe") - hpos(f"{S}Foot"))
        dirs[f"{s}_shoulder_yaw_link"] = (rpos(f"{s}_elbow_link")
                                          - rpos(f"{s}_shoulder_roll_link"),
                                          hpos(f"{S}ForeArm") - hpos(f"{S}Arm"))
        for b in (f"{s}_elbow_link", f"{s}_wrist_yaw_link"):
            dirs[b] = (rpos(f"{s}_wrist_roll_link") - rpos(f"{s}_elbow_link"),
                       hpos(f"{S}Hand") - hpos(f"{S}ForeArm"))
    out = {}
    for body, entry in table.items():
        human = entry[0]
        q0 = d.xquat[model.body(body).id]
        R_robot = R.from_quat(q0, scalar_first=True)
        D = R.identity()
        if body in dirs:
            a, b = dirs[body]
            D = _min_rotation(a, R_face.inv().apply(b))
        R_human = R.from_quat(pose[human][1], scalar_first=True)
        out[human] = R_human.inv() * R_face * D * R_robot
    return out


def load_cmu(path: str):
    """A CMU BVH as GMR's frames (``{body: (position [m], quaternion w x y z)}`` per frame, z
    up, LAFAN1 names, the FootMod bodies as GMR's loader makes them) with GMR's reader; the
    calibration frame apart; the frame rate; the height."""
    from general_motion_retargeting.utils.lafan_vendor import utils
    from general_motion_retargeting.utils.lafan_vendor.extract import read_bvh
    from scipy.spatial.transform import Rotation as R

    data = read_bvh(path)
    rates = [float(line.split(":")[1]) for line in open(path) if line.startswith("Frame Time")]
    fps = 1.0 / rates[0]
    rot, pos = utils.quat_fk(data.quats, data.pos, data.parents)
    M = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])  # GMR's Y-up → Z-up (load_lafan1_file)
    qM = R.from_matrix(M).as_quat(scalar_first=True)
    frames = []
    for k in range(pos.shape[0]):
        f = {}
        for i, bone in enumerate(data.bones):
            f[RENAMES.get(bone, bone)] = (pos[k, i] @ M.T * CMU_UNIT,
                                          utils.quat_mul(qM, rot[k, i]))
        f["LeftFootMod"] = (f["LeftFoot"][0], f["LeftToe"][1])
        f["RightFootMod"] = (f["RightFoot"][0], f["RightToe"][1])
        frames.append(f)
    calib = frames[0]
    height = float(calib["Head"][0][2] - min(calib["LeftToe"][0][2], calib["RightToe"][0][2])
                   + HEAD_TOP)
    return frames[1:], calib, fps, height


def main(repo: str, src: str, out: str) -> None:
    _stand_ins(Path(repo))
    import mujoco as mj
    from general_motion_retargeting import GeneralMotionRetargeting as GMR

    frames, calib, fps, height = load_cmu(src)
    gmr = GMR(src_human="bvh", tgt_robot="unitree_g1", actual_human_height=height)
    offsets = _frame_offsets(gmr.model, gmr.ik_match_table1, calib)
    for table, rots in ((gmr.ik_match_table1, gmr.rot_offsets1),
                        (gmr.ik_match_table2, gmr.rot_offsets2)):
        for entry in table.values():
            if entry[0] in rots:
                rots[entry[0]] = offsets[entry[0]]
    qpos = []
    t0 = time.perf_counter()
    for f in frames:
        qpos.append(gmr.retarget({k: (p.copy(), q.copy()) for k, (p, q) in f.items()}))
    seconds = time.perf_counter() - t0
    m = gmr.model
    names = [mj.mj_id2name(m, mj.mjtObj.mjOBJ_JOINT, i) for i in range(m.njnt)
             if m.jnt_type[i] != mj.mjtJoint.mjJNT_FREE]
    np.savez(out, qpos=np.array(qpos), joint_names=np.array(names), fps=fps, seconds=seconds,
             height=height, scale=gmr.human_scale_table[gmr.human_root_name])


if __name__ == "__main__":
    main(*sys.argv[1:4])
