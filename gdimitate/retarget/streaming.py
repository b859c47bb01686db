"""Streaming mode: the same formulation on a two-knot window, one demonstration frame at a
time (``mode="per_frame"``, or :class:`StreamingAdaptor` for live input).

Frame k is solved on the window (k − 1, k) of the trajectory problem (:mod:`.problem`,
``T = 2``: the same tasks and constraints, cached once): knot k − 1 holds the committed
configuration and velocity of the previous frame (fixed), knot k is free; the solve chooses
``a_{k−1}`` and the wrenches of frame k − 1 (which the dynamics, the cones and the force
direction constrain there) together with ``q_k``, ``v_k`` (linked by the integration rows).
So each frame is final one frame late: ``a`` and the wrenches of the last frame come from its
own window. The first frame is solved on a window of two copies of itself.

Each frame's feasibility flag is the audit's (:func:`gdimitate.audit.audit`) on the window
where that frame became final — recomputed from the output, not read from the optimiser.
Force models: ``segment``, ``com`` and ``measured`` (the demonstrator's measured force of the
frame, ``step(..., forces=...)``); ``dynamics`` needs the demonstrator's future accelerations.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from ..contact import ContactForces, FootForces, SoleContact
from ..errors import InvalidInputError, UnknownNameError
from ..kinematics import robot_motion
from ..motion import Motion
from ..result import AdaptedMotion, compare
from ..robot import SIDES, Robot
from . import limits as limits_mod
from . import problem as pb
from .bodymap import BodyMap, body_map
from .knot import base_dofs
from .params import Contact, Limits, Weights
from .parts import FlatContact
from .receding import SOLVED, qp_step, wrench_qp
from .solve import (
    SolverInfo,
    Unmet,
    limited_robot,
    problem_for,
    resolve_contacts,
    run_solver,
    setup,
    wrenches_of,
)
from .targets import demonstration_targets
from .threads import single_thread

__all__ = ["StreamingAdaptor", "FrameResult", "adapt_per_frame", "STREAMING_FORCE_MODELS"]

STREAMING_FORCE_MODELS = ("segment", "com", "measured")


class FrameResult(NamedTuple):
    """One :meth:`StreamingAdaptor.step`: the new frame's ``q`` ``(nq,)`` and ``v`` ``(nv,)``;
    the previous frame, now final (``None`` at the first step): its ``a`` ``(nv,)``,
    ``wrenches`` ``{side: (6,)}`` and ``feasible`` (the audit's verdict); the solve's
    ``status``, ``iterations`` and ``time_s``."""

    q: np.ndarray
    v: np.ndarray
    previous_a: np.ndarray | None
    previous_wrenches: dict | None
    previous_feasible: bool | None
    status: str
    iterations: int
    time_s: float


class StreamingAdaptor:
    """Adapt a demonstration frame by frame (module docstring).

    ``demonstrator``, ``imitator``: robots; ``force``: one of
    :data:`STREAMING_FORCE_MODELS`; ``weights``, ``limits``, ``contact``: as for
    :func:`~.solve.adapt_optimal` (the ``"all"`` contact rule only); ``contacts``: sole
    overrides; ``body_map``; ``dt`` [s]: default frame period; ``ipopt``: extra IPOPT options
    (the first frame's solve); ``audit``: audit each frame's window in :meth:`step`
    (``FrameResult.previous_feasible``; False keeps the audit off the hot path: audit the
    assembled motion afterwards, as :func:`adapt_per_frame` does).
    """

    def __init__(self, demonstrator: Robot, imitator: Robot, force: str = "segment", *,
                 weights: Weights | None = None, limits: Limits | None = None,
                 contact: Contact | None = None, contacts: dict | None = None,
                 body_map: BodyMap | dict | str | None = None, dt: float = 1 / 60,
                 ipopt: dict | None = None, audit: bool = True):
        if force not in STREAMING_FORCE_MODELS:
            raise UnknownNameError("streaming force model", force, STREAMING_FORCE_MODELS)
        if not (np.isfinite(dt) and dt > 0):
            raise InvalidInputError(f"dt must be a positive period in seconds; got {dt!r}")
        self.contact = contact or Contact()
        if self.contact.rule != "all":
            raise InvalidInputError("the streaming mode needs contact rule 'all' (the anchor "
                                    "rule looks at the whole stance history)")
        self.demonstrator, self.imitator, self.force, self.dt = (demonstrator, imitator, force,
                                                                 float(dt))
        self.weights, self.limits = weights or Weights(), limits or Limits()
        self.audit = bool(audit)
        self.contacts: dict[str, SoleContact] = resolve_contacts(imitator, self.contact,
                                                                 contacts)
        bm = body_map if isinstance(body_map, BodyMap) else None
        self.body_map = bm or _body_map(demonstrator, imitator, body_map)
        _, act = base_dofs(imitator)
        self._lim = limits_resolved = limits_mod.resolve(imitator, act, self.limits)
        self._act_names = limits_resolved.names
        self._audit_robot = limited_robot(imitator, limits_resolved)
        self._form = problem_for(imitator, force, self.contact, self.body_map, self._act_names)
        ng = self._form.ngk * 2 + self._form.ns
        self._c, _ = pb.compiled(self._form, 2, np.arange(ng), {"max_iter": 60,
                                                                 **(ipopt or {})})
        self.reset()

    def reset(self) -> None:
        """Forget the previous frames."""
        self._prev: tuple | None = None  # (t, q_demo, contact, force)
        self._x: np.ndarray | None = None  # committed knot (n_x,)
        self._n = 0

    # ------------------------------------------------------------------ one frame
    def _window(self, t1: float, q_demo: np.ndarray, contact: dict, forces) -> tuple:
        if self._prev is None:
            rows = [(t1 - self.dt, q_demo, contact, forces), (t1, q_demo, contact, forces)]
        else:
            rows = [self._prev, (t1, q_demo, contact, forces)]
        t = np.array([r[0] for r in rows])
        q = np.array([r[1] for r in rows])
        c = {s: np.array([bool(r[2][s]) for r in rows]) for s in SIDES}
        d = self.demonstrator
        demo = robot_motion(d, t, q, c)
        fs = None
        if self.force == "measured":
            fs = ContactForces(t, {s: FootForces(np.array([r[3][s] for r in rows]),
                                                 np.full((2, 3), np.nan), np.zeros((2, 3)),
                                                 c[s]) for s in SIDES}, "streaming")
        return demo, fs

    def step(self, q_demo: np.ndarray, contact: dict[str, bool], dt: float | None = None,
             forces: dict[str, np.ndarray] | None = None, verbose: bool = False) -> FrameResult:
        """Adapt one demonstrator configuration ``q_demo`` ``(nq_demo,)`` with its stance flags
        ``{"left": bool, "right": bool}``; ``dt`` [s] since the previous frame; ``forces``
        ``{side: (3,)}`` [N] the measured ground force on each foot (``force="measured"``)."""
        d = self.demonstrator
        q_demo = np.asarray(q_demo, dtype=float)
        if q_demo.shape != (d.model.nq,):
            raise InvalidInputError(f"q_demo must have shape ({d.model.nq},) for {d.name}; "
                                    f"got {q_demo.shape}")
        if set(contact) != set(SIDES):
            raise InvalidInputError(f"contact must give 'left' and 'right'; got {list(contact)}")
        if self.force == "measured" and forces is None:
            raise InvalidInputError("force='measured' needs forces={side: (3,)} at each step")
        dt = self.dt if dt is None else float(dt)
        t1 = (self._prev[0] + dt) if self._prev is not None else 0.0
        demo, fs = self._window(t1, q_demo, contact, forces)
        c = self._c
        tg = demonstration_targets(d, demo, self.imitator, self.body_map, self._act_names,
                                   self.force, fs, "all")
        var = c.knot.var
        x_start = None
        if self._x is not None:
            x_start = np.column_stack([self._x, self._x])
            x_start[var["q"], 1] = self._integrate(self._x, dt)  # constant velocity
        num = setup(self._form, tg, self.imitator, d, self.weights, self.limits, self.contact,
                    self.contacts, x_start)
        num.keep = np.arange(num.lbg.size)
        if self._x is not None:  # the previous frame's configuration and velocity are final
            for blk in ("q", "v"):
                num.lbx[var[blk], 0] = num.ubx[var[blk], 0] = self._x[var[blk]]
            fc = self._form.rows_of(FlatContact)  # and so is its foot velocity
            rows = fc.start + FlatContact().start_velocity_rows(num.spec)
            num.lbg[rows], num.ubg[rows] = -np.inf, np.inf
        t0 = time.perf_counter()
        if self._x is None:  # the first frame: the window's NLP from the warm start
            Z, status, iters = self._nlp(c, num, verbose)
        else:  # every later frame: one linearised QP (:mod:`.receding`)
            with single_thread():
                Z, flag = qp_step(self._form, num.x0, num.P, num.lbx, num.ubx, num.lbg,
                                  num.ubg)
                status, iters = "QP", 1
                if flag in SOLVED:
                    Z = self._polish(Z, tg, num.P, dt)
            if flag not in SOLVED:  # no step from here: the window's NLP
                Z, status, iters = self._nlp(c, num, verbose)
        elapsed = time.perf_counter() - t0
        prev_a = prev_w = prev_ok = None
        if self._x is not None:
            prev_a = Z[var["a"], 0].copy()
            W = _wrenches(c, Z)
            prev_w = {s: W[s][0] for s in SIDES}
            prev_ok = self._audit_window(tg, Z, W) if self.audit else None
        self._prev = (t1, q_demo, {s: bool(contact[s]) for s in SIDES}, forces)
        self._x = Z[:, 1].copy() if self._x is not None else Z[:, 0].copy()
        self._last = (tg, Z, num.P)
        self._n += 1
        return FrameResult(self._x[var["q"]].copy(), self._x[var["v"]].copy(), prev_a, prev_w,
                           prev_ok, status, iters, elapsed)

    def _nlp(self, c, num, verbose: bool) -> tuple[np.ndarray, str, int]:
        """The window's NLP with IPOPT (the first frame, or a frame whose QP failed)."""
        var = c.knot.var
        z, st = run_solver(c, num, num.x0, False, verbose, "frame", "converged")
        Z = z.reshape(2, -1).T
        iters = int(st.get("iter_count", 0))
        if not st.get("success"):
            z2, st2 = run_solver(c, num, Z, True, verbose, "frame, least-infeasible",
                                 "converged")
            Z = z2.reshape(2, -1).T.copy()
            for name in ("s_plus", "s_minus"):
                Z[var[name]] = 0.0
            st = st2
            iters += int(st2.get("iter_count", 0))
        return Z, str(st.get("return_status")), iters

    def _polish(self, Z: np.ndarray, tg, P: np.ndarray, dt: float) -> np.ndarray:
        """The window's equalities exact on the step's numbers (:mod:`.receding`): ``q_k``'s
        quaternion, ``v_k`` and ``a_{k−1}`` by the integration rule, knot k − 1's wrenches by
        :func:`~.receding.wrench_qp`."""
        import pinocchio as pin

        Z = Z.copy()
        var, m = self._form.knot.var, self.imitator.model
        q0, q1 = Z[var["q"], 0], Z[var["q"], 1].copy()
        if self.imitator.base == "free":
            q1[3:7] /= np.linalg.norm(q1[3:7])
        h = tg.t[1] - tg.t[0]
        v1 = pin.difference(m, q0, q1) / h
        Z[var["q"], 1], Z[var["v"], 1] = q1, v1
        Z[var["a"], 0] = (v1 - Z[var["v"], 0]) / h
        self._wrench_fix(Z, 0, tg, P)
        return Z

    def _wrench_fix(self, Z: np.ndarray, col: int, tg, P: np.ndarray) -> None:
        k, var = self._form.knot, self._form.knot.var
        W = _wrenches(self._c, Z)
        Wk = {s: W[s][col] for s in SIDES}
        stance = {s: bool(tg.stance[s][col]) for s in SIDES}
        goal = None
        if self.force == "measured":
            goal = {s: ((P[k.par[f"e1_{s}"], col],) if k.planar else
                        (P[k.par[f"e1_{s}"], col], P[k.par[f"e2_{s}"], col]))
                    if np.all(np.isfinite(tg.push[s][col])) else None for s in SIDES}
        out, _ = wrench_qp(self.imitator, Z[var["q"], col], Z[var["v"], col],
                           Z[var["a"], col], Wk, stance, self.contacts, k.base_idx, k.act_idx,
                           P[k.par["inv_effort"], col], self.contact.f_min,
                           self.contact.cop_margin, goal)
        cols = [0, 2, 4] if k.planar else list(range(6))
        for s in SIDES:
            Z[var[f"w_{s}"], col] = out[s][cols] / k.mg

    def final(self) -> tuple[np.ndarray, dict, bool | None]:
        """``(a (nv,), wrenches {side: (6,)}, feasible)`` of the last frame, from its own
        window (call after the last :meth:`step`); ``feasible`` None without the per-frame
        audit."""
        tg, Z, P = self._last
        var = self._c.knot.var
        col = 0 if self._n == 1 else 1
        Z = Z.copy()
        if col == 1:
            self._wrench_fix(Z, 1, tg, P)
        W = _wrenches(self._c, Z)
        ok = self._audit_window(tg, Z, W, col) if self.audit else None
        return Z[var["a"], col].copy(), {s: W[s][col] for s in SIDES}, ok

    def _integrate(self, x: np.ndarray, dt: float) -> np.ndarray:
        import pinocchio as pin

        var = self._c.knot.var
        return pin.integrate(self.imitator.model, x[var["q"]], dt * x[var["v"]])

    def _audit_window(self, tg, Z, W, col: int = 0) -> bool:
        from ..audit import audit

        var = self._c.knot.var
        m = robot_motion(self.imitator, tg.t, Z[var["q"]].T, tg.stance).replace(
            v=Z[var["v"]].T, a=Z[var["a"]].T)
        target = tg.push if self.force == "measured" else None
        rep = audit(self._audit_robot, m, W, self.contacts, target=target,
                    cone_half_angle=self.contact.cone_half_angle)
        return bool(rep.knot_feasible[col])


def _body_map(demonstrator: Robot, imitator: Robot, given) -> BodyMap:
    return body_map(demonstrator, imitator, given)


def _wrenches(c: pb.Compiled, Z: np.ndarray) -> dict[str, np.ndarray]:
    return wrenches_of(c, Z)


def adapt_per_frame(demo: Motion, demonstrator: Robot, imitator: Robot, force: str = "segment",
                    forces: ContactForces | None = None, weights: Weights | None = None,
                    limits: Limits | None = None, contact: Contact | None = None,
                    contacts: dict | None = None, body_map=None, tol: float = 1e-6,
                    ipopt: dict | None = None):
    """:class:`StreamingAdaptor` over every frame of ``demo`` (what ``adapt(...,
    method="optimal", mode="per_frame")`` runs). Returns an
    :class:`~gdimitate.adapt.AdaptedMotion` whose ``motion`` has the frames' ``q``, ``v``,
    ``a``, whose ``solver`` is a :class:`~.solve.SolverInfo` (frames per second in
    ``time_s``/``knots``) and whose ``frame_feasible`` ``(T,)`` are the per-frame flags —
    the audit of the assembled motion, knot by knot, run once after the frames (also in
    ``solver``'s ``unmet`` when some frames fail); ``audit`` is that whole motion's."""
    from ..audit import audit

    if demo.base_nq and demo.q.shape[1] != demonstrator.model.nq:
        raise InvalidInputError("the demonstration does not match the demonstrator")
    ad = StreamingAdaptor(demonstrator, imitator, force, weights=weights, limits=limits,
                          contact=contact, contacts=contacts, body_map=body_map, dt=demo.dt,
                          ipopt=ipopt, audit=False)
    T = demo.T
    nq, nv = imitator.model.nq, imitator.model.nv
    q, v, a = np.zeros((T, nq)), np.zeros((T, nv)), np.zeros((T, nv))
    W = {s: np.zeros((T, 6)) for s in SIDES}
    iters, statuses = 0, []
    t0 = time.perf_counter()
    for k in range(T):
        f_k = None
        if force == "measured":
            f_k = {s: np.array([np.interp(demo.t[k], forces.t, forces[s].force[:, i])
                                for i in range(3)]) for s in SIDES}
        dt = demo.t[k] - demo.t[k - 1] if k else demo.dt
        r = ad.step(demo.q[k], {s: bool(demo.contact[s][k]) for s in SIDES}, dt, f_k)
        q[k], v[k] = r.q, r.v
        if k:
            a[k - 1] = r.previous_a
            for s in SIDES:
                W[s][k - 1] = r.previous_wrenches[s]
        iters += r.iterations
        statuses.append(r.status)
    a[-1], wl, _ = ad.final()
    for s in SIDES:
        W[s][-1] = wl[s]
    elapsed = time.perf_counter() - t0
    contact_used = {s: np.asarray(demo.contact[s], bool) for s in SIDES}
    motion = robot_motion(imitator, demo.t, q, contact_used).replace(v=v, a=a)
    aud = audit(ad._audit_robot, motion, W, ad.contacts,
                cone_half_angle=ad.contact.cone_half_angle)
    ok = np.asarray(aud.knot_feasible, bool)  # every frame's verdict, off the hot path
    report = compare(demonstrator, demo, imitator, motion, "optimal",
                     {s: ok.copy() for s in SIDES}, force if force != "measured" else "segment")
    bad = tuple(Unmet(f"frame {k}", 1.0, int(k)) for k in np.flatnonzero(~ok))
    info = SolverInfo(status=max(set(statuses), key=statuses.count), success=bool(ok.all()),
                      iterations=iters, time_s=elapsed, build_s=0.0, cached=True,
                      elastic=not ok.all(), knots=T, variables=0, constraints=0, unmet=bad)
    return AdaptedMotion(motion=motion, report=report, robot=imitator, wrenches=W,
                         contacts=dict(ad.contacts), audit=aud, solver=info,
                         force_model=force, frame_feasible=ok)
