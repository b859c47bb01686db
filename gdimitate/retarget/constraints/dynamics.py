"""Whole-body dynamics with every joint's torque limit.

``rnea(q, v, a) − Σ_c J_c(q)ᵀ w_c = Sᵀ τ`` (Featherstone's recursive Newton-Euler with the
contact wrenches inside the recursion, :meth:`gdimitate.symbolic.SymbolicModel.rnea_contact`):
the unactuated base rows vanish (in N and N·m, so that IPOPT's absolute constraint tolerance
is the audit's: equalities, never relaxed) and each actuated
joint's ``τ_j / τ_max,j`` lies in [−1, 1] (relaxable). A joint the user freezes still has its
torque counted here.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..knot import Knot

NAME = "dynamics"
RELAX = True


def torques(k: Knot) -> ca.SX:
    """Generalised forces ``(nv,)`` [N, N·m] the actuators must supply at this knot."""
    frames = [k.contacts[s].frame for s in ("left", "right")]
    return k.sym.rnea_contact_expr(frames, [k.wrench_world(s) for s in ("left", "right")])


def expr(k: Knot) -> tuple[ca.SX, ca.SX]:
    """``(base rows [N, N·m] (nb,), τ_act / τ_max (n_act,) + slack)``."""
    tau = torques(k)
    base = tau[k.base_idx.tolist()]
    act = tau[k.act_idx.tolist()] * k.P("inv_effort")
    return base, act + k.slack(len(k.act_idx))


def bounds(spec) -> tuple[np.ndarray, np.ndarray]:
    nb, na, T = spec.n_base, spec.n_act, spec.T
    lo = np.concatenate([np.zeros((T, nb)), -np.ones((T, na))], axis=1)
    return lo, -lo
