"""What the commands share: the exit statuses, the argument types, the robot and
demonstration options (:func:`add_robot_args`, :func:`add_demonstration_args`) and what they
load, and the adaptation of ``adapt``, ``view`` and ``entrain``."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, cast

from ...assess.verdict import EXIT_NOT_FEASIBLE

if TYPE_CHECKING:
    from ...types import ForceModel

__all__ = ["EXIT_STATUS", "METHODS", "METHOD_HELP", "add_demonstration_args", "add_robot_args",
           "default_story", "force_goal", "json_object", "load_robot", "port_number",
           "positive_seconds", "read_demonstration", "run_adaptation"]

#: The command's exit statuses and what each means (also in ``gdimitate --help``).
EXIT_STATUS = {
    0: "done",
    1: "batch: some files failed (listed in its summary)",
    2: "error (the message on stderr says what to fix)",
    EXIT_NOT_FEASIBLE: "written, but not feasible, a goal unmet, the CPG replay check failed "
                       "or the simulated robot fell",
    130: "interrupted (Ctrl-C)",
    143: "terminated (SIGTERM)",
}


def port_number(text: str) -> int:
    """argparse type of a TCP port 1–65535."""
    try:
        p = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 1 <= p <= 65535:
        raise argparse.ArgumentTypeError(f"port must be in 1-65535, got {p}")
    return p


def positive_seconds(text: str) -> float:
    """argparse type of a finite duration > 0 [s]."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds > 0, got {text}")
    return v


def json_object(path: str | None, what: str):
    """The JSON object in ``path`` (``--legs``/``--contacts``), or None."""
    if path is None:
        return None
    from ...errors import InvalidInputError
    from ...model.inputs import read_json

    value = read_json(path, what)  # bounded: size, nesting, digits, no NaN
    if not isinstance(value, dict):
        raise InvalidInputError(f"{what} {path}: expected a JSON object "
                                '{"left": {...}, "right": {...}}')
    return value


def load_robot(spec: str, a: argparse.Namespace):
    """``Robot.load`` of a library name or a .urdf/.osim path with the command's
    ``--package-dir``/``--contacts``/``--legs``/``--massless-joints``."""
    from ...model.robot import Robot

    massless = [j for j in (a.massless_joints or "").split(",") if j.strip()]
    return Robot.load(spec, package_dir=a.package_dir,
                      contacts=json_object(a.contacts, "--contacts"),
                      legs=json_object(a.legs, "--legs"),
                      massless_joints=[j.strip() for j in massless])


def add_robot_args(p: argparse.ArgumentParser, flag: str, default: str | None,
                   what: str) -> None:
    from ...model.library import list_robots

    p.add_argument(flag, default=default,
                   help=f"{what}: a library name ({', '.join(list_robots())}) or a .urdf/.osim "
                        "path" + (" (default: %(default)s)" if default else ""))
    p.add_argument("--package-dir", default=None,
                   help=f"folder resolving the {flag[2:]} URDF's package:// meshes (default: "
                        "the URDF's folder)")
    p.add_argument("--legs", default=None, metavar="FILE.json",
                   help=f"the {flag[2:]}'s legs where names don't tell them: "
                        '{"left": {"hip": J, "knee": J, "ankle": J, "sole": FRAME}, "right": …}')
    p.add_argument("--contacts", default=None, metavar="FILE.json",
                   help=f"the {flag[2:]}'s sole rectangles: "
                        '{"left": {"half_length": m, "half_width": m, "frame"?: F, "mu"?: x}, …}')
    p.add_argument("--massless-joints", default=None, metavar="J[,J…]",
                   help=f"moving joints of the {flag[2:]} URDF allowed to carry no mass (e.g. "
                        "a hand's finger joints); a library robot's presets are kept")


def add_demonstration_args(p: argparse.ArgumentParser, positional: str, default_note: str
                           ) -> None:
    p.add_argument(positional, nargs="?", default=None,
                   help="demonstration: OpenSim .mot/.sto, .osim (with --coordinates or "
                        "--markers), markers .trc/.c3d (with --osim), .bvh or a gdimitate .npz "
                        f"(default: {default_note})")
    p.add_argument("--grf", default=None,
                   help="OpenSim ground-reaction-force .mot/.sto of a .mot/.sto/.osim "
                        "demonstration (its ExternalLoads .xml is used when it lies beside it)")
    p.add_argument("--coordinates", default=None,
                   help="the .mot/.sto joint angles of an .osim demonstration")
    p.add_argument("--markers", default=None,
                   help="the .trc/.c3d markers of an .osim demonstration (marker-based IK)")
    p.add_argument("--osim", default=None,
                   help="the OpenSim model of a full-body .mot/.sto or a .trc/.c3d "
                        "demonstration")
    p.add_argument("--demonstrator", default=None,
                   help="robot of a .npz that records none (library name or .urdf path)")
    p.add_argument("--treadmill", action="store_true",
                   help="keep a treadmill trial's kinematics (default: turned overground "
                        "when forces are given)")


def read_demonstration(path: str | None, a: argparse.Namespace):
    """The command's demonstration (:func:`gdimitate.io.demonstration.load_demonstration`);
    ``None`` → ``None``."""
    if path is None:
        return None
    from ...io.demonstration import load_demonstration
    from ...model.robot import Robot

    robot = None
    if a.osim is not None:
        robot = Robot.from_osim(a.osim)
    elif a.demonstrator is not None:
        robot = Robot.load(a.demonstrator)
    return load_demonstration(path, grf=a.grf, coordinates=a.coordinates, robot=robot,
                              overground=not a.treadmill, markers=a.markers)


#: the adaptor methods of demo, adapt, view and entrain, and their help
METHODS = ["optimal", "analytic", "copy"]


METHOD_HELP = ("adaptor: optimal (whole-body, contact-consistent, within the imitator's "
                "limits), analytic (the paper's Eq. 1, sagittal), copy (joint angles; the "
                "baseline) (default: %(default)s)")


def default_story(imitator: str | None, a: argparse.Namespace):
    """The default demonstration and imitator
    (:func:`gdimitate.apps.demo.default_demonstration`,
    G1 unless ``imitator`` names another), announced."""
    from ..demo import DEFAULT_IMITATOR, default_demonstration

    robot, motion, forces = default_demonstration()
    print(f"no demonstration given: one stride of the shipped real 3-D walk ({motion.T} frames, "
          f"{motion.t[-1] - motion.t[0]:.2f} s, measured forces)", flush=True)
    return robot, motion, forces, load_robot(imitator or DEFAULT_IMITATOR, a)


def run_adaptation(a: argparse.Namespace, demonstration: str | None):
    """``(demonstrator, demonstration, forces, result)`` of the command's adaptation."""
    from ...adaptation.adaptor import adapt

    demo = read_demonstration(demonstration, a)
    if demo is None:
        robot, motion, forces, imitator = default_story(a.imitator, a)
    else:
        robot, motion, forces = demo.robot, demo.motion, demo.forces
        print(f"read {demo.source}: {demo.note}", flush=True)
        imitator = load_robot(a.imitator, a)
    force = cast("ForceModel", force_goal(getattr(a, "force", None), a.method, forces))
    print(f"adapting {motion.T} frames of {robot.name} → {imitator.name} "
          f"(method={a.method}, force={force}) …", flush=True)
    options = {"forces": forces} if a.method == "optimal" and forces is not None else {}
    if getattr(a, "periodic", False):  # one stride as a periodic cycle (optimal only)
        options["periodic"] = True
    return robot, motion, forces, adapt(motion, robot, imitator, a.method, force=force,
                                        **options)


def force_goal(given: str | None, method: str, forces) -> str:
    """The force-direction goal: the one given, else the measured push where the
    demonstration has forces and the method keeps them (optimal), else ``segment``."""
    if given is not None:
        return given
    return "measured" if forces is not None and method == "optimal" else "segment"
