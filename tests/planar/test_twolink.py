"""Eq. (1) against an independent geometric statement of it (docs/design.md §4)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdimitate import InvalidInputError
from gdimitate.planar import ROUNDOFF, eq1, fk2, ik2
from tests.helpers import shared

angle = st.floats(-1.2, 1.2, allow_nan=False)
knee = st.floats(-2.0, 0.0, allow_nan=False)
length = st.floats(0.02, 1.5, allow_nan=False)


def vertical(l1, l2, th1, th2):
    """Hip height over the ankle of a two-link leg, written out independently."""
    return l1 * math.cos(th1) + l2 * math.cos(th1 + th2)


@settings(max_examples=300, deadline=None)
@given(angle, knee, length, length, length, length)
def test_eq1_geometry(th1, th2, lm1, lm2, lr1, lr2):
    r = eq1(th1, th2, (lm1, lm2), (lr1, lr2))
    # 1. shank direction preserved exactly (1e-12 rad)
    assert abs((float(r.theta1) + float(r.theta2)) - (th1 + th2)) <= 1e-12
    # 2. feasible ⇔ |arg| ≤ 1; where feasible, hip-over-ankle height / leg length preserved
    assert bool(r.feasible) == (abs(float(r.argument)) <= 1.0 + ROUNDOFF)
    if r.feasible:
        hm = vertical(lm1, lm2, th1, th2) / (lm1 + lm2)
        hr = vertical(lr1, lr2, float(r.theta1), float(r.theta2)) / (lr1 + lr2)
        assert abs(hr - hm) <= 1e-12
        # thigh sign follows the demonstrator's
        if abs(th1) > 1e-9 and abs(float(r.theta1)) > 1e-9:
            assert np.sign(float(r.theta1)) == np.sign(th1)
    else:  # clipped to the nearest reachable angle: straight (arg>1) or folded (arg<-1)
        assert abs(float(r.theta1)) in (0.0, pytest.approx(math.pi))


@settings(max_examples=200, deadline=None)
@given(angle, knee, length, length, st.floats(0.05, 20.0))
def test_eq1_same_proportions_gives_same_angles(th1, th2, l1, l2, k):
    r = eq1(th1, th2, (l1, l2), (k * l1, k * l2))
    assert bool(r.feasible)
    assert abs(float(r.theta1) - th1) <= 1e-7 * (1 + abs(th1)) or abs(th1) < 1e-7
    assert abs(float(r.theta2) - th2) <= 1e-7 * (1 + abs(th2)) or abs(th1) < 1e-7


@settings(max_examples=50, deadline=None)
@given(st.lists(st.integers(1, 5), min_size=0, max_size=3))
def test_eq1_vectorised_any_shape(shape):
    rng = np.random.default_rng(len(shape))
    th1 = rng.uniform(-0.6, 0.6, shape)
    th2 = rng.uniform(-1.2, 0.0, shape)
    r = eq1(th1, th2, (0.06, 0.04), (0.1, 0.1))
    for f in r:
        assert np.shape(f) == tuple(shape)
    flat = [eq1(a, b, (0.06, 0.04), (0.1, 0.1)) for a, b in zip(th1.ravel(), th2.ravel())]
    assert np.array_equal(np.ravel(r.theta1), [float(f.theta1) for f in flat])
    assert np.array_equal(np.ravel(r.feasible), [bool(f.feasible) for f in flat])


def test_case_ii_is_infeasible_where_thigh_share_is_larger():
    # demonstrator thigh share 0.6 > imitator 0.5: a straight-ish leg with bent knee can't be
    # matched (docs/design.md §4): arg > 1
    r = eq1(0.0, -0.6, (0.06, 0.04), (0.1, 0.1))
    assert not r.feasible and r.argument > 1.0
    assert r.theta1 == 0.0 and abs(r.theta2 - (-0.6)) < 1e-15


@settings(max_examples=200, deadline=None)
@given(angle, knee, length, length)
def test_ik2_inverts_fk2(th1, th2, l1, l2):
    if th2 > -1e-3:  # near-straight knee: ill-conditioned, skip
        return
    _, ankle = fk2(th1, th2, (l1, l2))
    a1, a2, ok = ik2(ankle[0], ankle[1], (l1, l2))
    assert ok
    assert abs(float(a1) - th1) < 1e-6 and abs(float(a2) - th2) < 1e-6


@pytest.mark.parametrize(
    "args, match",
    [
        ((np.nan, 0.0), "NaN"),
        ((0.1, np.inf), "NaN or inf"),
        ((np.zeros(3), np.zeros(4)), "broadcast"),
    ],
)
def test_eq1_bad_angles(args, match):
    with pytest.raises(InvalidInputError, match=match):
        eq1(*args, (0.4, 0.6), (0.1, 0.1))


@pytest.mark.parametrize("lengths", [(0.0, 0.1), (-0.1, 0.1), (np.nan, 0.1), (0.1,), "ab"])
def test_eq1_bad_lengths(lengths):
    with pytest.raises(InvalidInputError):
        eq1(0.1, -0.2, lengths, (0.1, 0.1))


# ---------------------------------------------------------------------- the planar corner
def test_planar_signs_and_offsets_are_sagittal_leg_s():
    """The planar signs and offsets are :func:`gdimitate.planar.sagittal_leg`'s (a ``Leg`` has
    none), which for our planar model follow from its URDF: joints about −y (a positive angle
    moves the distal end forward: sign +1) and legs hanging straight down (offsets 0)."""
    from gdimitate.planar import sagittal_leg

    r = shared.library_robot("hoap2")
    for s in ("left", "right"):
        sag = sagittal_leg(r, s)
        assert sag.signs == (1.0, 1.0, 1.0) and sag.offsets == (0.0, 0.0, 0.0)
        assert (sag.thigh, sag.shank) == (r.legs[s].thigh, r.legs[s].shank)
        assert not hasattr(r.legs[s], "signs") and not hasattr(r.legs[s], "offsets")
        assert sagittal_leg(r, s) is sag  # measured once per robot
