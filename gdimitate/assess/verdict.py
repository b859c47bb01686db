"""What an adaptation's result may claim, in words: the verdict every output prints.

docs/design.md §12: "feasible" only where the judge says so — the independent audit
(:func:`gdimitate.assess.audit.audit`, Pinocchio recomputation) for the optimal adaptor; Eq. (1)'s
reachability and the imitator's position limits for the kinematic methods — and a goal the
optimiser could not keep (an ``unmet`` row of its least-infeasible fallback,
:class:`gdimitate.retarget.Unmet`) is part of the verdict, not a footnote. The command line
exits with :data:`EXIT_NOT_FEASIBLE` when it wrote a result that is not feasible or leaves a
goal unmet (distinct from 2, an error).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, is_dataclass
from typing import Any

import numpy as np

from .audit.report import AT_BOUND, at_bound

__all__ = ["EXIT_NOT_FEASIBLE", "Verdict", "solver_record", "verdict", "gait_lines",
           "limits_at_bound", "push_errors", "report_lines", "written_gait_lines"]

#: Exit status of a command whose result was written but is not feasible, or whose goal (an
#: optimiser row, a replay check, a simulation that fell) is unmet.
EXIT_NOT_FEASIBLE = 3


@dataclass(frozen=True)
class Verdict:
    """``feasible``: the judge's verdict; ``judge``: who judged; ``failed``: the checks that
    failed, most violated first (the audit's ``binding``; for the kinematic methods the
    unreachable frames and violated limits); ``unmet``: ``(name, violation, knot)`` of each
    goal the optimiser's least-infeasible fallback leaves unmet (violation in the row's own
    scaled units; a push direction's in radians, :func:`push_errors`); ``solver``: the
    solver's record (:func:`solver_record`) or None;
    ``reasons``: each failed check as the judge measured it, ``"name value unit > bound at
    knot k"`` (the audit's numbers: what the console prints as the reason); ``at_bound``:
    per unmet goal, the imitator's limits the audit finds at their bound at its knot
    (:meth:`~gdimitate.assess.audit.report.AuditReport.limits_at`: what may hold it back)."""

    feasible: bool
    judge: str
    failed: tuple[str, ...]
    unmet: tuple[tuple[str, float, int], ...]
    solver: dict[str, Any] | None
    reasons: tuple[str, ...] = ()
    at_bound: tuple[tuple[str, ...], ...] = ()

    @property
    def ok(self) -> bool:
        """Feasible and no goal unmet."""
        return self.feasible and not self.unmet

    @property
    def exit_status(self) -> int:
        """0 when :attr:`ok`, else :data:`EXIT_NOT_FEASIBLE`."""
        return 0 if self.ok else EXIT_NOT_FEASIBLE

    def lines(self) -> list[str]:
        """The verdict as console lines (no leading indentation)."""
        said = self.reasons or self.failed
        out = [f"{self.judge}: " + ("feasible" if self.feasible else
                                    "NOT feasible; failed: " + "; ".join(said[:6])
                                    + (f" (and {len(said) - 6} more)"
                                       if len(said) > 6 else ""))]
        s = self.solver
        if s is not None:
            out.append(f"solver: {s['status']}, {s['iterations']} iterations, "
                       f"{s['time_s']:.1f} s" + ("; the hard problem failed: this is the "
                                                 "least-infeasible motion" if s["elastic"]
                                                 else ""))
            if s.get("retry"):
                out.append(s["retry"])
        if self.unmet:
            out.append("goals unmet: " + "; ".join(self.unmet_texts()[:6]))
        if not self.ok:
            why = "a goal is unmet" if self.feasible else "it is not feasible"
            out.append(f"result written, but {why}: exit status {EXIT_NOT_FEASIBLE}")
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any], solver: dict[str, Any] | None) -> Verdict:
        """The verdict written by :meth:`to_dict`, with the solver's record written beside it
        (a report's ``solver``): what a console renders from a written report."""
        return cls(bool(d["feasible"]), d["judge"], tuple(d["failed"]),
                   tuple((u["name"], _num(u["violation"]), int(u["knot"])) for u in d["unmet"]),
                   solver, tuple(d.get("reasons", ())),
                   tuple(tuple(u.get("at_bound", ())) for u in d["unmet"]))

    def unmet_texts(self) -> list[str]:
        """Each unmet goal as every output prints it: ``"name off by v unit at knot k"``, and
        ``" (at their bound there: …)"`` where limits are (:attr:`at_bound`)."""
        return [f"{n} off by {v:.3g}{_unit(n, v)} at knot {k}"
                + (f" (at their bound there: {', '.join(b[:4])})" if b else "")
                for (n, v, k), b in zip(self.unmet, self._bounds())]

    def _bounds(self) -> tuple[tuple[str, ...], ...]:
        return self.at_bound or tuple(() for _ in self.unmet)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``feasible``, ``ok``, ``judge``, ``failed``, ``unmet`` (list of
        ``{name, violation, knot, at_bound}``)."""
        return {"feasible": self.feasible, "ok": self.ok, "judge": self.judge,
                "failed": list(self.failed), "reasons": list(self.reasons),
                "unmet": [{"name": n, "violation": v, "knot": k, "at_bound": list(b)}
                          for (n, v, k), b in zip(self.unmet, self._bounds())]}


def push_errors(result: Any) -> dict[str, tuple[float, int, str]]:
    """Each foot's largest push-direction error, the one definition every output prints:
    ``{side: (angle [rad], knot, measure)}`` — the audit's (``measure`` ``"audit"``: the angle
    between the push of the output's wrenches and its target,
    :class:`~gdimitate.assess.audit.report.
    ForceDirectionAudit`) where it measured one (the measured and dynamics models), else the
    adaptation report's (``"sagittal"``: the force model's sagittal angle, imitator −
    demonstrator, :attr:`~gdimitate.assess.result.AdaptationReport.force_direction_error`); a side
    with neither is left out."""
    out: dict[str, tuple[float, int, str]] = {}
    aud = getattr(result, "audit", None)
    for s, fd in (aud.force_direction_error.items() if aud is not None else ()):
        if fd is not None and fd.knots > 0 and np.isfinite(fd.error_max):
            out[s] = (float(fd.error_max), int(fd.knot), "audit")
    rep = getattr(result, "report", None)
    for s, e in (rep.force_direction_error.items() if rep is not None else ()):
        a = np.abs(np.asarray(e, dtype=float))
        if s not in out and np.isfinite(a).any():
            k = int(np.nanargmax(a))
            out[s] = (float(a[k]), k, "sagittal")
    return out


def _measured(name: str, violation: float, knot: int,
              push: dict[str, tuple[float, int, str]]) -> tuple[str, float, int]:
    """An unmet solver row as said: a push direction by :func:`push_errors`' angle and knot,
    any other row by its own scaled violation."""
    head, _, side = name.partition(": ")
    if head == "force direction" and side in push:
        return name, push[side][0], push[side][1]
    return name, float(violation), int(knot)


def _as_check(row: str) -> str:
    """The audit check that measures a solver row group (``"force direction: left"`` →
    ``"force_direction:left"``; ``"audit: cop:left"`` → ``"cop:left"``)."""
    if row.startswith("audit: "):
        return row[len("audit: "):]
    head, _, side = row.partition(": ")
    return f"{head.replace(' ', '_')}:{side}" if side else row


def _reason(c: Any) -> str:
    """A failed audit check as the console says it: ``"cop:left -0.0031 m < 0 at knot 12"``."""
    op = ">" if c.sense == "max" else "<"
    where = f" at knot {c.knot}" if c.knot >= 0 else ""
    unit = f" {c.unit}" if c.unit not in ("", "-") else ""
    return f"{c.name} {c.value:.3g}{unit} {op} {c.bound:.3g}{where}"


def _unit(name: str, v: float) -> str:
    """A reading of a scaled violation where its unit is known (directions: radians)."""
    low = name.lower()
    if "direction" in low or "angle" in low or "orient" in low:
        return f" rad ({np.degrees(v):.1f}°)"
    return " (scaled)"


def solver_record(solver: Any) -> dict[str, Any] | None:
    """The optimiser's record (:class:`gdimitate.retarget.SolverInfo`: status, success,
    iterations, time, elastic, knots, variables, constraints, unmet) as plain JSON types."""
    if solver is None:
        return None
    d = asdict(solver) if is_dataclass(solver) and not isinstance(solver, type) \
        else dict(solver)
    d["unmet"] = [{"name": u["name"] if isinstance(u, dict) else u.name,
                   "violation": float(u["violation"] if isinstance(u, dict) else u.violation),
                   "knot": int(u["knot"] if isinstance(u, dict) else u.knot)}
                  for u in d.get("unmet", ())]
    return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in d.items()}


def verdict(result: Any) -> Verdict:
    """The verdict of an :class:`~gdimitate.AdaptedMotion`: the audit's for the optimal
    method, Eq. (1)'s reachability and the position limits for the kinematic ones; plus the
    solver's unmet goals that the judge does not measure itself. A goal the audit checks (the
    push direction against its target, ``force_direction:<side>``) is judged by the audit's
    value and bound alone: the solver's scaled row violation is not a second number for it.
    An unmet push direction the audit does not check (the segment and com models) is said by
    the output's own angle (:func:`push_errors`), not by the solver's row (the sine of that
    angle, or a force component over m·g)."""
    solver = solver_record(getattr(result, "solver", None))
    push = push_errors(result)
    unmet = tuple(_measured(u["name"], u["violation"], u["knot"], push)
                  for u in (solver or {}).get("unmet", ()))
    aud = getattr(result, "audit", None)
    if aud is not None:
        checked = {c.name for c in aud.checks}
        unmet = tuple(u for u in unmet if _as_check(u[0]) not in checked)
        worst = sorted((c for c in aud.checks if not c.passed), key=lambda c: -c.violation)
        return Verdict(bool(aud.feasible), "audit (Pinocchio)", tuple(aud.binding), unmet,
                       solver, tuple(_reason(c) for c in worst),
                       tuple(tuple(aud.limits_at(k)) for _, _, k in unmet))
    r = result.report
    failed = [f"{s}: {n} frames unreachable" for s, n in r.infeasible_frames.items() if n]
    failed += [f"position:{j} exceeded by {v:.3g} rad" for j, v in
               sorted(r.joint_limit_violation.items(), key=lambda kv: -kv[1])]
    return Verdict(bool(r.all_feasible), f"{r.method} method (reachability and position "
                   "limits; no dynamics checked)", tuple(failed), unmet, solver)


def limits_at_bound(aud: Any, share: float = AT_BOUND) -> list[str]:
    """The actuated joints' limits the audited motion reaches (torque or velocity at ≥
    ``share`` of its limit, most used first; then positions within
    :data:`~gdimitate.assess.audit.report.AT_POSITION` of a limit), as
    ``"velocity:J 1.00"`` — where a gait is not kept, the limits that may hold it back (at
    their bound somewhere in the motion, not proven to be the cause;
    :func:`~gdimitate.assess.audit.report.at_bound`)."""
    return at_bound(((j.name, j.torque_ratio, j.velocity_ratio, j.position_margin)
                     for j in getattr(aud, "joints", ())), share)


def gait_lines(result: Any) -> list[str]:
    """The gait comparison's console lines
    (:attr:`~gdimitate.AdaptedMotion.gait`),
    with the limits at their bound where the gait is not kept; empty without a gait."""
    g = getattr(result, "gait", None)
    if g is None:
        return []
    out = g.lines()
    aud = getattr(result, "audit", None)
    if not g.kept and aud is not None:
        lim = limits_at_bound(aud)
        out.append("limits at their bound: " + (", ".join(lim[:6]) + (
            f" (and {len(lim) - 6} more)" if len(lim) > 6 else "") if lim else "none"))
    return out


def _num(x: Any) -> float:
    """A number of a written report (``None``: NaN or infinite in the run) as a float."""
    return float("nan") if x is None else float(x)


def written_gait_lines(report: dict[str, Any]) -> list[str]:
    """:func:`gait_lines` rendered from a written report's ``gait``
    (:meth:`gdimitate.model.footsteps.GaitComparison.to_dict`) and ``audit`` (its joints)."""
    from types import SimpleNamespace

    from ..model.footsteps import GaitComparison, Step

    g = report.get("gait")
    if g is None:
        return []

    def steps(rows) -> tuple[Step, ...]:
        return tuple(Step(r["side"], -1, _num(r["t_s"]), _num(r["length_m"]),
                          _num(r["width_m"]), _num(r["stride_m"]), _num(r["duration_s"]))
                     for r in rows)

    gait = GaitComparison(
        scaling=g["scaling"], ratio=_num(g["leg_ratio"]), time_scale=_num(g["time_scale"]),
        demo=steps(g["steps_demo_scaled"]), imitator=steps(g["steps"]),
        travel_demo=_num(g["travel_demo_scaled_m"]), travel=_num(g["travel_m"]),
        duration_demo=_num(g["duration_demo_scaled_s"]), duration=_num(g["duration_s"]))
    aud = report.get("audit")
    joints = [SimpleNamespace(name=j["name"], torque_ratio=_num(j["torque_ratio"]),
                              velocity_ratio=_num(j["velocity_ratio"]),
                              position_margin=_num(j["position_margin"]))
              for j in (aud or {}).get("joints", ())]
    return gait_lines(SimpleNamespace(gait=gait, audit=None if aud is None else
                                      SimpleNamespace(joints=joints)))


def report_lines(report: dict[str, Any]) -> list[str]:
    """The verdict's and the gait's console lines rendered from a written report (its
    ``verdict``, ``solver``, ``gait`` and ``audit``): what ``gdimitate adapt`` prints, each
    number as the file holds it."""
    v = Verdict.from_dict(report["verdict"], report.get("solver"))
    return v.lines() + written_gait_lines(report)
