"""One knot of the whole-body problem: its decision variables, parameters and the symbolic
quantities (CasADi SX) that tasks and constraints are written in.

Variables of knot k, stacked in this order (:class:`Layout`): ``q`` ``(nq,)``, ``v`` ``(nv,)``,
``a`` ``(nv,)`` (Pinocchio's conventions), one contact wrench per foot in its sole frame at the
sole origin, divided by the robot's weight m·g — ``[f; τ]`` ``(6,)``, or ``(f_x, f_z, τ_y)``
``(3,)`` for planar models — and the elastic slacks ``s⁺, s⁻ ≥ 0`` of every relaxable row
(fixed at 0 except in the least-infeasible solve). Parameters of knot k are named blocks of
one vector (step ``h``; targets ``height_<side>``, ``placement_<side>``, ``shank_<side>``,
``thigh_<side>``, ``foot_<side>``, ``torso``, ``joint_target``; the force-direction frame
``d_<side>``, ``e1_<side>``, ``e2_<side>``; ``sole_<side>`` = X, Y, μ, X − margin, Y −
margin; ``joint_weight``, ``inv_effort``, ``weights`` (√ of each cost part's weight),
``elastic``, ``tan2``, ``f_min``; then any block a part declares), so the NLP built from
these expressions is reused for any demonstration of the same shape.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..model.kinematics import actuated_v_indices, base_v_indices
from ..model.robot import SIDES, Robot
from ..model.symbolic import SymbolicModel

__all__ = ["Layout", "Knot", "Flags", "base_dofs"]


@dataclass(frozen=True)
class Flags:
    """What selects a structurally different NLP (part of the cache key): the force model's
    kind (``"force"`` for ``measured``/``dynamics``: the contact force itself; ``"segment"``,
    ``"com"``: the imitator's shank or centre-of-mass line) and whether the direction is a cone
    (half-angle > 0) rather than an equality; the number of mapped segment pairs."""

    goal: str = "force"
    cone: bool = False
    segments: int = 1


class Layout:
    """Named slices of a flat vector (``add(name, n)``, then ``sl[name]``)."""

    def __init__(self) -> None:
        self.slices: dict[str, slice] = {}
        self.size = 0

    def add(self, name: str, n: int) -> None:
        self.slices[name] = slice(self.size, self.size + n)
        self.size += n

    def __getitem__(self, name: str) -> slice:
        return self.slices[name]


def base_dofs(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """``(base velocity indices (nb,), actuated velocity indices (nv − nb,))`` of the
    imitator (:func:`gdimitate.model.kinematics.base_v_indices`, :func:`~gdimitate.model.kinematics.
    actuated_v_indices`)."""
    return base_v_indices(robot), actuated_v_indices(robot)


class Knot:
    """The SX symbols and derived expressions of one knot (see the module docstring).

    ``robot``: the imitator; ``sym``: its :class:`SymbolicModel`; ``flags``: :class:`Flags`;
    ``weights``: the weight names of the cost parts, in the order of the ``weights`` parameter
    block; ``extra``: further parameter blocks ``{name: size}`` the parts declare. The elastic
    slacks are added by :meth:`add_slacks` once the relaxable rows are counted; ``x`` (the
    knot's variables) exists from then on. ``memo`` holds quantities parts share (built
    once per knot: :meth:`torques`)."""

    def __init__(self, robot: Robot, sym: SymbolicModel, flags: Flags,
                 weights: tuple[str, ...] = (), extra: dict[str, int] | None = None):
        self.robot, self.sym, self.flags = robot, sym, flags
        self.var, self.par = Layout(), Layout()
        self.memo: dict = {}
        r, s = robot, sym
        self.planar = r.base == "planar"
        self.nw = 3 if self.planar else 6
        self.base_idx, self.act_idx = base_dofs(r)
        m = r.model
        self.act_names = tuple(
            next(m.names[j] for j in range(1, m.njoints)
                 if m.joints[j].idx_v <= iv < m.joints[j].idx_v + m.joints[j].nv)
            for iv in self.act_idx)
        self.contacts = r.require_contacts()
        self.mg = float(r.mass * np.linalg.norm(s.gravity))  # weight m·g [N]
        self.leg = {side: r.legs[side] for side in SIDES}
        self.weight_names = tuple(weights)
        v = self.var
        v.add("q", s.nq)
        v.add("v", s.nv)
        v.add("a", s.nv)
        for side in SIDES:
            v.add(f"w_{side}", self.nw)
        p = self.par
        p.add("h", 1)
        for side in SIDES:
            p.add(f"height_{side}", 1)
            p.add(f"placement_{side}", 2)
            p.add(f"shank_{side}", 3)
            p.add(f"thigh_{side}", 3)
            p.add(f"foot_{side}", 9)
            p.add(f"d_{side}", 3)
            p.add(f"e1_{side}", 3)
            p.add(f"e2_{side}", 3)
            p.add(f"sole_{side}", 5)  # X, Y, mu, X − margin, Y − margin
        p.add("torso", 9 * self.flags.segments)
        p.add("joint_target", len(self.act_idx))
        p.add("joint_weight", len(self.act_idx))
        p.add("inv_effort", len(self.act_idx))
        # √ of each cost part's weight (the residuals carry them; a parameter under a sqrt
        # would put inf·0 in the derivatives), then the elastic weight itself
        p.add("weights", len(self.weight_names))
        p.add("elastic", 1)
        p.add("tan2", 1)
        p.add("f_min", 1)
        for name, n in (extra or {}).items():
            p.add(name, n)
        # q, v, a are the symbolic model's own symbols, so that kinematics, centre of mass
        # and dynamics share one forward pass
        self.w = {side: ca.SX.sym(f"w_{side}", self.nw) for side in SIDES}
        self.p = ca.SX.sym("p", p.size)
        self.q, self.v, self.a = s.q, s.v, s.a
        self.slack_rows = 0
        self._kin()

    def add_slacks(self, n: int) -> None:
        """Add the elastic slack pairs ``s⁺, s⁻ ≥ 0`` of ``n`` relaxable rows; defines ``x``."""
        self.slack_rows = n
        self.var.add("s_plus", n)
        self.var.add("s_minus", n)
        self.s_plus = ca.SX.sym("s_plus", n)
        self.s_minus = ca.SX.sym("s_minus", n)
        self.x = ca.vertcat(self.q, self.v, self.a, *[self.w[side] for side in SIDES],
                            self.s_plus, self.s_minus)

    # ------------------------------------------------------------------ access
    def P(self, name: str) -> ca.SX:
        """Parameter block ``name`` of this knot."""
        return self.p[self.par[name]]

    def weight(self, name: str) -> ca.SX:
        """``√w`` of the cost weight ``name`` (a :class:`~.params.Weights` field)."""
        return self.P("weights")[self.weight_names.index(name)]

    def torques(self) -> ca.SX:
        """Generalised forces ``(nv,)`` [N, N·m] the actuators must supply at this knot:
        ``rnea(q, v, a) − Σ_c J_c(q)ᵀ w_c`` (built once, shared by the dynamics parts)."""
        if "torques" not in self.memo:
            frames = [self.contacts[s].frame for s in SIDES]
            self.memo["torques"] = self.sym.rnea_contact_expr(
                frames, [self.wrench_world(s) for s in SIDES])
        return self.memo["torques"]

    def wrench_local(self, side: str) -> ca.SX:
        """``(6,)`` ``[f; τ]`` [N, N·m] of a foot in its sole frame (planar: f_y = τ_x = τ_z =
        0). The decision variables are this wrench divided by m·g (scaling: a standing foot's
        variables are of order 1, like the configuration's)."""
        w = self.mg * self.w[side]
        if self.planar:
            z = ca.SX(0)
            return ca.vertcat(w[0], z, w[1], z, w[2], z)
        return w

    # ------------------------------------------------------------------ kinematics
    def _kin(self) -> None:
        s = self.sym
        self.sole_p, self.sole_R = {}, {}
        self.hip, self.knee, self.ankle = {}, {}, {}
        for side in SIDES:
            c = self.contacts[side]
            self.sole_R[side], self.sole_p[side] = s.placement(c.frame)
            leg = self.leg[side]
            # every joint has a JOINT frame of its own name in a Pinocchio model
            self.hip[side] = s.placement(leg.hip)[1]
            self.knee[side] = s.placement(leg.knee)[1]
            self.ankle[side] = s.placement(leg.ankle or leg.sole)[1]
        self.com = s.com_expr

    def wrench_world(self, side: str) -> ca.SX:
        """The foot's wrench in world axes at the sole origin ``(6,)``."""
        w = self.wrench_local(side)
        R = self.sole_R[side]
        return ca.vertcat(ca.mtimes(R, w[:3]), ca.mtimes(R, w[3:]))
