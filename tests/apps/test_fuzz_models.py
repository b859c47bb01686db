"""Fuzzing robot models and motions (issue 33: nothing lost, nothing let in, no crash).

Classes of inputs, each from a generator (parametrised lists: NaN/inf/huge/unicode in every
numeric field, nesting and size bombs, wrong types):

1. URDFs at and beyond the size limits (degrees of freedom — Pinocchio's data grows as
   64·nv³ bytes —, shapes — its geometry parser's time is cubic —, XML nesting), loaded in a
   child process capped at 3 GiB and 30 s (:mod:`isolated`).
2. URDF content Pinocchio rejects with one generic message or accepts wrongly: every
   structural fault named, every numeric field fuzzed (an inertial origin of two numbers used
   to drop the torso's mass silently, a zero axis passed), absurd magnitudes refused; mesh
   file names the file system cannot look up.
3. BVH: the size bound, unicode digits, non-finite and absurd numbers in every kind of field.
4. ``.npz`` motions: a recorded package folder may not widen the mesh sandbox; the base's
   layout comes from the robot (a file's ``base_nq=0`` skipped the quaternion check);
   malformed recorded JSON and arrays.
5. JSON option text (legs, contacts, body maps: files or strings) and API argument types:
   a :class:`~gdimitate.errors.GdimitateError` naming the argument, never a bare exception.
"""

from __future__ import annotations

import json
import math
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import gdimitate as gd
from gdimitate.errors import (
    BVHError,
    ExportError,
    FileFormatError,
    GdimitateError,
    InvalidInputError,
    MeshPathError,
    ResourceLimitError,
    RobotMismatchError,
    URDFError,
    URDFLimitError,
)
from gdimitate.safety import MAX_BVH_BYTES, MAX_URDF_DOF, MAX_URDF_GEOMETRIES
from tests.helpers.isolated import call

CMU = Path(gd.__file__).parent / "data" / "gait" / "cmu_02_01" / "cmu_02_01.bvh"
BAD_NUMBERS = ["nan", "inf", "-inf", "1e309", "", "x", "١", "0x10", "1_0"]


# ---------------------------------------------------------------------------- a biped
def _inertial(m: float = 1.0, i: float = 0.01, xyz: str = "0 0 0") -> str:
    return (f'<inertial><origin xyz="{xyz}" rpy="0 0 0"/><mass value="{m}"/><inertia '
            f'ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>')


def _joint(name: str, parent: str, child: str, xyz: str = "0 0 0", axis: str = "0 1 0",
           kind: str = "revolute") -> str:
    lim = ('<limit lower="-1" upper="1" effort="10" velocity="5"/>'
           if kind in ("revolute", "prismatic") else "")
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="0 0 0"/><axis xyz="{axis}"/>{lim}</joint>')


def biped(links: str = "", joints: str = "", pelvis: str = "", mesh: str = "") -> str:
    """A 6-DoF biped whose legs and soles are detected (feet: collision boxes), with extra
    ``links``/``joints``, extra elements of the pelvis link and a pelvis ``mesh`` visual."""
    if mesh:
        pelvis += f'<visual><geometry><mesh filename="{mesh}"/></geometry></visual>'
    L = [f'<link name="pelvis">{_inertial(10, 0.1, "0 0 0.05")}{pelvis}</link>']
    J = []
    for s, y in (("left", 0.1), ("right", -0.1)):
        L += [f'<link name="{s}_thigh">{_inertial(2)}</link>',
              f'<link name="{s}_shank">{_inertial(1.5)}</link>',
              f'<link name="{s}_foot">{_inertial(0.6)}<collision><origin xyz="0 0 -0.02"/>'
              '<geometry><box size="0.2 0.08 0.04"/></geometry></collision></link>',
              f'<link name="{s}_sole"/>']
        J += [_joint(f"{s}_hip", "pelvis", f"{s}_thigh", f"0 {y} 0"),
              _joint(f"{s}_knee", f"{s}_thigh", f"{s}_shank", "0 0 -0.3"),
              _joint(f"{s}_ankle", f"{s}_shank", f"{s}_foot", "0 0 -0.3"),
              _joint(f"{s}_sole_joint", f"{s}_foot", f"{s}_sole", "0 0 -0.04", kind="fixed")]
    return f'<robot name="b">{"".join(L)}{links}{"".join(J)}{joints}</robot>'


def tail(n: int, kind: str = "revolute", star: bool = False) -> tuple[str, str]:
    """``n`` extra links on joints of ``kind``: a chain hanging from the pelvis, or a star."""
    links = "".join(f'<link name="t{i}">{_inertial(0.1, 0.001)}</link>' for i in range(n))
    joints = "".join(_joint(f"tj{i}", "pelvis" if star or i == 0 else f"t{i - 1}", f"t{i}",
                            "0 0 0.01", "1 0 0", kind) for i in range(n))
    return links, joints


def boxes(n: int) -> str:
    return "".join('<visual><origin xyz="0 0 0.1"/><geometry><box size="0.01 0.01 0.01"/>'
                   "</geometry></visual>" for _ in range(n))


def _write(folder: Path, text: str, name: str = "robot.urdf") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / name
    p.write_text(text)
    return p


# ---------------------------------------------------------------------------- 1. sizes
@pytest.mark.parametrize("case", ["chain", "star", "planar+floating", "shapes"])
def test_urdf_beyond_the_size_limits_is_refused_before_pinocchio(tmp_path, case):
    """A 500-joint chain reached 5.2 GB and MemoryError in createData; 20 000 boxes did not
    load in 150 s. Beyond MAX_URDF_DOF / MAX_URDF_GEOMETRIES: URDFLimitError with the count
    and the limit, within the 3 GiB / 30 s cap."""
    n = 2 * MAX_URDF_DOF
    if case == "chain":
        text, count = biped(*tail(n)), n + 6
    elif case == "star":
        text, count = biped(*tail(n, star=True)), n + 6
    elif case == "planar+floating":  # 3 and 6 degrees of freedom each
        a, b = tail(n // 6, "planar", star=True)
        c, d = tail(n // 6, "floating", star=True)
        text = biped(a + c.replace('name="t', 'name="u'), b + d.replace('"t', '"u'))
        count = 6 + 9 * (n // 6)
    else:
        text, count = biped(pelvis=boxes(3 * MAX_URDF_GEOMETRIES)), 3 * MAX_URDF_GEOMETRIES + 2
    path = _write(tmp_path, text)
    o = call("gdimitate.model.robot:Robot.from_urdf", str(path))
    assert o.handled(), o
    assert "URDFLimitError" in o.mro, o
    limit = MAX_URDF_GEOMETRIES if case == "shapes" else MAX_URDF_DOF
    assert f"has {count:,} " in o.message and f"the limit is {limit:,}" in o.message, o
    assert o.elapsed < 15, o


def test_urdf_at_the_size_limits_loads_within_2_gib_and_30_s(tmp_path):
    """The limits are what the library can do: MAX_URDF_DOF degrees of freedom and
    MAX_URDF_GEOMETRIES shapes together load through Robot.from_urdf (pin.Data and the
    library's own tables) under the child's cap — and one more of either is refused."""
    links, joints = tail(MAX_URDF_DOF - 6)
    at = _write(tmp_path, biped(links, joints, pelvis=boxes(MAX_URDF_GEOMETRIES - 2)))
    o = call("gdimitate.model.robot:Robot.from_urdf", str(at))
    assert o.handled() and o.ok, o
    over = biped(links + '<link name="x">' + _inertial() + "</link>",
                 joints + _joint("xj", "pelvis", "x"))
    with pytest.raises(URDFLimitError, match=f"has {MAX_URDF_DOF + 1} degrees of freedom"):
        gd.Robot.from_urdf(_write(tmp_path, over, "over.urdf"))
    over = biped(pelvis=boxes(MAX_URDF_GEOMETRIES - 1))
    with pytest.raises(URDFLimitError, match=f"the limit is {MAX_URDF_GEOMETRIES:,}"):
        gd.Robot.from_urdf(_write(tmp_path, over, "shapes.urdf"))


@pytest.mark.parametrize("depth", [1_500, 3_000])
def test_urdf_nested_deep_is_an_error_not_a_recursion(tmp_path, depth):
    nest = "<a>" * depth + "</a>" * depth
    path = _write(tmp_path, biped(pelvis=f"<visual>{nest}<geometry><box size='1 1 1'/>"
                                         "</geometry></visual>"))
    with pytest.raises(URDFError) as e:
        gd.Robot.from_urdf(path)
    assert "nest" in str(e.value).lower() or "deep" in str(e.value).lower()


# ---------------------------------------------------------------------------- 2. content
STRUCTURE = [  # (mutation of the biped's text, what the message must say)
    (('<parent link="left_thigh"/>', '<parent link="nowhere"/>'),
     "parent link 'nowhere' is not defined"),
    (('<child link="left_shank"/>', '<child link="ghost"/>'), "child link 'ghost' is not defined"),
    (('<parent link="left_thigh"/>', ""), "joint 'left_knee' has no <parent link"),
    (('<child link="left_shank"/>', ""), "joint 'left_knee' has no <child link"),
    (('name="left_knee" type="revolute"', 'name="left_knee" type="hinge"'),
     "joint 'left_knee' has type 'hinge'"),
    (('name="left_knee" type="revolute"', 'name="left_knee"'), "joint 'left_knee' has type None"),
    (('<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="5"/></joint>'
      '<joint name="left_ankle"', '<axis xyz="0 1 0"/></joint><joint name="left_ankle"'),
     "joint 'left_knee' (revolute) has no <limit>"),
    (('effort="10" ', ""), "<limit> has no effort"),
    (('velocity="5"', ""), "<limit> has no velocity"),
    (("</robot>", '<link name="lonely"/></robot>'), "2 root links"),
    (("</robot>", '<joint name="again" type="fixed"><parent link="right_foot"/>'
                  '<child link="left_sole"/></joint></robot>'),
     "link 'left_sole' is the child of two joints"),
    (("</robot>", '<joint name="back" type="fixed"><parent link="left_sole"/>'
                  '<child link="pelvis"/></joint></robot>'), "loop"),
    (('<joint name="left_knee"', '<joint'), "has no name"),
    (('<link name="left_sole"/>', "<link/>"), "has no name"),
    (('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>'), "zero vector"),
    (('xyz="0 0 0.05"', 'xyz="0 0.13"'), "link 'pelvis' <inertial>: <origin xyz='0 0.13'>"),
    (('<box size="0.2 0.08 0.04"/>', '<box size="0.2 0.08"/>'), "<box size='0.2 0.08'>"),
    (('<box size="0.2 0.08 0.04"/>', '<sphere/>'), "<sphere radius=None>"),
    (('<box size="0.2 0.08 0.04"/>', '<cylinder radius="0.1"/>'), "<cylinder length=None>"),
    (('<box size="0.2 0.08 0.04"/>', '<box size="0.2 -0.08 0.04"/>'), "outside"),
]


@pytest.mark.parametrize("mutation, said", STRUCTURE, ids=[s for _, s in STRUCTURE])
def test_urdf_faults_are_named(tmp_path, mutation, said):
    """Each fault Pinocchio answered with "The XML stream does not contain a valid URDF model"
    (or accepted: a second parent, a two-number inertial origin that dropped the pelvis's
    10 kg, a zero axis, a malformed box that dropped the foot's collision geometry)."""
    old, new = mutation
    text = biped()
    assert old in text
    path = _write(tmp_path, text.replace(old, new, 1))
    with pytest.raises(URDFError) as e:
        gd.Robot.from_urdf(path)
    msg = str(e.value)
    assert said in msg and str(path) in msg, msg
    assert "not contain a valid URDF" not in msg


#: (attribute text in the biped, index of the number in it, is it a length/mass/inertia)
FIELDS = [('<origin xyz="0 0.1 0"', 1, True), ('<origin xyz="0 0 -0.3" rpy="0 0 0"', 0, False),
          ('<inertial><origin xyz="0 0 0.05"', 2, True), ('<axis xyz="0 1 0"', 1, False),
          ('<mass value="10"', 0, True), ('ixx="0.1"', 0, True),
          ('<box size="0.2 0.08 0.04"', 2, True), ('lower="-1"', 0, False),
          ('effort="10"', 0, False)]


@pytest.mark.parametrize("field", FIELDS, ids=[f[0] for f in FIELDS])
@pytest.mark.parametrize("value", [*BAD_NUMBERS, "1e308", "-1e308", "1e6"])
def test_urdf_numeric_fields_are_finite_and_bounded(tmp_path, field, value):
    """Every numeric field with NaN, inf, overflow, junk, unicode digits, underscores and
    absurd magnitudes: refused naming the element (lengths over 1 km, masses over 100 t and
    inertias over 1e7 kg·m² are refused with the bound), never silently loaded."""
    text, k, magnitude = field
    q = text.rindex('"')
    head, nums = text[:text.rindex('"', 0, q) + 1], text[text.rindex('"', 0, q) + 1:q].split()
    nums[k] = value
    new = head + " ".join(nums) + '"'
    src = biped()
    assert text in src
    path = _write(tmp_path, src.replace(text, new, 1))
    try:
        x = float(value) if value.isascii() and "_" not in value else None
    except ValueError:
        x = None
    absurd = x is None or not math.isfinite(x) or (magnitude and abs(x) > 1e3)
    if field[0].startswith("<mass") and x is not None and x < 0:
        absurd = True
    if not absurd:
        return  # e.g. 1e6 N·m of effort: a number, just large
    with pytest.raises(URDFError) as e:
        gd.Robot.from_urdf(path)
    assert str(path) in str(e.value)
    assert "valid URDF model" not in str(e.value)


@pytest.mark.parametrize("name", ["a" * 5000 + ".stl", "d/" * 3 + "b" * 300 + ".stl",
                                  "package://" + "p" * 4000 + "/m.stl"])
def test_mesh_names_the_file_system_cannot_look_up(tmp_path, name):
    path = _write(tmp_path, biped(mesh=name))
    with pytest.raises(MeshPathError) as e:
        gd.Robot.from_urdf(path)
    assert "link 'pelvis'" in str(e.value) and len(str(e.value)) < 2000


# ---------------------------------------------------------------------------- 3. BVH
def _cmu_lines() -> list[str]:
    return CMU.read_text().splitlines()


def _bvh_mutations() -> list[tuple[str, str, str]]:
    """(id, old text of one line, new text) on CMU's clip."""
    lines = _cmu_lines()
    first = next(i for i, s in enumerate(lines) if s.strip() == "MOTION") + 3
    row = lines[first].split()
    out = [("frames_superscript", "Frames: 344", "Frames: ²"),
           ("frames_arabic", "Frames: 344", "Frames: ٣٤٤"),
           ("frametime_arabic", "Frame Time: .0083333", "Frame Time: ٠.٠١"),
           ("channels_superscript", "CHANNELS 6", "CHANNELS ⁶"),
           ("offset_huge", "OFFSET 0.00000 0.00000 0.00000", "OFFSET 1e308 0 0"),
           ("offset_unicode", "OFFSET 0.00000 0.00000 0.00000", "OFFSET ١ 0 0"),
           ("offset_underscore", "OFFSET 0.00000 0.00000 0.00000", "OFFSET 1_0 0 0")]
    for i, v in (("root_position_huge", "1e300"), ("root_position_inf", "inf")):
        out.append((i, lines[first], " ".join([v, *row[1:]])))
    out.append(("rotation_huge", lines[first], " ".join([*row[:5], "1e300", *row[6:]])))
    out.append(("value_unicode", lines[first], " ".join([*row[:5], "٣", *row[6:]])))
    return out


@pytest.mark.parametrize("mutation", _bvh_mutations(), ids=lambda m: m[0])
def test_bvh_fields_refused_naming_line_and_field(tmp_path, mutation):
    """Unicode digits (Python's int()/float() accept them), overflowing and absurd numbers:
    BVHError naming the line and the field (they raised ValueError, Pinocchio's "not a valid
    URDF model", or passed)."""
    from gdimitate.io.bvh.parse import parse_bvh

    key, old, new = mutation
    text = CMU.read_text()
    assert old in text
    path = tmp_path / "clip.bvh"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    line = next(i + 1 for i, s in enumerate(path.read_text().splitlines()) if new in s)
    with pytest.raises(BVHError) as e:
        parse_bvh(path)
    msg = str(e.value)
    assert f"line {line}" in msg, msg
    field = {"frames": "Frames", "frametime": "Frame Time", "channels": "CHANNELS",
             "offset": "OFFSET", "root": "Hips", "rotation": "rotation", "value": "frame 0"}
    assert field[key.split("_")[0]] in msg, msg
    if key in ("offset_huge", "root_position_huge"):
        with pytest.raises(BVHError):  # the whole reader, as users call it
            gd.bvh.read_bvh(path)


def test_bvh_size_is_bounded_before_reading(tmp_path):
    """A 300 MB BVH hit MemoryError at ~5 GB (reading peaks at up to 16 bytes per byte);
    beyond MAX_BVH_BYTES it is refused from its size alone."""
    from gdimitate.io.bvh.parse import parse_bvh

    path = tmp_path / "huge.bvh"
    with open(path, "wb") as f:
        f.write(b"HIERARCHY\n")
        f.truncate(MAX_BVH_BYTES + 1)  # sparse: nothing to read unless it is read
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        with pytest.raises(ResourceLimitError, match=f"the limit is {MAX_BVH_BYTES:,}"):
            parse_bvh(path)
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peak < 5e6 and time.perf_counter() - t0 < 1.0


# ---------------------------------------------------------------------------- 4. npz
@pytest.fixture(scope="module")
def walker(tmp_path_factory):
    """A free-flyer biped (its URDF in its own folder) and a motion of it written to .npz."""
    folder = tmp_path_factory.mktemp("walker")
    robot = gd.Robot.from_urdf(_write(folder / "robot", biped()))
    t = np.arange(20) / 50.0
    q = np.tile(robot.neutral, (t.size, 1))
    q[:, robot.idx_q("left_knee")] += 0.2 * np.sin(t)
    motion = gd.Motion(t, robot.joint_names, q, base_nq=7,
                       joint_nq=tuple(robot.model.joints[j].nq
                                      for j in range(1, robot.model.njoints)))
    path = folder / "walk.npz"
    motion.to_npz(path, robot=robot)
    return robot, motion, path


def _tampered(src: Path, dst: Path, **changes) -> Path:
    with np.load(src) as z:
        d = {k: z[k] for k in z.files}
    d.update({k: np.asarray(v) for k, v in changes.items()})
    np.savez(dst, **d)
    return dst


def test_npz_recorded_package_dir_never_widens_the_mesh_sandbox(walker, tmp_path, capsys):
    """`robot_package_dir="/"` (with the URDF's fingerprint) let `gdimitate view evil.npz`
    open and embed a mesh outside the URDF's folder. A recorded folder is used only if it is
    the URDF's folder or below it; else MeshPathError unless the caller passes it."""
    robot, _, good = walker
    outside = tmp_path / "outside"
    (outside / "pkg").mkdir(parents=True)
    stl = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n" \
          "endloop\nendfacet\nendsolid s\n"
    (outside / "pkg" / "secret.stl").write_text(stl)
    urdf = _write(tmp_path / "evil", biped(mesh="package://pkg/secret.stl"))
    legit = gd.Robot.from_urdf(urdf, package_dir=outside)  # the user's own choice
    assert legit.fingerprint == robot.fingerprint  # the walk fits it (meshes not hashed)
    for pkg in ("/", str(outside), str(tmp_path)):
        evil = _tampered(good, tmp_path / "evil.npz", robot_source=str(urdf.resolve()),
                         robot_package_dir=pkg, robot_fingerprint=legit.fingerprint)
        with pytest.raises(MeshPathError, match="robot_package_dir"):
            gd.load_demonstration(evil)
    from gdimitate.apps.cli import main

    html = tmp_path / "v.html"  # the reported command: refused before any page is made
    assert main(["view", str(evil), "--html", str(html)]) == 2
    assert "robot_package_dir" in capsys.readouterr().err and not html.exists()
    # below the URDF's folder: used; passed by the caller: used
    sub = tmp_path / "evil" / "pkg"
    sub.mkdir()
    (sub / "secret.stl").write_text(stl)
    below = _tampered(good, tmp_path / "below.npz", robot_source=str(urdf.resolve()),
                      robot_package_dir=str(tmp_path / "evil"),
                      robot_fingerprint=legit.fingerprint)
    assert gd.load_demonstration(below).robot.fingerprint == legit.fingerprint
    evil = _tampered(good, tmp_path / "evil2.npz", robot_source=str(urdf.resolve()),
                     robot_package_dir="/", robot_fingerprint=legit.fingerprint)
    demo = gd.load_demonstration(evil, package_dir=outside)
    assert demo.robot.fingerprint == legit.fingerprint


@pytest.mark.parametrize("change", [{"base_nq": 0}, {"base_nq": 3}, {"base_nq": 5},
                                    {"base_nq": 0, "joint_nq": "ones"}])
def test_npz_base_layout_comes_from_the_robot(walker, tmp_path, change):
    """`base_nq=0` (or 3) skipped the unit-quaternion check: a zero quaternion was exported
    (CSV wrote it as identity) and entrained. The file's layout must agree with the robot's."""
    robot, motion, good = walker
    q = motion.q.copy()
    q[:, 3:7] = 0.0
    change = dict(change)
    if change.get("joint_nq") == "ones":
        change["joint_nq"] = np.ones(robot.model.nq, dtype=int)
        change["joint_names"] = np.array([f"c{i}" for i in range(robot.model.nq)])
    path = _tampered(good, tmp_path / "zero.npz", q=q, **change)
    with pytest.raises(GdimitateError) as e:
        gd.load_demonstration(path)
    assert isinstance(e.value, FileFormatError | RobotMismatchError | InvalidInputError)
    assert str(path) in str(e.value)
    assert "base_nq" in str(e.value) or "joint" in str(e.value)


@pytest.mark.parametrize("base_nq", [0, 3, 7])
def test_export_checks_the_quaternion_itself(walker, tmp_path, base_nq):
    """Through the API: a Motion with a zero quaternion (whatever base_nq it claims) is not
    exported — the CSV used to write it as the identity."""
    robot, motion, _ = walker
    q = motion.q.copy()
    q[:, 3:7] = 0.0
    bad = gd.Motion(motion.t, motion.joint_names, q, base_nq=base_nq, joint_nq=motion.joint_nq)
    out = tmp_path / "out.csv"
    with pytest.raises(InvalidInputError, match="joint 'root_joint': its quaternion"):
        gd.export_motion(robot, bad, out, "csv")
    assert not out.exists()


NPZ_JSON = ['{"left": ', "[" * 10_000 + "]" * 10_000, '{"left": ' + "9" * 5000 + "}",
            '{"left": NaN}', '{"left": 1e999}', "\udcff", '"just a string"']


@pytest.mark.parametrize("text", NPZ_JSON, ids=["truncated", "nested", "digits", "nan", "inf",
                                                "surrogate", "string"])
@pytest.mark.parametrize("field", ["legs", "contacts"])
def test_npz_recorded_json_is_checked(walker, tmp_path, text, field):
    _, _, good = walker
    value = np.array(text.encode("utf-8", "surrogatepass").decode("utf-8", "replace"))
    path = _tampered(good, tmp_path / "j.npz", **{f"robot_{field}": value})
    with pytest.raises(FileFormatError) as e:
        gd.load_demonstration(path)
    assert f"robot_{field}" in str(e.value) and str(path) in str(e.value)


@pytest.mark.parametrize("change", [
    {"v": "narrow"}, {"v": "wide"}, {"joint_names": np.arange(3)},
    {"joint_nq": np.array(["a", "b"])}, {"base_nq": np.array("7")},
    {"base_nq": np.array([7, 7])}, {"q": np.array([["a"]])}])
def test_npz_arrays_of_the_wrong_kind(walker, tmp_path, change):
    robot, motion, good = walker
    change = dict(change)
    if isinstance(change.get("v"), str):
        nv = robot.model.nv + (-1 if change["v"] == "narrow" else 1)
        change["v"] = np.zeros((motion.T, nv))
        change["a"] = np.zeros((motion.T, nv))
    path = _tampered(good, tmp_path / "w.npz", **change)
    with pytest.raises(InvalidInputError) as e:  # FileFormatError, RobotMismatchError
        gd.load_demonstration(path)
    assert str(path) in str(e.value)


# ---------------------------------------------------------------------------- 5. JSON, API
JSON_BOMBS = [(b"[" * 100_000 + b"]" * 100_000, "nested"), (b"\xff\xfe{}", "UTF-8"),
              (b'{"left": ' + b"1" * 5000 + b"}", "digits"), (b'{"a": NaN}', "NaN"),
              (b'{"a": -Infinity}', "Infinity"), (b'{"a": 1e400}', "overflows"),
              (b'{"a": ', "not valid JSON"), (b" " * (2**20 + 1), "limit")]


@pytest.mark.parametrize("data, said", JSON_BOMBS, ids=[s for _, s in JSON_BOMBS])
def test_json_options_files_and_strings(tmp_path, data, said):
    """--legs/--contacts/body-map JSON: nested, not UTF-8, a 5000-digit number (Python's
    int-string limit), NaN/Infinity, overflow, truncated, oversized — InvalidInputError naming
    the source, from a file and from a string."""
    from gdimitate.model.inputs import loads_json, read_json

    p = tmp_path / "legs.json"
    p.write_bytes(data)
    with pytest.raises(InvalidInputError, match=said) as e:
        read_json(p, "--legs")
    assert str(p) in str(e.value)
    with pytest.raises(InvalidInputError, match=said):
        loads_json(data.decode("utf-8", "surrogateescape"), "the body map")
    assert loads_json('{"left": {"hip": "a", "half_length": 0.1}}', "x") == {
        "left": {"hip": "a", "half_length": 0.1}}


def _nested(depth: int) -> dict:
    d: dict = {}
    for _ in range(depth):
        d = {"hip": d}
    return d


@pytest.fixture(scope="module")
def biped_path(tmp_path_factory) -> Path:
    return _write(tmp_path_factory.mktemp("b"), biped())


API = [
    ("gdimitate.model.robot:Robot.from_urdf", (123,), {}, "path"),
    ("gdimitate.model.robot:Robot.from_urdf", (None,), {}, "path"),
    ("gdimitate.model.robot:Robot.from_urdf", (b"robot.urdf",), {}, "path"),
    ("gdimitate.model.robot:Robot.from_urdf", ("URDF",), {"contacts": "feet"}, "contacts="),
    ("gdimitate.model.robot:Robot.from_urdf", ("URDF",), {"legs": "auto"}, "legs="),
    ("gdimitate.model.robot:Robot.from_urdf", ("URDF",), {"legs": {"left": _nested(3)}}, "legs="),
    ("gdimitate.model.robot:Robot.from_urdf", ("URDF",), {"floating": "yes"}, "floating"),
    ("gdimitate.model.robot:Robot.from_urdf", ("URDF",), {"massless_joints": "left_knee"},
     "massless_joints"),
    ("gdimitate.model.robot:Robot.from_urdf", ("URDF",), {"package_dir": 5}, "package_dir"),
    ("gdimitate.model.robot:Robot.load", (123,), {}, "robot spec"),
    ("gdimitate.model.robot:Robot.from_library", (5,), {}, "robot name"),
    ("gdimitate:load_demonstration", (None,), {}, "path"),
    ("gdimitate:load_demonstration", (3.5,), {}, "path"),
    ("gdimitate:load_demonstration", ("walk.npz",), {"robot": "g1"}, "robot"),
    ("gdimitate:load_demonstration", ("walk.bvh",), {"grf": 1}, "grf"),
]
SOLE_VALUES = [True, False, None, "0.1", 1e308, -0.1, 0.0, float("nan"), float("inf"), [0.1],
               {"m": 0.1}, 2.5]


@pytest.mark.parametrize("spec, args, kwargs, said", API, ids=[f"{a[0]}{a[1]}" for a in API])
def test_api_argument_types(biped_path, spec, args, kwargs, said):
    """Wrong argument types raise InvalidInputError naming the argument (they raised
    TypeError/AttributeError from deep inside)."""
    import importlib

    args = tuple(str(biped_path) if a == "URDF" else a for a in args)
    mod, _, name = spec.partition(":")
    fn = importlib.import_module(mod)
    for part in name.split("."):
        fn = getattr(fn, part)
    with pytest.raises(InvalidInputError) as e:
        fn(*args, **kwargs)
    assert said in str(e.value), str(e.value)


@pytest.mark.parametrize("value", SOLE_VALUES, ids=repr)
@pytest.mark.parametrize("key", ["half_length", "half_width", "mu"])
def test_sole_sizes_are_real_finite_and_bounded(biped_path, key, value):
    """JSON `true` and 1e308 as a sole size passed unremarked."""
    if key == "mu" and value == 2.5:
        value = 11.0  # within the sole bound, beyond the friction bound
    contact = {"half_length": 0.1, "half_width": 0.04, "mu": 0.7, key: value}
    with pytest.raises(InvalidInputError) as e:
        gd.Robot.from_urdf(biped_path, contacts={"left": contact, "right": contact})
    assert f"['{key}']" in str(e.value)


@pytest.mark.parametrize("field, value", [
    ("q", np.array([[object()] * 2] * 3)), ("q", "abc"), ("q", [[1.0, 2.0], [3.0]]),
    ("q", np.ones((3, 2), complex)), ("t", ["a", "b", "c"]), ("t", np.array([None] * 3)),
    ("joint_names", "ab"), ("joint_names", (1, 2)), ("joint_nq", ("1", "1")),
    ("joint_nq", (True, 1)), ("base_nq", 5), ("base_nq", "7"), ("contact", [1, 2]),
    ("v", np.array([[{}]] * 3)), ("a", "x")])
def test_motion_fields_of_the_wrong_type(field, value):
    kw = dict(t=np.arange(3) / 10.0, joint_names=("a", "b"), q=np.zeros((3, 2)))
    kw[field] = value
    with pytest.raises(InvalidInputError) as e:
        gd.Motion(**kw)
    assert field.rstrip("s") in str(e.value) or "time" in str(e.value)


@pytest.mark.parametrize("fps", [float("nan"), float("inf"), -30.0, 0.0, "30", True, None])
@pytest.mark.parametrize("fmt", ["csv", "lafan1_csv"])
def test_export_fps_is_checked(walker, tmp_path, fps, fmt):
    robot, motion, _ = walker
    out = tmp_path / "o.csv"
    with pytest.raises(ExportError, match="fps"):
        gd.export_motion(robot, motion, out, fmt, fps=fps)
    assert not out.exists()
    with pytest.raises(ExportError, match="format"):
        gd.export_motion(robot, motion, out, 5)
    with pytest.raises(ExportError, match="robot"):
        gd.export_motion(None, motion, out, "csv")


def test_bounds_are_generous_for_real_robots():
    """Example-robot-data's largest robot (TIAGo dual: 101 degrees of freedom, 223 shapes)
    and every library robot are well inside the limits."""
    import xml.etree.ElementTree as ET

    from gdimitate.model.library import erd_robots_dir
    from gdimitate.model.urdfcheck import check_urdf_size, check_urdf_structure

    paths = sorted(erd_robots_dir().rglob("*.urdf"))
    assert len(paths) > 30
    for p in paths:
        root = ET.parse(p).getroot()
        check_urdf_size(root, p)
        check_urdf_structure(root, p)
    assert json.loads(json.dumps({"ok": True}))


@pytest.mark.parametrize("content", [b"[" * 100_000 + b"]" * 100_000, b'{"joints": \xff}',
                                     b'{"joints": ' + b"9" * 5000 + b"}", b"[1, 2]",
                                     b'{"joints": NaN}'],
                         ids=["nested", "not-utf8", "5000-digits", "not-an-object", "nan"])
def test_a_body_map_file_that_cannot_be_one_says_so(tmp_path, content):
    """A body-map JSON file nested deep, not UTF-8 or with a 5,000-digit number raised a
    bare RecursionError/ValueError (BodyMap.from_json caught only OSError/JSONDecodeError)."""
    from gdimitate.errors import InvalidInputError
    from gdimitate.retarget.bodymap import BodyMap

    p = tmp_path / "map.json"
    p.write_bytes(content)
    with pytest.raises(InvalidInputError, match="body map"):
        BodyMap.from_json(p)
