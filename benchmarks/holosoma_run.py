"""Run OmniRetarget's retargeter (``holosoma-retargeting`` 0.1.0, PyPI) on global joint
positions, in the Python that has it installed (``pip install -e '.[peers]'``, or a venv of
its own: it pins numpy==2.3.5 and pulls torch). ``benchmarks/peers.py --holosoma-python``
calls this script; nothing of gdimitate is imported here.

Usage: ``python holosoma_run.py IN.npz OUT.npz``

``IN.npz``: ``global_joint_positions`` ``(T, 22, 3)`` [m] in holosoma's ``smplx`` joint
layout (Pelvis, L_Hip, R_Hip, Spine1, L_Knee, R_Knee, Spine2, L_Ankle, R_Ankle, Spine3,
L_Foot, R_Foot, Neck, L_Collar, R_Collar, Head, L_Shoulder, R_Shoulder, L_Elbow, R_Elbow,
L_Wrist, R_Wrist), z up, centred on the origin, and ``height`` [m] of the demonstrator.
Runs holosoma's own ``robot_only`` pipeline (its G1 model, interaction-mesh SQP with foot
sticking and joint limits, its defaults but for the ground grid, widened at its default
spacing to cover the whole walk) through ``examples.robot_retarget.main``. Writes
``OUT.npz``: ``qpos`` ``(T, 36)`` in its MuJoCo G1 order (x y z, quaternion w x y z, 29
joints), ``joint_names`` (that order), ``seconds`` (the retargeting's wall time), ``scale``
(robot over human height, as holosoma scaled the input).
"""

import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np


def main(src: str, out: str) -> None:
    import holosoma_retargeting
    import mujoco
    from holosoma_retargeting.config_types.retargeting import RetargetingConfig
    from holosoma_retargeting.config_types.robot import RobotConfig
    from holosoma_retargeting.examples import robot_retarget

    pkg = Path(holosoma_retargeting.__file__).parent
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "data"
        data.mkdir()
        d = np.load(src)
        np.savez(data / "demo.npz", global_joint_positions=d["global_joint_positions"],
                 height=d["height"])
        cfg = RetargetingConfig(task_type="robot_only", robot="g1", data_format="smplx",
                                task_name="demo", data_path=data, save_dir=Path(tmp) / "res")
        # the ground grid (its default: 15 x 15 points over ±1 m) widened at the same spacing
        # to cover the whole walk, scaled as holosoma scales it
        scale = RobotConfig(robot_type="g1").ROBOT_HEIGHT / float(d["height"])
        reach = float(np.abs(d["global_joint_positions"][..., :2]).max()) * scale + 1.0
        lo, hi = cfg.task_config.ground_range
        size = int(round((cfg.task_config.ground_size - 1) * 2 * reach / (hi - lo))) + 1
        cfg.task_config = replace(cfg.task_config, ground_range=(-reach, reach),
                                  ground_size=max(size, cfg.task_config.ground_size))
        here = Path.cwd()
        t0 = time.perf_counter()
        try:
            import os

            os.chdir(pkg)  # its configs name models/… relative to the package
            robot_retarget.main(cfg)
        finally:
            os.chdir(here)
        seconds = time.perf_counter() - t0
        res = np.load(Path(tmp) / "res" / "demo.npz")
        qpos = res["qpos"]
    model = mujoco.MjModel.from_xml_path(str(pkg / "models/g1/g1_29dof.xml"))
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, i) for i in range(model.njnt)]
    names = [n for i, n in enumerate(names) if model.jnt_type[i] != mujoco.mjtJoint.mjJNT_FREE]
    np.savez(out, qpos=qpos, joint_names=np.array(names), seconds=seconds, scale=scale)


if __name__ == "__main__":
    main(*sys.argv[1:3])
