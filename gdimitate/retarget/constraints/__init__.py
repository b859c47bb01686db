"""The constraints of the whole-body problem, one module each. A per-knot constraint exposes
``NAME``, ``RELAX`` (whether the least-infeasible fallback may relax it), ``expr(knot)`` — its
rows at one knot as SX — and ``bounds(spec)`` — lower and upper bounds ``(T, n)`` for a
demonstration (infinite where the schedule does not impose a row). :mod:`.integration` and
:mod:`.contact`'s hold rows link neighbouring knots; :mod:`.limits` gives variable bounds."""

from . import cone, contact, dynamics, force, integration, limits, swing

PER_KNOT = (dynamics, contact, cone, swing, force)
"""Per-knot constraint modules in row order."""

__all__ = ["PER_KNOT", "cone", "contact", "dynamics", "force", "integration", "limits",
           "swing"]
