"""The batch's summary table (CSV and JSON) and its progress bar."""

from __future__ import annotations

import csv
import io
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

from .job import BatchRow

__all__ = ["Progress", "console_table", "write_summary"]


def console_table(rows: Sequence[BatchRow]) -> str:
    """The console's table: per file its status, the judge's verdict (``feasible``), whether
    every goal was met, the physics check's outcome (``walked`` / ``FELL at … s``), the wall
    time and the unmet goals or the error."""
    lines = [f"{'file':<32} {'status':<8} {'feasible':<8} {'goals':<8} {'simulation':<16} "
             f"{'seconds':>8}  unmet / error"]
    for r in rows:
        feas = "" if r.feasible is None else ("yes" if r.feasible else "NO")
        goals = "" if r.goals_unmet is None else ("UNMET" if r.goals_unmet else "met")
        sim = "" if r.sim_fell is None else (
            f"FELL at {r.sim_fall_time_s:.2f} s" if r.sim_fell and r.sim_fall_time_s is not None
            else "FELL" if r.sim_fell else "walked")
        secs = "" if r.seconds is None else f"{r.seconds:.2f}"
        lines.append(f"{r.file:<32} {r.status:<8} {feas:<8} {goals:<8} {sim:<16} {secs:>8}  "
                     f"{(r.error or r.goals_unmet or '')[:100]}")
    return "\n".join(lines)


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
    """The batch's progress bar on ``stream`` (stderr), drawn by ``tqdm``: files finished of
    ``total``, failures and skips, files per second and the time left; on a terminal the line
    is redrawn, elsewhere (a log file, CI) tqdm prints it at intervals. ``enabled=False``:
    silent."""

    def __init__(self, total: int, *, stream: TextIO | None = None, enabled: bool = True):
        from tqdm import tqdm

        self.total = total
        self.done = self.failed = self.skipped = 0
        self.bar = tqdm(total=total, unit="file", file=stream or sys.stderr,
                        disable=not enabled, dynamic_ncols=True, mininterval=0.5)

    def update(self, row: BatchRow) -> None:
        """Count one finished row and redraw."""
        self.done += 1
        self.failed += row.status == "failed"
        self.skipped += row.status == "skipped"
        self.bar.set_postfix_str(f"{self.failed} failed, {self.skipped} skipped, "
                                 f"{row.status}: {Path(str(row.file)).name}", refresh=False)
        self.bar.update(1)
        if self.done == self.total:
            self.bar.close()
