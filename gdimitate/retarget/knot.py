"""One knot of the whole-body problem: its decision variables, parameters and the symbolic
quantities (CasADi SX) that tasks and constraints are written in.

Variables of knot k, stacked in this order (:class:`Layout`): ``q`` ``(nq,)``, ``v`` ``(nv,)``,
``a`` ``(nv,)`` (Pinocchio's conventions), one contact wrench per foot in its sole frame at the
sole origin, divided by the robot's weight m·g — ``[f; τ]`` ``(6,)``, or ``(f_x, f_z, τ_y)``
``(3,)`` for planar models — and the
elastic slacks ``s⁺, s⁻ ≥ 0`` of every relaxable row (fixed at 0 except in the
least-infeasible fallback). Parameters of knot k are named blocks of one vector (targets, the
force-direction frame, sole sizes, weights, step ``h``), so the NLP built from these
expressions is reused for any demonstration of the same shape.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..robot import SIDES, Robot
from ..symbolic import SymbolicModel

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
    """``(base velocity indices, actuated velocity indices)`` of the imitator: the free-flyer's
    6 or the planar base's 3 unactuated rows, and every other joint's."""
    m = robot.model
    nb = 6 if robot.base == "free" else 0
    base = list(range(nb))
    if robot.base == "planar":
        base = [robot.idx_v(j) for j in ("base_x", "base_z", "base_pitch")]
    act = [i for i in range(m.nv) if i not in base]
    return np.array(base, int), np.array(act, int)


@dataclass
class Knot:
    """The SX symbols and derived expressions of one knot (see the module docstring).

    ``robot``: the imitator; ``sym``: its :class:`SymbolicModel`; ``flags``: :class:`Flags`;
    ``slack_rows``: how many relaxable rows the constraints declare (set before
    :meth:`build`)."""

    robot: Robot
    sym: SymbolicModel
    flags: Flags
    slack_rows: int
    var: Layout = field(default_factory=Layout)
    par: Layout = field(default_factory=Layout)

    def __post_init__(self) -> None:
        r, s = self.robot, self.sym
        self.planar = r.base == "planar"
        self.nw = 3 if self.planar else 6
        self.base_idx, self.act_idx = base_dofs(r)
        self.contacts = r.require_contacts()
        self.mg = float(r.mass * np.linalg.norm(s.gravity))  # weight m·g [N]
        self.leg = {side: r.legs[side] for side in SIDES}
        v = self.var
        v.add("q", s.nq)
        v.add("v", s.nv)
        v.add("a", s.nv)
        for side in SIDES:
            v.add(f"w_{side}", self.nw)
        v.add("s_plus", self.slack_rows)
        v.add("s_minus", self.slack_rows)
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
        # √ of the weights height, placement, shank, thigh, torso, smoothness, wrench, foot
        # (the residuals carry them; a parameter under a sqrt would put inf·0 in the
        # derivatives), then the elastic weight itself
        p.add("weights", 9)
        p.add("tan2", 1)
        p.add("f_min", 1)
        # q, v, a are the symbolic model's own symbols, so that kinematics, centre of mass
        # and dynamics share one forward pass
        self._w = {side: ca.SX.sym(f"w_{side}", self.nw) for side in SIDES}
        self.s_plus = ca.SX.sym("s_plus", self.slack_rows)
        self.s_minus = ca.SX.sym("s_minus", self.slack_rows)
        self.x = ca.vertcat(s.q, s.v, s.a, *[self._w[side] for side in SIDES], self.s_plus,
                            self.s_minus)
        self.p = ca.SX.sym("p", p.size)
        self.q, self.v, self.a = s.q, s.v, s.a
        self._slack_used = 0
        self._kin()

    # ------------------------------------------------------------------ access
    def P(self, name: str) -> ca.SX:
        """Parameter block ``name`` of this knot."""
        return self.p[self.par[name]]

    def weight(self, i: int) -> ca.SX:
        return self.P("weights")[i]

    def slack(self, n: int) -> ca.SX:
        """The next ``n`` relaxation terms ``s⁺ − s⁻`` (a constraint adds them to its rows)."""
        i = self._slack_used
        self._slack_used += n
        if self._slack_used > self.slack_rows:
            raise RuntimeError("more relaxable rows than declared")
        return self.s_plus[i:i + n] - self.s_minus[i:i + n]

    def wrench_local(self, side: str) -> ca.SX:
        """``(6,)`` ``[f; τ]`` [N, N·m] of a foot in its sole frame (planar: f_y = τ_x = τ_z =
        0). The decision variables are this wrench divided by m·g (scaling: a standing foot's
        variables are of order 1, like the configuration's)."""
        w = self.mg * self._w[side]
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
