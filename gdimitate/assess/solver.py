"""The optimal adaptor's solver record, held by :class:`~gdimitate.AdaptedMotion`
(``adapted.solver``): how the optimiser ran (:class:`SolverInfo`) and the constraint groups its
motion leaves unmet (:class:`Unmet`). Both modes of :mod:`gdimitate.retarget` fill it."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SolverInfo", "Unmet"]


@dataclass(frozen=True)
class Unmet:
    """A constraint group the returned motion does not meet (optimiser's view; the audit is
    the judge): ``name``, worst ``violation`` (in the row's own scaled units: torque/limit,
    force/(m·g), height/leg length, rad, m) and its ``knot``."""

    name: str
    violation: float
    knot: int


@dataclass(frozen=True)
class SolverInfo:
    """How the optimiser ran: IPOPT's ``status``, ``success``, ``iterations``, ``time_s``
    (solves only), ``build_s`` (0 when the NLP came from the cache), ``cached`` (the NLP was
    already built in this process), ``elastic`` (True when the hard problem failed and the
    least-infeasible solve ran), ``knots``, ``variables`` (free ones), ``constraints`` (rows
    the schedule imposes), ``unmet``, ``compiled`` (this call compiled the robot's
    derivatives to C — or started their compilation in the background; False: none needed,
    or they came from the on-disk cache), ``derivatives`` (what evaluated them: ``"C"``, or
    ``"virtual machine"``, CasADi's, while their C is compiled in the background or without
    a compiler: :mod:`gdimitate.retarget.trajectory.codegen`) and ``retry``
    (empty, or the line that says the motion was solved again for its stride and which one
    was kept: :mod:`gdimitate.retarget.trajectory.stride`; ``iterations`` and ``time_s``
    then count both solves)."""

    status: str
    success: bool
    iterations: int
    time_s: float
    build_s: float
    cached: bool
    elastic: bool
    knots: int
    variables: int
    constraints: int
    unmet: tuple[Unmet, ...] = ()
    compiled: bool = False
    retry: str = ""
    derivatives: str = "C"
