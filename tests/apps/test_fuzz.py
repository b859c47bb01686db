"""Issue 11, fuzzing: random malformed files and parameters through the public readers and
``adapt`` — only :class:`~gdimitate.errors.GdimitateError` subclasses may escape, and nothing
is written outside the requested output folder (nor left in the temporary folder).

Bounded to about a minute (``max_examples`` per reader, no deadline). Inputs are mutations of
valid files (a line dropped, duplicated or cut, a token replaced by junk, a number by NaN or
1e308) plus raw bytes, so the parsers get past their first line.
"""

from __future__ import annotations

import contextlib
import functools
import os
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gdimitate as gd
from gdimitate.apps.cli import main
from gdimitate.errors import BVHError, GdimitateError
from gdimitate.io.bvh import read_bvh
from gdimitate.io.gait import read_mot, read_opensim
from gdimitate.io.opensim import read_coordinates, read_grf
from gdimitate.model.motion import Motion
from gdimitate.model.robot import Robot
from tests.helpers import shared

FAST = settings(max_examples=200, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
SLOW = settings(FAST, max_examples=30)

JUNK = ["", "nan", "-nan", "inf", "1e308", "-1e999", "abc", "0x10", "1,5", "é", "\x00", "{",
        "}", "endheader", "inDegrees=no", "ROOT", "JOINT", "End Site", "Frames: 9999999",
        "Frame Time: 0", "CHANNELS 99", "OFFSET", "<link", '"', "../../etc/passwd"]


@contextlib.contextmanager
def sandbox(**files: str | bytes | dict):
    """A private working folder (the current one) holding ``files`` (name → text, bytes, or
    a dict of arrays for ``np.savez``) and a private temporary folder; yields ``(paths, out)``
    and checks on exit that nothing changed outside ``out`` and the temporary folder is empty."""
    with tempfile.TemporaryDirectory() as base:
        root = Path(base)
        work, tmp, out = root / "work", root / "tmp", root / "work" / "out"
        for d in (work, tmp):
            d.mkdir()
        paths = {}
        for name, content in files.items():
            paths[name] = p = work / name
            if isinstance(content, dict):
                np.savez(p, **content)
            elif isinstance(content, str):
                p.write_bytes(content.encode("utf-8", "surrogatepass"))
            else:
                p.write_bytes(content)
        before = {p: p.stat().st_mtime_ns for p in work.rglob("*")}
        old_tmp, old_cwd = tempfile.tempdir, os.getcwd()
        tempfile.tempdir = str(tmp)
        os.chdir(work)
        try:
            yield paths, out
        finally:
            os.chdir(old_cwd)
            tempfile.tempdir = old_tmp
        after = {p: p.stat().st_mtime_ns for p in work.rglob("*")
                 if p != out and not p.is_relative_to(out)}
        assert after == before, f"written outside the output folder: {set(after) ^ set(before)}"
        assert list(tmp.iterdir()) == [], f"left in the temporary folder: {list(tmp.iterdir())}"


def _ours(fn, *args, **kwargs):
    """Call ``fn``; an exception other than a GdimitateError fails the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return fn(*args, **kwargs)
        except GdimitateError:
            return None


@st.composite
def mutated(draw, lines: list[str], junk: list[str] = JUNK) -> str:
    """``lines`` with a few random edits (tokens replaced by items of ``junk``)."""
    lines = list(lines)
    for _ in range(draw(st.integers(1, 4))):
        if not lines:
            break
        i = draw(st.integers(0, len(lines) - 1))
        op = draw(st.sampled_from(["drop", "dup", "junk", "token", "token", "token", "cut",
                                   "swap"]))
        if op == "drop":
            del lines[i]
        elif op == "dup":
            lines.insert(i, lines[i])
        elif op == "junk":
            lines[i] = draw(st.sampled_from(junk))
        elif op == "token":
            toks = lines[i].split() or [""]
            toks[draw(st.integers(0, len(toks) - 1))] = draw(st.sampled_from(junk))
            lines[i] = " ".join(toks)
        elif op == "cut":
            lines = lines[:i]
        else:
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
    return "\n".join(lines)


# ------------------------------------------------------------------------- .mot / .sto
def _mot_lines() -> list[str]:
    t = np.arange(20) / 60
    cols = ["pelvis_tilt", "pelvis_tx", "pelvis_ty", "hip_flexion_r", "knee_angle_r",
            "ankle_angle_r", "hip_flexion_l", "knee_angle_l", "ankle_angle_l"]
    rows = [" \t".join(f"{v:.5f}" for v in [ti, *(20 * np.sin(ti * (k + 1)) for k in
                                                  range(len(cols)))]) for ti in t]
    return ["Coordinates", "version=1", "nRows=20", "nColumns=10", "inDegrees=yes",
            "endheader", "\t".join(["time", *cols]), *rows]


def _grf_lines() -> list[str]:
    cols = [f"{p}ground_{k}{a}" for p in ("", "1_") for k in ("force_v", "force_p", "torque_")
            for a in "xyz"]
    rows = []
    for i in range(20):
        f = [30.0, 700 * abs(np.sin(i / 6)), 5.0, 0.1 * i, 0.0, 0.1, 0.0, 0.0, 2.0]
        rows.append("\t".join(f"{v:.4f}" for v in [i / 60, *f, *f]))
    return ["grf.mot", "version=1", "nRows=20", "nColumns=19", "inDegrees=yes", "endheader",
            "\t".join(["time", *cols]), *rows]


HOAP2 = shared.library_robot("hoap2")


@FAST
@given(st.one_of(mutated(_mot_lines()), mutated(_grf_lines()),
                 st.binary(max_size=300).map(bytes)))
def test_fuzz_opensim_tables(content):
    with sandbox(**{"walk.mot": content}) as (paths, _):
        p = paths["walk.mot"]
        _ours(read_mot, p)
        _ours(read_opensim, p)
        _ours(read_coordinates, p, HOAP2)
        _ours(read_grf, p, HOAP2)


# ------------------------------------------------------------------------- .npz
KEYS = ["t", "q", "joint_names", "joint_nq", "base_nq", "contact_left", "contact_right", "v"]


@st.composite
def npz_content(draw) -> dict[str, np.ndarray]:
    m = Motion(np.arange(6) / 60, HOAP2.joint_names, np.tile(HOAP2.neutral, (6, 1)))
    good = {"t": m.t, "q": m.q, "joint_names": np.array(m.joint_names),
            "joint_nq": np.array(m.joint_nq), "base_nq": np.array(0),
            "contact_left": np.ones(6, bool), "contact_right": np.zeros(6, bool)}
    out = {k: v for k, v in good.items() if draw(st.booleans()) or k in ("t", "q")}
    for _ in range(draw(st.integers(0, 3))):
        k = draw(st.sampled_from(KEYS))
        kind = draw(st.sampled_from(["nan", "shape", "str", "bool", "empty", "big", "neg"]))
        out[k] = {"nan": np.full((6, 6), np.nan), "shape": np.zeros((3, 2, 2)),
                  "str": np.array(["x", "y"]), "bool": np.array(True), "empty": np.array([]),
                  "big": np.array(2**62), "neg": np.arange(-6.0, 0.0)}[kind]
    return out


@FAST
@given(st.one_of(npz_content(), st.binary(max_size=200).map(bytes)))
def test_fuzz_npz_motions(content):
    with sandbox(**{"m.npz": content}) as (paths, _):
        _ours(Motion.from_npz, paths["m.npz"])


# ------------------------------------------------------------------------- BVH
def _bvh_lines() -> list[str]:
    def joint(name, off, kids, ind):
        head = ["\t" * ind + f"JOINT {name}", "\t" * ind + "{",
                "\t" * ind + f"\tOFFSET {off}", "\t" * ind + "\tCHANNELS 3 Zrotation Xrotation "
                "Yrotation"]
        return head + kids + ["\t" * ind + "}"]

    end = ["\t\t\t\tEnd Site", "\t\t\t\t{", "\t\t\t\t\tOFFSET 0 -3 12", "\t\t\t\t}"]
    legs = []
    for side, x in (("Left", 9), ("Right", -9)):
        foot = joint(f"{side}Foot", "0 -40 0", end, 3)
        legs += joint(f"{side}UpLeg", f"{x} 0 0", joint(f"{side}Leg", "0 -42 0", foot, 2), 1)
    lines = ["HIERARCHY", "ROOT Hips", "{", "\tOFFSET 0 90 0",
             "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", *legs,
             *joint("Spine", "0 10 0", ["\t\tEnd Site", "\t\t{", "\t\t\tOFFSET 0 40 0", "\t\t}"],
                    1), "}", "MOTION", "Frames: 12", "Frame Time: 0.0333333"]
    n = 6 + 3 * 7
    for k in range(12):
        row = [0.0, 90.0, 4.0 * k] + [20 * np.sin(0.5 * k + c) for c in range(n - 3)]
        lines.append(" ".join(f"{v:.4f}" for v in row))
    return lines


@settings(FAST, max_examples=150)
@given(st.one_of(mutated(_bvh_lines(), JUNK), st.binary(max_size=200).map(bytes)))
def test_fuzz_bvh(content):
    with sandbox(**{"clip.bvh": content}) as (paths, _):
        _ours(read_bvh, paths["clip.bvh"])


def test_bvh_joint_name_with_a_control_character(tmp_path):
    """Found by fuzzing: a NUL in a BVH joint name escaped as lxml's ValueError; now BVHError."""
    p = tmp_path / "clip.bvh"
    p.write_text("\n".join(_bvh_lines()).replace("ROOT Hips", "ROOT \x00"))
    with pytest.raises(BVHError, match="control character"):
        read_bvh(p)


# ------------------------------------------------------------------------- URDF
MESHES = ["package://robot/../../../etc/passwd", "/etc/passwd", "file:///etc/hostname",
          "../outside.stl", "nope.stl", "http://example.com/x.stl", "", "torso.stl"]


@st.composite
def urdf_text(draw) -> str:
    """A random tree of links and joints: half the time with valid numbers (so Pinocchio
    parses it), else with NaN, negative, huge or missing values, missing parents and loops;
    sometimes with meshes pointing anywhere, and a junk token inserted anywhere."""
    n = draw(st.integers(1, 6))
    valid = draw(st.booleans())
    bad = ["0", "-6.98", "nan", "inf", "1e308", "x", ""]
    num = st.sampled_from(["1", "0.01", "0.2", "0.05"] * 12 + ([] if valid else bad))
    off = st.sampled_from(["0"] * 20 + ([] if valid else bad))
    links, joints = [], []
    for i in range(n):
        body = ""
        if valid or draw(st.integers(0, 4)):
            d = draw(num) if not valid else "0.01"
            I = ([d, d, d] if valid else [draw(num) for _ in range(3)]) + [draw(off)
                                                                          for _ in range(3)]
            body += (f'<inertial><origin xyz="0 0 {draw(num)}"/><mass value="{draw(num)}"/>'
                     f'<inertia ixx="{I[0]}" iyy="{I[1]}" izz="{I[2]}" ixy="{I[3]}" '
                     f'ixz="{I[4]}" iyz="{I[5]}"/></inertial>')
        if not draw(st.integers(0, 3)):
            body += (f'<visual><geometry><mesh filename="{draw(st.sampled_from(MESHES))}"/>'
                     '</geometry></visual>')
        links.append(f'<link name="{"left" if i % 2 else "right"}_l{i}">{body}</link>')
    for i in range(1, n):
        jt = draw(st.sampled_from(["revolute"] * 6 + ["fixed", "continuous", "prismatic",
                                                      "floating"] + ([] if valid else ["x"])))
        parent = draw(st.integers(0, i - 1) if valid else st.integers(0, n))
        side = lambda k: "left" if k % 2 else "right"  # noqa: E731
        joints.append(f'<joint name="{side(i)}_hip{i}" type="{jt}"><parent '
                      f'link="{side(parent)}_l{parent}"/><child link="{side(i)}_l{i}"/>'
                      f'<origin xyz="0 0 {draw(num)}"/><axis xyz="0 1 0"/><limit lower="-1" '
                      'upper="1" effort="1" velocity="1"/></joint>')
    return mutated_text(draw, f'<robot name="r">{"".join(links)}{"".join(joints)}</robot>')


def mutated_text(draw, text: str) -> str:
    if not draw(st.integers(0, 3)):
        i = draw(st.integers(0, len(text)))
        text = text[:i] + draw(st.sampled_from(JUNK)) + text[i:]
    return text


@FAST
@given(urdf_text())
def test_fuzz_urdf(text):
    stl = b"solid x\nendsolid x\n"
    with sandbox(**{"r.urdf": text, "torso.stl": stl}) as (paths, _):
        (paths["r.urdf"].parent.parent / "outside.stl").write_bytes(stl)
        _ours(Robot.from_urdf, paths["r.urdf"])


# ------------------------------------------------------------------------- adapt
DEMO = shared.library_robot("case1_demonstrator")


def _demo_motion(rng: np.random.Generator, T: int) -> Motion:
    t = np.arange(T) / 60
    q = np.tile(DEMO.neutral, (T, 1))
    for side, ph in (("left", 0.0), ("right", np.pi)):
        q[:, DEMO.idx_q(f"{side}_hip")] += 0.4 * np.sin(2 * np.pi * t + ph)
        q[:, DEMO.idx_q(f"{side}_knee")] -= 0.5 + 0.4 * np.sin(2 * np.pi * t + ph + 1)
    q += rng.normal(scale=rng.choice([0.0, 0.1, 3.0]), size=q.shape)
    c = np.sin(2 * np.pi * t) > 0
    return Motion(t, DEMO.joint_names, q, contact={"left": c, "right": ~c})


@SLOW
@given(seed=st.integers(0, 2**16), T=st.sampled_from([2, 3, 40]),
       method=st.sampled_from(["analytic", "copy", "nope"]),
       force=st.sampled_from(["segment", "com", "dynamics", "measured", "x"]),
       imitator=st.sampled_from(["hoap2", "case1_imitator", "humanoid_imitator", "bolt_x"]),
       options=st.dictionaries(st.sampled_from(["rate", "bogus"]),
                               st.sampled_from([0.0, -1.0, float("nan"), 30.0]), max_size=1))
def test_fuzz_adapt(seed, T, method, force, imitator, options):
    rng = np.random.default_rng(seed)
    motion = _demo_motion(rng, T)
    z = {"t": motion.t, "q": motion.q, "joint_names": np.array(motion.joint_names),
         "joint_nq": np.array(motion.joint_nq), "base_nq": np.array(motion.base_nq),
         **{f"contact_{k}": v for k, v in motion.contact.items()}}
    with sandbox(**{"demo.npz": z}) as (paths, out):
        _ours(gd.adapt, motion, DEMO, HOAP2, method, force=force, **options)
        with contextlib.redirect_stdout(None), contextlib.redirect_stderr(None):
            rc = main(["adapt", str(paths["demo.npz"]), "--demonstrator", "case1_demonstrator",
                       "--imitator", imitator if imitator != "bolt_x" else "hoap2",
                       "--method", method if method != "nope" else "copy",
                       "--force", force if force in ("segment", "com") else "segment",
                       "--out", str(out)])
        assert rc in (0, 2, 3)  # 3 (issue 22): written, but not feasible
        if rc in (0, 3):
            assert {p.name for p in out.iterdir()} == {"imitator_joints.csv", "gait.png",
                                                        "imitator_motion.npz", "report.json"}


def test_fuzz_seeds_are_valid(tmp_path):
    """The mutation seeds themselves are valid: the fuzzers start from files that load."""
    p = tmp_path / "walk.mot"
    p.write_text("\n".join(_mot_lines()))
    assert read_mot(p)["hip_flexion_r"].shape == (20,)
    p.write_text("\n".join(_grf_lines()))
    forces = read_grf(p, HOAP2)
    assert forces.feet["left"].force.shape == (20, 3)
    b = tmp_path / "clip.bvh"
    b.write_text("\n".join(_bvh_lines()))
    robot, motion = read_bvh(b)
    assert motion.T in (11, 12)
    assert motion.q.shape[1] == robot.model.nq


# ----------------------------------------------------- issue 22: the classes of hostile input
@functools.cache
def _g1() -> Robot:
    return shared.library_robot("g1")


@contextlib.contextmanager
def _cheap(peak_bytes: float = 100e6):
    """Refused (or done) without allocating more than ``peak_bytes``."""
    import tracemalloc

    tracemalloc.start()
    try:
        yield
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peak < peak_bytes, f"allocated {peak / 1e6:.0f} MB"


def _chain_bvh(frames: str, frame_time: str, depth: int) -> str:
    head = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 90 0",
            "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for k in range(1, depth):
        head += [f"JOINT J{k}", "{", "OFFSET 0 -1 0", "CHANNELS 3 Zrotation Xrotation Yrotation"]
    head += ["End Site", "{", "OFFSET 0 -1 0", "}"] + ["}"] * depth
    row = " ".join(["0"] * (6 + 3 * (depth - 1)))
    return "\n".join(head + ["MOTION", f"Frames: {frames}", f"Frame Time: {frame_time}",
                             row, row]) + "\n"


@settings(FAST, max_examples=30)
@given(frames=st.sampled_from(["2", "3", "100000000", "1000000000000", "99999999999999999999"]),
       frame_time=st.sampled_from(["0.0083333", "1e6", "2.5", "1e-9", "1e-5", "0.99", "inf"]),
       depth=st.sampled_from([1, 2, 50, 200, 201, 1500]))
def test_fuzz_bvh_sizes_are_bounded(frames, frame_time, depth):
    """Headers claiming huge frame counts, absurd frame times or deep chains: a
    GdimitateError (never MemoryError/RecursionError), without a large allocation."""
    from gdimitate.io.bvh.parse import parse_bvh

    with sandbox(**{"c.bvh": _chain_bvh(frames, frame_time, depth)}) as (paths, _):
        with _cheap():
            bvh = _ours(parse_bvh, paths["c.bvh"])
        if bvh is not None:  # accepted: within every bound, exactly as the file says
            assert bvh.frames.shape[0] == int(frames) == 2 and len(bvh.joints) == depth


LIMIT_VALUES = ["-1", "1", "0", "-0.5", "2.5", "nan", "inf", "-inf", "x", "1e308"]


@settings(FAST, max_examples=80)
@given(lower=st.sampled_from(LIMIT_VALUES), upper=st.sampled_from(LIMIT_VALUES),
       effort=st.sampled_from(LIMIT_VALUES), velocity=st.sampled_from(LIMIT_VALUES),
       xyz=st.sampled_from(["0 0 -0.1", "nan 0 0", "0 inf 0", "0 0", "a b c", "0 0 0 0"]),
       dup=st.booleans())
def test_fuzz_urdf_joint_numbers(lower, upper, effort, velocity, xyz, dup):
    """A joint's limits and origin from hostile numbers: refused with URDFError, or loaded
    with lower ≤ upper (so the audit checks its position)."""
    import re

    from gdimitate.errors import URDFError
    from gdimitate.model.urdfgen import PLANAR_MODELS, planar_biped_urdf

    text = planar_biped_urdf(PLANAR_MODELS["hoap2"])
    block = re.search(r'<joint name="left_knee".*?</joint>', text, re.S).group(0)
    new = re.sub(r'<origin xyz="[^"]*"', f'<origin xyz="{xyz}"', block, count=1)
    new = re.sub(r"<limit [^>]*/>", f'<limit lower="{lower}" upper="{upper}" '
                 f'effort="{effort}" velocity="{velocity}"/>', new)
    text = text.replace(block, new)
    if dup:
        text = text.replace('<link name="left_thigh">', '<link name="left_thigh"/>'
                            '<link name="left_thigh">', 1)
    with sandbox(**{"r.urdf": text}) as (paths, _):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                robot = Robot.from_urdf(paths["r.urdf"])
        except URDFError:
            return
    m = robot.model
    i = m.joints[m.getJointId("left_knee")].idx_q
    assert m.lowerPositionLimit[i] <= m.upperPositionLimit[i]
    assert not dup and "nan" not in (lower, upper, effort, velocity) and "nan" not in xyz


@settings(FAST, max_examples=30)
@given(quat=st.tuples(*[st.sampled_from([0.0, 1.0, -1.0, 0.5, 1e-3, 2.0, 0.7071067811865476])
                        for _ in range(4)]))
def test_fuzz_npz_base_quaternion(quat):
    """A free-flyer motion file with any base quaternion: read iff it is of unit norm."""
    from gdimitate.errors import InvalidInputError

    g1 = _g1()
    q = np.tile(g1.neutral, (3, 1))
    q[1, 3:7] = quat
    z = {"t": np.arange(3) / 30, "q": q, "joint_names": np.array(g1.joint_names),
         "joint_nq": np.array([g1.model.joints[j].nq for j in range(1, g1.model.njoints)]),
         "base_nq": np.array(7)}
    with sandbox(**{"m.npz": z}) as (paths, _):
        unit = abs(np.linalg.norm(quat) - 1) <= 1e-5
        try:
            Motion.from_npz(paths["m.npz"])
            assert unit
        except InvalidInputError as e:
            assert not unit and "unit quaternion" in str(e)


@settings(FAST, max_examples=30)
@given(rate=st.one_of(st.floats(1000.5, 1e300), st.sampled_from([float("nan"), float("inf"),
                                                                 -1.0, 0.0])),
       fps=st.one_of(st.floats(2e6, 1e300), st.sampled_from([float("nan"), -30.0, 0.0])),
       shape=st.lists(st.integers(1, 10**9), min_size=1, max_size=4).filter(
           lambda s: int(np.prod(s, dtype=object)) * 32 > 2**30))
def test_fuzz_user_numbers_that_size_arrays(rate, fps, shape):
    """Knot rates, export frame rates and bank shapes beyond the bounds: refused (a
    GdimitateError) before anything large is allocated — never MemoryError or a long run."""
    import time

    from gdimitate.export.writers import export_motion
    from gdimitate.model.kinematics import kinematic_contact

    hoap2 = HOAP2
    t = np.arange(40) / 60
    q = np.tile(hoap2.neutral, (40, 1))
    q[:, hoap2.idx_q("left_hip")] += 0.3 * np.sin(2 * np.pi * t)
    m = Motion(t, hoap2.joint_names, q, contact=kinematic_contact(hoap2, q))
    g1 = _g1()
    gm = Motion(t, g1.joint_names, np.tile(g1.neutral, (40, 1)), base_nq=7,
                joint_nq=tuple(g1.model.joints[j].nq for j in range(1, g1.model.njoints)))
    p = gd.oscillator.MatsuokaParams(tau_r=0.1, tau_a=0.4, b=2.5, w=2.5, s=1.0)
    with sandbox() as (_, out):
        out.mkdir()
        t0 = time.perf_counter()
        with _cheap():
            for call in (lambda: gd.adapt(m, hoap2, hoap2, rate=rate),
                         lambda: export_motion(g1, gm, out / "x.csv", "lafan1_csv", fps=fps),
                         lambda: gd.oscillator.MatsuokaBank(p, shape=tuple(shape))):
                with pytest.raises(GdimitateError):
                    call()
        assert time.perf_counter() - t0 < 5.0
        assert list(out.iterdir()) == []


# ------------------------------------------------------------------ issue 33: let in
_BOMB = ('<?xml version="1.0" encoding="{enc}"?>\n<!DOCTYPE r [<!ENTITY e "{big}">]>\n'
         "<{root}>&e;</{root}>")


@pytest.mark.parametrize("enc", ["UTF-8", "UTF-16", "UTF-16LE", "UTF-16BE", "UTF-32"])
@pytest.mark.parametrize(("kind", "root"), [("urdf", "robot"), ("osim", "OpenSimDocument"),
                                            ("xml", "OpenSimDocument")])
def test_no_dtd_or_entity_in_any_encoding(tmp_path, enc, kind, root):
    """A UTF-16 .osim with <!DOCTYPE>/<!ENTITY> was accepted and the entity expanded (the
    guard scanned the raw bytes for ASCII): now every XML reader — URDF, OpenSim model,
    ExternalLoads — refuses a declaration in whatever encoding the file declares."""
    from gdimitate.io.opensim.grf import read_external_loads

    text = _BOMB.format(enc=enc, big="x" * 1000, root=root)
    codec = {"UTF-16": "utf-16", "UTF-16LE": "utf-16-le", "UTF-16BE": "utf-16-be",
             "UTF-32": "utf-32"}.get(enc, "utf-8")
    p = tmp_path / f"bomb.{kind}"
    p.write_bytes(text.encode(codec))
    read = {"urdf": Robot.from_urdf, "osim": Robot.from_osim, "xml": read_external_loads}[kind]
    # refused as a declaration, or before: not UTF-8 (URDF), an encoding expat lacks (UTF-32)
    with pytest.raises(GdimitateError, match="(DOCTYPE|not UTF-8|malformed XML)"):
        read(p)


def test_xml_nested_too_deep_is_refused(tmp_path):
    """A URDF nested 2,000 elements deep raised RecursionError further on."""
    p = tmp_path / "deep.urdf"
    p.write_text('<robot name="r">' + "<a>" * 2000 + "</a>" * 2000 + "</robot>")
    with pytest.raises(GdimitateError, match="nested 257 elements deep"):
        Robot.from_urdf(p)
