"""The batch's summary table (CSV and JSON) and its progress bar."""

from __future__ import annotations

import csv
import io
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

from .job import BatchRow

__all__ = ["Progress", "write_summary"]


def write_summary(rows: Sequence[BatchRow], out_dir: str | Path,
                  meta: dict | None = None) -> tuple[Path, Path]:
    """Write ``summary.csv`` (one line per file, :meth:`BatchRow.columns`; empty cell =
    not applicable) and ``summary.json`` (``{"meta": ..., "rows": [...]}``) into ``out_dir``,
    each atomically; returns their paths."""
    from ..safety import atomic_write

    out = Path(out_dir)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=BatchRow.columns(), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: "" if v is None else v for k, v in r.to_dict().items()})
    paths = out / "summary.csv", out / "summary.json"
    with atomic_write(paths[0]) as tmp:
        tmp.write_text(buf.getvalue())
    with atomic_write(paths[1]) as tmp:
        tmp.write_text(json.dumps({"meta": meta or {}, "rows": [r.to_dict() for r in rows]},
                                  indent=1))
    return paths


class Progress:
    """A one-line progress bar on ``stream`` (stderr): files finished of ``total``, failures,
    files per second and the time left. On a terminal the line is redrawn; elsewhere (a log
    file, CI) one line is printed per finished file. ``enabled=False``: silent."""

    def __init__(self, total: int, *, stream: TextIO | None = None, enabled: bool = True,
                 width: int = 24):
        self.total, self.width, self.enabled = total, width, enabled
        self.stream = stream or sys.stderr
        self.done = self.failed = self.skipped = 0
        self.start = time.perf_counter()
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def update(self, row: BatchRow) -> None:
        """Count one finished row and redraw."""
        self.done += 1
        self.failed += row.status == "failed"
        self.skipped += row.status == "skipped"
        if not self.enabled:
            return
        el = time.perf_counter() - self.start
        worked = self.done - self.skipped
        rate = worked / el if el > 0 and worked else 0.0
        left = (self.total - self.done) / rate if rate else float("nan")
        fill = round(self.width * self.done / max(self.total, 1))
        line = (f"[{'#' * fill}{'.' * (self.width - fill)}] {self.done}/{self.total} files"
                f"  {self.failed} failed  {self.skipped} skipped  {rate:.2f} files/s"
                + (f"  ~{left:.0f} s left" if left == left else "")
                + f"  {row.status}: {row.file}")
        if self.tty:
            self.stream.write("\r\x1b[2K" + line + ("\n" if self.done == self.total else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
