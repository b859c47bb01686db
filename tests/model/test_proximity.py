"""Which self-collision pairs are near (:class:`gdimitate.model.selfcollision.Proximity`):
the audit's closest pair, measured as few times as can be, against measuring every pair with
coal (``SelfCollision.distances``); the streaming frames' pairs and their distance rates
against those distances and their central finite differences.

The paths are smooth (a walk-like sinusoid of every joint, the streaming mode's use) and
jumpy (random configurations one after another, the Gauss–Newton start's use): the bound it
keeps from call to call must hold for both."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.model.selfcollision import Proximity, self_collision
from tests.helpers import shared


def _path(robot, kind: str, n: int = 60) -> np.ndarray:
    """``(n, nq)`` configurations of ``robot``: ``"smooth"`` (every joint a sinusoid about a
    random posture, 60 frames a period) or ``"jumps"`` (independent random postures)."""
    rng = np.random.default_rng(7)
    m = robot.model
    nj = m.nq - 7
    if kind == "smooth":
        mid, amp = 0.3 * rng.standard_normal(nj), 0.6 * rng.standard_normal(nj)
        phase = rng.uniform(0, 2 * np.pi, nj)
        t = np.arange(n) / n
        joints = mid + amp * np.sin(2 * np.pi * t[:, None] + phase)
    else:
        joints = 0.6 * rng.standard_normal((n, nj))
    return np.array([np.r_[robot.neutral[:7], j] for j in joints])


@pytest.mark.parametrize("name", ["talos", "icub"])
@pytest.mark.parametrize("kind", ["smooth", "jumps"])
def test_the_closest_pair_is_the_one_measuring_every_pair_finds(name, kind):
    """``closest`` (the audit's ``self_collision`` check) gives, at every configuration, the
    least distance and its pair that measuring all the pairs gives (Talos: 988 pairs), to
    GJK's tolerance."""
    robot = shared.library_robot(name)
    sc = self_collision(robot)
    Q = _path(robot, kind)
    every = sc.distances(Q)
    dist, pair = sc.closest(Q)
    np.testing.assert_allclose(dist, every.min(axis=1), atol=1e-6)
    assert np.array_equal(pair, every.argmin(axis=1))


@pytest.mark.parametrize("name", ["talos", "g1"])
@pytest.mark.parametrize("kind", ["smooth", "jumps"])
def test_the_tracked_pairs_and_their_rates(name, kind):
    """Along a path, ``tracked`` (the streaming frames' collision rows; every pair measured
    every fifth call) returns the pairs that measuring all of them finds closer than the watch
    distance — among those within 10 cm at the last refresh — with their distances, and each
    distance's rate ``J_d v`` equals the central finite difference of coal's distance along a
    random velocity (step 1e-6) wherever the two shapes are apart and the distance has a
    derivative (its one-sided differences agree)."""
    robot = shared.library_robot(name)
    m, sc = robot.model, self_collision(robot)
    Q = _path(robot, kind)
    every = sc.distances(Q)
    near, data = Proximity(sc), m.createData()
    rng = np.random.default_rng(3)
    checked, kept = 0, np.arange(len(sc.pairs))
    for k, q in enumerate(Q):
        pin.computeJointJacobians(m, data, q)
        if k % 5 == 0:
            kept = np.flatnonzero(every[k] < 0.1)
        idx, dist, rate = near.tracked(data, q, k % 5 == 0, 0.1, 0.03)
        want = kept[every[k][kept] < 0.03]
        assert sorted(idx.tolist()) == sorted(want.tolist()), k
        np.testing.assert_allclose(dist, every[k][idx], atol=1e-6)
        v = rng.standard_normal(m.nv)
        eps = 1e-6
        d0 = every[k][idx]
        up = (sc.distances(pin.integrate(m, q, eps * v))[idx] - d0) / eps
        down = (d0 - sc.distances(pin.integrate(m, q, -eps * v))[idx]) / eps
        # where the distance has a derivative: apart (not inside each other, where EPA's
        # depth is only as good as its polytope) and both one-sided differences agreeing
        # (not where the nearest points jump from a vertex to another)
        smooth = (dist > 1e-3) & (np.abs(up - down) < 1e-4)
        if not smooth.any():
            continue
        # GJK stops within 1e-6 m of the distance; the nearest points' direction is then
        # good to ~√(1e-6 / d), a few 1e-3 at centimetres: the rate to that, relatively
        np.testing.assert_allclose(rate[smooth] @ v, (up + down)[smooth] / 2, rtol=5e-3,
                                   atol=1e-4)
        checked += int(smooth.sum())
    assert checked >= 20  # the rates were compared on enough pairs


def test_a_robot_without_pairs_has_no_closest_pair():
    """A robot whose every pair is left out: ``closest`` answers ``inf`` and ``-1``."""
    robot = shared.library_robot("g1")
    sc = self_collision(robot, margin=10.0)  # every pair closer than 10 m at the neutral pose
    assert not sc.pairs
    dist, pair = sc.closest(robot.neutral[None])
    assert dist[0] == np.inf and pair[0] == -1
