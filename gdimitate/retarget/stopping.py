"""When to stop a solve: the best feasible iterate once the cost has settled.

On the whole-body problems IPOPT reaches a feasible, near-optimal iterate in a few dozen
iterations and then crawls: at barrier parameter 1e-11 its steps alternately break and restore
feasibility while the cost falls by ~1e-5 per iteration (Talos, 100 knots: cost 0.8926 at
iteration 48, 0.8904 at iteration 99, its own convergence test still unmet after 200; dual
infeasibility stays near 1.5e-4 so no "acceptable" test passes either). :class:`Plateau`
watches every iterate from the iteration callback, keeps the best *feasible* one (every row
within ``viol_tol`` in its scaled units — the base rows of the dynamics, in N and N·m, are
divided by m·g for this test and made exact afterwards by :mod:`.polish`) and asks IPOPT to
stop once the best feasible cost has improved by less than ``rel_tol`` over ``window``
iterations. The solve then returns that iterate, marked :data:`PLATEAU`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Plateau", "PLATEAU"]

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

    def violation(self, g: np.ndarray) -> float:
        """Largest scaled row violation of the row values ``g``."""
        if not g.size:
            return 0.0
        v = (np.maximum(self.lbg - g, 0) + np.maximum(g - self.ubg, 0)) / self.row_scale
        return float(np.max(v))

    def update(self, f: float, x: np.ndarray, g: np.ndarray) -> bool:
        """Record one iterate; True when the solve should stop."""
        if self.violation(g) <= self.viol_tol and f < self.best_f:
            self.best_f, self.best_x = f, np.array(x, dtype=float).ravel()
        self.trace.append(self.best_f)
        n = self.window
        if len(self.trace) <= n or not np.isfinite(self.trace[-1 - n]):
            return False
        old, new = self.trace[-1 - n], self.trace[-1]
        return bool(old - new <= self.rel_tol * max(1.0, abs(new)))
