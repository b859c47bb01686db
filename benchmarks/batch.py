"""Batch throughput: the same N demonstration files through 1 and 2 workers, on the process
pool and on a local Dask cluster, in one run.

Run: ``python benchmarks/batch.py [--files 8] [--frames 40] [--method optimal]``. The files are
slices of the shipped sagittal walk (OpenSim subject01, 60 Hz) written to a temporary folder;
each configuration writes into a fresh output folder (nothing is skipped). "wall" is the whole
``run_batch`` call — worker start (fork server or Dask cluster, each worker importing
gdimitate), every file, the summary — so it is what a user waits for; "work" is the sum of the
files' own times measured in the workers (load, adapt, save). Prints one markdown table; the
load average is printed too, because other processes on the machine share its cores.
(Scenario code, not API.)
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from results import add_flag, recording

from gdimitate.batch import BatchOptions, run_batch
from gdimitate.io.gait import human_walk_path


def write_inputs(folder: Path, files: int, frames: int) -> None:
    """``files`` slices of ``frames`` rows of the shipped walk, start shifted by 5 rows each."""
    lines = human_walk_path().read_text().splitlines()
    end = next(i for i, line in enumerate(lines) if line.strip().lower() == "endheader")
    head, rows = lines[: end + 2], [line for line in lines[end + 2:] if line.strip()]
    if frames + 5 * (files - 1) > len(rows):
        raise SystemExit(f"{files} files of {frames} frames do not fit in {len(rows)} rows")
    for k in range(files):
        (folder / f"walk{k:02d}.mot").write_text(
            "\n".join(head + rows[5 * k: 5 * k + frames]) + "\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--files", type=int, default=8)
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--method", default="optimal", choices=["analytic", "copy", "optimal"])
    ap.add_argument("--imitator", default="hoap2")
    add_flag(ap)
    a = ap.parse_args()
    options = BatchOptions(a.imitator, method=a.method)
    with tempfile.TemporaryDirectory() as tmp:
        demos = Path(tmp) / "demos"
        demos.mkdir()
        write_inputs(demos, a.files, a.frames)
        load0 = os.getloadavg()[0]
        table = []
        for executor in ("process", "dask"):
            base = None
            for workers in (1, 2):
                res = run_batch(demos, Path(tmp) / f"{executor}{workers}", options,
                                workers=workers, executor=executor, progress=False)
                failed = res.by_status("failed")
                if failed:
                    raise SystemExit(f"{len(failed)} files failed: {failed[0].error}")
                rate = res.files_per_second
                base = base or rate
                work = sum(r.seconds or 0.0 for r in res.rows)
                table.append((executor, workers, len(res.rows), res.wall_s, work, rate,
                              rate / base))
        load1 = os.getloadavg()[0]
    print(f"{a.files} files x {a.frames} frames (60 Hz), method {a.method}, imitator "
          f"{a.imitator}; {os.cpu_count()} CPUs, load average {load0:.1f} -> {load1:.1f}\n")
    print("| executor | workers | files | wall [s] | work [s] | files/s | speed-up |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for ex, w, n, wall, work, rate, up in table:
        print(f"| {ex} | {w} | {n} | {wall:.1f} | {work:.1f} | {rate:.3f} | {up:.2f}x |")


if __name__ == "__main__":
    with recording("batch", "--results" in sys.argv[1:]):
        main()
