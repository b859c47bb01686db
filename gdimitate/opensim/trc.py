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

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import (
    MarkerGapWarning,
    OpenSimDataError,
    ResourceLimitError,
    TimeGridError,
    UnitError,
)
from ..motion import check_time
from ..safety import MAX_TABLE_BYTES, read_text_bounded
from .grf import ground_to_world

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
            from ..errors import UnknownNameError

            raise UnknownNameError("marker", name, self.names) from None


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
    lines = read_text_bounded(path, MAX_TABLE_BYTES, "TRC file", OpenSimDataError,
                              ResourceLimitError).splitlines()
    if len(lines) < 6 or not lines[0].startswith("PathFileType"):
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
    if n != int(float(head["NumMarkers"])):
        raise OpenSimDataError(f"{path}: header says NumMarkers={head['NumMarkers']} but line 4 "
                               f"names {n} markers")
    rows = []
    for lineno, ln in enumerate(lines[5:], start=6):
        if not ln.strip():
            continue
        f = ln.split("\t")
        extra = [v for v in f[2 + 3 * n:] if v.strip()]
        if len(f) < 2 or extra:
            raise OpenSimDataError(f"{path}, line {lineno}: expected frame, time and {3 * n} "
                                   f"coordinates; got {len(f)} fields")
        vals = f[1:2 + 3 * n] + [""] * max(0, 2 + 3 * n - len(f))
        try:
            rows.append([float(v) if v.strip() else np.nan for v in vals])
        except ValueError as e:
            raise OpenSimDataError(f"{path}, line {lineno}: not a number ({e})") from None
    if len(rows) < 2:
        raise OpenSimDataError(f"{path}: {len(rows)} frames; at least 2 are needed")
    data = np.array(rows)
    try:
        t = check_time(data[:, 0])
    except TimeGridError as e:
        raise TimeGridError(f"{path}: {e}") from None
    frames = head.get("NumFrames")
    if frames is not None and int(float(frames)) != len(rows):
        warnings.warn(f"{path}: header says NumFrames={frames}; the file has {len(rows)} rows "
                      "(all read)", MarkerGapWarning, stacklevel=2)
    raw = data[:, 1:].reshape(len(rows), n, 3) * _UNITS[unit]
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
