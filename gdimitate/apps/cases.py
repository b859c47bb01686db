"""The paper's three cases (docs/design.md §4): the exact inputs behind its figures."""

from __future__ import annotations

from ..errors import UnknownNameError
from ..model.motion import Motion
from ..model.robot import Robot
from ..planar.walking import HUMAN_GAIT, GaitSpec, walking_motion

__all__ = ["PAPER_CASES", "paper_case"]

#: case name → (demonstrator model, imitator model); lengths in docs/design.md §4's table.
PAPER_CASES = {
    "I": ("case1_demonstrator", "hoap2"),
    "II": ("case2_demonstrator", "hoap2"),
    "humanoid": ("humanoid_demonstrator", "humanoid_imitator"),
}


def paper_case(name: str, gait: GaitSpec = HUMAN_GAIT) -> tuple[Robot, Robot, Motion]:
    """``(demonstrator, imitator, demonstration)`` for case ``"I"``, ``"II"`` or
    ``"humanoid"``: the planar models of ``urdf/`` and the generated human-like walk (85 %
    single support, step 0.6 leg lengths, two strides of 1.2 s at 100 Hz) of the
    demonstrator."""
    if name not in PAPER_CASES:
        raise UnknownNameError("paper case", name, PAPER_CASES)
    d, i = PAPER_CASES[name]
    demo = Robot.from_library(d)
    return demo, Robot.from_library(i), walking_motion(demo, gait)
