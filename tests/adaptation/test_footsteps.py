"""Footsteps and the gait kept (docs/design.md §13): footprints against the force plates'
measured centres of pressure, steps on a synthetic walk of known steps, the gait comparison's
ratios from its own definition, and the adapted G1 stride covering the scaled distance."""

from __future__ import annotations

import numpy as np
import pytest

import gdimitate as gd
from gdimitate.model.footsteps import (
    compare_gait,
    footprints,
    leg_ratio,
    stance_phases,
    steps,
    time_scale,
    travel,
)
from gdimitate.model.heading import turn_motion
from gdimitate.model.robot import SIDES


@pytest.fixture(scope="module")
def walk(walk_3d):
    return walk_3d


def test_stance_phases():
    c = np.array([0, 1, 1, 0, 0, 1, 1, 1], bool)
    assert stance_phases(c) == [(1, 3), (5, 8)]
    assert stance_phases(np.zeros(4, bool)) == []
    assert stance_phases(np.ones(3, bool)) == [(0, 3)]


def test_footprints_sit_on_the_measured_centres_of_pressure(walk):
    """Each stance phase's footprint (mean sole-frame place, Pinocchio) against the mean
    measured centre of pressure of the same phase (force plates, vertical force > 20 N),
    for every phase the clip holds whole (measured here: 0.6–3.3 cm along the walk, the
    pressure's mean a little ahead of the mid-foot sole frame, ≤ 0.5 cm across): within 4 cm
    and 1 cm; the step lengths the two give agree within 3 cm."""
    h, m, f = walk
    fps = footprints(h, m)
    assert len(fps) >= 6  # 3.5 s of walking: about three strides
    full = [fp for fp in fps if 0 < fp.start and fp.stop < m.T]
    assert len(full) >= 4
    for fp in full:
        cop = f[fp.side].cop[fp.start:fp.stop]
        ok = np.all(np.isfinite(cop), axis=1) & f[fp.side].contact[fp.start:fp.stop]
        mean = cop[ok, :2].mean(axis=0)
        assert abs(fp.xy[0] - mean[0]) < 0.04
        assert abs(fp.xy[1] - mean[1]) < 0.01
    for a, b in zip(full, full[1:]):
        ca = f[a.side].cop[a.start:a.stop, :2]
        cb = f[b.side].cop[b.start:b.stop, :2]
        d_cop = np.nanmean(cb, axis=0)[0] - np.nanmean(ca, axis=0)[0]
        assert (b.xy - a.xy)[0] == pytest.approx(d_cop, abs=0.03)


def test_steps_of_a_synthetic_walk(robot):
    """A G1 'walk' of rigid jumps: the base moves 0.3 m forward and the feet alternate, so
    every step is 0.3 m long (a closed form), as wide as the neutral stance, 0.5 s long; the
    same walk turned by 2 rad has the same steps."""
    r = robot("g1")
    T, dt = 60, 0.05
    t = np.arange(T) * dt
    q = np.tile(r.neutral, (T, 1))
    left = (np.arange(T) // 10) % 2 == 0
    contact = {"left": left, "right": ~left}
    # place the base so that the stance foot's sole lands 0.3 m ahead of the other's
    q[:, 0] = 0.3 * (np.arange(T) // 10)
    nq = tuple(int(r.model.joints[j].nq) for j in range(1, r.model.njoints))
    m = gd.Motion(t, r.joint_names, q, contact, base_nq=7, joint_nq=nq)
    width = abs(np.subtract(*[footprints(r, m)[i].xy[1] for i in (0, 1)]))
    for mm in (m, turn_motion(m, 2.0)):
        ss = steps(r, mm)
        assert len(ss) == 5
        for s in ss:
            assert s.length == pytest.approx(0.3, abs=1e-9)
            assert s.width == pytest.approx(width, abs=1e-9)
        for s in ss[:-1]:
            assert s.duration == pytest.approx(0.5, abs=1e-9)
        for s in ss[1:]:
            assert s.stride == pytest.approx(0.6, abs=1e-9)
    assert travel(r, m) == pytest.approx(1.5, abs=1e-12)


def test_gait_comparison_of_the_demonstrator_with_itself(walk):
    """The walk against itself: every ratio 1 at geometric scaling; at Froude scaling of a
    robot its own size the same (√1)."""
    h, m, _ = walk
    g = compare_gait(h, m, h, m)
    assert leg_ratio(h, h) == 1.0 and time_scale("froude", 1.0) == 1.0
    for x in (g.travel_ratio, g.speed_ratio, g.stride_ratio, g.step_ratio):
        assert x == pytest.approx(1.0, abs=1e-12)
    assert g.kept
    d = g.to_dict()
    assert d["travel_ratio"] == g.travel_ratio and len(d["steps"]) == len(g.imitator)


@pytest.mark.slow
def test_the_adapted_stride_covers_the_scaled_distance(g1_stride, robot):
    """One stride of the shipped walk → G1 with the defaults (measured push): audit-feasible
    and travelling 0.8–1.25 of the demonstrator's distance × G1's leg ratio (0.725), its
    step 0.8–1.25 of the scaled step. Before the steps cost: 0.37."""
    h, stride, fs, r = g1_stride
    g1 = robot("g1")
    assert r.audit.feasible
    g = r.gait
    assert g.ratio == pytest.approx(leg_ratio(h, g1))
    # the ratio from its definition: base travel over the demonstrator's × r
    own = np.hypot(*(r.motion.q[-1, :2] - r.motion.q[0, :2]))
    demo = np.hypot(*(stride.q[-1, :2] - stride.q[0, :2]))
    assert g.travel_ratio == pytest.approx(own / (demo * g.ratio), rel=1e-12)
    assert 0.8 <= g.travel_ratio <= 1.25
    assert 0.8 <= g.step_ratio <= 1.25
    assert all(s in SIDES for s in (x.side for x in g.imitator))


@pytest.mark.slow
def test_a_clip_cut_mid_stride_covers_the_scaled_distance(walk, robot):
    """The stride cut 0.3 s at each end — it starts and ends in single support, with one
    double support between — → G1: audit-feasible and travelling 0.8–1.25 of the
    demonstrator's distance × r. With the steps cost alone (which acts in double support
    only) it travelled 0.36: the body started slow and ended 0.2 m behind its stance foot;
    the body-over-feet cost (retarget/parts/over_feet.py) carries it."""
    h, clip, forces = _cut_stride(walk)
    assert all(clip.contact[s][0] != clip.contact[s][-1] for s in SIDES)  # single support
    r = gd.adapt(clip, h, robot("g1"), force="measured", forces=forces, verbose=False)
    assert r.audit.feasible
    own = np.hypot(*(r.motion.q[-1, :2] - r.motion.q[0, :2]))
    demo = np.hypot(*(clip.q[-1, :2] - clip.q[0, :2]))
    assert r.gait.travel_ratio == pytest.approx(own / (demo * r.gait.ratio), rel=1e-12)
    assert 0.8 <= r.gait.travel_ratio <= 1.25


def _cut_stride(walk):
    """The shipped stride cut 0.3 s at each end (single support at both ends) and its
    forces."""
    from gdimitate.model.contact import ContactForces, FootForces

    h, m, f = walk
    stride, fs = gd.gait.one_stride(m, f)
    n = int(round(0.3 / np.median(np.diff(stride.t))))
    cut = slice(n, stride.T - n)
    clip = stride.replace(t=stride.t[cut], q=stride.q[cut], v=None, a=None,
                          contact={s: np.asarray(c)[cut] for s, c in stride.contact.items()})
    forces = ContactForces(fs.t[cut], {s: FootForces(v.force[cut], v.cop[cut], v.torque[cut],
                                                     v.contact[cut])
                                       for s, v in fs.feet.items()}, fs.source)
    return h, clip, forces


@pytest.mark.slow
def test_a_short_motion_is_solved_again_with_the_gait_weights_raised(walk, robot):
    """The cut stride → G1 with the body-over-feet weight at 15 (half the default) travels
    0.69 of the scaled distance: audit-feasible but short, so the adaptor solves it again with
    the steps and body-over-feet weights × ``STRIDE_RETRY`` and keeps that motion — the same
    as an independent solve at those weights (0.84) — because it is audit-feasible, misses no
    goal and travels further. ``solver.retry`` says so with both ratios, and the record counts
    both solves' iterations."""
    from gdimitate.retarget.params import Weights
    from gdimitate.retarget.trajectory.stride import STRIDE_RETRY, stride_weights

    h, clip, forces = _cut_stride(walk)
    g1, w = robot("g1"), Weights(over_feet=15.0)
    kw = dict(force="measured", forces=forces, verbose=False)
    r = gd.adapt(clip, h, g1, weights=w, **kw)
    once = gd.adapt(clip, h, g1, weights=w, stride_retry=False, **kw)
    again = gd.adapt(clip, h, g1, weights=stride_weights(w), stride_retry=False, **kw)
    r1, r2 = once.gait.travel_ratio, again.gait.travel_ratio
    assert once.audit.feasible and r1 < 0.8 and not once.solver.retry
    assert again.audit.feasible and not again.solver.unmet and 0.8 <= r2 <= 1.25
    assert r.solver.retry == (f"travel {r1:.2f} of the scaled demonstrator's: solved again "
                              f"with the gait's weights × {STRIDE_RETRY:g}: "
                              f"{r2:.2f}, kept")
    np.testing.assert_array_equal(r.motion.q, again.motion.q)
    assert r.gait.travel_ratio == r2 and r.audit.feasible
    assert r.solver.iterations == once.solver.iterations + again.solver.iterations


def test_unknown_gait_scaling_is_refused(walk, robot):
    """A scaling that is not one of SCALINGS is named with the valid ones, before any work;
    Froude scaling needs the trajectory mode."""
    from gdimitate.errors import InvalidInputError, UnknownNameError

    h, m, f = walk
    with pytest.raises(UnknownNameError, match="froude"):
        gd.adapt(m, h, robot("g1"), force="measured", forces=f, gait_scaling="inches")
    with pytest.raises(InvalidInputError, match="trajectory"):
        gd.adapt(m, h, robot("g1"), force="measured", forces=f, gait_scaling="froude",
                 mode="per_frame")


def test_limits_at_bound_from_the_joint_audit():
    """Closed form on audit rows: a torque at 0.995 of its limit and a velocity at 1.0 are at
    their bound, 0.98 is not, a position 0.5 mm from its limit is; no limit (NaN) is never."""
    from gdimitate.assess.audit.report import JointAudit
    from gdimitate.assess.verdict import limits_at_bound

    def row(name, tr, vr, pm):
        return JointAudit(name, tr, 0, 1.0, tr, vr, 0, 1.0, vr, pm, 0)

    class Aud:
        joints = (row("a", 0.995, 0.2, 1.0), row("b", 0.98, 1.0, 1.0),
                  row("c", float("nan"), float("nan"), 5e-4), row("d", 0.5, 0.5, 0.2))

    assert limits_at_bound(Aud()) == ["velocity:b 1.00", f"torque:a {0.995:.2f}", "position:c"]


@pytest.mark.slow
def test_a_gait_not_kept_says_so_and_names_the_limits(robot):
    """HOAP-2 cannot take the sagittal walk's scaled steps at the demonstrator's cadence (nor
    can Romeo the 3-D walk's: travel ratio 0.52, whose derivatives cost the suite a compile):
    its result is audit-feasible, prints "gait NOT kept" with the travel ratio, and lists
    limits at their bound that the Pinocchio audit recomputed (each ratio ≥ 0.99 in
    audit.joints)."""
    from gdimitate.assess.verdict import gait_lines

    h, m = gd.gait.human_walk()
    r = gd.adapt(m, h, robot("hoap2"), verbose=False)
    assert r.audit.feasible and not r.gait.kept
    lines = gait_lines(r)
    assert any(f"gait NOT kept: travel ratio {r.gait.travel_ratio:.2f}" in x for x in lines)
    named = lines[-1].removeprefix("limits at their bound: ").split(", ")
    ratios = {j.name: np.nanmax([j.torque_ratio, j.velocity_ratio, 0.0])
              for j in r.audit.joints}
    assert named and named[0] != "none"
    for item in named[:6]:
        kind, rest = item.split(":", 1)
        name = rest.split(" ")[0]
        assert kind == "position" or ratios[name] >= 0.99
