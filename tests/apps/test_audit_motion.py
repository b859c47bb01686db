"""``gd.audit_motion`` and ``gdimitate audit``: a robot motion dataset checked for physical
feasibility. Each verdict and number is compared with an independent reference: the audit of
the same motion computed here step by step (:func:`gdimitate.model.motion.differentiate`,
:func:`gdimitate.assess.wrenches.estimate_wrenches`, :func:`gdimitate.assess.audit.audit`), and the
same
motion before it was written to another format."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest

import gdimitate as gd
from gdimitate.apps.cases import paper_case
from gdimitate.apps.cli import main
from gdimitate.assess.audit import audit
from gdimitate.assess.verdict import EXIT_NOT_FEASIBLE
from gdimitate.assess.wrenches import estimate_wrenches
from gdimitate.io.demonstration import load_demonstration
from gdimitate.model.motion import differentiate
from tests.helpers import shared


def _slice(m, a, b):
    return m.replace(t=m.t[a:b], q=m.q[a:b], contact={s: c[a:b] for s, c in m.contact.items()})


@pytest.fixture(scope="module")
def case2():
    d, i, m = paper_case("II")
    return d, i, _slice(m, 0, 60)


@pytest.fixture(scope="module")
def optimal(case2):
    d, i, m = case2
    return gd.adapt(m, d, i, method="optimal", rate=25, verbose=False)


def _same_checks(got: list[dict], ref, tol: float) -> None:
    """Every check of the report ``ref`` has the same value, bound and verdict in the JSON
    checks ``got`` (NaN ↔ None), and the same worst knot where ``tol`` is round-off only."""
    by = {c["name"]: c for c in got}
    assert set(by) == {c.name for c in ref.checks}
    for c in ref.checks:
        g = by[c.name]
        for key in ("value", "bound"):
            want, have = getattr(c, key), g[key]
            if not math.isfinite(want):
                assert have is None, (c.name, key, have)
            else:
                assert have == pytest.approx(want, rel=tol, abs=tol), (c.name, key)
        assert g["passed"] == c.passed, c.name
        if tol <= 1e-9:  # read back from another format, two knots may tie for the worst
            assert g["knot"] == c.knot, c.name


def _cli(capsys, *args):
    status = main(["audit", *map(str, args)])
    out = capsys.readouterr()
    return status, out.out, out.err


def test_an_optimal_result_audits_feasible_as_its_direct_audit(case2, optimal, tmp_path, capsys):
    _, i, _ = case2
    path = tmp_path / "optimal.npz"
    optimal.save(path, "npz")
    status, out, _ = _cli(capsys, path, "--out", tmp_path / "out")  # robot recorded
    # the reference: the file's motion, its wrenches estimated and audited here
    motion = load_demonstration(path).motion
    assert motion.v is not None and motion.contact
    ref = audit(i, motion, estimate_wrenches(i, motion).wrenches)
    assert ref.feasible and optimal.audit.feasible  # and the adaptor's own audit agrees
    assert status == 0 and "1 of 1 clip(s) feasible" in out and "optimal.npz" in out
    (row,) = json.loads((tmp_path / "out" / "report.json").read_text())
    assert row["summary"]["feasible"] is True and row["audit"]["feasible"] is True
    _same_checks(row["audit"]["checks"], ref, 1e-9)
    assert row["summary"]["share_feasible"] == ref.knot_feasible.mean() == 1.0
    lines = (tmp_path / "out" / "audit.csv").read_text().splitlines()
    assert lines[0].startswith("file,format,robot,frames,share_feasible,torque_ratio")
    assert lines[1].split(",")[:4] == ["optimal.npz", "npz", "hoap2", str(motion.T)]
    assert lines[1].split(",")[12] == "yes"


def test_a_joint_copy_is_not_feasible_with_its_failed_checks_printed(case2, tmp_path, capsys):
    d, i, m = case2
    copy = gd.adapt(m, d, i, method="copy")
    path = tmp_path / "copy.npz"
    copy.save(path, "npz")
    status, out, _ = _cli(capsys, path, "--robot", "hoap2", "--out", tmp_path / "out")
    motion = load_demonstration(path).motion
    motion = differentiate(i.model, motion)
    ref = audit(i, motion, estimate_wrenches(i, motion).wrenches)
    assert not ref.feasible
    assert status == EXIT_NOT_FEASIBLE and "0 of 1 clip(s) feasible" in out
    for name in ref.binding:
        assert f"  {name}: " in out, name
    c = ref.check(ref.binding[0])
    assert f"{c.value:.4g}" in out and f"at knot {c.knot}" in out
    (row,) = json.loads((tmp_path / "out" / "report.json").read_text())
    _same_checks(row["audit"]["checks"], ref, 1e-9)
    assert row["summary"]["binding"] == list(ref.binding)
    assert row["summary"]["share_feasible"] == pytest.approx(ref.knot_feasible.mean(), abs=0)


def test_summary_numbers_are_the_reports_checks(case2):
    """Each per-clip number against the check of the same quantity (another path through the
    report: its checks rather than its feet and joints)."""
    d, i, m = case2
    a = gd.audit_motion(i, gd.adapt(m, d, i, method="copy").motion)
    r = a.report
    sides = ("left", "right")
    assert a.share_feasible == np.mean(np.all(r.knot_checks, axis=0))
    assert a.slip == max(r.check(f"slip:{s}").value for s in sides)
    assert a.cop_margin == min(r.check(f"cop:{s}").value for s in sides)
    assert a.friction == max(r.check(f"friction:{s}").value for s in sides)
    assert a.hover == max(r.check(f"contact_gap:{s}").value for s in sides)
    assert a.penetration == r.check("penetration").value
    torque = {c.name[7:]: c.value for c in r.checks if c.name.startswith("torque:")}  # |τ|/limit
    joint = max(torque, key=torque.__getitem__)
    assert a.torque_joint == joint and a.torque_ratio == pytest.approx(torque[joint], rel=1e-12)
    assert a.self_collision is None and a.frames == m.T and not a.feasible
    assert a.to_dict()["summary"]["torque_joint"] == joint


def test_a_csv_export_audits_as_the_motion_it_holds(case2, optimal, tmp_path, capsys):
    """A planar robot's motion through the ``csv`` export (base as a 3-D pose): no contacts,
    no velocities in the file — found from the sole heights and speeds and differenced, the
    same as auditing the motion's q alone."""
    _, i, _ = case2
    path = tmp_path / "optimal.csv"
    optimal.save(path, "csv")
    status, out, _ = _cli(capsys, path, "--robot", "hoap2", "--out", tmp_path / "out")
    ref = gd.audit_motion(i, optimal.motion.replace(contact={}, v=None, a=None))
    assert ref.contact_source != "motion"
    (row,) = json.loads((tmp_path / "out" / "report.json").read_text())
    assert row["format"] == "csv" and row["summary"]["contact_source"] == ref.contact_source
    _same_checks(row["audit"]["checks"], ref.report, 1e-6)
    assert status == (0 if ref.feasible else EXIT_NOT_FEASIBLE)


@pytest.fixture(scope="module")
def g1_copy(walk_3d, robot):
    """G1, a joint copy of 70 frames (60 Hz) of the shipped 3-D walk (no compilation) and the
    reference: the audit of its q alone."""
    human, walk, _ = walk_3d
    g1 = robot("g1")
    motion = gd.adapt(_slice(walk, 0, 70), human, g1, method="copy").motion
    assert np.allclose(np.diff(motion.t), 1 / 60)
    return g1, motion, gd.audit_motion(g1, motion.replace(contact={}, v=None, a=None))


#: every export format, a file name for it (one folder holds them all) and the reading rule
FORMAT_FILES = {"csv": "walk.csv", "npz": "walk.npz", "mujoco": "walk_mujoco.npz",
                "lafan1_csv": "walk_lafan1.csv", "gmr": "walk.pkl",
                "isaaclab_amp": "walk_amp.npz", "beyondmimic_npz": "walk_beyondmimic.npz"}


@functools.cache
def _talos_copy():
    human, walk, _ = shared.walk_3d()
    talos = shared.library_robot("talos")
    return talos, gd.adapt(_slice(walk, 0, 70), human, talos, method="copy").motion


@pytest.fixture(params=["g1 copy", "g1 walk", "talos copy"])
def motion_case(request):
    """``(robot, motion, feasible)``: a joint copy (q only, 60 Hz; not feasible) on G1 and
    Talos and an adapted walk (the adaptor's q, v, a and stance; feasible) on G1. Talos's
    adapted walk (its repaired joint copy) held too when measured, but it compiles Talos's
    problem (190 s on 2 cores), so the suite leaves it out."""
    if request.param == "g1 copy":
        g1, m, _ = request.getfixturevalue("g1_copy")
        return g1, m.replace(contact={}, v=None, a=None), False
    if request.param == "g1 walk":
        adapted = request.getfixturevalue("g1_stride")[3]
        return adapted.robot, adapted.motion, True
    talos, m = _talos_copy()
    return talos, m.replace(contact={}, v=None, a=None), False


def test_every_export_format_audits_as_the_motion_it_holds(motion_case, tmp_path, capsys):
    """Issue 36's Done-when: a motion written in each export format (:data:`FORMAT_FILES`)
    and read back by ``gdimitate audit`` (one folder, ``--fps`` the motion's own rate) gets
    the audit of the original margin by margin within 1e-6 (value, bound, verdict of every
    check; the share of knots feasible; the closest self-collision).

    Each format is written at the motion's own frame rate (60 Hz for the copies, their clock
    put on the exact 60 Hz grid; the walks' knot rates), so the resampling onto the format's
    ``fps`` grid is the identity: a format
    written at another rate holds the motion resampled, and must be compared with the
    original sampled at that rate (not with looser tolerances). What "the original" is
    follows what the file holds: ``npz`` holds q, v, a and the stance — compared with the
    original's audit as it is (an adapted walk: feasible); every other format holds q alone —
    compared with the audit of the original's q alone (stance from the soles' height and
    speed, v and a central differences). For an adapted walk that audit is NOT feasible: the
    soles' lowest corner finds the stance ending a few knots after the adaptor lifts the foot
    (``contact_gap``, ``slip``, ``stance_velocity``) and central differences of q are not the
    adaptor's semi-implicit v and a (``base_residual``, ``velocity_consistency``, ankle
    torques a few % over their limits) — the same verdict, read back or not."""
    robot, motion, feasible = motion_case
    fps = float(round(1.0 / float(np.median(np.diff(motion.t)))))
    # the shipped walk's clock is 59.99999 Hz (its times rounded to 1e-6 s): the copies on
    # the exact 60 Hz grid the files hold (the walks' knots are on it already)
    assert np.abs(np.diff(motion.t) - 1 / fps).max() < 1e-6
    motion = motion.replace(t=motion.t[0] + np.arange(motion.T) / fps)
    folder = tmp_path / "in"
    folder.mkdir()
    for fmt, name in FORMAT_FILES.items():
        gd.export_motion(robot, motion, folder / name, fmt, fps=fps)
    status, out, _ = _cli(capsys, folder, "--robot", robot.name, "--fps", f"{fps:.17g}",
                          "--out", tmp_path / "out")
    rows = {r["format"]: r for r in json.loads((tmp_path / "out" / "report.json").read_text())}
    assert set(rows) == set(FORMAT_FILES)
    full = gd.audit_motion(robot, motion)
    bare = gd.audit_motion(robot, motion.replace(contact={}, v=None, a=None))
    assert full.feasible is feasible
    for fmt, row in rows.items():
        ref = full if fmt == "npz" else bare
        assert row["summary"]["frames"] == motion.T, fmt
        assert row["summary"]["feasible"] is ref.feasible, fmt
        assert row["summary"]["share_feasible"] == pytest.approx(ref.share_feasible, abs=1e-6)
        _same_checks(row["audit"]["checks"], ref.report, 1e-6)
        assert ref.self_collision is not None and row["summary"]["self_collision"] == \
            pytest.approx(ref.self_collision, abs=1e-6), fmt
    n_ok = sum(r["summary"]["feasible"] for r in rows.values())
    assert n_ok == (feasible + 6 * bare.feasible)
    assert status == (0 if n_ok == len(rows) else EXIT_NOT_FEASIBLE)
    assert f"{n_ok} of {len(rows)} clip(s)" in out


def test_bad_inputs_exit_2_saying_what_to_pass(case2, tmp_path, capsys):
    _, i, m = case2
    odd = tmp_path / "motion.txt"
    odd.write_text("1,2,3\n")
    status, _, err = _cli(capsys, odd, "--robot", "hoap2", "--out", tmp_path / "o1")
    assert status == 2 and "unknown motion format '.txt'" in err and "lafan1_csv" in err
    csv = tmp_path / "m.csv"
    gd.export_motion(i, m, csv, "csv")
    status, _, err = _cli(capsys, csv, "--out", tmp_path / "o2")
    assert status == 2 and "records no robot" in err and "--robot" in err
    bare = tmp_path / "bare.npz"
    m.to_npz(bare)  # no robot recorded
    status, _, err = _cli(capsys, bare, "--out", tmp_path / "o3")
    assert status == 2 and "--robot" in err
    status, _, err = _cli(capsys, tmp_path / "missing.npz", "--out", tmp_path / "o4")
    assert status == 2 and "does not exist" in err
    assert not (tmp_path / "o1").exists() and not (tmp_path / "o2").exists()
