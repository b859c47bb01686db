"""Demonstrations from files: OpenSim coordinate files (``.mot``) and the shipped real walk."""

from __future__ import annotations

import re
import warnings
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import InvalidInputError, UnitsWarning
from ..model.contact import ContactForces, FootForces
from ..model.motion import Motion

__all__ = ["read_mot", "read_opensim", "human_walk", "human_walk_path", "human_walk_3d",
           "human_walk_3d_folder", "one_stride", "cmu_walk_path", "write_subject01_c3d"]


def human_walk_path() -> Path:
    """Path of the shipped OpenSim walk (``walk_gait1018_state_reference.mot``, 60 Hz, degrees)."""
    folder = resources.files("gdimitate") / "data" / "gait" / "opensim_subject01_walk"
    return Path(str(folder / "walk_gait1018_state_reference.mot"))


def read_mot(path: str | Path) -> dict[str, np.ndarray]:
    """Read an OpenSim ``.mot``/``.sto`` table into ``{column: (T,) array}``, values as stored
    (read by :func:`gdimitate.io.opensim.read_table`, whose errors it raises; one row suffices).

    Column names are shortened to their coordinate name (``/jointset/hip_r/hip_flexion_r/value``
    → ``hip_flexion_r``). Angles stay in the file's unit (the header's ``inDegrees`` tells);
    the key ``"__in_degrees__"`` holds that flag as a 0-d boolean array. A flag that the
    angle-like columns contradict (``inDegrees=no`` with values beyond 2π, ``yes`` with every
    angle within ±π°) gives a :class:`~gdimitate.errors.UnitsWarning`.

    Raises:
        OpenSimFormatError (a FileFormatError): not text (a binary file), no column names,
            repeated column names (also after shortening); OpenSimDataError (an
            InvalidInputError): no such file, no ``endheader``, a malformed numeric table.
    """
    from ..errors import OpenSimFormatError
    from ..model.osim._table import read_table

    table = read_table(path, min_rows=1)
    short = [n.split("/")[-2] if n.endswith("/value") else n.split("/")[-1]
             for n in table.names]
    twice = sorted({n for n in short if short.count(n) > 1})
    if twice:
        raise OpenSimFormatError(f"{table.path}: repeated column names {twice}")
    out = {n: table.data[:, i] for i, n in enumerate(short)}  # views: no copy of a big table
    flag = table.header.get("indegrees", "").strip().lower()
    if flag in ("yes", "no"):
        _check_degrees_flag(table.path, out, flag == "yes")
    out["__in_degrees__"] = np.asarray(flag == "yes")
    return out


#: Columns that are not angles (time, translations, forces, torques, points, speeds).
_NOT_ANGLE = re.compile(r"^time$|_t[xyz]$|_[vp][xyz]$|force|torque|moment|speed|activation",
                        re.IGNORECASE)


def _check_degrees_flag(path: Path, table: dict[str, np.ndarray], in_degrees: bool) -> None:
    """Warn when the angle-like columns contradict the ``inDegrees`` flag."""
    angles = [a for n, a in table.items() if not _NOT_ANGLE.search(n)]
    big = max((float(np.nanmax(np.abs(np.where(np.isfinite(a), a, np.nan))))
               for a in angles if np.isfinite(a).any()), default=0.0)  # one column at a time
    if not angles or big == 0.0:
        return
    if not in_degrees and big > 2 * np.pi:
        warnings.warn(f"{path}: inDegrees=no, but angle columns reach {big:.3g} (> 2π rad); "
                      "are they in degrees? Fix the header's inDegrees flag.", UnitsWarning,
                      stacklevel=3)
    elif in_degrees and big < np.pi:
        warnings.warn(f"{path}: inDegrees=yes, but every angle column stays within ±{big:.3g}°"
                      " (a motion in radians?). Fix the header's inDegrees flag.",
                      UnitsWarning, stacklevel=3)


def _grf_contact(grf_path: Path, t: np.ndarray, threshold: float) -> tuple[dict, float]:
    """Stance flags from measured vertical GRF (OpenSim: ``ground_force_vy`` right foot,
    ``1_ground_force_vy`` left foot, Y up) resampled onto ``t``; and the body mass [kg] from the
    mean total vertical force."""
    g = read_mot(grf_path)
    for col in ("ground_force_vy", "1_ground_force_vy"):
        if col not in g:
            raise InvalidInputError(f"{grf_path}: no column {col!r} (OpenSim GRF file expected)")
    right = np.interp(t, g["time"], g["ground_force_vy"])
    left = np.interp(t, g["time"], g["1_ground_force_vy"])
    mass = float(np.mean(g["ground_force_vy"] + g["1_ground_force_vy"]) / 9.81)
    return {"left": left > threshold, "right": right > threshold}, mass


def read_opensim(path: str | Path, height: float = 1.75, mass: float | None = None,
                 grf: str | Path | None = None, contact_threshold: float = 20.0,
                 base: str = "ground", belt_speed: float | None = None):
    """Read an OpenSim sagittal coordinates file → ``(robot, motion)``.

    The file needs ``pelvis_tilt``, ``hip_flexion_r/l``, ``knee_angle_r/l`` and
    ``ankle_angle_r/l`` (OpenSim's signs: hip flexion +, knee negative in flexion, ankle
    dorsiflexion +; ``pelvis_tx``/``pelvis_ty`` are not used: the base is placed so that the
    stance foot stands on the ground without slipping, which also turns a treadmill walk into
    overground progression). The demonstrator is a planar human with Winter's segment ratios
    scaled to ``height`` [m] (default 1.75 m); ``mass`` [kg] defaults to the mean measured
    vertical GRF / g when ``grf`` is given, else 70 kg.

    Contact: from the measured vertical GRF in ``grf`` (an OpenSim GRF ``.mot``; a foot is in
    stance above ``contact_threshold`` [N]); without it, a foot is in stance while its sole is
    within 1 % of the body height of the lower sole.

    ``base``: ``"ground"`` (default) places the floating base so the stance sole stands still on
    z = 0 — consistent contacts for the adaptor; ``"measured"`` uses the file's
    ``pelvis_tx``/``pelvis_ty`` plus a treadmill ``belt_speed`` [m/s] (estimated from the
    stance feet when ``None``), shifted so the stance soles touch z = 0 on average — the
    measured body motion, whose centre-of-mass acceleration reproduces the measured GRF
    direction (see ``tests/io/test_gait.py``).
    """
    from ..model.kinematics import kinematic_contact, robot_motion
    from ..model.robot import Robot
    from ..model.sagittal import compose_q, ground_base
    from ..model.urdfgen import human_spec

    d = read_mot(path)
    _refuse_full_body(path, d)
    need = ["time", "pelvis_tilt", "hip_flexion_r", "knee_angle_r", "ankle_angle_r",
            "hip_flexion_l", "knee_angle_l", "ankle_angle_l"]
    missing = [c for c in need if c not in d]
    if missing:
        raise InvalidInputError(f"{path}: missing columns {missing}; found {sorted(d)}")
    scale = np.pi / 180.0 if bool(d["__in_degrees__"]) else 1.0
    t = d["time"] - d["time"][0]
    for c in need[1:]:
        if not np.all(np.isfinite(d[c])):
            raise InvalidInputError(f"{path}: column {c} has NaN/inf")
    contact = None
    if grf is not None:
        contact, measured_mass = _grf_contact(Path(grf), d["time"], contact_threshold)
        mass = measured_mass if mass is None else mass
    robot = Robot.from_spec(human_spec(height=height, mass=70.0 if mass is None else mass))
    torso = d["pelvis_tilt"] * scale
    angles = {}
    for side, s in (("left", "l"), ("right", "r")):
        angles[side] = np.column_stack([
            torso + d[f"hip_flexion_{s}"] * scale,
            d[f"knee_angle_{s}"] * scale,
            d[f"ankle_angle_{s}"] * scale,
        ])
    q = compose_q(robot, torso, angles)
    if contact is None:
        contact = kinematic_contact(robot, q, tol=0.01 * height)
    if base == "ground":
        q = ground_base(robot, q, contact)
    elif base == "measured":
        q = _measured_base(robot, q, contact, d, t, belt_speed)
    else:
        raise InvalidInputError(f"base must be 'ground' or 'measured'; got {base!r}")
    return robot, robot_motion(robot, t, q, contact)


#: Coordinates of full-body (3-D) OpenSim models that a sagittal model has no joint for.
_OUT_OF_PLANE = ("pelvis_list", "pelvis_rotation", "hip_adduction_r", "hip_adduction_l",
                 "hip_rotation_r", "hip_rotation_l", "subtalar_angle_r", "subtalar_angle_l",
                 "lumbar_bending", "lumbar_rotation")


def _refuse_full_body(path, d: dict) -> None:
    """A full-body 3-D coordinates file would lose its out-of-plane angles here: refuse it."""
    from ..errors import OpenSimDataError

    found = [c for c in _OUT_OF_PLANE if c in d]
    if found:
        raise OpenSimDataError(
            f"{path} is a full-body 3-D coordinates file (it has {found[:4]}); the sagittal "
            "reader would drop those angles. Read it with gdimitate.opensim.read_coordinates("
            "path, Robot.from_osim(model.osim)) (gdimitate.gait.human_walk_3d() for the shipped "
            "walk)")


def _measured_base(robot, q, contact, d, t, belt_speed):
    from ..model.kinematics import frame_paths

    for c in ("pelvis_tx", "pelvis_ty"):
        if c not in d:
            raise InvalidInputError(f"base='measured' needs column {c!r}")
    q = q.copy()
    ix, iz = robot.idx_q("base_x"), robot.idx_q("base_z")
    q[:, ix], q[:, iz] = d["pelvis_tx"], d["pelvis_ty"]
    soles = frame_paths(robot, q, [robot.legs[s].sole for s in ("left", "right")])
    sole = {s: soles[robot.legs[s].sole] for s in ("left", "right")}
    if belt_speed is None:  # stance feet ride the belt backwards at -belt_speed
        v = [np.gradient(sole[s][:, 0], t)[contact[s]] for s in ("left", "right")]
        belt_speed = -float(np.median(np.concatenate(v)))
    q[:, ix] = d["pelvis_tx"] - d["pelvis_tx"][0] + belt_speed * t
    low = [sole[s][contact[s], 2] for s in ("left", "right")]
    q[:, iz] -= float(np.median(np.concatenate(low)))
    return q


def human_walk(height: float = 1.75):
    """The shipped real treadmill walk (OpenSim subject01, 60 Hz, 2.5 s, about two strides)
    with measured-GRF contact → ``(robot, motion)``. See :func:`read_opensim`."""
    folder = human_walk_path().parent
    return read_opensim(human_walk_path(), height=height,
                        grf=folder / "walk_gait1018_subject01_grf.mot")


def human_walk_3d_folder() -> Path:
    """Folder of the shipped full-body 3-D walk (OpenSim subject01 walk1: ``subject01.osim``,
    ``subject01_walk1_ik.mot``, ``subject01_walk1_grf.mot`` + ``.xml``, ``subject01_walk1.trc``,
    OpenSim's own ``std_subject01_InverseDynamics.sto``; README.txt, LICENSE.txt, NOTICE)."""
    return Path(str(resources.files("gdimitate") / "data" / "gait" / "opensim_subject01_walk1_3d"))


def cmu_walk_path() -> Path:
    """The shipped BVH walk: CMU motion-capture subject 02, trial 01 (``cmu_02_01.bvh``; its
    README.txt gives the origin and terms)."""
    return Path(str(resources.files("gdimitate") / "data" / "gait" / "cmu_02_01" /
                    "cmu_02_01.bvh"))


def write_subject01_c3d(path: str | Path) -> Path:
    """Write the shipped 3-D walk (OpenSim subject01 walk1) as a gait-lab C3D at ``path`` →
    the path: its 41 markers (60 Hz) and one force plate per foot (the measured ground
    reaction at the file's 600 Hz; each plate the rectangle around that foot's centres of
    pressure, 10 cm wider on every side), read back like a lab's own file (the README's
    gait-lab example, the docs' figure)."""
    import warnings

    from ..model.robot import Robot
    from .c3d import ForcePlate, write_c3d
    from .opensim import read_grf, read_trc

    folder = human_walk_3d_folder()
    robot = Robot.from_osim(folder / "subject01.osim")
    forces = read_grf(folder / "subject01_walk1_grf.mot", robot,
                      folder / "subject01_walk1_grf.xml")
    with warnings.catch_warnings():  # the trial's own marker gaps, reported when it is read
        warnings.simplefilter("ignore")
        markers = read_trc(folder / "subject01_walk1.trc")
    plates = []
    for k, side in enumerate(("right", "left"), start=1):
        f = forces[side]
        c = f.cop[f.contact]
        lo, hi, z = c.min(0) - 0.1, c.max(0) + 0.1, float(c[:, 2].mean())
        corners = np.array([[lo[0], lo[1], z], [hi[0], lo[1], z], [hi[0], hi[1], z],
                            [lo[0], hi[1], z]])
        plates.append(ForcePlate(forces.t, f.force, f.cop, f.torque, corners, k))
    return write_c3d(path, markers, plates)


def human_walk_3d(overground: bool = True):
    """The shipped full-body 3-D treadmill walk → ``(robot, motion, forces)``.

    ``robot``: :meth:`Robot.from_osim` of the subject's scaled OpenSim model (free-flyer
    pelvis, 72.6 kg; soles on the lab floor below the foot markers of the trial's ``.trc``);
    ``motion``: its inverse-kinematics angles (60 Hz, t = 0.5–4.0 s, 211
    frames) read by :func:`gdimitate.io.opensim.read_coordinates`, ``contact`` the measured stance
    (vertical force > 20 N); ``forces``: the measured ground reaction forces of both feet on
    the motion's times (:func:`gdimitate.io.opensim.read_grf` with the trial's ExternalLoads).

    ``overground`` (default ``True``): the treadmill trial turned overground — the belt speed,
    estimated from the stance feet, times t added to the pelvis x and to the centres of
    pressure (:func:`gdimitate.io.opensim.treadmill_to_overground`); ``forces.frame_note`` says
    which was done and the speed. ``False`` keeps the treadmill kinematics (as OpenSim's own
    inverse dynamics of this trial used them).
    """
    from ..model.robot import Robot
    from .opensim.coordinates import read_coordinates
    from .opensim.grf import read_grf
    from .opensim.treadmill import treadmill_to_overground

    folder = human_walk_3d_folder()
    robot = Robot.from_osim(folder / "subject01.osim", markers=folder / "subject01_walk1.trc")
    motion = read_coordinates(folder / "subject01_walk1_ik.mot", robot)
    forces = read_grf(folder / "subject01_walk1_grf.mot", robot,
                      folder / "subject01_walk1_grf.xml", t=motion.t)
    motion = motion.replace(contact=forces.contact)
    if overground:
        motion, forces = treadmill_to_overground(robot, motion, forces)
    return robot, motion, forces


def one_stride(motion: Motion, forces: ContactForces, side: str = "right"
               ) -> tuple[Motion, ContactForces]:
    """The first full stride of ``motion`` (from one heel strike of ``side`` to the next, found
    in its contact schedule) and the forces on the same frames."""
    c = np.asarray(motion.contact[side], int)
    strikes = np.flatnonzero(np.diff(c) == 1) + 1
    if strikes.size < 2:
        raise InvalidInputError(f"the demonstration has fewer than two {side} heel strikes; "
                                "no full stride to adapt")
    sl = slice(int(strikes[0]), int(strikes[1]) + 1)
    m = motion.replace(t=motion.t[sl], q=motion.q[sl], v=None, a=None,
                       contact={s: v[sl] for s, v in motion.contact.items()})
    f = ContactForces(forces.t[sl], {s: FootForces(x.force[sl], x.cop[sl], x.torque[sl],
                                                   x.contact[sl])
                                     for s, x in forces.feet.items()},
                      forces.source, forces.frame_note + f"; one {side} stride")
    return m, f
