"""Motion-capture markers from ``.trc`` files (the Track Row Column format OpenSim reads).

Layout: a ``PathFileType`` line; a line of header keys (``DataRate CameraRate NumFrames
NumMarkers Units …``) and one of their values, paired by name (single tabs, runs of tabs,
spaces around them and trailing tabs are all seen in the wild); the marker names
(``Frame#  Time  name1 …``, each name over its three columns); the ``X1 Y1 Z1 …`` line;
then one row per frame (frame number, time [s], x y z per marker; an empty field is a marker
not seen in that frame).

Units come from the header's ``Units`` (``mm``, ``cm``, ``m``); positions are returned in
metres in our world frame (x forward, y left, z up). The lab's vertical axis is the axis
along which the markers spread most in a frame (a person is taller than long or wide; median
over frames) unless ``up=`` says it: ``"Y"`` (OpenSim's convention, Z to the right; x = X,
y = −Z, z = Y) or ``"Z"`` (x = X, y = Y, z = Z). Gaps stay NaN and are listed in a
:class:`~gdimitate.errors.MarkerGapWarning`.
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import (
    MarkerGapWarning,
    OpenSimDataError,
    ResourceLimitError,
    TimeGridError,
    UnitError,
)
from ...safety import MAX_TABLE_BYTES, read_text_bounded
from ..motion import check_time
from ._table import iter_lines
from .joints import ground_to_world

__all__ = ["Markers", "read_trc"]

_UNITS = {"mm": 1e-3, "millimeters": 1e-3, "millimetres": 1e-3, "cm": 1e-2,
          "centimeters": 1e-2, "m": 1.0, "meters": 1.0, "metres": 1.0}


@dataclass(frozen=True)
class Markers:
    """Marker trajectories: ``t`` ``(T,)`` [s]; ``names`` (``n`` marker names); ``xyz``
    ``(T, n, 3)`` [m] in our world frame (NaN where a marker was not seen); ``source`` (the
    file) and ``frame_note`` (units and axes as read)."""

    t: np.ndarray
    names: tuple[str, ...]
    xyz: np.ndarray
    source: str = ""
    frame_note: str = ""

    def __post_init__(self) -> None:
        t = check_time(self.t)
        xyz = np.asarray(self.xyz, dtype=float)
        names = tuple(self.names)
        if xyz.shape != (t.size, len(names), 3):
            raise OpenSimDataError(f"Markers.xyz must be (T, n, 3) = ({t.size}, {len(names)}, "
                                   f"3); got {xyz.shape}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "xyz", xyz)

    @property
    def rate(self) -> float:
        """Frame rate [Hz]: frames per second over the whole clip (time columns are often
        rounded, e.g. 0.017, 0.033 s at 60 Hz)."""
        return float((self.t.size - 1) / (self.t[-1] - self.t[0]))

    def __getitem__(self, name: str) -> np.ndarray:
        """Trajectory ``(T, 3)`` [m] of one marker."""
        try:
            return self.xyz[:, self.names.index(name)]
        except ValueError:
            from ...errors import UnknownNameError

            raise UnknownNameError("marker", name, self.names) from None


#: Largest table of numbers a ``.trc`` may unpack to [bytes] (lines × (1 + 3 × markers) ×
#: 8): reading needs about 4 such tables at its peak (measured: docs/security.md).
MAX_TRC_ARRAY_BYTES = 400 * 10**6
#: Largest extent [m] of one frame's markers (median over frames): a person spans about
#: 0.2–2.5 m; more means the numbers are not in the unit the file states.
MAX_MARKER_EXTENT_M = 10.0
#: Smallest such extent [m] with three or more markers seen (less: metres read as mm).
MIN_MARKER_EXTENT_M = 0.01
#: Largest distance [m] of one marker from its frame's other markers (their median): farther
#: is a corrupt value (a bit flip, a ghost marker), not a body.
MAX_MARKER_OUTLIER_M = 10.0
_LOOKS = (("mm", 1e-3), ("cm", 1e-2), ("m", 1.0))


def check_marker_values(xyz: np.ndarray, names, t: np.ndarray, source: object, unit: str,
                        scale: float, field: str = "Units") -> None:
    """Refuse marker positions ``xyz`` ``(T, n, 3)`` [m] (NaN: not seen) that cannot be a body
    measured in ``unit`` (``scale`` metres per file unit; ``field`` the header field that
    states it): infinite values, a median frame extent beyond :data:`MAX_MARKER_EXTENT_M` or
    below :data:`MIN_MARKER_EXTENT_M` (:class:`~gdimitate.errors.UnitError` saying which unit
    the numbers look like), a marker more than :data:`MAX_MARKER_OUTLIER_M` from its frame's
    others (:class:`~gdimitate.errors.OpenSimDataError` naming the marker, frame and time)."""
    inf = np.argwhere(np.isinf(xyz))
    if inf.size:
        k, i, _ = inf[0]
        raise OpenSimDataError(f"{source}: marker {names[i]!r} is infinite in frame {k + 1} "
                               f"(t = {t[k]:g} s) and {len(inf) - 1} more values; mark those "
                               "samples as not seen (empty) or fix the file")
    seen = np.isfinite(xyz).all(axis=2)
    multi = seen.sum(axis=1) >= 2
    if not multi.any():
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        X = xyz if multi.all() else xyz[multi]
        extent = np.nanmax(np.nanmax(X, axis=1) - np.nanmin(X, axis=1), axis=1)  # per frame
        size = float(np.median(extent))
        many = seen[multi].sum(axis=1) >= 3
        small = float(np.median(extent[many])) if many.any() else np.inf
    if small == 0:
        raise OpenSimDataError(f"{source}: the markers of a frame all lie at one point (median "
                               "over frames): not a body; check the file's columns")
    if size > MAX_MARKER_EXTENT_M or small < MIN_MARKER_EXTENT_M:
        ext = size if size > MAX_MARKER_EXTENT_M else small
        raw = ext / scale
        guess = min(_LOOKS, key=lambda u: abs(np.log10(max(raw * u[1], 1e-300) / 1.0)))
        raise UnitError(
            f"{source}: {field}={unit!r}, but the markers of a frame span {ext:g} m (median "
            f"over frames; a person spans about 0.2–2.5 m): the numbers look like "
            f"{guess[0]} ({raw * guess[1]:.3g} m); set {field} to {guess[0]!r}")
    del X
    frames = np.flatnonzero(multi)
    for lo in range(0, frames.size, 4096):  # in chunks: a few copies of a big file cost GBs
        Xc = xyz[frames[lo:lo + 4096]]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            dist = np.linalg.norm(Xc - np.nanmedian(Xc, axis=1)[:, None], axis=2)
        if np.nanmax(dist) > MAX_MARKER_OUTLIER_M:
            f, i = np.unravel_index(np.nanargmax(dist), dist.shape)
            k = int(frames[lo + f])
            raise OpenSimDataError(
                f"{source}: marker {names[i]!r} is {dist[f, i]:.3g} m from the frame's other "
                f"markers in frame {k + 1} (t = {t[k]:g} s): a corrupt value or a ghost "
                "marker, not a body; mark it as not seen there (empty, or a negative residual "
                "in a C3D) or fix the file")


def _up_axis(xyz: np.ndarray, path: Path) -> str:
    spread = np.nanmax(xyz, axis=1) - np.nanmin(xyz, axis=1)  # (T, 3)
    k = int(np.argmax(np.nanmedian(spread, axis=0)))
    if k == 0:
        raise OpenSimDataError(f"{path}: the markers spread most along X; cannot tell the "
                               "vertical axis: pass up='Y' or up='Z'")
    return "XYZ"[k]


def _header(keys_line: str, values_line: str, path: Path) -> dict[str, str]:
    """The header's ``{key: value}`` by name. Writers separate the values with single tabs,
    runs of tabs, tabs padded with spaces, or leave trailing tabs; keys and values hold no
    spaces. Pair the whitespace-separated tokens when there are as many values as keys; else
    pair the tab-separated fields by position (a field left empty is a key without value)."""
    keys, vals = keys_line.split(), values_line.split()
    if len(keys) == len(vals):
        return dict(zip(keys, vals))
    kf, vf = keys_line.split("\t"), values_line.split("\t")
    if len(vf) <= len(kf) or not any(v.strip() for v in vf[len(kf):]):
        return {k.strip(): v.strip() for k, v in zip(kf, vf) if k.strip() and v.strip()}
    raise OpenSimDataError(f"{path}: line 2 names {len(keys)} header keys {keys} but line 3 "
                           f"holds {len(vals)} values {vals}; write one value per key")


def _count(head: dict[str, str], key: str, path: Path) -> int:
    """The header's ``key`` as a whole number ≥ 0 (``"41"`` or ``"41.0"``); else
    :class:`~gdimitate.errors.OpenSimDataError` naming the field."""
    text = head[key]
    try:
        x = float(text)
    except ValueError:
        x = math.nan
    if not (math.isfinite(x) and 0 <= x <= 1e9 and x == int(x)):
        raise OpenSimDataError(f"{path}: header field {key}={text!r} is not a whole number in "
                               f"0…1e9; write the count of {key[3:].lower()} (line 3, under "
                               f"{key})")
    return int(x)


def _rows(it, cap: int, n: int, path: Path) -> tuple[np.ndarray, int]:
    """The data rows of ``it`` (``(index, line)`` pairs after the 5 header lines; at most
    ``cap``) → ``((cap, 1 + 3·n) table: time then x, y, z per marker, NaN in gaps; rows
    filled)``, bounded by :data:`MAX_TRC_ARRAY_BYTES` before it is allocated."""
    if 8.0 * cap * (1 + 3 * n) > MAX_TRC_ARRAY_BYTES:
        raise ResourceLimitError(
            f"{path}: {cap:,} lines of {n} markers would need {8e-9 * cap * (1 + 3 * n):.2f} "
            f"GB as numbers; the limit is {MAX_TRC_ARRAY_BYTES / 1e9:g} GB "
            "(gdimitate.model.osim.trc.MAX_TRC_ARRAY_BYTES): cut the trial or drop markers")
    data = np.empty((cap, 1 + 3 * n))
    rows = 0
    for lineno, ln in ((k + 5, x) for k, x in it):
        if not ln.strip():
            continue
        f = ln.split("\t")
        extra = [v for v in f[2 + 3 * n:] if v.strip()]
        if len(f) < 2 or extra:
            raise OpenSimDataError(f"{path}, line {lineno}: expected frame, time and {3 * n} "
                                   f"coordinates; got {len(f)} fields")
        vals = f[1:2 + 3 * n] + [""] * max(0, 2 + 3 * n - len(f))
        try:
            data[rows] = [float(v) if v.strip() else np.nan for v in vals]
        except ValueError as e:
            raise OpenSimDataError(f"{path}, line {lineno}: not a number ({e})") from None
        rows += 1
    return data, rows


def read_trc(path: str | Path, *, up: str | None = None) -> Markers:
    """Read a ``.trc`` marker file → :class:`Markers` (metres, our world frame).

    ``up``: the file's vertical axis, ``"Y"`` or ``"Z"`` (detected when ``None``, see the
    module docstring). Raises :class:`~gdimitate.errors.OpenSimDataError` (missing file,
    malformed header or rows, marker count disagreeing with the header),
    :class:`~gdimitate.errors.UnitError` (unknown ``Units``) and
    :class:`~gdimitate.errors.TimeGridError` (time not strictly increasing).
    """
    path = Path(path)
    if not path.is_file():
        raise OpenSimDataError(f"no such TRC file: {path}")
    text = read_text_bounded(path, MAX_TABLE_BYTES, "TRC file", OpenSimDataError,
                             ResourceLimitError)
    it = iter_lines(text)
    lines = [ln for _, ln in itertools.islice(it, 5)]
    if len(lines) < 5 or not lines[0].startswith("PathFileType"):
        raise OpenSimDataError(f"{path}: not a TRC file (the first line must start with "
                               "'PathFileType' and five header lines precede the data)")
    head = _header(lines[1], lines[2], path)
    for k in ("NumMarkers", "Units"):
        if k not in head:
            raise OpenSimDataError(f"{path}: header has no {k!r} (line 2 names the keys, line "
                                   f"3 their values); found {sorted(head)}")
    unit = head["Units"].lower()
    if unit not in _UNITS:
        raise UnitError(f"{path}: Units={head['Units']!r}; expected one of {sorted(_UNITS)}")
    names = tuple(n.strip() for n in lines[3].split("\t")[2:] if n.strip())
    n = len(names)
    twice = sorted({m for m in names if names.count(m) > 1})
    if twice:
        raise OpenSimDataError(f"{path}: line 4 names markers more than once: {twice[:20]}"
                               f"{' …' if len(twice) > 20 else ''} ({n} names, {len(set(names))}"
                               " distinct); give every marker its own name")
    if n != _count(head, "NumMarkers", path):
        raise OpenSimDataError(f"{path}: header says NumMarkers={head['NumMarkers']} but line 4 "
                               f"names {n} markers")
    # one row per line at most (a row may leave its trailing markers out: they are gaps)
    cap = max(text.count("\n"), text.count("\r")) + 1
    data, rows = _rows(it, cap, n, path)
    del text
    if rows < 2:
        raise OpenSimDataError(f"{path}: {rows} frames; at least 2 are needed")
    data = data[:rows]
    try:
        t = check_time(data[:, 0])
    except TimeGridError as e:
        raise TimeGridError(f"{path}: {e}") from None
    frames = head.get("NumFrames")
    if frames is not None and _count(head, "NumFrames", path) != rows:
        warnings.warn(f"{path}: header says NumFrames={frames}; the file has {rows} rows "
                      "(all read)", MarkerGapWarning, stacklevel=2)
    raw = data[:, 1:].reshape(rows, n, 3)  # a copy: the table itself is let go
    del data
    raw *= _UNITS[unit]
    check_marker_values(raw, names, t, path, head["Units"], _UNITS[unit])
    gaps = [names[i] for i in range(n) if np.isnan(raw[:, i]).any()]
    if gaps:
        warnings.warn(f"{path}: markers missing in some frames (NaN there): {gaps}",
                      MarkerGapWarning, stacklevel=2)
    detected = up is None
    up = _up_axis(raw, path) if up is None else str(up).upper()
    xyz = raw @ ground_to_world(up).T
    note = (f"units {head['Units']} → m; {'detected' if detected else 'given'} {up} up → world "
            + ("x = X, y = −Z, z = Y" if up == "Y" else "x = X, y = Y, z = Z"))
    return Markers(t, names, xyz, source=str(path), frame_note=note)
