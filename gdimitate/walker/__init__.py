"""The walk that keeps going (docs/design.md §14): a demonstration → a periodic gait cycle
(``adapt(..., periodic=True)``) → a whole-body Matsuoka network tuned to it
(:class:`~.network.WalkNetwork`) → N steps in MuJoCo with the network's phase indexing the
plan and the ground feeding back into the network (:mod:`.loop`) → :class:`~.result.
WalkResult` (``walk.json``, plots, trajectory, HTML)."""

from __future__ import annotations

import warnings
from collections.abc import Callable

from ..model.robot import Robot
from .loop import WalkPush, run_loop
from .network import WalkNetwork
from .result import WalkResult

__all__ = ["walk", "periodic_cycle", "WalkResult", "WalkNetwork", "WalkPush", "WALK_RATE",
           "DEFAULT_GAIN"]

#: Knots per second of the cycle's optimal solve. The shipped walk's stride (1.233 s) at
#: 45 knots/s: G1's cycle audit-feasible in 76 iterations, Talos's in 91 (HOAP-2's too);
#: at 30 G1's solve spent its 150 iterations and missed the audit (stance velocity), at 40
#: it passed in 149 but the walk fell after 10 steps, at 35 it missed the push direction.
WALK_RATE = 45.0
#: Feedback gain of the ground into the network's input (0: open loop).
DEFAULT_GAIN = 0.5


def periodic_cycle(demo=None, demonstrator: Robot | None = None,
                   imitator: str | Robot = "g1", forces=None, rate: float = WALK_RATE,
                   say: Callable[[str], None] | None = None):
    """The periodic cycle (an :class:`~gdimitate.AdaptedMotion`) of a demonstration on
    ``imitator``: the measured push directions kept (``force="measured"``) when ``forces``
    are given. Without ``demo``: one stride (:func:`gdimitate.io.gait.one_stride`) of the shipped
    3-D walk (:func:`gdimitate.io.gait.human_walk_3d`). A feasible cycle that travels less
    than 0.8 of the scaled demonstrator's stride is solved again by the adaptor with its gait
    weights raised (:mod:`gdimitate.retarget.trajectory.stride`); ``say`` is told that line
    (``cycle.solver.retry``). Returns ``(cycle, forces)``."""
    if demo is None:
        from ..io import gait

        demonstrator, whole, forces = gait.human_walk_3d()
        demo, forces = gait.one_stride(whole, forces)
    elif demonstrator is None:
        from ..errors import InvalidInputError

        raise InvalidInputError("periodic_cycle: a demo needs its demonstrator (a Robot)")
    imit = imitator if isinstance(imitator, Robot) else Robot.load(imitator)
    opts = dict(force="measured", forces=forces) if forces is not None else {}
    cyc = _cycle(demo, demonstrator, imit, rate, opts)
    if say is not None and cyc.solver.retry:
        say(cyc.solver.retry)
    return cyc, forces


def _cycle(demo, demonstrator: Robot, imitator: Robot, rate: float, opts: dict):
    """One periodic solve (:func:`periodic_cycle`)."""
    from ..adaptation.adaptor import adapt

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return adapt(demo, demonstrator, imitator, "optimal", rate=rate, periodic=True,
                     verbose=False, **opts)


def walk(demo=None, demonstrator: Robot | None = None, imitator: str | Robot = "g1",
         steps: int = 20, *, forces=None, feedback_gain: float = DEFAULT_GAIN,
         push: WalkPush | None = None, cycle=None, network: WalkNetwork | None = None,
         rate: float = WALK_RATE) -> WalkResult:
    """Walk ``steps`` steps in MuJoCo under a whole-body oscillator network.

    ``demo``/``demonstrator``/``forces``: the demonstration (default: the shipped 3-D walk
    with its measured forces); ``imitator``: a library name or :class:`Robot` (default G1);
    ``feedback_gain``: the ground's feedback into the network (0 = open-loop replay);
    ``push``: a :class:`~.loop.WalkPush`; ``cycle``: a periodic cycle already adapted
    (skips the adaptation; pass its ``forces`` too), ``network``: a tuned
    :class:`WalkNetwork` of that cycle. Returns a :class:`WalkResult`."""
    from ..errors import InvalidInputError
    from ..sim.periodic import PeriodicReference

    if not (isinstance(steps, int) and 1 <= steps <= 1000):
        raise InvalidInputError(f"steps must be an integer in 1..1000; got {steps!r}")
    if not (feedback_gain >= 0 and feedback_gain < 100):
        raise InvalidInputError(f"feedback_gain must be in [0, 100); got {feedback_gain!r}")
    if cycle is None:
        cycle, forces = periodic_cycle(demo, demonstrator, imitator, forces, rate)
    robot = cycle.robot
    pref = PeriodicReference(robot, cycle)
    net = network or WalkNetwork.tune(robot, cycle.motion)
    tr = run_loop(robot, pref, net, steps, float(feedback_gain), push)
    return WalkResult(robot, cycle, net, pref, tr, steps, float(feedback_gain), forces)
