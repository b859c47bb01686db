"""``adapt_optimal``: the whole-body optimal adaptor's entry point — its options checked
(:func:`check_options`) and its mode picked: the trajectory mode (:mod:`.trajectory`) or the
streaming one over the frames (:mod:`.streaming`). The two modes never import each other."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..assess.metrics import FORCE_MODELS
from ..errors import InvalidInputError, UnknownNameError
from ..model.footsteps import SCALINGS, compare_gait
from ..model.motion import Motion
from ..model.robot import Robot
from .bodymap import body_map
from .info import resolve_contacts
from .params import Contact, Limits, Weights
from .streaming.adaptor import adapt_per_frame
from .trajectory.solve import STOPS, trajectory_mode

__all__ = ["adapt_optimal", "check_options", "OPTIONS", "MODES", "GAIT_SCALING"]

MODES = ("trajectory", "per_frame")

GAIT_SCALING = "geometric"
"""``gait_scaling=``'s default (:data:`gdimitate.model.footsteps.SCALINGS`): lengths × the legs'
ratio r at the demonstrator's cadence (the paper's); ``"froude"`` also runs the
demonstration's clock × √r (docs/design.md §13 says how the default was chosen)."""

OPTIONS = ("force", "forces", "rate", "mode", "weights", "limits", "contact", "body_map",
           "tol", "ipopt", "verbose", "contacts", "stop", "periodic", "gait_scaling",
           "stride_retry")
"""Keywords :func:`adapt_optimal` accepts (``adapt(..., method="optimal", **options)``)."""


def adapt_optimal(demo: Motion, demonstrator: Robot, imitator: Robot, force: str = "segment",
                  **options):
    """The whole-body optimal adaptor (``adapt(..., method="optimal", ...)`` calls it).

    Options (:data:`OPTIONS`):

    - ``forces``: the demonstrator's measured :class:`~gdimitate.contact.ContactForces`
      (needed by ``force="measured"``; they also give the contact schedule);
    - ``rate`` [knots/s]: the knot grid (default :data:`~.params.DEFAULT_RATE`, 50 Hz);
    - ``mode``: ``"trajectory"`` (one problem over all knots) or ``"per_frame"`` (the
      streaming adaptor, :class:`~.streaming.adaptor.StreamingAdaptor`, over the frames);
    - ``weights`` (:class:`~.params.Weights`), ``limits`` (:class:`~.params.Limits`),
      ``contact`` (:class:`~.params.Contact`: μ, f_min, margins, clearance, cone half-angle,
      contact rule), ``contacts`` (``{side: SoleContact | {half_length, half_width, mu}}``
      overriding the measured sole rectangles), ``body_map`` (a
      :class:`~.bodymap.BodyMap`, dict or JSON path; default: the preset);
    - ``tol``: feasibility tolerance of the optimiser's own row check (scaled units, default
      1e-6); ``stop``: when a solve ends (:data:`~.trajectory.solve.STOPS`); ``ipopt``: extra
      IPOPT options; ``verbose`` (default True): progress lines (iteration, cost, constraint
      violation) on stderr;
    - ``gait_scaling`` (:data:`GAIT_SCALING`): ``"geometric"`` — the imitator's steps are
      the demonstrator's × r, the legs' ratio, at its cadence — or ``"froude"`` — also the
      demonstration's durations × √r (the motion's times then run on that clock); the
      result's ``gait`` (:class:`~gdimitate.model.footsteps.GaitComparison`) measures the steps
      against the demonstrator's so scaled;
    - ``stride_retry`` (default True; the trajectory mode — a stream follows its frames): a
      3-D motion that is audit-feasible but travels less than 0.8 of the scaled
      demonstrator's distance is solved again with the gait's weights raised, and the second
      motion kept only where it is audit-feasible, misses no goal by more and travels further
      (:mod:`.trajectory.stride`; ``solver.retry`` says what happened); False: one solve;
    - ``periodic`` (default False): a periodic gait cycle (:mod:`.trajectory.periodic`) — one
      stride, heel strike to heel strike of the right foot, whose last knot is its first shifted
      by one stride (:class:`~.parts.periodic.PeriodicSeam`), the audit with its seam checks.

    Nothing assumes a heading (:func:`~.trajectory.solve.heading_frame`): the demonstration is
    adapted in its heading frame and the motion turned back about the vertical through the
    origin, so a walk along any direction gives the same motion up to that turn, and the report's
    sagittal angles are in the heading frame (forward = along the walk).

    Returns an :class:`~gdimitate.AdaptedMotion` with ``motion`` (``q``, ``v``, ``a``,
    ``contact`` = the schedule used), ``wrenches`` ``{side: (T, 6)}`` in each sole frame,
    ``contacts``, ``audit`` (:func:`gdimitate.assess.audit.audit` recomputed from the output) and
    ``solver`` (:class:`SolverInfo`). Never raises on an infeasible problem: the
    least-infeasible motion comes back with ``solver.unmet`` and the audit's ``binding``.
    """
    o = check_options(force, options)
    cs = resolve_contacts(imitator, o["contact"], options.get("contacts"))
    bmap = body_map(demonstrator, imitator, options.get("body_map"))
    if o["mode"] == "per_frame":
        return _per_frame(demo, demonstrator, imitator, force, o, cs, bmap,
                          options.get("ipopt"))
    return trajectory_mode(demo, demonstrator, imitator, force, o, cs, bmap, options)


def _per_frame(demo: Motion, demonstrator: Robot, imitator: Robot, force: str, o: dict,
               cs: dict, bmap, ipopt: dict | None):
    """The streaming mode over a whole demonstration, with its gait measured."""
    out = adapt_per_frame(demo, demonstrator, imitator, force=force, forces=o["forces"],
                          weights=o["weights"], limits=o["limits"], contact=o["contact"],
                          contacts=cs, body_map=bmap, tol=o["tol"], ipopt=ipopt)
    return dataclasses.replace(out, gait=compare_gait(demonstrator, demo, imitator,
                                                      out.motion))


def check_options(force: str, options: dict) -> dict:
    """:func:`adapt_optimal`'s options checked, with their defaults."""
    bad = [k for k in options if k not in OPTIONS]
    if bad:
        raise UnknownNameError("optimal-adaptor option", bad[0], OPTIONS)
    if force not in FORCE_MODELS:
        raise UnknownNameError("force model", force, FORCE_MODELS)
    o = {"mode": options.get("mode", "trajectory"), "stop": options.get("stop", "settled"),
         "weights": options.get("weights") or Weights(),
         "limits": options.get("limits") or Limits(),
         "contact": options.get("contact") or Contact(),
         "forces": options.get("forces"), "verbose": bool(options.get("verbose", True)),
         "periodic": bool(options.get("periodic", False)),
         "gait_scaling": options.get("gait_scaling", GAIT_SCALING),
         "stride_retry": bool(options.get("stride_retry", True))}
    if o["gait_scaling"] not in SCALINGS:
        raise UnknownNameError("gait scaling", o["gait_scaling"], SCALINGS)
    if o["mode"] not in MODES:
        raise UnknownNameError("mode", o["mode"], MODES)
    for name, typ in (("weights", Weights), ("limits", Limits), ("contact", Contact)):
        if not isinstance(o[name], typ):
            raise InvalidInputError(f"{name}= must be a gdimitate.retarget.{typ.__name__}; "
                                    f"got {type(o[name]).__name__}")
    o["tol"] = tol = float(options.get("tol", 1e-6))
    if not (np.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"tol must be a positive number; got {tol!r}")
    if force == "measured" and o["forces"] is None:
        raise InvalidInputError("force='measured' needs forces= (the demonstrator's measured "
                                "ContactForces)")
    if o["stop"] not in STOPS:
        raise UnknownNameError("stop rule", o["stop"], STOPS)
    if o["mode"] == "per_frame" and o["gait_scaling"] != "geometric":
        raise InvalidInputError("gait_scaling='froude' needs mode='trajectory' (a stream runs "
                                "on the demonstrator's clock)")
    if o["mode"] == "per_frame" and o["periodic"]:
        raise InvalidInputError("periodic=True needs mode='trajectory' (the seam links the "
                                "cycle's last knot to its first)")
    return o
