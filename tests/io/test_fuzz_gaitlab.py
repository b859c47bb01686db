"""Fuzzed gait-lab readers (issue 33: nothing lost, nothing let in, no crash): C3D, TRC,
OpenSim ``.mot``/``.sto`` tables, ``.osim`` models and ground-reaction-force files.

Classes of input covered, each by a generator:

* C3D truncated at every section boundary (inside the header, the parameter section, the
  data section; block boundaries and one byte short) — in a child process
  (``tests/helpers/isolated.py``): ezc3d segfaulted at 522 bytes, hung at 700, and read 13/74/136 of
  151 frames at 10/50/90 % — now a ``C3DFormatError`` saying "truncated" with both sizes;
  a complete file minus its last block's padding still reads every frame;
* C3D header and parameter fields overwritten with NaN/inf/huge/negative numbers and random
  byte flips (hypothesis), in the child process: crash, hang or bare exception are failures;
* C3D ``POINT:UNITS`` empty, wrong marker scale, a corrupt marker value (a bit flip in a
  float's exponent): our errors naming the file and the fix;
* TRC: ``Units`` contradicting the numbers (mm data under ``m``, m data under ``mm``),
  duplicate marker names, ``NumMarkers``/``NumFrames`` = abc/nan/inf/−1/1e400/unicode,
  infinite and far-off marker values;
* ``.mot``/``.trc``/``.osim`` over their size bounds (sparse files: no data is written);
* an all-zero GRF file ("all zero", not "must be negated");
* marker IK on a corrupt frame: a ``SolverError`` naming the file and frame, not pink's
  ``NoSolutionFound``.
"""

from __future__ import annotations

import functools
import math
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest

from gdimitate.errors import (
    C3DFormatError,
    ForceDataError,
    OpenSimDataError,
    OsimError,
    ResourceLimitError,
    SolverError,
    UnitError,
)
from gdimitate.io.c3d import ForcePlate, read_c3d, write_c3d
from gdimitate.io.c3d.layout import C3DLayout, check_c3d
from gdimitate.io.opensim import Markers, read_trc
from gdimitate.model.osim.model import MAX_OSIM_BYTES, read_osim
from gdimitate.safety import MAX_TABLE_BYTES
from tests.helpers import ROOT
from tests.helpers.isolated import call

D3 = ROOT / "gdimitate/data/gait/opensim_subject01_walk1_3d"
HEAD = ("PathFileType\t4\t(X/Y/Z)\tm.trc\n"
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n")


# ------------------------------------------------------------------------------- C3D files
def _trial(T: int = 40, rate: float = 100.0) -> tuple[Markers, ForcePlate]:
    """Three markers of a walking person [m] and one loaded plate at 10× the marker rate."""
    t = np.arange(T) / rate
    xyz = np.array([[0.0, 0.1, 1.7], [0.1, 0.1, 1.0], [0.2, -0.1, 0.05]])[None] + \
        np.column_stack([t, 0 * t, 0 * t])[:, None]
    ta = np.arange(T * 10) / (rate * 10)
    F = np.column_stack([30 * np.sin(5 * ta), -20 + 0 * ta, 600 + 100 * np.sin(3 * ta)])
    cop = np.column_stack([0.5 + 0.1 * ta, 0.2 - 0.05 * ta, 0 * ta])
    corners = np.array([[0.2, 0, 0], [0.8, 0, 0], [0.8, 0.5, 0], [0.2, 0.5, 0]])
    return Markers(t, ("head", "hip", "heel"), xyz), ForcePlate(ta, F, cop, 0 * F, corners)


@functools.cache
def _c3d_bytes(T: int = 40) -> bytes:
    import tempfile

    mk, plate = _trial(T)
    with tempfile.TemporaryDirectory() as d:
        return write_c3d(Path(d) / "t.c3d", mk, [plate]).read_bytes()


def _layout(data: bytes) -> tuple[int, int, int, int]:
    """(parameter section start, its end, data start, data end) [bytes] of a whole file."""
    pstart = (data[0] - 1) * 512
    pend = pstart + data[pstart + 2] * 512
    dstart = (struct.unpack_from("<H", data, 16)[0] - 1) * 512
    points, analog = struct.unpack_from("<HH", data, 2)
    frames = struct.unpack_from("<H", data, 8)[0] - struct.unpack_from("<H", data, 6)[0] + 1
    return pstart, pend, dstart, dstart + frames * (4 * points + analog) * 4


def test_c3d_truncated_at_every_section_boundary(tmp_path):
    """Cut inside the header, at and inside the parameter section, at the data's start,
    10/50/90 % and one byte short of its end: each refused as truncated, in the parent
    (no ezc3d: the layout check) and, for the cases that crashed, hung or lost frames, in a
    child process through read_c3d; cut only in the last block's padding, every frame reads."""
    data = _c3d_bytes()
    pstart, pend, dstart, dend = _layout(data)
    assert len(data) > dend > dstart >= pend > pstart >= 512
    cuts = sorted({1, 10, 100, 511, 512, 522, 700, pstart + 3, pstart + 4, pend - 1, pend,
                   dstart, dstart + 1, *(dstart + (dend - dstart) * k // 10 for k in (1, 5, 9)),
                   dend - 16, dend - 1})
    for n in cuts:
        p = tmp_path / f"cut{n}.c3d"
        p.write_bytes(data[:n])
        with pytest.raises(C3DFormatError) as e:
            check_c3d(p)
        msg = str(e.value)
        if n >= 2:
            assert "truncated" in msg and f"has {n:,}" in msg and "expected" in msg, msg
            need = int(msg.split("expected ")[1].split(" bytes")[0].replace(",", ""))
            assert need > n and need in (512, pstart + 512, pend, dend), msg
    for n in (522, 700, dstart + (dend - dstart) // 2, dend - 1):  # crashed, hung, lost frames
        o = call("gdimitate.io.c3d:read_c3d", str(tmp_path / f"cut{n}.c3d"))
        assert o.handled() and not o.ok, o
        assert o.type == "C3DFormatError" and "truncated" in o.message, o
    whole = tmp_path / "padding.c3d"
    whole.write_bytes(data[:dend])  # the last block's padding cut off: nothing is missing
    trial = read_c3d(whole)
    assert trial.markers.t.size == 40 and len(trial.plates[0].t) == 400


# header words (1-based) holding numbers, and values that break a reader trusting them
_HEADER_WORDS = {2: "points", 3: "analog samples per frame", 4: "first frame", 5: "last frame",
                 9: "data start block", 10: "analog samples per channel"}
_WORD_VALUES = [0, 1, 0x7FFF, 0x8000, 0xFFFF]
_FLOATS = [math.nan, math.inf, -math.inf, 1e38, -1e38, 0.0, -0.0, 1e-38]


def _param_offsets(data: bytes) -> dict[tuple[str, str], tuple[int, int, tuple[int, ...]]]:
    """{(GROUP, NAME): (data offset in the file, type, dims)} of a C3D file's parameters."""
    from gdimitate.io.c3d.layout import _Reader, _walk

    pstart = (data[0] - 1) * 512
    sec = data[pstart:pstart + data[pstart + 2] * 512]
    groups, params = _walk(_Reader(sec, False, Path("x")), 4, len(sec), Path("x"))
    return {(groups[g], n): (pstart + at, typ, dims) for (g, n), (typ, dims, at) in params.items()}


def _mutants() -> list[tuple[str, bytes]]:
    """Every numeric header field and numeric POINT/ANALOG/FORCE_PLATFORM parameter set to
    each value of a list of breaking numbers (NaN, inf, huge, negative, zero)."""
    data = _c3d_bytes()
    out = []
    for w, what in _HEADER_WORDS.items():
        for v in _WORD_VALUES:
            m = bytearray(data)
            struct.pack_into("<H", m, 2 * (w - 1), v)
            out.append((f"header {what}={v}", bytes(m)))
    for at, what in ((12, "scale factor"), (20, "frame rate")):
        for v in _FLOATS:
            m = bytearray(data)
            struct.pack_into("<f", m, at, v)
            out.append((f"header {what}={v}", bytes(m)))
    wanted = [("POINT", n) for n in ("USED", "SCALE", "RATE", "FRAMES", "DATA_START")] + \
        [("ANALOG", n) for n in ("USED", "RATE", "GEN_SCALE", "SCALE", "OFFSET")] + \
        [("FORCE_PLATFORM", n) for n in ("USED", "TYPE", "CHANNEL", "CORNERS", "ORIGIN")]
    offs = _param_offsets(data)
    for key in wanted:
        at, typ, _ = offs[key]
        vals = _FLOATS if typ == 4 else [-32768, -1, 0, 32767]
        for v in vals:
            m = bytearray(data)
            struct.pack_into("<f" if typ == 4 else "<h", m, at, v)
            out.append((f"{key[0]}:{key[1]}={v}", bytes(m)))
    return out


def test_c3d_breaking_numbers_in_every_header_field_and_parameter(tmp_path):
    """Each mutant is checked in the parent (the layout check is pure Python: it must raise
    our error or pass); the ones it passes are read by ezc3d in a child process, a few at a
    time (each child reads a list of files), where a crash or a hang fails the test."""
    passed = []
    for k, (what, m) in enumerate(_mutants()):
        p = tmp_path / f"m{k}.c3d"
        p.write_bytes(m)
        try:
            check_c3d(p)
            passed.append((what, p))
        except (C3DFormatError, ResourceLimitError):
            pass
    assert passed  # most fields take most values
    for lo in range(0, len(passed), 40):
        chunk = passed[lo:lo + 40]
        o = _read_each([str(p) for _, p in chunk], tmp_path)
        assert o.handled(), f"{[w for w, _ in chunk]}: {o}"


_CHILD = """
import warnings
from gdimitate.io.c3d import read_c3d
from gdimitate.errors import GdimitateError
for p in FILES:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            read_c3d(p)
    except GdimitateError:
        pass
"""


def _read_each(paths: list[str], folder: Path):
    """read_c3d of each file in one child process (``isolated.call`` of ``runpy.run_path``
    on a script that ignores our errors): any other exception, a crash or a hang shows."""
    script = folder / "read_each.py"
    script.write_text(_CHILD)
    return call("runpy:run_path", str(script), {"FILES": paths}, timeout=60)


def test_c3d_bit_flips_in_header_and_parameters(tmp_path):
    """80 files with 1–4 random bit flips in the first four blocks (header and parameter
    section; seeded): the layout check never raises a bare exception, and what it lets
    through ezc3d reads without crashing or hanging (one child process for all of them)."""
    import random

    rng = random.Random(33)
    data = _c3d_bytes()
    passed = []
    for k in range(80):
        m = bytearray(data)
        for _ in range(rng.randint(1, 4)):
            m[rng.randrange(2048)] ^= 1 << rng.randrange(8)
        p = tmp_path / f"f{k}.c3d"
        p.write_bytes(bytes(m))
        try:
            check_c3d(p)
            passed.append(str(p))
        except (C3DFormatError, ResourceLimitError):
            pass
    assert passed
    o = _read_each(passed, tmp_path)
    assert o.handled(), o


def test_c3d_layout_is_what_ezc3d_reads(tmp_path):
    data = _c3d_bytes()
    p = tmp_path / "t.c3d"
    p.write_bytes(data)
    L = check_c3d(p)
    assert isinstance(L, C3DLayout)
    assert (L.frames, L.points, L.analogs, L.subframes, L.floats, L.plates) == \
        (40, 3, 6, 10, True, 1)


def _with_point(data: bytes, key: str, value: float, typ: str = "<f") -> bytes:
    at = _param_offsets(data)[("POINT", key)][0]
    m = bytearray(data)
    struct.pack_into(typ, m, at, value)
    return bytes(m)


def test_c3d_empty_units_and_implausible_scale(tmp_path):
    """POINT:UNITS empty (was a bare IndexError), and mm data labelled metres."""
    import ezc3d

    mk, _ = _trial()
    for units, err, said in (([], UnitError, "POINT:UNITS is empty"),
                             (["m"], UnitError, "look like mm")):
        c = ezc3d.c3d()
        c["parameters"]["POINT"]["RATE"]["value"] = np.array([mk.rate])
        c["parameters"]["POINT"]["LABELS"]["value"] = list(mk.names)
        c["parameters"]["POINT"]["UNITS"]["value"] = units
        pts = np.ones((4, 3, mk.t.size))
        pts[:3] = mk.xyz.transpose(2, 1, 0) * 1000.0
        c["data"]["points"] = pts
        p = tmp_path / f"u{len(units)}.c3d"
        c.write(str(p))
        with pytest.raises(err, match=said) as e:
            read_c3d(p)
        assert str(p) in str(e.value)


def test_c3d_corrupt_marker_value(tmp_path):
    """A bit flip in the exponent of one marker coordinate (0.1 m → ~3e37 m) is refused
    naming the marker and the frame (it ended in pink's NoSolutionFound in the marker IK)."""
    data = bytearray(_c3d_bytes())
    _, _, dstart, _ = _layout(bytes(data))
    frame, per_frame = 7, (4 * 3 + 60) * 4
    at = dstart + frame * per_frame + 1 * 16 + 4  # frame 8, marker 'hip', y
    data[at + 3] ^= 0x20  # 100 mm → 1.8e21 mm
    p = tmp_path / "flip.c3d"
    p.write_bytes(bytes(data))
    with pytest.raises(OpenSimDataError, match="marker 'hip' is .* frame 8") as e:
        read_c3d(p)
    assert str(p) in str(e.value) and "corrupt value" in str(e.value)


def test_marker_ik_on_a_corrupt_frame_is_our_error():
    """pink's NoSolutionFound (or a non-finite step) becomes a SolverError naming the file,
    the frame and the markers farthest off."""
    from gdimitate import Robot
    from gdimitate.io.opensim import inverse_kinematics

    robot = Robot.from_osim(D3 / "subject01.osim")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mk = read_trc(D3 / "subject01_walk1.trc")
    xyz = mk.xyz[:3].copy()
    xyz[1, 5] = [1e30, -1e30, 1e30]  # what Markers lets through from another source
    bad = Markers(mk.t[:3], mk.names, xyz, source="corrupt.c3d")
    with pytest.raises(SolverError, match=r"corrupt\.c3d: marker IK found no solution in "
                                          r"frame 2") as e, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        inverse_kinematics(robot, bad, iterations=2, first_iterations=5)
    assert mk.names[5] in str(e.value) and "corrupt positions" in str(e.value)


# ------------------------------------------------------------------------------- TRC files
def _trc(path: Path, *, units: str = "mm", scale: float = 1000.0, names=None,
         frames: str | None = None, markers: str | None = None, T: int = 5,
         edit=None) -> Path:
    names = list(names or ["Head", "ASIS", "Heel"])
    n = len(names)
    base = np.array([[0.0, 1.7, 0.0], [0.0, 0.95, 0.1], [-0.05, 0.05, 0.1]])
    base = np.vstack([base] * (n // 3 + 1))[:n] + 0.001 * np.arange(n)[:, None]
    rows = []
    for k in range(T):
        xyz = (base + [0.012 * k, 0, 0]) * scale
        if edit is not None:
            edit(k, xyz)
        rows.append(f"{k + 1}\t{k / 100:.4f}\t" + "\t".join(f"{v:.6g}" for v in xyz.ravel()))
    vals = f"100\t100\t{frames if frames is not None else T}\t" \
        f"{markers if markers is not None else n}\t{units}\n"
    path.write_text(HEAD + vals + "Frame#\tTime\t" + "\t\t\t".join(names) + "\n\t\t" +
                    "\t".join(f"{a}{i + 1}" for i in range(n) for a in "XYZ") + "\n\n" +
                    "\n".join(rows) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize("units,scale,looks", [("m", 1000.0, "mm"), ("m", 100.0, "cm"),
                                               ("cm", 1000.0, "mm"), ("mm", 1.0, "m")])
def test_trc_units_contradicting_the_numbers(tmp_path, units, scale, looks):
    """The header's unit against the numbers (mm data under 'Units m' put the pelvis at
    z = 1118 m): refused, saying which unit the numbers look like."""
    p = _trc(tmp_path / "m.trc", units=units, scale=scale)
    with pytest.raises(UnitError, match=f"look like {looks} ") as e:
        read_trc(p)
    assert str(p) in str(e.value) and f"Units={units!r}" in str(e.value)
    assert read_trc(_trc(tmp_path / "ok.trc", units=looks, scale=scale)).xyz.shape == (5, 3, 3)


@pytest.mark.parametrize("names,twice", [(["A"] * 41, ["A"]), (["A", "B", "A", "C", "B"],
                                                               ["A", "B"])])
def test_trc_duplicate_marker_names(tmp_path, names, twice):
    with pytest.raises(OpenSimDataError, match="more than once") as e:
        read_trc(_trc(tmp_path / "d.trc", names=names))
    assert str(twice) in str(e.value)


BAD_COUNTS = ["abc", "nan", "inf", "-inf", "1e400", "-1", "3.5", "", "٣x", "0x3", "1e30"]


@pytest.mark.parametrize("field", ["NumMarkers", "NumFrames"])
@pytest.mark.parametrize("value", BAD_COUNTS)
def test_trc_bad_count_fields(tmp_path, field, value):
    """abc/nan/inf/huge/negative/fractional/unicode counts: an error naming the field (was a
    bare ValueError or OverflowError)."""
    kw = {"markers" if field == "NumMarkers" else "frames": value}
    p = _trc(tmp_path / "c.trc", **kw)
    if value == "":  # an empty field is a key without a value
        if field == "NumFrames":
            assert read_trc(p).t.size == 5  # NumFrames is optional
            return
        with pytest.raises(OpenSimDataError, match="header has no 'NumMarkers'"):
            read_trc(p)
        return
    with pytest.raises(OpenSimDataError, match=f"header field {field}=") as e:
        read_trc(p)
    assert str(p) in str(e.value)


@pytest.mark.parametrize("value,said", [("inf", "is infinite in frame 3"),
                                        ("-1e400", "is infinite in frame 3"),
                                        ("3e30", "from the frame's other markers in frame 3")])
def test_trc_infinite_and_far_off_values(tmp_path, value, said):
    p = _trc(tmp_path / "v.trc")
    lines = p.read_text().splitlines()
    f = lines[8].split("\t")
    f[5] = value  # frame 3, marker 'ASIS', x
    lines[8] = "\t".join(f)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(OpenSimDataError, match=said) as e:
        read_trc(p)
    assert "'ASIS'" in str(e.value) and str(p) in str(e.value)


# ------------------------------------------------------------------------ size bounds
def _sparse(path: Path, size: int, head: bytes) -> Path:
    with open(path, "wb") as f:
        f.write(head)
        f.truncate(size)  # no data written: a hole
    return path


def test_size_bounds_checked_before_reading(tmp_path):
    """A table or marker file over MAX_TABLE_BYTES (192 MiB: reading peaks at 5.4 (.mot) and
    8.4 (.trc) bytes a byte) and an .osim over MAX_OSIM_BYTES (64 MiB; none existed) are
    refused from their size on disk, before a byte is read."""
    from gdimitate.io.gait import read_mot
    from gdimitate.io.opensim import read_table

    assert MAX_TABLE_BYTES <= 2 * 10**9 / 8.4 and MAX_OSIM_BYTES <= 2 * 10**9 / 16
    big = MAX_TABLE_BYTES + 1
    mot = _sparse(tmp_path / "big.mot", big, b"endheader\ntime\ta\n")
    for read in (read_table, read_mot):
        with pytest.raises(ResourceLimitError, match=f"{big:,} bytes; the limit"):
            read(mot)
    with pytest.raises(ResourceLimitError, match="the limit"):
        read_trc(_sparse(tmp_path / "big.trc", big, HEAD.encode()))
    osim = _sparse(tmp_path / "big.osim", MAX_OSIM_BYTES + 1, b"<OpenSimDocument>")
    with pytest.raises(OsimError, match="over the .* bytes an OpenSim model may have") as e:
        read_osim(osim)
    assert isinstance(e.value, ResourceLimitError)


def test_trc_rows_that_would_unpack_beyond_the_bound(tmp_path):
    """Many short rows under a wide header ("1\\t0" lines are rows of gaps): the table they
    would unpack to is bounded before it is allocated."""
    names = [f"m{i}" for i in range(3000)]
    p = tmp_path / "wide.trc"
    with open(p, "w") as f:
        f.write(HEAD + f"100\t100\t1\t{len(names)}\tmm\nFrame#\tTime\t" +
                "\t\t\t".join(names) + "\n\t\t\n\n")
        f.write("1\t0\n" * 6000)
    with pytest.raises(ResourceLimitError, match="MAX_TRC_ARRAY_BYTES"):
        read_trc(p)


# --------------------------------------------------------------------------- GRF files
def test_all_zero_grf_is_called_unloaded(tmp_path):
    """An all-zero force file (an unloaded or unconnected plate) was told its forces 'must be
    negated'; so were forces below the stance threshold."""
    from gdimitate.io.opensim import read_grf

    src = (D3 / "subject01_walk1_grf.mot").read_text().splitlines()
    end = next(i for i, ln in enumerate(src) if ln.strip().lower() == "endheader")
    names = src[end + 1].split()
    for value, said in ((0.0, "are all zero"), (3.0, "never exceed 3 N")):
        rows = [f"{k / 100:.3f}\t" + "\t".join(f"{value:g}" for _ in names[1:])
                for k in range(20)]
        p = tmp_path / f"z{value:g}.mot"
        p.write_text("\n".join(src[:end + 2] + rows) + "\n")
        with pytest.raises(ForceDataError, match=said) as e:
            read_grf(p, None)
        assert "unloaded or unconnected plate" in str(e.value)
        assert "negated" not in str(e.value) and str(p) in str(e.value)


# ------------------------------------------------------------------- .mot breaking numbers
@pytest.mark.parametrize("cell", ["nan", "inf", "-inf", "1e400", "１２", "0x10", "1,5", "",
                                  "\u2212" + "1"])
def test_mot_breaking_numbers(tmp_path, cell):
    """A cell of a .mot set to NaN/inf/huge/unicode/hex/comma: our error naming the file,
    never a bare exception (full-width digits are numbers to Python and read as such)."""
    from gdimitate.io.opensim import read_table

    p = tmp_path / "c.mot"
    rows = ["0\t1\t2", f"0.01\t{cell}\t2", "0.02\t1\t2"]
    p.write_text("version=1\nendheader\ntime\ta\tb\n" + "\n".join(rows) + "\n")
    if cell == "１２":
        assert read_table(p).data[1, 1] == 12.0
        return
    with pytest.raises(OpenSimDataError) as e:
        read_table(p)
    assert str(p) in str(e.value)


def test_mot_line_endings_and_truncation(tmp_path):
    """CRLF and lone-CR line ends read as LF ones; a table cut at every line boundary and
    mid-row raises our error or reads the rows it has."""
    from gdimitate.io.opensim import read_table

    text = "version=1\ninDegrees=no\nendheader\ntime\ta\n" + \
        "".join(f"{k / 10:.1f}\t{k}\n" for k in range(5))
    for nl in ("\r\n", "\r"):
        p = tmp_path / "nl.mot"
        p.write_bytes(text.replace("\n", nl).encode())
        t = read_table(p)
        assert t.names == ("time", "a") and t.data.shape == (5, 2) and t.in_degrees is False
    for n in range(len(text)):
        p = tmp_path / "cut.mot"
        p.write_text(text[:n])
        try:
            t = read_table(p)
        except OpenSimDataError:
            continue
        assert t.data.shape[0] >= 2
