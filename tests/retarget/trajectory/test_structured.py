"""The stage-wise statement of the whole-body problem for CasADi's fatrop
(gdimitate.retarget.trajectory.structured; issue 37, docs/design.md §6 "what was tried for
speed"): the same rows and cost as the knot's compiled functions, the integration rows as
gap-closing rows ``x_{k+1} − F(x_k, u_k)``, the contact hold with the next state
substituted. Checked on the SX functions (no compilation); the solve itself is measured by
``python benchmarks/adaptor.py --structured`` (slower than IPOPT: not wired into ``adapt``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.helpers import shared

RNG = np.random.default_rng(37)


@pytest.fixture(scope="module")
def g1_problem(walk_3d):
    """G1's formulation of the shipped 3-D walk at 20 knots/s (the default parts, measured
    push) with a demonstration's parameters and warm start."""
    _, _, form, num = shared.g1_measured_problem(walk_3d, 20)
    return form, num


def test_stage_rows_and_cost_are_the_knots(g1_problem):
    """The pieces ``g0, g1, …`` stacked are the knot's rows ``kg`` and ``f`` its cost ``kf``
    (values at perturbed warm-start knots)."""
    from gdimitate.retarget.trajectory import codegen
    from gdimitate.retarget.trajectory import structured as SS

    form, num = g1_problem
    sx = {f.name(): f for f in SS._sx_functions(form)}
    pieces = codegen.pieces(sx, "g")
    assert len(pieces) > 1  # the inverse-dynamics rows apart from the others
    for k in (0, num.spec.T // 2, num.spec.T - 1):
        x = num.x0[:, k] + 0.01 * RNG.normal(size=form.nx)
        p = num.P[:, k]
        g = np.concatenate([np.asarray(f(x, p)).ravel() for f in pieces])
        np.testing.assert_allclose(g, np.asarray(form.fun["kg"](x, p)).ravel(),
                                   rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(float(sx["f"](x, p)), float(form.fun["kf"](x, p)),
                                   rtol=1e-10)


def test_gap_closing_rows_are_the_integration_rows(g1_problem):
    """Knot k + 1 with its ``q``, ``v`` from ``dyn`` (the gap-closing rows met) meets the
    integration rows (``pg``'s first nq + nv rows) to round-off, whatever its controls, and
    the other pair rows (the contact hold) equal ``pair`` there."""
    from gdimitate.retarget.parts.integration import Integration
    from gdimitate.retarget.trajectory import structured as SS

    form, num = g1_problem
    sx = {f.name(): f for f in SS._sx_functions(form)}
    nxs = form.knot.sym.nq + form.knot.sym.nv
    integ = next(s for p, s in zip(form.pairs, form.pair_slices) if isinstance(p, Integration))
    others = np.concatenate([np.arange(s.start, s.stop) for p, s in
                             zip(form.pairs, form.pair_slices) if not isinstance(p, Integration)])
    for k in (0, num.spec.T // 3, num.spec.T - 2):
        x0 = num.x0[:, k] + 0.02 * RNG.normal(size=form.nx)
        p1 = num.P[:, k + 1]
        x1 = num.x0[:, k + 1] + 0.02 * RNG.normal(size=form.nx)  # its controls: anything
        x1[:nxs] = np.asarray(sx["dyn"](x0, p1)).ravel()
        rows = np.asarray(form.fun["pg"](x0, x1, p1)).ravel()
        np.testing.assert_allclose(rows[integ], 0.0, atol=1e-12)
        np.testing.assert_allclose(np.asarray(sx["pair"](x0, p1)).ravel(), rows[others],
                                   rtol=1e-10, atol=1e-12)


def test_what_cannot_be_stated_stage_wise(g1_problem):
    """A seam between the last knot and the first (a periodic cycle) has no stage-wise form."""
    from gdimitate.retarget.trajectory import structured as SS

    form, _ = g1_problem
    assert SS._sx_functions(form) is not None
    assert not SS.supported(dataclasses.replace(form, seam={}))
