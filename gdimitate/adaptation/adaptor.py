"""``adapt``: regenerate a demonstrated motion for an imitator robot.

Methods: ``"analytic"`` — the paper's Eq. (1) per leg (docs/design.md §4); ``"copy"`` — the
paper's "without adaptor" baseline (same planar joint angles); ``"optimal"`` — the whole-body,
contact-consistent trajectory optimisation (:mod:`gdimitate.retarget`). Every method returns an
:class:`AdaptedMotion`: the motion, a kinematic comparison with the demonstration
(:class:`AdaptationReport`) and, for the optimal method, the contact wrenches, the contacts
used, the solver's account and the independent physical audit
(:func:`gdimitate.assess.audit.audit`).
"""

from __future__ import annotations

from ..assess.result import AdaptationReport, AdaptedMotion, compare
from ..errors import InvalidInputError, UnknownNameError
from ..model.motion import Motion
from ..model.robot import Robot
from ..planar.analytic import adapt_planar, check_pair
from ..types import AdaptMethod, ForceModel

__all__ = ["AdaptationReport", "AdaptedMotion", "adapt", "METHODS", "compare"]

METHODS: tuple[AdaptMethod, ...] = ("analytic", "copy", "optimal")


def _check_size(demo: Motion, imitator: Robot, method: str, rate: float | None) -> None:
    """Refuse, before any allocation, a time axis in the wrong unit and an optimal knot grid
    beyond :data:`~gdimitate.safety.MAX_KNOT_RATE` or :data:`~gdimitate.safety.MAX_ARRAY_BYTES`
    (e.g. a BVH frame time of 1e6 s, ``rate=1e6``)."""
    from ..safety import MAX_KNOT_RATE, check_array_size, check_positive, check_time_axis

    check_time_axis(demo.t, "the demonstration")
    if method != "optimal":
        return
    if rate is not None:
        check_positive("rate [knots/s]", rate, upper=MAX_KNOT_RATE)
    from ..retarget import DEFAULT_RATE

    knots = (demo.t[-1] - demo.t[0]) * (DEFAULT_RATE if rate is None else rate) + 1
    check_array_size("the optimal adaptor's knot grid (knots × state)",
                     (knots, imitator.model.nq + 2 * imitator.model.nv))


def adapt(demo: Motion, demonstrator: Robot, imitator: Robot, method: AdaptMethod = "optimal",
          force: ForceModel = "segment", forces=None, rate: float | None = None,
          **options) -> AdaptedMotion:
    """Regenerate ``demo`` (a motion of ``demonstrator``) for ``imitator``.

    ``method``: ``"analytic"`` (Eq. 1), ``"copy"`` (same planar joint angles — the paper's
    baseline) or ``"optimal"`` (the whole-body optimal adaptor,
    :func:`gdimitate.retarget.adapt_optimal`, which documents ``options``). ``force``: the
    force-direction model — ``"segment"``, ``"com"``, ``"dynamics"`` or ``"measured"`` (which
    needs ``forces``, the demonstrator's measured
    :class:`~gdimitate.contact.ContactForces`). ``rate`` [knots/s]: the optimal method's knot
    grid (default :data:`gdimitate.retarget.DEFAULT_RATE`). With Eq. (1) and joint copying
    the imitator keeps the demonstrator's torso and ankle angles and its base is placed so
    that the stance foot stands on the ground without slipping.
    """
    if method not in METHODS:
        raise UnknownNameError("method", method, METHODS)
    check_pair(demo, demonstrator, imitator)
    _check_size(demo, imitator, method, rate)
    if method == "optimal":
        from ..retarget import adapt_optimal

        return adapt_optimal(demo, demonstrator, imitator, force=force, forces=forces,
                             rate=rate, **options)
    if options or forces is not None or rate is not None:
        given = sorted(options) + [k for k, v in (("forces", forces), ("rate", rate))
                                   if v is not None]
        raise InvalidInputError(f"method {method!r} takes no options; got {given}")
    return adapt_planar(demo, demonstrator, imitator, method, force)
