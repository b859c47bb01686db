"""The OpenSim storage table (``.mot``/``.sto``): header, column names, numbers, time.

OpenSim writes two header styles, both read here: the 4.x one (``version=1``, ``nRows=…``,
``nColumns=…``, ``inDegrees=yes|no``, ``endheader``) and the older one of OpenSim 1–2 and many
lab exports (``name …``, ``datacolumns …``, ``datarows …``, ``range …``, ``endheader``; the
angle unit, where given, as a sentence such as ``Angles are in degrees.``). Columns are tab
separated (whitespace where a file has no tab); the first column must be ``time``.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import OpenSimDataError, OpenSimFormatError, ResourceLimitError, TimeGridError
from ...safety import MAX_TABLE_BYTES, read_text_bounded

__all__ = ["Table", "read_table"]


@dataclass(frozen=True)
class Table:
    """One OpenSim storage table: ``path``; ``header`` (lower-cased ``key=value`` pairs);
    ``header_text`` (the raw header lines); ``names`` (column names as written, ``time``
    first); ``data`` ``(T, n)``; ``in_degrees`` (``True``/``False`` from the header's
    ``inDegrees`` or an "Angles are in degrees/radians" sentence, ``None`` when the file
    does not say)."""

    path: Path
    header: Mapping[str, str]
    header_text: tuple[str, ...]
    names: tuple[str, ...]
    data: np.ndarray
    in_degrees: bool | None

    @property
    def t(self) -> np.ndarray:
        """Time ``(T,)`` [s]."""
        return self.data[:, 0]

    def column(self, name: str) -> np.ndarray:
        """Values ``(T,)`` of a column by its name as written."""
        return self.data[:, self.names.index(name)]


def _split(line: str) -> list[str]:
    parts = line.split("\t") if "\t" in line else line.split()
    return [p.strip() for p in parts]


_ENDHEADER = re.compile(r"(?:^|(?<=[\r\n]))[^\S\r\n]*endheader[^\S\r\n]*(?=\r|\n|\Z)",
                        re.IGNORECASE)
_LINE = re.compile(r"[^\r\n]*(?:\r\n|\r|\n)|[^\r\n]+\Z")


def iter_lines(text: str, start: int = 0, first: int = 1) -> Iterator[tuple[int, str]]:
    """``(line number, line)`` of ``text`` from character ``start`` (its line numbered
    ``first``), one at a time (a list of a large file's lines costs ~60 bytes a line), line
    ends ``\n``, ``\r\n`` or ``\r`` removed."""
    if text[start:start + 2] == "\r\n":
        start += 2
    elif text[start:start + 1] in ("\n", "\r"):
        start += 1
    for k, m in enumerate(_LINE.finditer(text, start), start=first):
        yield k, m.group().rstrip("\r\n")


def _in_degrees(header: Mapping[str, str], text: list[str], path: Path) -> bool | None:
    flag = header.get("indegrees")
    if flag is not None:
        v = flag.strip().lower()
        if v in ("yes", "true", "1"):
            return True
        if v in ("no", "false", "0"):
            return False
        raise OpenSimDataError(f"{path}: inDegrees={flag!r}; write inDegrees=yes or inDegrees=no")
    for line in text:
        m = re.search(r"angles\s+are\s+in\s+(degrees|radians)", line, re.IGNORECASE)
        if m:
            return m.group(1).lower() == "degrees"
    return None


def read_table(path: str | Path, *, min_rows: int = 2) -> Table:
    """Read an OpenSim ``.mot``/``.sto`` file → :class:`Table` (the package's one reader of
    OpenSim tables: coordinates, forces and :func:`gdimitate.io.gait.read_mot` read through it).

    ``min_rows``: the fewest data rows accepted (2: a motion needs a time step).
    Raises :class:`~gdimitate.errors.OpenSimFormatError` (not UTF-8 text, no column names,
    repeated column names: an :class:`~gdimitate.errors.OpenSimDataError` and a
    :class:`~gdimitate.errors.FileFormatError`), :class:`~gdimitate.errors.OpenSimDataError`
    (no such file, no ``endheader``, no ``time`` column, too few rows, rows of the wrong
    length, non-numeric or NaN/inf values — with the row and column),
    :class:`~gdimitate.errors.ResourceLimitError` (a file over
    :data:`~gdimitate.safety.MAX_TABLE_BYTES`) and :class:`~gdimitate.errors.TimeGridError`
    (time not strictly increasing).
    """
    path = Path(path)
    if not path.is_file():
        raise OpenSimDataError(f"no such OpenSim file: {path}")
    text = read_text_bounded(path, MAX_TABLE_BYTES, "OpenSim table", OpenSimFormatError,
                             ResourceLimitError)
    end = _ENDHEADER.search(text)
    if end is None:
        raise OpenSimDataError(f"{path}: no 'endheader' line; not an OpenSim .mot/.sto "
                               "file (its header must end with a line 'endheader')")
    head = text[:end.start()].splitlines()
    text_lines = [ln.strip() for ln in head]
    header = {}
    for ln in text_lines:
        if "=" in ln:
            k, _, v = ln.partition("=")
            header[k.strip().lower()] = v.strip()
    body = iter_lines(text, end.end(), len(head) + 2)
    first = next(((i, ln) for i, ln in body if ln.strip()), None)
    if first is None:
        raise OpenSimFormatError(f"{path}: no column names after 'endheader'")
    names = tuple(n for n in _split(first[1]) if n)
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise OpenSimFormatError(f"{path}: repeated column names {twice}")
    if not names or names[0].lower() != "time":
        raise OpenSimDataError(f"{path}: the first column must be 'time'; got "
                               f"{names[0] if names else 'nothing'!r}")
    # every row of n values takes at least 2n bytes: the table fits in 8 bytes per 2 of text
    lines = max(text.count("\n", end.end()), text.count("\r", end.end()))
    cap = min(lines + 2, (len(text) - end.end()) // (2 * len(names)) + 2)
    data = np.empty((cap, len(names)))
    rows = 0
    for lineno, ln in body:
        if not ln.strip():
            continue
        vals = [v for v in _split(ln) if v != ""]
        if len(vals) != len(names):
            raise OpenSimDataError(f"{path}, line {lineno}: {len(vals)} values for "
                                   f"{len(names)} columns; every row needs one value per column")
        try:
            data[rows] = [float(v) for v in vals]
        except ValueError as e:
            raise OpenSimDataError(f"{path}, line {lineno}: not a number ({e})") from None
        rows += 1
    del text
    if rows < max(min_rows, 1):
        raise OpenSimDataError(f"{path}: {rows} data rows; at least {max(min_rows, 1)} "
                               "are needed")
    data = data[:rows]
    bad = np.argwhere(~np.isfinite(data))
    if bad.size:
        r, c = bad[0]
        raise OpenSimDataError(
            f"{path}: column {names[c]!r} is NaN/inf at row {r} (t = {data[r, 0]:g} s) and "
            f"{len(bad) - 1} more cells; fill the gaps (e.g. interpolate) or cut the rows")
    steps = np.flatnonzero(np.diff(data[:, 0]) <= 0)
    if steps.size:
        i = int(steps[0])
        raise TimeGridError(f"{path}: time must be strictly increasing; row {i + 1} has "
                            f"t = {data[i + 1, 0]!r} after t = {data[i, 0]!r} "
                            f"({steps.size} such rows): remove duplicated or unsorted rows")
    return Table(path, header, tuple(text_lines), names, data,
                 _in_degrees(header, text_lines, path))
