"""A planar walking generator (the paper's Fig. 3): hip and foot paths → joint angles.

The hip moves forward at constant speed and constant height. Each step (half a stride) starts in
double support (both soles flat on the ground) for a fraction ``1 − single_support`` of its
duration, then the rear foot swings to one step length ahead of the stance foot along a cycloid
(zero velocity at lift-off and touch-down) raised by ``step_height``. Human walking spends 85 %
of each step in single support; small robots of the paper's era about 35 % (docs/design.md §4).
Joint
angles come from two-link inverse kinematics with the feet kept flat and the torso upright, and
the result is checked against Pinocchio forward kinematics on the robot's own model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError
from ..model.kinematics import frame_paths, joint_paths, robot_motion
from ..model.motion import Motion
from ..model.robot import Robot
from ..model.sagittal import compose_q, sagittal_leg
from ..types import SIDES
from .twolink import ik2

__all__ = ["GaitSpec", "HUMAN_GAIT", "ROBOT_GAIT", "walking_motion"]


@dataclass(frozen=True)
class GaitSpec:
    """Parameters of the generated gait.

    ``step_length``: distance between successive footholds, as a fraction of leg length
    (thigh + shank); ``step_height``: swing-sole clearance, fraction of leg length;
    ``period``: stride time (two steps) [s]; ``single_support``: fraction of each step in single
    support; ``extension``: hip-to-ankle distance at the most stretched instant as a fraction of
    the leg length (< 1 keeps the knee bent, away from the singularity); ``cycles``: strides;
    ``rate``: samples per second [Hz].
    """

    step_length: float = 0.6
    step_height: float = 0.06
    period: float = 1.2
    single_support: float = 0.85
    extension: float = 0.985
    cycles: int = 2
    rate: float = 100.0

    def __post_init__(self) -> None:
        checks = {
            "step_length": 0 < self.step_length < 1.9,
            "step_height": 0 <= self.step_height < 0.5,
            "period": 0 < self.period < 60,
            "single_support": 0 < self.single_support <= 1,
            "extension": 0.3 < self.extension < 1,
            "cycles": int(self.cycles) == self.cycles and self.cycles >= 1,
            "rate": 1 <= self.rate <= 10000,
        }
        for k, ok in checks.items():
            if not ok:
                raise InvalidInputError(f"GaitSpec.{k}={getattr(self, k)!r} is out of range")


HUMAN_GAIT = GaitSpec(single_support=0.85)
"""The paper's demonstrator gait (its Fig. 3): 85 % of each step in single support."""
ROBOT_GAIT = GaitSpec(single_support=0.35)
"""A small robot of the paper's era: 35 % of each step in single support."""


def walking_motion(robot: Robot, spec: GaitSpec = HUMAN_GAIT) -> Motion:
    """Generate a walking :class:`Motion` for ``robot`` (planar model or any biped with legs).

    Uses the left leg's thigh/shank/foot lengths for both legs. The stride starts with the left
    foot in front, in double support.
    """
    leg = sagittal_leg(robot, "left")
    L, f = leg.thigh + leg.shank, leg.foot
    S = spec.step_length * L
    h = spec.step_height * L
    d = 1.0 - spec.single_support
    Ts = spec.period / 2
    n_steps = 2 * int(spec.cycles)
    t = np.arange(0.0, n_steps * Ts + 0.5 / spec.rate, 1.0 / spec.rate)
    reach = S * (1 + d) / 2  # horizontal hip-to-ankle offset at the end of double support
    if reach >= spec.extension * L:
        raise InvalidInputError(
            f"step_length {spec.step_length} × leg {L:.3f} m is too long to reach with "
            f"single_support {spec.single_support}; shorten the step")
    H = np.sqrt((spec.extension * L) ** 2 - reach**2) + f  # hip height above the ground
    v = S / Ts
    hip_x = (S - d * S) / 2 + v * t - S  # rear foot (right) at x = -S at t = 0, left at 0
    k = np.minimum((t // Ts).astype(int), n_steps - 1)
    tau = (t - k * Ts) / Ts  # phase within the step, 0..1
    # footholds: right at -S, left at 0; step k: right swings if k even, left if odd
    sole = {s: np.zeros((t.size, 2)) for s in SIDES}
    contact = {s: np.ones(t.size, dtype=bool) for s in SIDES}
    for side, first in (("right", 0), ("left", 1)):
        start0 = -S if side == "right" else 0.0
        for i in range(t.size):
            steps_done = (k[i] - first + 1) // 2 if k[i] >= first else 0  # completed swings
            x = start0 + 2 * S * steps_done
            swinging = k[i] % 2 == first % 2 and tau[i] > d
            z = 0.0
            if swinging:
                s = (tau[i] - d) / (1 - d)
                x += 2 * S * (s - np.sin(2 * np.pi * s) / (2 * np.pi))
                z = h * (1 - np.cos(2 * np.pi * s)) / 2
                contact[side][i] = False
            sole[side][i] = (x, z)
    angles = {}
    for s in SIDES:
        ankle_x, ankle_z = sole[s][:, 0], sole[s][:, 1] + f
        th1, th2, ok = ik2(ankle_x - hip_x, ankle_z - H, (leg.thigh, leg.shank))
        if not ok.all():
            raise InvalidInputError(f"{robot.name}: the {s} foot path is out of reach; "
                                    "shorten step_length or lower extension")
        angles[s] = np.column_stack([th1, th2, -(th1 + th2)])  # feet flat
    q = compose_q(robot, np.zeros(t.size), angles)
    # place the base so the hip midpoint follows (hip_x, H)
    hips = joint_paths(robot, q, [robot.legs[s].hip for s in SIDES])
    mid = (hips[robot.legs["left"].hip] + hips[robot.legs["right"].hip]) / 2
    q = _shift_base(robot, q, hip_x - mid[:, 0], H - mid[:, 2])
    motion = robot_motion(robot, t, q, contact)
    _check_fk(robot, q, sole, f)
    return motion


def _shift_base(robot: Robot, q: np.ndarray, dx: np.ndarray, dz: np.ndarray) -> np.ndarray:
    q = q.copy()
    if robot.base == "planar":
        q[:, robot.idx_q("base_x")] += dx
        q[:, robot.idx_q("base_z")] += dz
    else:
        q[:, 0] += dx
        q[:, 2] += dz
    return q


def _check_fk(robot: Robot, q: np.ndarray, sole: dict[str, np.ndarray], foot: float) -> None:
    """Pinocchio FK of the generated q must put the soles where the planner put them."""
    got = frame_paths(robot, q, [robot.legs[s].sole for s in SIDES])
    for s in SIDES:
        p = got[robot.legs[s].sole]
        err = np.max(np.abs(p[:, [0, 2]] - sole[s]))
        tol = 1e-9 if robot.base == "planar" else 1e-3 * robot.legs[s].length + abs(
            robot.legs[s].foot - foot)
        if err > tol:
            raise InvalidInputError(
                f"{robot.name}: generated {s} sole path deviates {err:.3g} m from the plan in "
                "Pinocchio FK (legs not planar enough for this generator)")
