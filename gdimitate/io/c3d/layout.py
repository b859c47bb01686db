"""A C3D file's layout checked against its length before ``ezc3d`` reads it: :func:`check_c3d`.

``ezc3d`` trusts the file: a file cut inside its parameter section crashed the interpreter
(522 bytes of a gait trial: a segfault) or ran for minutes (700 bytes); one cut inside its
data section was read as fewer frames with no error (10/50/90 % of a 151-frame trial gave
13/74/136 frames, the last one rewritten). So the layout is read here first, the way
``ezc3d`` 1.7 reads it, and every section is checked to lie inside the file:

* the header (block 1): word 1 the parameter section's first block (and the key byte 0x50),
  words 2–5 points, analog samples per frame, first and last frame, words 7–8 the scale
  factor (negative: float data), word 9 the data's first block, word 10 analog samples per
  frame per channel, words 11–12 the frame rate;
* the parameter section: its own header (number of blocks, processor type: 84 Intel, 85 DEC;
  86 MIPS is not read by ``ezc3d``), then every group and parameter record, walked by its
  offset to the next, each inside the section (name, type −1/1/2/4, dimensions, data,
  description);
* the sizes ``ezc3d`` reads the data with, which the parameters override: frames
  (``POINT:FRAMES`` where non-zero, else the header), points (``POINT:USED``), analog
  channels (``ANALOG:USED``) and samples per frame (``ANALOG:RATE / POINT:RATE``), the
  format (float where the header's scale factor is negative), and ``ROTATION`` data where
  the group exists; the data must end inside the file;
* the parameters ``ezc3d`` indexes without checking: ``ANALOG:SCALE``/``OFFSET`` one per
  channel, ``FORCE_PLATFORM:CAL_MATRIX`` and ``FPCOPPOLY`` of the plates used,
  ``FORCE_PLATFORM:CHANNEL`` two-dimensional, scalars (``USED``, ``RATE``, ``SCALE``…) with a
  value; rates finite and ≥ 0.

Memory: ``ezc3d`` holds each frame, point and analog sample as objects, then numpy copies
them; :data:`MAX_C3D_MEMORY` bounds the estimate :func:`estimated_memory` makes from the
layout (measured: see ``docs/security.md``), so a header claiming many small frames is
refused before it is read, as is a file over :data:`MAX_C3D_BYTES`.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import C3DFormatError, ResourceLimitError

__all__ = ["C3DLayout", "MAX_C3D_BYTES", "MAX_C3D_MEMORY", "check_c3d", "estimated_memory"]

BLOCK = 512
#: Largest C3D file read [bytes]: an outer bound; what a file's layout needs to be read is
#: bounded by :data:`MAX_C3D_MEMORY` (ezc3d needs 30–55 bytes of memory per byte of a trial).
MAX_C3D_BYTES = 256 * 2**20
#: Most memory [bytes] the layout may need to be read, estimated by :func:`estimated_memory`
#: (ezc3d's objects and the numpy arrays built from them), on top of the interpreter's own.
MAX_C3D_MEMORY = 1.5e9
# Per-item cost of read_c3d(extract_forceplat_data=True) [bytes], rounded up from peak RSS
# measured on trials of 0.2-3.4 MB (docs/security.md): a fixed part, per frame, per point and
# frame, per analog sample (channel × subframe), per force-plate sample.
_COST_FIXED, _COST_FRAME, _COST_POINT, _COST_ANALOG, _COST_PLATE = 16e6, 300.0, 450.0, 150.0, 600.0


@dataclass(frozen=True)
class C3DLayout:
    """What :func:`check_c3d` read: ``frames``, ``points``, ``analogs`` (channels),
    ``subframes`` (analog samples per frame per channel), ``floats`` (data format),
    ``plates`` (``FORCE_PLATFORM:USED``), ``data_end`` [bytes] where the data ends,
    ``size`` [bytes] of the file; ``params`` ``{(GROUP, NAME): values}`` (numbers only)."""

    frames: int
    points: int
    analogs: int
    subframes: int
    floats: bool
    plates: int
    data_end: int
    size: int
    params: dict = field(default_factory=dict, repr=False)


def estimated_memory(L: C3DLayout) -> float:
    """Bytes :func:`gdimitate.io.c3d.read_c3d` needs to read a file of layout ``L`` (an upper
    estimate from measured per-item costs)."""
    samples = L.frames * L.subframes
    return (_COST_FIXED + L.frames * (_COST_FRAME + _COST_POINT * L.points)
            + samples * (_COST_ANALOG * L.analogs + _COST_PLATE * L.plates))


class _Reader:
    """Little-endian (Intel, DEC) numbers at byte offsets of ``data``; DEC floats as ezc3d
    converts them."""

    def __init__(self, data: bytes, dec: bool, path: Path):
        self.data, self.dec, self.path = data, dec, path

    def u8(self, at: int) -> int:
        return self.data[at]

    def i8(self, at: int) -> int:
        return struct.unpack_from("<b", self.data, at)[0]

    def u16(self, at: int) -> int:
        return struct.unpack_from("<H", self.data, at)[0]

    def floats(self, at: int, n: int) -> np.ndarray:
        raw = np.frombuffer(self.data, np.uint8, 4 * n, at).reshape(n, 4).copy()
        if self.dec:  # ezc3d: bytes 2, 3, 0, 1 − 1 (VAX F: exponent bias and hidden bit)
            b = raw.copy()
            raw[:, 0], raw[:, 1], raw[:, 2] = b[:, 2], b[:, 3], b[:, 0]
            raw[:, 3] = np.where(b[:, 1] != 0, b[:, 1] - 1, b[:, 1])
        return raw.view("<f4").ravel().astype(float)

    def ints(self, at: int, n: int, width: int) -> np.ndarray:
        dt = {1: "<i1", 2: "<i2"}[width]
        return np.frombuffer(self.data, dt, n, at).astype(np.int64)


def _truncated(path: Path, need: int, size: int, what: str) -> C3DFormatError:
    return C3DFormatError(
        f"{path}: the C3D file is truncated: expected {need:,} bytes ({what}), has {size:,}; "
        "it was cut short (an interrupted copy or download): get the complete file")


def _walk(r: _Reader, start: int, end: int, path: Path
          ) -> tuple[dict[int, str], dict[tuple[int, str], tuple[int, tuple[int, ...], int]]]:
    """Walk the parameter records from ``start`` as ezc3d does, each inside ``[start, end)``
    → ``({group id: name}, {(group id, NAME): (type, dims, data offset)})``."""
    groups: dict[int, str] = {}
    params: dict[tuple[int, str], tuple[int, tuple[int, ...], int]] = {}
    pos, k = start, 0

    def need(at: int, n: int, what: str) -> None:
        if at + n > end:
            raise C3DFormatError(
                f"{path}: parameter record {k} ({what}) runs past the end of the parameter "
                f"section (byte {at + n:,} of {end:,}): the parameter section is corrupt; "
                "re-export the file from the lab's software")

    while True:
        need(pos, 2, "name length")
        nchar, gid = r.i8(pos), r.i8(pos + 1)
        if nchar == 0:
            break
        if gid == 0:
            raise C3DFormatError(f"{path}: parameter record {k} at byte {pos:,} has group id "
                                 "0: the parameter section is corrupt")
        n = abs(nchar)
        need(pos + 2, n + 2, "name")
        name = r.data[pos + 2:pos + 2 + n].decode("latin-1")  # ezc3d: case-sensitive
        at_off = pos + 2 + n
        offset = r.u16(at_off)
        p = at_off + 2
        if gid < 0:
            need(p, 1, f"group {name!r}")
            dlen = r.i8(p)
            groups[-gid] = name
        else:
            need(p, 2, f"parameter {name!r}")
            typ, nd = r.i8(p), r.i8(p + 1)
            if typ not in (-1, 1, 2, 4):
                raise C3DFormatError(f"{path}: parameter {name!r} has data type {typ} (C3D "
                                     "types are -1, 1, 2, 4): the parameter section is corrupt")
            if nd < 0 or (nd == 0 and typ == -1):
                raise C3DFormatError(f"{path}: parameter {name!r} has {nd} dimensions: the "
                                     "parameter section is corrupt")
            need(p + 2, nd, f"parameter {name!r} dimensions")
            dims = tuple(r.u8(p + 2 + i) for i in range(nd)) or (1,)
            p += 2 + nd
            nbytes = math.prod(dims) * abs(typ)
            need(p, nbytes + 1, f"parameter {name!r} data")
            params[(gid, name)] = (typ, dims, p)
            p += nbytes
            dlen = r.i8(p)
        if dlen < 0:
            raise C3DFormatError(f"{path}: record {name!r} has a description of {dlen} "
                                 "characters: the parameter section is corrupt")
        need(p + 1, dlen, f"{name!r} description")
        p += 1 + dlen
        if offset == 0:
            break
        if at_off + offset != p:
            raise C3DFormatError(
                f"{path}: record {name!r} says the next record starts at byte "
                f"{at_off + offset:,}, but it ends at byte {p:,}: the parameter section is "
                "corrupt; re-export the file")
        pos, k = p, k + 1
    return groups, params


def _sections(path: Path, size: int) -> tuple[bytes, bytes, int, int, int]:
    """The header block and the parameter section of ``path`` →
    ``(header, section, first parameter block, parameter blocks, processor type)``, each
    checked against the file's ``size`` [bytes]."""
    with open(path, "rb") as fh:
        head = fh.read(BLOCK)
        if len(head) < BLOCK:
            if len(head) < 2 or head[1] != 0x50:
                raise C3DFormatError(f"{path}: not a readable C3D file ({size} bytes; a C3D file "
                                     "starts with a 512-byte header whose second byte is 0x50)")
            raise _truncated(path, BLOCK, size, "the 512-byte header")
        pblock = head[0]
        if head[1] != 0x50 or pblock < 2:
            raise C3DFormatError(f"{path}: not a readable C3D file (byte 2 must be 0x50 and "
                                 "byte 1 the parameter section's block ≥ 2; got "
                                 f"0x{head[1]:02x} and {pblock})")
        start = (pblock - 1) * BLOCK
        fh.seek(start)
        phead = fh.read(4)
        if len(phead) < 4:
            raise _truncated(path, start + BLOCK, size,
                             f"the header and the parameter section from block {pblock}")
        nblocks, proc = phead[2], phead[3]
        end = start + nblocks * BLOCK
        if nblocks == 0:
            raise C3DFormatError(f"{path}: the parameter section (block {pblock}) says it has "
                                 "0 blocks: the file is corrupt")
        if size < end:
            raise _truncated(path, end, size, f"the header and {nblocks} parameter blocks "
                             f"from block {pblock}")
        if proc == 86:
            raise C3DFormatError(f"{path}: a MIPS (big-endian) C3D file, which ezc3d cannot "
                                 "read; convert it to Intel format (e.g. with the lab's "
                                 "software or btk)")
        if proc not in (84, 85):
            raise C3DFormatError(f"{path}: processor type {proc} in the parameter section "
                                 "(84 Intel, 85 DEC, 86 MIPS): the file is corrupt")
        fh.seek(start)
        return head, fh.read(nblocks * BLOCK), pblock, nblocks, proc


class _Params:
    """The parameter section's values by ``(group, name)``, read as ezc3d reads them."""

    def __init__(self, ps: _Reader, path: Path):
        self.ps, self.path = ps, path
        self.groups, raw = _walk(ps, 4, len(ps.data), path)
        self.names = {(self.groups.get(g, f"#{g}"), n): v for (g, n), v in raw.items()}

    def values(self, group: str, name: str) -> np.ndarray | None:
        if (group, name) not in self.names:
            return None
        typ, dims, at = self.names[(group, name)]
        if typ == -1:
            return None
        n = math.prod(dims)
        return self.ps.floats(at, n) if typ == 4 else self.ps.ints(at, n, typ)

    def scalar(self, group: str, name: str, default: float) -> float:
        v = self.values(group, name)
        if v is None:
            if (group, name) in self.names:  # a character parameter where a number belongs
                raise C3DFormatError(f"{self.path}: {group}:{name} is text; it must be a "
                                     "number")
            return default
        if v.size == 0:
            raise C3DFormatError(f"{self.path}: {group}:{name} has no value; give it one")
        x = float(v[0])
        if not math.isfinite(x):
            raise C3DFormatError(f"{self.path}: {group}:{name} = {x}; it must be a finite "
                                 "number")
        return x

    def series(self, group: str, name: str) -> list[float]:
        out: list[float] = []
        for key in [name] + [f"{name}{i}" for i in range(2, 100)]:
            v = self.values(group, key)
            if v is None:
                break
            out += v.tolist()
        return out


def _counts(P: _Params) -> tuple[int, int, float, float]:
    """``(points, analog channels, POINT:RATE, ANALOG:RATE)``, each ≥ 0."""
    points = int(P.scalar("POINT", "USED", 0))
    channels_used = int(P.scalar("ANALOG", "USED", 0))
    rate = P.scalar("POINT", "RATE", 0.0)
    arate = P.scalar("ANALOG", "RATE", 0.0)
    for what, v in (("POINT:USED", points), ("ANALOG:USED", channels_used),
                    ("POINT:RATE", rate), ("ANALOG:RATE", arate)):
        if v < 0:
            raise C3DFormatError(f"{P.path}: {what} = {v:g}; it must be ≥ 0 (the file is "
                                 "corrupt)")
    if points:
        P.scalar("POINT", "SCALE", -1.0)
    return points, channels_used, rate, arate


def _frames(P: _Params, first: int, last: int) -> tuple[int, float]:
    """The frame count as ezc3d takes it (header 1-based, or 0-based where the first frame is
    0; a non-zero ``POINT:FRAMES`` wins) → ``(frames, POINT:FRAMES)``."""
    one = first != 0
    f0, f1 = (first - 1, last - 1 if last else 0) if one else (0, last)
    frames = f1 - f0 + 1
    pf = P.scalar("POINT", "FRAMES", 0)
    if pf < 0 and P.names.get(("POINT", "FRAMES"), (0,))[0] == 2:
        pf += 65536  # an unsigned 16-bit count (> 32767 frames) read as signed
    if int(pf) != 0 and int(pf) != frames:
        frames = int(pf)
    return frames, pf


def _subframes(P: _Params, rate: float, arate: float, byframe_h: int) -> int:
    """Analog samples per frame: ``ANALOG:RATE / POINT:RATE``, as ezc3d's ``updateHeader``."""
    if int(rate) == 0:
        return 1
    if int(arate / rate) != byframe_h and not (byframe_h == 1 and "SHADOW" in
                                               P.groups.values()):
        return int(arate / rate)
    return byframe_h


def _rotations_end(P: _Params, frames: int, rate: float) -> tuple[int, str]:
    """Where the ROTATION group's data ends [bytes] (0: none used), and what it holds."""
    rstart = int(P.scalar("ROTATION", "DATA_START", 0))
    rused = int(P.scalar("ROTATION", "USED", 0))
    if ("ROTATION", "RATIO") in P.names:
        ratio = int(P.scalar("ROTATION", "RATIO", 0))
    else:
        rrate = P.scalar("ROTATION", "RATE", 0.0)
        ratio = int(rrate / rate) if rate > 0 else 0
    if rstart < 1 or rused < 0 or ratio < 0:
        raise C3DFormatError(f"{P.path}: ROTATION:DATA_START {rstart}, USED {rused}, ratio "
                             f"{ratio}: the ROTATION group is corrupt")
    end = (rstart - 1) * BLOCK + frames * ratio * rused * 17 * 4 if ratio * rused else 0
    return end, (f"rotations from block {rstart}: {frames} frames × {ratio} × {rused} "
                 "rotations × 68 bytes")


def _check_analog(P: _Params, channels: int) -> None:
    """One ``ANALOG:SCALE`` and ``OFFSET`` per channel (ezc3d indexes them unchecked)."""
    for key in ("SCALE", "OFFSET"):
        have = len(P.series("ANALOG", key))
        if have < channels:
            raise C3DFormatError(f"{P.path}: ANALOG:{key} has {have} values for {channels} "
                                 "analog channels (ANALOG:USED); one per channel is needed")
    P.scalar("ANALOG", "GEN_SCALE", 1.0)


def check_c3d(path: Path) -> C3DLayout:
    """Check ``path``'s header, parameter section and data section against its length and
    each other (see the module docstring) → :class:`C3DLayout`. Raises
    :class:`~gdimitate.errors.C3DFormatError` (truncated, corrupt, not a C3D file: the message
    says which section, the expected and actual size) and
    :class:`~gdimitate.errors.ResourceLimitError` (over :data:`MAX_C3D_BYTES`, or a layout
    needing more than :data:`MAX_C3D_MEMORY` to read)."""
    size = path.stat().st_size
    if size > MAX_C3D_BYTES:
        raise ResourceLimitError(f"{path}: {size:,} bytes is over the {MAX_C3D_BYTES:,} bytes "
                                 "a C3D file may have (gdimitate.io.c3d.layout.MAX_C3D_BYTES); "
                                 "cut the trial into shorter ones")
    head, section, pblock, nblocks, proc = _sections(path, size)
    r = _Reader(head, proc == 85, path)
    w = [r.u16(2 * i) for i in range(12)]
    first, last, dstart, byframe_h = w[3], w[4], w[8], w[9]
    scale_h = r.floats(12, 1)[0]
    P = _Params(_Reader(section, proc == 85, path), path)
    if not math.isfinite(scale_h):
        raise C3DFormatError(f"{path}: header scale factor (words 7–8) is {scale_h}; it must "
                             "be a finite number (negative for float data)")
    floats = scale_h < 0
    points, channels_used, rate, arate = _counts(P)
    frames, pf = _frames(P, first, last)
    sub = _subframes(P, rate, arate, byframe_h)
    channels = channels_used if sub else 0  # ezc3d: ANALOG:USED, none without subframes
    rotation = "ROTATION" in P.groups.values()
    if points == 0 and channels == 0 and not rotation:
        frames = 0
    if frames < 0:
        raise C3DFormatError(f"{path}: the header says frames {first}–{last} and POINT:FRAMES "
                             f"is {pf:g}: {frames} frames; the file is corrupt")
    if channels:
        _check_analog(P, channels)
    if frames and dstart < 1 + (pblock - 1) + nblocks:
        raise C3DFormatError(f"{path}: the header's data start block {dstart} (word 9) lies "
                             f"before the end of the parameter section (blocks {pblock}–"
                             f"{pblock + nblocks - 1}): the file is corrupt")
    bpv = 4 if floats else 2
    data_end = (dstart - 1) * BLOCK + frames * (4 * points + channels * sub) * bpv \
        if frames else 0
    what = (f"data from block {dstart}: {frames} frames × ({points} points × 4 + "
            f"{channels} analog channels × {sub} samples) × {bpv} bytes")
    rend, rwhat = _rotations_end(P, frames, rate) if rotation and frames else (0, "")
    if rend > data_end:  # ezc3d writes the group with none used
        data_end, what = rend, rwhat
    if data_end > size:
        raise _truncated(path, data_end, size, what)
    plates = int(P.scalar("FORCE_PLATFORM", "USED", 0))
    if plates:
        _check_plates(path, plates, P.names, P.values)
    params = {k: P.values(*k) for k in P.names if P.names[k][0] != -1}
    layout = C3DLayout(frames, points, channels, sub, floats, max(plates, 0), data_end, size,
                       params)
    need = estimated_memory(layout)
    if need > MAX_C3D_MEMORY:
        raise ResourceLimitError(
            f"{path}: reading {frames:,} frames of {points} points and {channels} × {sub} "
            f"analog samples would need about {need / 1e9:.1f} GB; the limit is "
            f"{MAX_C3D_MEMORY / 1e9:g} GB (gdimitate.io.c3d.layout.MAX_C3D_MEMORY): cut the trial")
    return layout


def _check_plates(path: Path, plates: int, names: dict, values) -> None:
    """The FORCE_PLATFORM parameters ezc3d indexes without bounds checks."""
    if plates < 0:
        raise C3DFormatError(f"{path}: FORCE_PLATFORM:USED = {plates}; it must be ≥ 0")
    ch = names.get(("FORCE_PLATFORM", "CHANNEL"))
    if ch is None or len(ch[1]) != 2:
        raise C3DFormatError(f"{path}: FORCE_PLATFORM:CHANNEL must be a 2-D table (channels × "
                             f"plates) for {plates} plates; got "
                             f"{'none' if ch is None else f'dimensions {ch[1]}'}")
    cal = names.get(("FORCE_PLATFORM", "CAL_MATRIX"))
    if cal is not None and len(cal[1]) >= 3 and cal[1][2] > 0 and \
            (cal[1][0] < 6 or cal[1][1] < 6 or cal[1][0] * cal[1][1] < 36):
        raise C3DFormatError(f"{path}: FORCE_PLATFORM:CAL_MATRIX has dimensions {cal[1]}; a "
                             "calibration matrix is at least 6 × 6 per plate")
    types = values("FORCE_PLATFORM", "TYPE")
    poly = values("FORCE_PLATFORM", "FPCOPPOLY")
    if types is not None and poly is not None and poly.size:
        for i, t in enumerate(types[:plates].tolist()):
            if t == 3 and poly.size < 12 * (i + 1):
                raise C3DFormatError(f"{path}: FORCE_PLATFORM:FPCOPPOLY has {poly.size} "
                                     f"values; plate {i + 1} (type 3) needs 12")
