"""A strict reader of the BVH (Biovision hierarchy) text format.

Grammar (whitespace-separated tokens; braces may share a line with other tokens)::

    HIERARCHY
    ROOT <name> { OFFSET x y z  CHANNELS n <channel>…  (JOINT <name> {…} | End Site {…})* }
    MOTION
    Frames: <N>
    Frame Time: <seconds>
    <N lines of as many numbers as the hierarchy declares channels>

Channels are ``Xposition``, ``Yposition``, ``Zposition``, ``Xrotation``, ``Yrotation``,
``Zrotation`` (case-insensitive in the file, stored capitalised as above); rotations are in
degrees. Every joint (ROOT or JOINT) must declare ``CHANNELS`` (``CHANNELS 0`` is allowed); an
``End Site`` has an ``OFFSET`` only. Anything else — unbalanced braces, a missing OFFSET or
CHANNELS, an unknown channel, a frame line with the wrong number of values, NaN/inf values, a
zero or negative ``Frame Time``, fewer or more frame lines than ``Frames:`` says — raises
:class:`~gdimitate.errors.BVHError` naming the line and what to fix. Nothing is dropped.

Numbers are ASCII (``Frames: ²`` or ``CHANNELS ⁶``, digits Python's ``int()`` would take,
are refused), finite, offsets and positions within :data:`MAX_BVH_POSITION` file units and
rotations within :data:`MAX_BVH_ROTATION_DEG` (beyond them a value is corrupt, and the unit
detection and the URDF's placements overflow).

Bounds (:mod:`gdimitate.safety`, checked before anything is allocated): a file of at most
:data:`~gdimitate.safety.MAX_BVH_BYTES` (reading peaks at up to 16 bytes of memory per byte
of the file); a hierarchy at most :data:`MAX_BVH_DEPTH` joints
deep; a ``Frame Time`` between :data:`~gdimitate.safety.MIN_SAMPLE_INTERVAL_S` and
:data:`~gdimitate.safety.MAX_SAMPLE_INTERVAL_S` and a clip of at most
:data:`~gdimitate.safety.MAX_MOTION_DURATION_S`; frames × channels within
:data:`~gdimitate.safety.MAX_ARRAY_BYTES`. Beyond them:
:class:`~gdimitate.errors.ResourceLimitError` naming the file, the line and the limit.

Meaning of the numbers (used by :mod:`gdimitate.io.bvh.reader` and :mod:`gdimitate.io.bvh.urdf`):
a joint's transform relative to its parent is a translation by its OFFSET plus its position
channels (in the parent's axes), then the rotations of its rotation channels composed in the
file's order, ``R = R_c1 · R_c2 · …`` (right-handed, about the joint's own rotated axes),
whatever the position channels' place in the list. The root's position is OFFSET + position
channels in the file's world.

Why our own reader: the PyPI parsers checked (``bvh`` 0.3, 2017: no validation, unbalanced
braces pass silently; ``bvhio`` 1.5.4: transforms in single precision through PyGLM, pinned
``pyglm==2.8.2``; ``pybvh`` 0.9.0: assumes three rotation channels per joint, reorders root
channels and snaps the frame time) do not give channel-exact data with line-numbered errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import BVHError, ResourceLimitError
from ...safety import (
    MAX_BVH_BYTES,
    MAX_MOTION_DURATION_S,
    MAX_SAMPLE_INTERVAL_S,
    MIN_SAMPLE_INTERVAL_S,
    check_array_size,
    read_text_bounded,
)

__all__ = ["BVHJoint", "BVHFile", "parse_bvh", "CHANNEL_NAMES", "MAX_BVH_DEPTH",
           "MAX_BVH_POSITION", "MAX_BVH_ROTATION_DEG"]

#: Largest |OFFSET| or position channel value [file units]: 10 km in millimetres (a
#: skeleton is ~2000 mm tall; a clip of an hour's walk travels ~5e6 mm).
MAX_BVH_POSITION = 1e7
#: Largest |rotation channel| [degrees]: a million turns (unwrapped angles grow by 360 a
#: turn; sin and cos of larger numbers lose their digits).
MAX_BVH_ROTATION_DEG = 3.6e8

#: Deepest joint hierarchy read (a human skeleton with fingers is ~15 deep; the recursive
#: reader and Python's stack stop far above it).
MAX_BVH_DEPTH = 200

#: The six channel names, as stored.
CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
_CANON = {c.lower(): c for c in CHANNEL_NAMES}


@dataclass(frozen=True)
class BVHJoint:
    """One ROOT/JOINT of a BVH hierarchy.

    ``name``; ``parent``: index of the parent joint in :attr:`BVHFile.joints` (−1 for the
    root); ``offset`` ``(3,)`` [file units]: position in the parent's frame; ``channels``: the
    channel names in file order; ``column``: index of the first channel's column in
    :attr:`BVHFile.frames`; ``end_sites``: offsets ``(3,)`` of this joint's End Sites;
    ``line``: line number of its ROOT/JOINT keyword."""

    name: str
    parent: int
    offset: np.ndarray
    channels: tuple[str, ...]
    column: int
    end_sites: tuple[np.ndarray, ...]
    line: int


@dataclass(frozen=True)
class BVHFile:
    """A parsed BVH file: ``joints`` (depth-first, file order), ``frame_time`` [s] and
    ``frames`` ``(T, n_channels)`` — the numbers as written (file units, degrees)."""

    path: str
    joints: tuple[BVHJoint, ...]
    frame_time: float
    frames: np.ndarray

    @property
    def n_channels(self) -> int:
        """Number of values per frame line."""
        return sum(len(j.channels) for j in self.joints)

    def joint(self, name: str) -> BVHJoint:
        """The joint called ``name``."""
        for j in self.joints:
            if j.name == name:
                return j
        from ...errors import UnknownNameError

        raise UnknownNameError("BVH joint", name, [j.name for j in self.joints])

    def children(self, index: int) -> list[int]:
        """Indices of the joints whose parent is ``index``."""
        return [i for i, j in enumerate(self.joints) if j.parent == index]


class _Tokens:
    """Hierarchy tokens with their line numbers."""

    def __init__(self, path: str, lines: list[str]):
        self.path = path
        self.items: list[tuple[str, int]] = []
        for n, line in enumerate(lines, start=1):
            for tok in line.replace("{", " { ").replace("}", " } ").split():
                self.items.append((tok, n))
        self.i = 0

    def error(self, line: int, what: str) -> BVHError:
        return BVHError(f"{self.path}, line {line}: {what}")

    def peek(self) -> tuple[str, int]:
        if self.i >= len(self.items):
            last = self.items[-1][1] if self.items else 1
            return "", last
        return self.items[self.i]

    def take(self, expected: str | None = None, what: str = "") -> tuple[str, int]:
        tok, line = self.peek()
        desc = f"{expected!r} {what}".strip() if expected else what
        if tok == "":
            raise self.error(line, f"the file ends inside the HIERARCHY section where {desc} was "
                                   "expected (truncated file or unbalanced braces)")
        if expected is not None and tok.lower() != expected.lower():
            raise self.error(line, f"expected {desc} but found {tok!r}")
        self.i += 1
        return tok, line

    def number(self, what: str) -> float:
        tok, line = self.take(what=what)
        x = _ascii_float(tok)
        if x is None:
            raise self.error(line, f"{what}: {tok!r} is not a number") from None
        if not math.isfinite(x):
            raise self.error(line, f"{what} is {tok!r}; give a finite number")
        if abs(x) > MAX_BVH_POSITION:
            raise self.error(line, f"{what} is {tok!r}; offsets must lie within "
                                   f"±{MAX_BVH_POSITION:g} file units (gdimitate.io.bvh.parse."
                                   "MAX_BVH_POSITION): is the file corrupt?")
        return x


def _read_offset(tk: _Tokens, owner: str) -> np.ndarray:
    tok, line = tk.peek()
    if tok == "":
        tk.take(what=f"the OFFSET of {owner}")
    if tok.upper() != "OFFSET":
        raise tk.error(line, f"{owner} needs an 'OFFSET x y z' line first; found {tok!r}")
    tk.take()
    return np.array([tk.number(f"OFFSET {a} of {owner}") for a in "xyz"])


def _read_block(tk: _Tokens, name: str, kind: str, line0: int, parent: int,
                joints: list[BVHJoint], column: int, depth: int = 1) -> int:
    """Read one ROOT/JOINT block after its name; append it and its descendants; returns the
    next free column."""
    owner = f"{kind} {name!r} (line {line0})"
    if depth > MAX_BVH_DEPTH:
        raise ResourceLimitError(f"{tk.path}, line {line0}: {owner} is {depth} joints deep; "
                                 f"the limit is {MAX_BVH_DEPTH} (a human skeleton is ~15)")
    if not name.isprintable():
        raise tk.error(line0, f"{kind} name {name!r} holds a control character; joint names "
                              "become URDF link and joint names and must be printable text")
    tk.take("{", f"after {kind} {name!r} ")
    offset = _read_offset(tk, owner)
    tok, line = tk.peek()
    if tok == "":
        tk.take(what=f"the CHANNELS of {owner}")
    if tok.upper() != "CHANNELS":
        raise tk.error(line, f"{owner} has no CHANNELS line after its OFFSET (found {tok!r}); "
                             "write 'CHANNELS 0' for a joint without channels, or e.g. "
                             "'CHANNELS 3 Zrotation Xrotation Yrotation'")
    tk.take()
    n_tok, n_line = tk.take(what=f"the channel count of {owner}")
    if not (n_tok.isascii() and n_tok.isdigit()) or int(n_tok) > 6:
        raise tk.error(n_line, f"CHANNELS of {owner}: the count {n_tok!r} must be an integer "
                               "0..6")
    channels = []
    for _ in range(int(n_tok)):
        c, cl = tk.take(what=f"a channel name of {owner}")
        if c.lower() not in _CANON:
            raise tk.error(cl, f"{owner}: unknown channel {c!r} (CHANNELS says {n_tok}); valid: "
                               f"{', '.join(CHANNEL_NAMES)}")
        if _CANON[c.lower()] in channels:
            raise tk.error(cl, f"{owner}: channel {c!r} appears twice")
        channels.append(_CANON[c.lower()])
    index = len(joints)
    ends: list[np.ndarray] = []
    joints.append(BVHJoint(name, parent, offset, tuple(channels), column, (), line0))
    column += len(channels)
    while True:
        tok, line = tk.peek()
        key = tok.upper()
        if key == "}":
            tk.take()
            break
        if key == "JOINT":
            tk.take()
            child, cl = tk.take(what="a joint name after JOINT")
            if child in ("{", "}"):
                raise tk.error(cl, "JOINT needs a name before '{'")
            column = _read_block(tk, child, "JOINT", cl, index, joints, column, depth + 1)
        elif key == "END":
            tk.take()
            tk.take("Site", "after 'End' ")
            tk.take("{", "after 'End Site' ")
            ends.append(_read_offset(tk, f"the End Site of {owner}"))
            t2, l2 = tk.peek()
            if t2 != "}":
                raise tk.error(l2, f"the End Site of {owner} must hold only an OFFSET and a "
                                   f"closing '}}'; found {t2!r}")
            tk.take()
        elif key == "":
            raise tk.error(line, f"the file ends before {owner} is closed: a '}}' is missing "
                                 "(unbalanced braces)")
        elif key in ("MOTION", "ROOT"):
            raise tk.error(line, f"{tok} found while {owner} is still open: a '}}' is missing "
                                 "(unbalanced braces)")
        else:
            raise tk.error(line, f"unexpected {tok!r} inside {owner}; expected JOINT, End Site "
                                 "or '}'")
    j = joints[index]
    joints[index] = BVHJoint(j.name, j.parent, j.offset, j.channels, j.column, tuple(ends),
                             j.line)
    return column


def _header_value(lines: list[str], i: int, path: str, key: str) -> tuple[str, int]:
    """The text after ``key`` on the next non-blank line from index ``i``; (value, next i)."""
    while i < len(lines) and not lines[i].strip():
        i += 1
    if i >= len(lines):
        raise BVHError(f"{path}, line {i}: the MOTION section is truncated: {key!r} is missing")
    text = lines[i].strip()
    if not text.lower().startswith(key.lower()):
        raise BVHError(f"{path}, line {i + 1}: expected '{key} …' in the MOTION section; found "
                       f"{text[:40]!r}")
    return text[len(key):].strip(), i + 1


def parse_bvh(path: str | Path) -> BVHFile:
    """Read and check a BVH file (see the module docstring for what is checked)."""
    path = Path(path)
    if not path.is_file():
        raise BVHError(f"no such BVH file: {path}")
    lines = read_text_bounded(path, MAX_BVH_BYTES, "BVH file", BVHError,
                              ResourceLimitError).splitlines()
    p = str(path)
    motion_at = next((i for i, s in enumerate(lines) if s.strip().upper() == "MOTION"), None)
    tk = _Tokens(p, lines[: motion_at + 1] if motion_at is not None else lines)
    tk.take("HIERARCHY", "at the start of the file ")
    joints: list[BVHJoint] = []
    tok, line = tk.take("ROOT", "after HIERARCHY ")
    root, rl = tk.take(what="the root's name")
    column = _read_block(tk, root, "ROOT", rl, -1, joints, 0)
    tok, line = tk.peek()
    if tok.upper() != "MOTION":
        what = ("a second ROOT (only one skeleton per file is supported)" if tok.upper() == "ROOT"
                else "an extra '}' (unbalanced braces)" if tok == "}" else repr(tok))
        raise tk.error(line, f"after the ROOT block closes, MOTION was expected; found {what}")
    names = [j.name for j in joints]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise BVHError(f"{p}: joint names must be unique; repeated: {dup}")
    assert motion_at is not None
    value, i = _header_value(lines, motion_at + 1, p, "Frames:")
    if not (value.isascii() and value.isdigit()) or int(value) < 1:
        raise BVHError(f"{p}, line {i}: 'Frames: {value}' must be a positive integer")
    n_frames = int(value)
    value, i = _header_value(lines, i, p, "Frame Time:")
    dt = _ascii_float(value)
    if dt is None:
        raise BVHError(f"{p}, line {i}: 'Frame Time: {value}' is not a number") from None
    if not (math.isfinite(dt) and dt > 0):
        raise BVHError(f"{p}, line {i}: 'Frame Time: {value}' must be a positive number of "
                       "seconds per frame (e.g. 0.0083333 for 120 Hz)")
    _check_clip(p, i, n_frames, dt, column)
    frames = _read_frames(lines, i, p, n_frames, column, joints)
    return BVHFile(p, tuple(joints), dt, frames)


def _check_clip(path: str, line: int, n_frames: int, dt: float, n_channels: int) -> None:
    """Refuse a frame time or clip length out of the bounds of :mod:`gdimitate.safety` and a
    frame array too large to allocate — before reading the frames."""
    where = f"{path}, line {line}"
    if dt > MAX_SAMPLE_INTERVAL_S or dt < MIN_SAMPLE_INTERVAL_S:
        raise ResourceLimitError(
            f"{where}: 'Frame Time: {dt:g}' s is outside {MIN_SAMPLE_INTERVAL_S:g}–"
            f"{MAX_SAMPLE_INTERVAL_S:g} s; it is the time between frames in seconds (e.g. "
            "0.0083333 for 120 Hz)")
    if dt * (n_frames - 1) > MAX_MOTION_DURATION_S:
        raise ResourceLimitError(
            f"{where}: {n_frames:,} frames of {dt:g} s last {dt * (n_frames - 1):.3g} s; the "
            f"limit is {MAX_MOTION_DURATION_S:g} s")
    check_array_size(f"{where}: 'Frames: {n_frames}' × {n_channels} channels",
                     (n_frames, n_channels))


def _channel_label(joints: list[BVHJoint], col: int) -> str:
    for j in joints:
        if j.column <= col < j.column + len(j.channels):
            return f"{j.name} {j.channels[col - j.column]}"
    return f"column {col}"


def _read_frames(lines: list[str], start: int, path: str, n_frames: int, n_channels: int,
                 joints: list[BVHJoint]) -> np.ndarray:
    data = np.empty((n_frames, n_channels))
    limit = np.full(n_channels, MAX_BVH_ROTATION_DEG)
    for j in joints:
        for c, name in enumerate(j.channels):
            if name.endswith("position"):
                limit[j.column + c] = MAX_BVH_POSITION
    k = 0
    last_line = start
    for i in range(start, len(lines)):
        parts = lines[i].split()
        if not parts:
            continue
        last_line = i + 1
        if k >= n_frames:
            raise BVHError(f"{path}, line {i + 1}: more frame lines than 'Frames: {n_frames}' "
                           "declares; fix the Frames count or remove the extra lines")
        if len(parts) != n_channels:
            raise BVHError(f"{path}, line {i + 1}: frame {k} has {len(parts)} values; the "
                           f"hierarchy declares {n_channels} channels")
        try:
            if not lines[i].isascii() or "_" in lines[i]:
                raise ValueError
            row = [float(x) for x in parts]
        except ValueError:
            bad = next(x for x in parts if _ascii_float(x) is None)
            raise BVHError(f"{path}, line {i + 1}: frame {k}: {bad!r} is not a number") from None
        data[k] = row
        bad_cols = np.flatnonzero(~(np.abs(data[k]) <= limit))
        if bad_cols.size:
            c = int(bad_cols[0])
            label = _channel_label(joints, c)
            if not math.isfinite(data[k, c]):
                raise BVHError(f"{path}, line {i + 1}: frame {k}, value {c + 1} ({label}) is "
                               f"{parts[c]!r}; every value must be finite (fill or cut the gap "
                               "before reading)")
            kind, name = (("a position", "MAX_BVH_POSITION") if "position" in label else
                          ("a rotation", "MAX_BVH_ROTATION_DEG"))
            raise BVHError(f"{path}, line {i + 1}: frame {k}, value {c + 1} ({label}) is "
                           f"{parts[c]!r}; {kind} must lie within ±{limit[c]:g} "
                           f"(gdimitate.io.bvh.parse.{name}): is the file corrupt?")
        k += 1
    if k < n_frames:
        raise BVHError(f"{path}, line {last_line}: the MOTION section is truncated: 'Frames: "
                       f"{n_frames}' but only {k} frame lines follow; fix the Frames count or "
                       "restore the missing lines")
    return data


def _ascii_float(x: str) -> float | None:
    """``float(x)`` for ASCII number text without underscores (Python's ``float`` also takes
    ``"١٫٥"`` and ``"1_0"``); ``None`` for anything else."""
    if not x.isascii() or "_" in x:
        return None
    try:
        return float(x)
    except ValueError:
        return None
