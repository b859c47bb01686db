"""``gdimitate batch``: every demonstration file of a folder adapted, in parallel
(:mod:`gdimitate.batch`)."""

from __future__ import annotations

import argparse

from ...assess.verdict import EXIT_NOT_FEASIBLE

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate batch``: every demonstration file of a folder adapted, in parallel."""
    ba = sub.add_parser("batch", help="adapt every demonstration file in a folder, in parallel "
                        "(process pool or a Dask cluster), resumable, with a summary table")
    ba.add_argument("input_dir", help="folder of demonstration files (.mot, .sto, .bvh, .npz)")
    ba.add_argument("--imitator", required=True,
                    help="imitator robot: a library name or a .urdf/.osim path")
    ba.add_argument("--out", required=True, help="output folder (results + summary.csv/json)")
    ba.add_argument("--method", default="optimal", choices=["analytic", "copy", "optimal"],
                    help="adaptor (default: %(default)s; analytic: planar sagittal inputs)")
    ba.add_argument("--force", default="segment",
                    choices=["segment", "com", "dynamics", "measured"])
    ba.add_argument("--simulate", action="store_true",
                    help="also replay each result in MuJoCo (optimal method)")
    ba.add_argument("--demonstrator", default=None,
                    help="demonstrator model for inputs that need one (full-body .mot: the .osim)")
    ba.add_argument("--workers", type=int, default=1,
                    help="worker processes (process pool, local Dask cluster; default: 1)")
    ba.add_argument("--executor", default="process", choices=["process", "dask"],
                    help="process: a pool on this machine; dask: a Dask cluster")
    ba.add_argument("--address", default=None,
                    help="Dask scheduler to join (tcp://host:8786; default: a local cluster)")
    ba.add_argument("--pattern", default="*", help="file-name glob in INPUT_DIR (default: *)")
    ba.add_argument("--quiet", action="store_true", help="no progress bar")
    ba.set_defaults(func=run)


def run(a: argparse.Namespace) -> int:
    from ...batch import BatchOptions, run_batch

    options = BatchOptions(a.imitator, method=a.method, force=a.force, simulate=a.simulate,
                           demonstrator=a.demonstrator)
    where = (f"the workers of Dask scheduler {a.address}" if a.address else
             f"a local Dask cluster of {a.workers} worker process(es)" if a.executor == "dask"
             else f"{a.workers} local worker process(es)")
    print(f"batch: {a.input_dir} → {a.out} ({options.method}, imitator {options.imitator}; "
          f"{where}) …", flush=True)
    res = run_batch(a.input_dir, a.out, options, workers=a.workers, executor=a.executor,
                    address=a.address, pattern=a.pattern, progress=not a.quiet)
    from ...batch.table import console_table

    print(console_table(res.rows))
    counts = ", ".join(f"{len(res.by_status(s))} {s}" for s in ("done", "skipped", "failed"))
    bad = [r.file for r in res.rows if r.status != "failed" and not r.ok]
    print(f"{counts}; {len(bad)} not feasible, with a goal unmet or fallen; {res.wall_s:.1f} s "
          f"on {res.workers} worker(s), {res.files_per_second:.2f} files/s\nwrote "
          f"{res.summary_csv}, {res.summary_json}")
    if res.by_status("failed"):
        return 1
    return EXIT_NOT_FEASIBLE if bad else 0
