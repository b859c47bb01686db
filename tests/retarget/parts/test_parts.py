"""Each part of the optimal adaptor's problem (gdimitate.retarget.parts) on its own: its rows
(or residual) at random states against an independent NumPy/Pinocchio re-derivation, and its
Jacobian against central finite differences; the weight layout, slacks and labels derived from
the list of parts. A small 3-D humanoid (``alexander``) and the planar HOAP-2 keep it fast."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from gdimitate.model.contact import wrench_cone
from gdimitate.model.robot import SIDES
from gdimitate.retarget import parts as P
from gdimitate.retarget.knot import Flags, Knot
from gdimitate.retarget.trajectory.problem import symbolic_model

RNG = np.random.default_rng(7)


def knot_of(robot, part, flags: Flags | None = None):
    """A :class:`Knot` with ``part``'s parameter blocks and ``(x, p) -> rows`` of the part
    (a per-knot constraint's rows, a cost's unweighted residual)."""
    sym = symbolic_model(robot)
    flags = flags or Flags()
    k0 = Knot(robot, sym, flags)
    k = Knot(robot, sym, flags, extra=part.params(k0))
    expr = part.residual(k) if isinstance(part, P.Cost) else part.rows(k)
    k.add_slacks(0)
    return k, ca.Function("rows", [k.x, k.p], [expr])


def random_point(robot, k: Knot) -> tuple[np.ndarray, np.ndarray, dict]:
    """A random ``(x, p)`` and the named pieces (q, v, a, sole wrenches [N, N·m], params)."""
    m = robot.model
    lo = np.where(np.isfinite(m.lowerPositionLimit), m.lowerPositionLimit, -1.0)
    hi = np.where(np.isfinite(m.upperPositionLimit), m.upperPositionLimit, 1.0)
    q = pin.randomConfiguration(m, np.maximum(lo, -1.0), np.minimum(hi, 1.0))
    x = np.zeros(k.var.size)
    x[k.var["q"]] = q
    x[k.var["v"]] = RNG.normal(size=m.nv)
    x[k.var["a"]] = RNG.normal(size=m.nv)
    for s in SIDES:
        x[k.var[f"w_{s}"]] = RNG.normal(size=k.nw) * 0.3
    p = RNG.uniform(0.1, 1.0, size=k.par.size)
    for s in SIDES:
        for name in ("d", "e1", "e2"):
            v = RNG.normal(size=3)
            p[k.par[f"{name}_{s}"]] = v / np.linalg.norm(v)
    W = {}
    for s in SIDES:
        w = x[k.var[f"w_{s}"]] * k.mg
        W[s] = np.array([w[0], 0, w[1], 0, w[2], 0]) if k.planar else w
    return x, p, {"q": q, "v": x[k.var["v"]], "a": x[k.var["a"]], "W": W}


def _frames(robot, q):
    m, d = robot.model, robot.data
    pin.framesForwardKinematics(m, d, q)
    oMf = [pin.SE3(M) for M in d.oMf]  # copies: later calls reuse robot.data
    return lambda name: oMf[m.getFrameId(name)]


def _fd_check(fun, x, p, atol=2e-5):
    xs, ps = fun.sx_in(0), fun.sx_in(1)
    J = np.array(ca.Function("J", [xs, ps], [ca.jacobian(fun(xs, ps), xs)])(x, p))
    eps = 1e-6
    num = np.column_stack([(np.array(fun(x + eps * e, p)).ravel()
                            - np.array(fun(x - eps * e, p)).ravel()) / (2 * eps)
                           for e in np.eye(x.size)])
    np.testing.assert_allclose(J, num, atol=atol, rtol=1e-5)


ROBOTS = ["alexander", "hoap2"]


@pytest.mark.parametrize("name", ROBOTS)
def test_dynamics_rows_match_pinocchio(robot, name):
    r = robot(name)
    for part in (P.BaseDynamics(), P.TorqueLimits()):
        k, f = knot_of(r, part)
        x, p, s = random_point(r, k)
        tau = pin.rnea(r.model, r.data, s["q"], s["v"], s["a"]).copy()
        pin.computeJointJacobians(r.model, r.data, s["q"])
        pin.updateFramePlacements(r.model, r.data)
        for side in SIDES:
            fid = r.model.getFrameId(k.contacts[side].frame)
            tau -= pin.getFrameJacobian(r.model, r.data, fid, pin.LOCAL).T @ s["W"][side]
        if isinstance(part, P.BaseDynamics):
            ref = tau[k.base_idx]
        else:
            ref = tau[k.act_idx] * p[k.par["inv_effort"]]
        np.testing.assert_allclose(np.array(f(x, p)).ravel(), ref, atol=1e-9, rtol=1e-9)
        assert part.labels(k)[0].startswith(part.name.split(":")[0])
        _fd_check(f, x, p, atol=1e-4)


@pytest.mark.parametrize("name", ROBOTS)
def test_contact_rows_match_pinocchio(robot, name):
    r = robot(name)
    k, f = knot_of(r, P.FlatContact())
    x, p, s = random_point(r, k)
    m, d = r.model, r.data
    pin.forwardKinematics(m, d, s["q"], s["v"])
    pin.updateFramePlacements(m, d)
    ref = []
    for side in SIDES:
        fid = m.getFrameId(k.contacts[side].frame)
        M = d.oMf[fid]
        ref += [M.translation[2], M.rotation[2, 0]] + ([] if k.planar else [M.rotation[2, 1]])
        V = pin.getFrameVelocity(m, d, fid, pin.LOCAL_WORLD_ALIGNED).vector
        ref += list(V[[0, 2, 4]] if k.planar else V)
    np.testing.assert_allclose(np.array(f(x, p)).ravel(), ref, atol=1e-10)
    _fd_check(f, x, p)


@pytest.mark.parametrize("name", ROBOTS)
def test_cone_and_swing_rows(robot, name):
    r = robot(name)
    k, f = knot_of(r, P.WrenchCone())
    x, p, s = random_point(r, k)
    got = np.array(f(x, p)).ravel().reshape(2, -1)
    fmin = p[k.par["f_min"]][0]
    for i, side in enumerate(SIDES):
        X, Y, mu, Xc, Yc = p[k.par[f"sole_{side}"]]
        w = s["W"][side]
        if k.planar:  # friction along x, centre of pressure along x, f_min
            ref = [w[0] - mu * w[2], -w[0] - mu * w[2], w[4] - Xc * w[2], -w[4] - Xc * w[2]]
        else:  # Caron et al.'s 16 rows (CoP rows with the margin-reduced sole)
            A = wrench_cone(X, Y, mu)
            ref = list(A @ w)
            ref[4:8] = [w[3] - Yc * w[2], -w[3] - Yc * w[2], w[4] - Xc * w[2], -w[4] - Xc * w[2]]
        ref.append(fmin - w[2])
        np.testing.assert_allclose(got[i], np.array(ref) / k.mg, atol=1e-10)
    _fd_check(f, x, p)
    k, f = knot_of(r, P.SwingClearance())
    x, p, s = random_point(r, k)
    F = _frames(r, s["q"])
    ref = []
    for side in SIDES:
        M = F(k.contacts[side].frame)
        X, Y = p[k.par[f"sole_{side}"]][:2]
        pts = [(X, 0), (-X, 0)] if k.planar else [(X, Y), (X, -Y), (-X, -Y), (-X, Y)]
        ref += [(M.act(np.array([cx, cy, 0.0]))[2]) / r.legs["left"].length for cx, cy in pts]
    np.testing.assert_allclose(np.array(f(x, p)).ravel(), ref, atol=1e-10)
    _fd_check(f, x, p)


@pytest.mark.parametrize("goal", ["force", "segment", "com"])
@pytest.mark.parametrize("cone", [False, True])
def test_force_direction_rows(robot, goal, cone):
    r = robot("alexander")
    k, f = knot_of(r, P.ForceDirection(), Flags(goal=goal, cone=cone))
    x, p, s = random_point(r, k)
    F = _frames(r, s["q"])
    data = r.data
    com = pin.centerOfMass(r.model, data, s["q"])
    ref = []
    for side in SIDES:
        leg = r.legs[side]
        if goal == "force":
            c = F(k.contacts[side].frame).rotation @ s["W"][side][:3] / k.mg
        elif goal == "segment":
            c = (F(leg.knee).translation - F(leg.ankle or leg.sole).translation) / leg.shank
        else:
            c = (com - F(k.contacts[side].frame).translation) / leg.length
        d, e1, e2 = (p[k.par[f"{n}_{side}"]] for n in ("d", "e1", "e2"))
        a, b, dc = e1 @ c, e2 @ c, d @ c
        ref += [a * a + b * b - p[k.par["tan2"]][0] * dc * dc, dc] if cone else [a, b, dc]
    np.testing.assert_allclose(np.array(f(x, p)).ravel(), ref, atol=1e-10)
    _fd_check(f, x, p)


@pytest.mark.parametrize("name", ROBOTS)
def test_pair_rows_match_pinocchio(robot, name):
    r = robot(name)
    for part in (P.Integration(), P.ContactHold()):
        sym = symbolic_model(r)
        k = Knot(r, sym, Flags())
        k.add_slacks(0)
        x0s = ca.SX.sym("x0", k.var.size)
        carry = ca.Function("c", [k.x], [part.carry(k)])
        f = ca.Function("pair", [x0s, k.x, k.p], [part.rows(k, carry(x0s), part.carry(k))])
        (x0, p, s0), (x1, _, s1) = random_point(r, k), random_point(r, k)
        got = np.array(f(x0, x1, p)).ravel()
        h = p[k.par["h"]][0]
        if isinstance(part, P.Integration):
            ref = np.r_[s1["q"] - pin.integrate(r.model, s0["q"], h * s1["v"]),
                        s1["v"] - s0["v"] - h * s0["a"]]
        else:
            ref = []
            M0 = {sd: _frames(r, s0["q"])(k.contacts[sd].frame) for sd in SIDES}
            M1 = {sd: _frames(r, s1["q"])(k.contacts[sd].frame) for sd in SIDES}
            for sd in SIDES:
                dp = M1[sd].translation - M0[sd].translation
                if k.planar:
                    ref += [dp[0]]
                else:
                    a0, a1 = M0[sd].rotation[:2, 0], M1[sd].rotation[:2, 0]
                    ref += [dp[0], dp[1], a0[0] * a1[1] - a0[1] * a1[0]]
        np.testing.assert_allclose(got, ref, atol=1e-10)
        J = np.array(ca.Function("J", [x0s, k.x, k.p], [ca.jacobian(
            f(x0s, k.x, k.p), ca.vertcat(x0s, k.x))])(x0, x1, p))
        xx, eps = np.r_[x0, x1], 1e-6
        n = x0.size
        num = np.column_stack([
            (np.array(f(*np.split(xx + eps * e, [n]), p)).ravel()
             - np.array(f(*np.split(xx - eps * e, [n]), p)).ravel()) / (2 * eps)
            for e in np.eye(2 * n)])
        np.testing.assert_allclose(J, num, atol=2e-5)


def test_costs_match_pinocchio(robot):
    r = robot("alexander")
    frames = (r.model.frames[2].name,)
    q_index = tuple(range(7, r.model.nq))
    for part in (P.Height(), P.Placement(), P.Shank(), P.Thigh(), P.Foot(),
                 P.Segments(frames), P.Joints(q_index), P.Smoothness(),
                 P.WrenchRegularisation(), P.QuaternionNorm()):
        k, f = knot_of(r, part, Flags(segments=1))
        x, p, s = random_point(r, k)
        F = _frames(r, s["q"])
        ref = []
        for side in SIDES:
            leg = r.legs[side]
            hip, knee = F(leg.hip).translation, F(leg.knee).translation
            ankle = F(leg.ankle or leg.sole).translation
            N = _frames(r, r.neutral)
            lt = np.linalg.norm(N(leg.knee).translation - N(leg.hip).translation)
            ls = np.linalg.norm(N(leg.ankle or leg.sole).translation - N(leg.knee).translation)
            tgt = {n: p[k.par[f"{n}_{side}"]] for n in ("height", "placement", "shank",
                                                        "thigh", "foot")}
            ref.append({
                "height": [(hip[2] - ankle[2]) / leg.length - tgt["height"][0]],
                "placement": list((ankle[:2] - hip[:2]) / leg.length - tgt["placement"]),
                "shank": list((ankle - knee) / ls - tgt["shank"]),
                "thigh": list((knee - hip) / lt - tgt["thigh"]),
                "foot": list(F(k.contacts[side].frame).rotation.T.ravel() - tgt["foot"]),
            })
        if part.name in ("height", "placement", "shank", "thigh", "foot"):
            want = ref[0][part.name] + ref[1][part.name]
        elif part.name == "segments":
            want = F(frames[0]).rotation.T.ravel() - p[k.par["torso"]]
        elif part.name == "joints":
            want = p[k.par["joint_weight"]] * (s["q"][list(q_index)] - p[k.par["joint_target"]])
        elif part.name == "smoothness":
            want = s["a"]
        elif part.name == "wrench":
            want = np.r_[x[k.var["w_left"]], x[k.var["w_right"]]]
        else:
            want = [s["q"][3:7] @ s["q"][3:7] - 1.0]
        np.testing.assert_allclose(np.array(f(x, p)).ravel(), want, atol=1e-10,
                                   err_msg=part.name)
        _fd_check(f, x, p)


def test_layout_slacks_and_labels_follow_the_list(robot):
    """The weight block, the elastic slacks and the labels are derived from the parts: drop a
    cost and its weight leaves the layout; drop a relaxable constraint and its slacks go."""
    from gdimitate.retarget.trajectory.problem import _knot_expressions, _weights

    r = robot("hoap2")
    full = P.default_parts((), tuple(range(3, r.model.nq)))
    assert _weights(full) == ("height", "placement", "shank", "thigh", "foot", "torso",
                              "smoothness", "wrench")
    fewer = tuple(p for p in full if not isinstance(p, (P.Thigh, P.SwingClearance)))
    assert "thigh" not in _weights(fewer)
    sym = symbolic_model(r)
    sizes = {}
    for name, parts in (("full", full), ("fewer", fewer)):
        k = Knot(r, sym, Flags(), _weights(parts))
        cons, slices, rows, labels, *_ = _knot_expressions(k, parts)
        relax = sum(sl.stop - sl.start for c, sl in zip(cons, slices) if c.relaxable)
        assert k.slack_rows == relax and len(labels) == slices[-1].stop
        sizes[name] = (k.slack_rows, labels)
    assert sizes["full"][0] - sizes["fewer"][0] == 4  # planar swing: 2 corners per foot
    assert "swing clearance: left" in sizes["full"][1]
    assert "swing clearance: left" not in sizes["fewer"][1]


def test_parts_state_typed_rows_and_bounds(robot):
    """The kinds of part are abstract (a part missing its residual, rows, carry or box cannot
    be made); every constraint of the default list states its rows at a knot as one
    :class:`P.Rows` (one label and one screenable flag per row, checked) and its bounds as
    :class:`P.Bounds` of ``(T, n)``; a :class:`P.Rows` with a label short is refused."""

    class Unfinished(P.Constraint):
        pass

    for kind in (P.Cost, P.Constraint, P.PairConstraint, P.Bound, Unfinished):
        with pytest.raises(TypeError):
            kind()
    r = robot("hoap2")
    parts = P.default_parts((), tuple(range(3, r.model.nq)))
    k0 = Knot(r, symbolic_model(r), Flags())
    T = 5
    on = {s: np.ones(T, bool) for s in SIDES}
    spec = P.Spec(T=T, stance=on, swing={s: ~on[s] for s in SIDES}, liftoff=on,
                  goal_active=on, planar=True, free=False, cone=False, clearance=0.01,
                  leg_length=0.2, n_base=len(k0.base_idx), n_act=len(k0.act_idx))
    for c in (p for p in parts if isinstance(p, P.Constraint)):
        rows = c.at(k0)
        assert isinstance(rows, P.Rows) and rows.n == c.size(k0) == len(rows.labels)
        assert rows.screenable.shape == (rows.n,) and rows.scale == c.scale(k0)
        b = c.bounds(spec)
        assert isinstance(b, P.Bounds) and b.lower.shape == b.upper.shape == (T, rows.n)
    with pytest.raises(RuntimeError, match="1 labels for 2 rows"):
        P.Rows(ca.SX.sym("g", 2), ("one",), 1.0, np.zeros(2, bool))


@pytest.mark.parametrize("mu", [0.3, 0.7, 1.2])
def test_cone_pyramid_lies_inside_coulombs_circle(mu):
    """The trajectory adaptor's 3-D cone rows take the friction coefficient of a square
    pyramid inside Coulomb's circle ``‖f_t‖ ≤ μ f_z`` (what the audit checks): every
    tangential direction just outside the circle violates a row, and the pyramid's corner
    touches the circle (closed form: ratio √2·μ_p = μ). With μ itself the corner reached
    √2·μ (CMU → G1 planned 0.99 against μ = 0.7). A planar model's one row is the circle."""
    from gdimitate.retarget.trajectory.solve import _pyramid_mu

    A = wrench_cone(1.0, 1.0, _pyramid_mu(mu, planar=False))[:4]  # the friction rows
    th = np.linspace(0, 2 * np.pi, 721)
    out = np.column_stack([mu * (1 + 1e-9) * np.cos(th), mu * (1 + 1e-9) * np.sin(th),
                           np.ones_like(th), np.zeros((th.size, 3))])
    assert np.all(np.max(out @ A.T, axis=1) > 0)
    corner = np.array([mu / np.sqrt(2), mu / np.sqrt(2), 1.0, 0, 0, 0])
    assert np.max(A @ corner) == pytest.approx(0.0, abs=1e-12)
    assert np.hypot(*corner[:2]) == pytest.approx(mu, rel=1e-12)
    assert _pyramid_mu(mu, planar=True) == mu
