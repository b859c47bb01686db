"""When to stop a solve: the best feasible iterate once the cost has settled.

On the whole-body problems IPOPT reaches a feasible, near-optimal iterate in a few dozen
iterations and then crawls: at barrier parameter 1e-11 its steps alternately break and restore
feasibility while the cost falls by ~1e-5 per iteration (Talos, 100 knots: cost 0.8926 at
iteration 48, 0.8904 at iteration 99, its own convergence test still unmet after 200; dual
infeasibility stays near 1.5e-4 so no "acceptable" test passes either). :class:`Plateau`
watches every iterate from the iteration callback, keeps the best *feasible* one (every row
within ``viol_tol`` in its scaled units — the adaptor's ``tol``, 1e-6 by default; the base
rows of the dynamics, in N and N·m, are divided by m·g for this test and made exact
afterwards by :mod:`.polish`) and asks IPOPT to
stop once the best feasible cost has improved by less than ``rel_tol`` over ``window``
iterations. The solve then returns that iterate, marked :data:`PLATEAU`.

An iterate counts only once IPOPT's barrier parameter μ is at most ``mu_tol`` (:data:`MU_TOL`
= 1e-8 against the cost as the adaptor states it; the solve passes ``MU_TOL`` times IPOPT's
``obj_scaling_factor``, since IPOPT's μ weighs the barrier against the *scaled* cost): a
feasible iterate of a barrier subproblem with a large μ is still pushed away from its active
bounds by the barrier. Without this test, monotone μ from 1e-3
stopped the paper's Case I at an iterate with μ = 1.8e-7 that missed Eq. (1) by 1.96e-6 rad;
with it, 4.3e-8 rad (36 iterations instead of 28). Under adaptive μ Case I settles at
iteration 10 instead of 7 with the same 6.4e-7 rad.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Plateau", "PLATEAU", "MU_TOL"]

MU_TOL = 1e-8
"""The stop's barrier-parameter test against the unscaled cost (module docstring)."""

PLATEAU = "Feasible_Cost_Settled"
"""``SolverInfo.status`` of a solve that :class:`Plateau` stopped."""


@dataclass
class Plateau:
    """The stopping rule (module docstring). ``lbg``, ``ubg``: row bounds; ``row_scale``:
    per-row divisor of the violation; thresholds with their defaults."""

    lbg: np.ndarray
    ubg: np.ndarray
    row_scale: np.ndarray
    viol_tol: float = 1e-8
    rel_tol: float = 1e-3
    window: int = 5
    best_f: float = np.inf
    best_x: np.ndarray | None = None
    trace: list = field(default_factory=list)
    settle: bool = True
    budget: int = 10**9
    stall_after: int = 40
    stall_window: int = 20
    stall_ratio: float = 0.9
    stall_floor: float = 1e-2
    least_viol: float = np.inf
    least_x: np.ndarray | None = None
    viol_trace: list = field(default_factory=list)
    reason: str = ""
    mu_tol: float = 1e-8
    mu_trace: list = field(default_factory=list)

    def violation(self, g: np.ndarray) -> float:
        """Largest scaled row violation of the row values ``g``."""
        if not g.size:
            return 0.0
        v = (np.maximum(self.lbg - g, 0) + np.maximum(g - self.ubg, 0)) / self.row_scale
        return float(np.max(v))

    def update(self, f: float, x: np.ndarray, g: np.ndarray, mu: float = 0.0) -> bool:
        """Record one iterate (cost ``f``, variables ``x``, row values ``g``, ``mu``: IPOPT's
        barrier parameter there — a feasible iterate is a candidate only when ``mu`` ≤
        :attr:`mu_tol`); True when the solve should stop (:attr:`reason` says why:
        ``"settled"``, ``"stalled"`` or ``"budget"``)."""
        viol = self.violation(g)
        self.mu_trace.append(mu)
        if viol <= self.viol_tol and f < self.best_f and mu <= self.mu_tol:
            self.best_f, self.best_x = f, np.array(x, dtype=float).ravel()
        if viol < self.least_viol:
            self.least_viol, self.least_x = viol, np.array(x, dtype=float).ravel()
        self.trace.append(self.best_f)
        self.viol_trace.append(viol)
        if len(self.trace) >= self.budget:
            self.reason = "budget"
            return True
        if self._stalled():
            self.reason = "stalled"
            return True
        if not self.settle:
            return False
        n = self.window
        if len(self.trace) <= n or not np.isfinite(self.trace[-1 - n]):
            return False
        old, new = self.trace[-1 - n], self.trace[-1]
        if old - new <= self.rel_tol * max(1.0, abs(new)):
            self.reason = "settled"
            return True
        return False

    def _stalled(self) -> bool:
        """No feasible iterate yet, and the least violation of the last ``stall_window``
        iterations is still above ``stall_floor`` (clearly infeasible, not a solve closing in
        on feasibility: Talos's violation wanders around 1e-3 before it converges) and no better
        than ``stall_ratio`` × the least before them (after at least ``stall_after``
        iterations): the rows cannot all be met from here."""
        v, n = self.viol_trace, self.stall_window
        if self.best_x is not None or len(v) < max(self.stall_after, n + 1):
            return False
        recent = min(v[-n:])
        return recent > self.stall_floor and recent > self.stall_ratio * min(v[:-n])
