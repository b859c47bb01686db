"""Contact wrench cone (closed form) against its definition: four corner forces in their
friction cones (an LP, scipy's HiGHS); sole rectangles against the feet's geometry."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

import gdimitate as gd
from gdimitate.errors import ContactError, InvalidInputError
from gdimitate.model.contact import SoleContact, cone_margin, wrench_cone
from gdimitate.model.robot import LEG_PRESETS


def _corner_lp(w: np.ndarray, X: float, Y: float, mu: float) -> bool:
    """Whether four corner forces f_i with |f_ix|,|f_iy| ≤ μ f_iz (the cone's linearised
    form that Caron et al. use) produce the wrench w = Σ (f_i; p_i × f_i) at the centre."""
    corners = SoleContact("left", "f", X, Y, mu).corners()
    # unknowns: 12 corner force components
    A_eq = np.zeros((6, 12))
    for i, p in enumerate(corners):
        A_eq[:3, 3 * i:3 * i + 3] = np.eye(3)
        A_eq[3:, 3 * i:3 * i + 3] = pin.skew(p)
    A_ub, b_ub = [], []
    for i in range(4):
        for k in (0, 1):
            for sgn in (1.0, -1.0):
                row = np.zeros(12)
                row[3 * i + k] = sgn
                row[3 * i + 2] = -mu
                A_ub.append(row)
                b_ub.append(0.0)
        row = np.zeros(12)
        row[3 * i + 2] = -1.0
        A_ub.append(row)
        b_ub.append(0.0)
    res = linprog(np.zeros(12), A_ub=np.array(A_ub), b_ub=b_ub, A_eq=A_eq, b_eq=w,
                  bounds=[(None, None)] * 12, method="highs")
    return res.status == 0


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_closed_form_cone_equals_corner_lp(seed):
    rng = np.random.default_rng(seed)
    X, Y, mu = rng.uniform(0.03, 0.15), rng.uniform(0.02, 0.08), rng.uniform(0.2, 1.2)
    fz = rng.uniform(10, 500)
    # wrenches around the cone's boundary: scale a random direction
    w = np.array([rng.normal() * mu * fz, rng.normal() * mu * fz, fz,
                  rng.normal() * Y * fz, rng.normal() * X * fz,
                  rng.normal() * mu * (X + Y) * fz * 0.5])
    A = wrench_cone(X, Y, mu)
    slack = A @ w
    scale = np.abs(A).sum(axis=1) * np.abs(w).max()
    if np.all(np.abs(slack) > 1e-7 * scale):  # skip wrenches on the boundary
        assert bool(np.all(slack <= 0)) == _corner_lp(w, X, Y, mu)


def test_corner_lp_sample_has_both_outcomes():
    """The property above is not vacuous: on a fixed sample, both in- and out-of-cone cases
    occur and the closed form agrees with the LP on every one."""
    rng = np.random.default_rng(0)
    X, Y, mu = 0.1, 0.05, 0.6
    agree, inside = [], []
    for _ in range(200):
        fz = 200.0
        w = np.array([rng.normal() * mu * fz, rng.normal() * mu * fz, fz, rng.normal() * Y * fz,
                      rng.normal() * X * fz, rng.normal() * mu * (X + Y) * fz * 0.5])
        cf = bool(np.all(wrench_cone(X, Y, mu) @ w <= 0))
        agree.append(cf == _corner_lp(w, X, Y, mu))
        inside.append(cf)
    assert all(agree)
    assert 0.05 < np.mean(inside) < 0.95


def test_cone_margin_matches_matrix():
    c = SoleContact("left", "f", 0.1, 0.05, 0.7)
    rng = np.random.default_rng(1)
    W = rng.normal(size=(2000, 6)) * [150, 150, 0, 20, 20, 15] + [0, 0, 300, 0, 0, 0]
    inside = np.all(W @ c.cone().T <= 0, axis=1)
    m = cone_margin(c, W)
    # friction margin here is the circular one (stricter than the square rows): compare the
    # three rows that are exact
    exact = (m["cop"] >= 0) & (m["yaw"] >= 0) & (np.abs(W[:, 0]) <= 0.7 * W[:, 2]) & (
        np.abs(W[:, 1]) <= 0.7 * W[:, 2])
    assert np.array_equal(inside, exact)
    assert 0.1 < inside.mean() < 0.9  # the sample straddles the boundary


def test_cop_is_where_the_moment_vanishes():
    c = SoleContact("left", "f", 0.1, 0.05, 0.7)
    f = np.array([10.0, -5.0, 400.0])
    p = np.array([0.03, -0.02, 0.0])  # a point force at p: τ = p × f
    w = np.r_[f, np.cross(p, f)]
    np.testing.assert_allclose(gd.contact.centre_of_pressure(w), p[:2], atol=1e-12)
    assert cone_margin(c, w)["cop"] == pytest.approx(min(0.1 - 0.03, 0.05 - 0.02))


@pytest.mark.parametrize("bad", [dict(half_length=0.0), dict(half_width=-1.0),
                                 dict(mu=0.0), dict(mu=float("nan"))])
def test_bad_contact_parameters_raise(bad):
    kw = dict(side="left", frame="f", half_length=0.1, half_width=0.05, mu=0.7) | bad
    with pytest.raises(InvalidInputError, match=next(iter(bad))):
        SoleContact(**kw)


@pytest.mark.parametrize("name", ["talos", "g1", "icub", "romeo", "hoap2"])
def test_measured_soles_sit_on_the_floor_under_the_feet(name):
    """The measured sole frame is at the centre of the foot's lowest vertices, on z = 0 at the
    neutral pose, world-aligned, and the rectangle is foot-sized (longer than wide)."""
    r = gd.Robot.from_library(name)
    pin.framesForwardKinematics(r.model, r.data, r.neutral)
    for side, c in r.contacts.items():
        M = r.data.oMf[r.frame_id(c.frame)]
        assert abs(M.translation[2]) < 1e-5  # iCub's two soles differ by 1.4 µm in height
        np.testing.assert_allclose(M.rotation, np.eye(3), atol=1e-6)
        assert c.half_length > c.half_width > 0.01
        assert c.half_length < 0.25 * r.legs[side].length + 0.05
        # left foot on the left
        assert (M.translation[1] > 0) == (side == "left")


def test_sole_overrides_and_missing_feet():
    r = gd.Robot.from_library("simple_humanoid")
    assert r.contacts == {}
    with pytest.raises(ContactError, match="contacts="):
        r.require_contacts()
    path = r.urdf_path
    r2 = gd.Robot.from_urdf(path, name="sh", contacts={
        s: {"frame": r.legs[s].sole, "half_length": 0.1, "half_width": 0.05} for s in ("left",
                                                                                      "right")})
    assert r2.require_contacts()["left"].half_length == 0.1
    t = gd.Robot.from_library("talos")
    legs = LEG_PRESETS["talos"]
    t2 = gd.Robot.from_urdf(t.urdf_path, legs, name="talos", package_dir=t.package_dir,
                            contacts={"left": {"mu": 0.4}})
    assert t2.contacts["left"].mu == 0.4
    assert t2.contacts["left"].half_length == pytest.approx(t.contacts["left"].half_length)
    with pytest.raises(InvalidInputError, match="unknown keys"):
        gd.Robot.from_urdf(t.urdf_path, legs, package_dir=t.package_dir,
                           contacts={"left": {"X": 1}})


def test_optimiser_rows_and_numpy_cone_are_one_formula():
    """The contact wrench cone is written once (``contact.wrench_cone_rows``). Its users agree
    on random soles and wrenches: the optimiser's rows (``retarget.parts.cone.cone_rows`` on
    CasADi symbols, evaluated by a ``casadi.Function``), the NumPy matrix ``wrench_cone``
    (force estimation, the receding controller) and the audit's yaw margin ``cone_margin``.
    Independent reference: rows written out by hand from Caron et al. (2015), Eq. 4-6, and the
    yaw bounds τ_min/τ_max in their |·| form (the module docstring)."""
    import casadi as ca

    from gdimitate.model.contact import PLANAR_CONE_ROWS, wrench_cone_rows
    from gdimitate.retarget.parts.cone import cone_rows, rows_per_side

    ws, ps = ca.SX.sym("w", 6), ca.SX.sym("p", 6)
    par = [ps[i] for i in range(6)]  # X, Y, mu, Xc, Yc, f_min
    sym = {planar: ca.Function("rows", [ws, ps], [ca.vertcat(*cone_rows(ws, *par,
                                                                           planar=planar))])
           for planar in (False, True)}
    assert [rows_per_side(p) for p in (False, True)] == [17, 5]
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(300):
        X, Y, mu = rng.uniform(0.03, 0.15), rng.uniform(0.02, 0.08), rng.uniform(0.2, 1.2)
        Xc, Yc, fmin = X - rng.uniform(0, 0.02), Y - rng.uniform(0, 0.01), rng.uniform(0, 50)
        fz = rng.uniform(-50, 600)
        w = rng.normal(size=6) * [mu * fz, mu * fz, 0, Y * fz, X * fz, mu * (X + Y) * fz]
        w[2] = fz
        fx, fy, _, tx, ty, tz = w
        p = [X, Y, mu, Xc, Yc, fmin]
        got = np.array(sym[False](w, p)).ravel()
        # the NumPy users: the matrix, and the formula on arrays
        A = wrench_cone(X, Y, mu, Xc, Yc)
        scale = np.abs(A).sum(axis=1) * np.abs(w).max()
        worst = max(worst, float(np.max(np.abs(got[:16] - A @ w) / scale)))
        np.testing.assert_array_equal(got[:16], np.array(wrench_cone_rows(w, X, Y, mu, Xc, Yc)))
        # by hand: friction, centre of pressure (margin-reduced), yaw (s1, s2) = (+,+), (−,−)
        hand = {0: fx - mu * fz, 3: -fy - mu * fz, 5: -tx - Yc * fz, 6: ty - Xc * fz,
                8: Y * fx + X * fy - mu * (X + Y) * fz - mu * tx - mu * ty - tz,
                15: -Y * fx - X * fy - mu * (X + Y) * fz - mu * tx - mu * ty + tz,
                16: fmin - fz}
        for i, ref in hand.items():
            assert got[i] == pytest.approx(ref, rel=1e-12, abs=1e-12 * np.abs(w).max())
        # planar models: friction and centre of pressure along x, then f_min
        wp = w * [1, 0, 1, 0, 1, 0]
        planar = np.array(sym[True](wp, p)).ravel()
        np.testing.assert_allclose(planar, [fx - mu * fz, -fx - mu * fz, ty - Xc * fz,
                                            -ty - Xc * fz, fmin - fz], rtol=1e-12, atol=1e-9)
        np.testing.assert_array_equal(planar[:4], np.array(sym[False](wp, p)).ravel()[
            list(PLANAR_CONE_ROWS)])
        # the audit's yaw margin: min(τ_z − τ_min, τ_max − τ_z)
        tmin = -mu * (X + Y) * fz + abs(Y * fx - mu * tx) + abs(X * fy - mu * ty)
        tmax = mu * (X + Y) * fz - abs(Y * fx + mu * tx) - abs(X * fy + mu * ty)
        yaw = cone_margin(SoleContact("left", "f", X, Y, mu), w)["yaw"]
        assert yaw == pytest.approx(min(tz - tmin, tmax - tz), rel=1e-12,
                                    abs=1e-12 * np.abs(w).max())
    assert worst < 1e-15  # the matrix product sums the same terms in another order


def test_cone_margin_is_elementwise_over_wrenches():
    """``cone_margin`` on ``(N, 6)`` wrenches equals it wrench by wrench (the yaw margin is taken
    from the cone's rows with ``w[i]`` of shape ``(N,)``)."""
    c = SoleContact("left", "f", 0.1, 0.05, 0.7)
    W = np.random.default_rng(2).normal(size=(50, 6)) * [150, 150, 100, 20, 20, 15] + [
        0, 0, 300, 0, 0, 0]
    m = cone_margin(c, W)
    for key, col in m.items():
        assert col.shape == (50,)
        np.testing.assert_array_equal(col, [cone_margin(c, w)[key] for w in W])
