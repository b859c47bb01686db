"""Built-in examples: a demonstrator, its motion, an imitator and its adapted motion, by name.

Used by ``gdimitate view`` and the notebooks. Names: ``human-walk`` (the shipped real walk →
HOAP-2-sized imitator), ``case-I``, ``case-II``, ``humanoid`` (the paper's cases), and any
library robot name (the real walk retargeted onto it, e.g. ``talos``, ``g1``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from ..errors import UnknownNameError
from ..model.library import list_robots
from ..types import AdaptMethod
from .cases import PAPER_CASES

if TYPE_CHECKING:  # the command line reads EXAMPLES without loading Pinocchio
    from ..assess.result import AdaptedMotion
    from ..model.motion import Motion
    from ..model.robot import Robot

__all__ = ["Example", "EXAMPLES", "example"]


class Example(NamedTuple):
    """A demonstration and its adaptation."""

    demonstrator: Robot
    demonstration: Motion
    imitator: Robot
    adapted: AdaptedMotion


def _names() -> list[str]:
    return ["human-walk", *(f"case-{c}" if c != "humanoid" else c for c in PAPER_CASES),
            *[r for r in list_robots() if r not in ("hoap2",)]]


EXAMPLES = _names()


def example(name: str = "human-walk", method: AdaptMethod = "analytic") -> Example:
    """Build a named example (see the module docstring) with the given adaptor method."""
    from ..adaptation.adaptor import adapt
    from ..io.gait import human_walk
    from ..model.robot import Robot
    from .cases import paper_case

    if name not in EXAMPLES:
        raise UnknownNameError("example", name, EXAMPLES)
    if name.startswith("case-") or name == "humanoid":
        demo, imit, motion = paper_case(name.removeprefix("case-"))
    else:
        demo, motion = human_walk()
        imit = Robot.from_library("hoap2" if name == "human-walk" else name)
    return Example(demo, motion, imit, adapt(motion, demo, imit, method))
