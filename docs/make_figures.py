"""Regenerate the documentation's figures (docs/img, shown by the user guide) from the project's own
functions (scenario code, not API).

    python docs/make_figures.py [NAME ...]      # default: all; writes docs/img/<name>.png
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

IMG = Path(__file__).parent / "img"


def force_direction_3d() -> Path:
    """Measured vs estimated (dynamics, com) force directions of the shipped 3-D walk."""
    import gdimitate as gd
    from gdimitate.apps.figures import plot_force_directions
    from gdimitate.assess.metrics import force_direction

    robot, motion, forces = gd.gait.human_walk_3d()
    dirs = {"measured": force_direction(robot, motion, "measured", forces=forces),
            "dynamics (kinematics only)": force_direction(robot, motion, "dynamics"),
            "com (measured CoP)": force_direction(robot, motion, "com", forces=forces)}
    path = IMG / "force_direction_3d.png"
    plot_force_directions(motion.t, dirs, motion.contact,
                          "subject01 walk: push on the ground, measured vs estimated", path)
    return path


def adaptor_g1() -> Path:
    """The whole shipped 3-D walk adapted to G1: each sole's centre of pressure inside its
    rectangle, and the push direction of G1's planned wrenches vs the measured one."""
    import gdimitate as gd
    from gdimitate.apps.figures import plot_force_directions, plot_sole_cop
    from gdimitate.assess.metrics import ForceDirection, force_direction, frame_rotations

    human, walk, forces = gd.gait.human_walk_3d()
    robot = gd.Robot.from_library("g1")
    r = gd.adapt(walk, human, robot, "optimal", force="measured", forces=forces, verbose=False)
    M = r.motion
    plot_sole_cop(r.wrenches, r.contacts, M.contact,
                  "G1, whole 3-D walk: planned centre of pressure in each sole",
                  IMG / "adaptor_g1_cop.png")
    push = {s: -np.einsum("tij,tj->ti", frame_rotations(robot, M.q, r.contacts[s].frame),
                          r.wrenches[s][:, :3]) for s in ("left", "right")}
    mine = {s: ForceDirection.from_vectors(push[s], M.contact[s], "G1 plan")
            for s in ("left", "right")}
    path = IMG / "adaptor_g1_push.png"
    plot_force_directions(walk.t, {"measured (human)": force_direction(
        human, walk, "measured", forces=forces), "G1 plan (its wrenches)": mine},
        walk.contact, "push on the ground: G1's planned wrenches vs the subject's measured",
        path, times={"G1 plan (its wrenches)": M.t})
    return path


def gait_lab() -> Path:
    """From the gait lab to G1: the subject01 trial as a C3D → marker-based inverse
    kinematics (vs OpenSim's own IK .mot), the plates' forces on the feet, and for one stride
    (right heel strike to the next) G1's planned push vs the measured one (whole-body optimal
    adaptor, audited)."""
    import tempfile

    import matplotlib.pyplot as plt

    import gdimitate as gd
    from gdimitate.assess.metrics import ForceDirection, force_direction, frame_rotations

    folder = gd.gait.human_walk_3d_folder()
    with tempfile.TemporaryDirectory() as tmp:
        c3d = gd.gait.write_subject01_c3d(Path(tmp) / "subject01_walk1.c3d")
        demo = gd.load_demonstration(folder / "subject01.osim", markers=c3d)
    human, walk, forces = demo.robot, demo.motion, demo.forces
    ref = gd.opensim.read_coordinates(folder / "subject01_walk1_ik.mot", human)
    g1 = gd.Robot.from_library("g1")
    stride, stride_forces = gd.gait.one_stride(walk, forces, "right")  # heel strike to strike
    r = gd.adapt(stride, human, g1, "optimal", force="measured", forces=stride_forces,
                 verbose=False)
    push = {s: -np.einsum("tij,tj->ti", frame_rotations(g1, r.motion.q, r.contacts[s].frame),
                          r.wrenches[s][:, :3]) for s in ("left", "right")}
    measured = force_direction(human, stride, "measured", forces=stride_forces)
    fig, ax = plt.subplots(2, 2, figsize=(11, 7))
    for j, style in (("hip_flexion_r", "C0"), ("knee_angle_r", "C1"), ("ankle_angle_r", "C2")):
        i = human.idx_q(j)
        ax[0, 0].plot(walk.t, np.degrees(walk.q[:, i]), style, label=f"{j}: our IK (C3D)")
        ax[0, 0].plot(ref.t, np.degrees(ref.q[:, i]), style + "--", label="OpenSim's IK")
    ax[0, 0].set(xlim=(walk.t[0], walk.t[-1]), ylabel="angle [deg]",
                 title=f"marker IK, {len(demo.ik.names)} markers")
    ax[0, 0].legend(fontsize=7, ncol=2)
    for s, style in (("left", "C0"), ("right", "C3")):
        ax[0, 1].plot(walk.t, forces[s].force[:, 2], style, label=f"{s} foot")
    ax[0, 1].set(ylabel="vertical force [N]", title="C3D force plates, assigned by proximity")
    ax[0, 1].legend(fontsize=8)
    for k, s in enumerate(("left", "right")):
        mine = ForceDirection.from_vectors(push[s], r.motion.contact[s], "G1")
        a = ax[1, k]
        a.plot(stride.t, np.degrees(measured[s].sagittal), "k", label="measured (human)")
        a.plot(r.motion.t, np.degrees(mine.sagittal), "C1--", label="G1 plan")
        a.set(xlabel="t [s]", ylabel="sagittal push [deg]",
              title=f"{s} foot: push direction, one stride")
        a.legend(fontsize=8)
    verdict = "feasible" if r.audit.feasible else "NOT feasible"
    fig.suptitle(f"gait-lab C3D → marker IK → G1, one stride (audit: {verdict})")
    fig.tight_layout()
    path = IMG / "gait_lab_g1.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(r.audit.summary() if hasattr(r.audit, "summary") else r.audit)
    return path


def arms_g1() -> Path:
    """One stride of the 3-D walk on a full-body demonstrator (subject01 with Rajagopal-style
    arms swinging against the legs, tests/opensim_ref/with_arms.py) adapted to G1: each
    shoulder pitch against the demonstrator's arm flexion (mapped), and the closest approach
    of G1's own collision geometries (limb–limb, limb–trunk) over the stride."""
    import tempfile
    import warnings

    import matplotlib.pyplot as plt

    import gdimitate as gd
    from gdimitate.io.opensim import read_coordinates, read_grf
    from gdimitate.model.selfcollision import self_collision
    from gdimitate.retarget.bodymap import body_map, following

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "opensim_ref"))
    from with_arms import arm_swing, write_model

    folder = gd.gait.human_walk_3d_folder()
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        human = gd.Robot.from_osim(write_model(folder / "subject01.osim",
                                               Path(tmp) / "armed.osim"))
        walk = arm_swing(human, read_coordinates(folder / "subject01_walk1_ik.mot", human))
        forces = read_grf(folder / "subject01_walk1_grf.mot", human,
                          folder / "subject01_walk1_grf.xml", t=walk.t)
        g1 = gd.Robot.from_library("g1")
    demo, fs = gd.gait.one_stride(walk.replace(contact=forces.contact), forces, "left")
    r = gd.adapt(demo, human, g1, "optimal", force="measured", forces=fs, rate=20,
                 verbose=False)
    rep = following(body_map(human, g1), demo, human, r.motion, g1)
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.4))
    for s, c in (("left", "C0"), ("right", "C1")):
        f = rep[f"{s}_shoulder_pitch_joint"]
        _, scale, offset = body_map(human, g1).joints[f.demonstrator]
        ax[0].plot(demo.t, scale * demo.column(f.demonstrator) + offset, c + "--",
                   label=f"demonstrator {f.demonstrator} (mapped)")
        ax[0].plot(r.motion.t, r.motion.column(f.imitator), c,
                   label=f"G1 {s} shoulder pitch: r = {f.r:.2f}, range ×{f.ratio:.2f}")
    ax[0].set(xlabel="t [s]", ylabel="angle [rad]", title="arms: G1 vs the demonstrator")
    ax[0].legend(fontsize=7)
    d = self_collision(g1).distances(r.motion.q).min(axis=1)
    ax[1].plot(r.motion.t, d * 1e3, "k")
    ax[1].axhline(0, color="r", lw=0.8)
    ax[1].set(xlabel="t [s]", ylabel="closest pair [mm]",
              title=f"self-collision clearance ({len(self_collision(g1).pairs)} pairs)")
    fig.tight_layout()
    path = IMG / "arms_g1.png"
    fig.savefig(path, dpi=110)
    print(r.audit.summary(only_failed=True))
    return path


FIGURES = {"force_direction_3d": force_direction_3d, "adaptor_g1": adaptor_g1,
           "gait_lab": gait_lab, "arms_g1": arms_g1}

if __name__ == "__main__":
    names = sys.argv[1:] or list(FIGURES)
    for n in names:
        print("wrote", FIGURES[n]())
    np.seterr(all="ignore")
