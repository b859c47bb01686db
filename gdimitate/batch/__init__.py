"""Batches: every demonstration file in a folder, adapted in parallel — on this machine (a
process pool) or on a Dask cluster — resumable, with a summary table.

::

    from gdimitate.batch import BatchOptions, run_batch
    res = run_batch("demos/", "out/", BatchOptions("hoap2", method="analytic"), workers=2)
    res.by_status("failed"), res.summary_csv, res.files_per_second

The command line: ``gdimitate batch INPUT_DIR --imitator ROBOT --out OUT_DIR [--workers N]
[--method optimal|analytic|copy] [--simulate] [--executor process|dask --address tcp://...]``.
Modules: :mod:`~.job` (one file: load, adapt, simulate, save, its :class:`BatchRow`),
:mod:`~.run` (the executors and :func:`run_batch`), :mod:`~.table` (summary CSV/JSON,
progress bar).
"""

from .job import STATUSES, BatchOptions, BatchRow, output_paths, process_file, read_finished
from .run import EXECUTORS, INPUT_SUFFIXES, BatchResult, find_inputs, run_batch
from .table import Progress, write_summary

__all__ = [
    "EXECUTORS",
    "INPUT_SUFFIXES",
    "STATUSES",
    "BatchOptions",
    "BatchResult",
    "BatchRow",
    "Progress",
    "find_inputs",
    "output_paths",
    "process_file",
    "read_finished",
    "run_batch",
    "write_summary",
]
