"""Run a folder of demonstrations through :func:`~gdimitate.batch.job.process_file` in
parallel: a pool of local processes, or the workers of a Dask cluster.

Why Dask (``dask.distributed``) and not Ray: dask and distributed are pure Python from PyPI
(``pip install "dask[distributed]"``, 33 MB installed with their dependencies) with no daemon
to manage; the same :class:`distributed.Client` joins an existing scheduler
(``tcp://host:8786``) or a :class:`distributed.LocalCluster` of worker processes started here,
and each task is one function call with plain arguments (a path, a folder, frozen options).
Ray is a large compiled wheel that runs its own control store, a raylet per node, an object
store and a dashboard — more than a batch of independent files needs.

On a cluster, the workers must see the input and output folders at the same paths (a shared
file system): paths, not data, are sent to them.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fnmatch
import multiprocessing as mp
import os
import secrets
import shutil
import signal
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import BatchError, UnknownNameError
from .job import (
    GRF_SUFFIX,
    BatchOptions,
    BatchRow,
    load_robot,
    process_file,
    read_finished,
)
from .table import Progress, write_summary

__all__ = ["EXECUTORS", "INPUT_SUFFIXES", "BatchResult", "find_inputs", "run_batch"]

#: Where the files are processed: local worker processes, or a Dask cluster.
EXECUTORS = ("process", "dask")
#: Extensions of the demonstration files a batch picks up (``.osim`` models are not inputs
#: on their own: pass one as ``BatchOptions.demonstrator``).
INPUT_SUFFIXES = (".mot", ".sto", ".bvh", ".npz")

Task = tuple[str, str, BatchOptions, str]  # (path, out_dir, options, name in the table)


@dataclass(frozen=True)
class BatchResult:
    """A finished batch: ``rows`` (one :class:`BatchRow` per input, sorted by file name),
    the summary files ``summary_csv``/``summary_json``, ``wall_s`` [s] (the whole run,
    worker start included), ``executor``, ``workers`` (worker processes used)."""

    rows: tuple[BatchRow, ...]
    summary_csv: Path
    summary_json: Path
    wall_s: float
    executor: str
    workers: int

    def by_status(self, status: str) -> tuple[BatchRow, ...]:
        """The rows whose status is ``status`` (``"done"``, ``"skipped"``, ``"failed"``)."""
        return tuple(r for r in self.rows if r.status == status)

    @property
    def files_per_second(self) -> float:
        """Files adapted or failed in this run per second of :attr:`wall_s` (skipped files
        excluded)."""
        n = sum(r.status != "skipped" for r in self.rows)
        return n / self.wall_s if self.wall_s > 0 else 0.0


def find_inputs(input_dir: str | os.PathLike, pattern: str = "*") -> tuple[Path, ...]:
    """The demonstration files directly in ``input_dir`` matching the glob ``pattern``, with
    an extension in :data:`INPUT_SUFFIXES`, sorted by name; hidden files and ground-reaction-
    force files (``<stem>_grf.mot``/``.sto``, read with the demonstration ``<stem>.mot``)
    excluded.

    ``pattern`` is matched against the names of the folder's own entries (``fnmatch``), so
    it can never reach another folder.

    Raises :class:`BatchError` when the folder does not exist or holds no such file, or the
    pattern names a folder (``/``, ``..``)."""
    d = Path(input_dir).expanduser()
    if not d.is_dir():
        raise BatchError(f"input folder {d} does not exist or is not a folder")
    if not isinstance(pattern, str) or "/" in pattern or os.sep in pattern \
            or pattern in (".", ".."):
        raise BatchError(f"pattern {pattern!r} is not a file-name glob: give one without "
                         f"folder parts (e.g. '*.bvh'); the files are taken from {d} only")
    files = sorted(p for p in d.iterdir() if fnmatch.fnmatchcase(p.name, pattern)
                   and p.is_file() and not p.name.startswith(".")
                   and p.suffix.lower() in INPUT_SUFFIXES and not p.stem.endswith(GRF_SUFFIX))
    if not files:
        raise BatchError(f"no demonstration files matching {pattern!r} in {d} (extensions "
                         f"read: {', '.join(INPUT_SUFFIXES)})")
    return tuple(files)


def _failed(task: Task, why: str) -> BatchRow:
    path, _, options, name = task
    return BatchRow(file=name, output="", status="failed", method=options.method,
                    imitator=options.imitator, error=why)


# ------------------------------------------------------------------------- process pool
def _worker_init() -> None:
    # Ctrl-C reaches the whole foreground process group: the workers leave it to the parent,
    # which stops them (terminate) after cancelling what is queued.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # terminate() sends SIGTERM: end as an exception, so that a file being written is removed
    # (safety.atomic_write) instead of a half-written temporary being left in the output folder
    signal.signal(signal.SIGTERM, _exit_on_sigterm)


def _exit_on_sigterm(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)


def _pool_job(*task: Any) -> BatchRow:
    """:func:`process_file` in a pool worker that ends with it when SIGTERM stops it: the
    executor's worker loop catches a job's ``SystemExit`` and would take the next queued file
    (then be killed while writing it, its temporary left in the output folder); here the
    file's temporary is removed on the way out and the process exits."""
    try:
        return process_file(*task)
    except SystemExit as e:
        os._exit(e.code if isinstance(e.code, int) else 1)


#: The longest AF_UNIX socket path, in bytes (Linux's ``sun_path`` holds 108 with its NUL).
SUN_PATH_MAX = 107
#: What the forkserver's socket adds to the temporary folder: ``/pymp-XXXXXXXX/listener-XXXXXXXX``.
_SOCKET_TAIL = len("/pymp-XXXXXXXX/listener-XXXXXXXX")


def forkserver_fits(tmp: str | None = None) -> bool:
    """Whether multiprocessing's forkserver can bind its socket under the temporary folder
    ``tmp`` (default :func:`tempfile.gettempdir`, i.e. ``$TMPDIR``): Python before 3.14 puts
    it there and fails with ``OSError: AF_UNIX path too long`` when the folder's path exceeds
    about 75 bytes (CPython issue 132124), as a cluster's per-job ``$TMPDIR`` can."""
    return len(os.fsencode(tmp or tempfile.gettempdir())) + _SOCKET_TAIL <= SUN_PATH_MAX


def _context() -> mp.context.BaseContext:
    # forkserver: workers fork from a clean server that imported gdimitate once (not from this
    # process and its threads); spawn where there is none (Windows, macOS without it) or where
    # its socket's path would be too long (forkserver_fits): spawn talks through pipes.
    if "forkserver" in mp.get_all_start_methods() and forkserver_fits():
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(["gdimitate.batch.job"])
        return ctx
    return mp.get_context("spawn")


def _stop_pool(ex: ProcessPoolExecutor) -> None:
    """Cancel queued work and end the worker processes now (no orphans)."""
    stop = getattr(ex, "terminate_workers", None)  # Python >= 3.14
    if callable(stop):
        stop()
        return
    procs = list((getattr(ex, "_processes", None) or {}).values())
    for p in procs:
        with contextlib.suppress(Exception):
            p.terminate()
    for p in procs:
        p.join(5)
        if p.is_alive():
            p.kill()
            p.join(1)


def _run_process(tasks: Sequence[Task], workers: int, on_row: Callable[[BatchRow], None]
                 ) -> int:
    ex = ProcessPoolExecutor(max_workers=workers, mp_context=_context(),
                             initializer=_worker_init)
    finished = False
    try:
        futures = {ex.submit(_pool_job, *t): t for t in tasks}
        for f in as_completed(futures):
            try:
                row = f.result()
            except Exception as e:  # noqa: BLE001 — a worker that died (BrokenProcessPool)
                row = _failed(futures[f], f"{type(e).__name__}: {e} (a worker process died; "
                              "rerun the batch: finished files are skipped)")
            on_row(row)
        finished = True
    finally:
        if not finished:
            _stop_pool(ex)
        ex.shutdown(wait=True, cancel_futures=True)
    return workers


# ------------------------------------------------------------------------- Dask
def _dask():
    try:
        import distributed
    except ImportError:
        raise BatchError("executor 'dask' needs dask.distributed: pip install "
                         "'dask[distributed]'") from None
    return distributed


def _run_dask(tasks: Sequence[Task], workers: int, address: str | None,
              on_row: Callable[[BatchRow], None]) -> int:
    distributed = _dask()
    import dask

    # the scheduler's and workers' scratch space in a folder of this run's own, removed after
    # (Dask's default, dask-scratch-space/ in the temporary folder, outlives the batch)
    scratch = tempfile.mkdtemp(prefix="gdimitate-dask-")
    with dask.config.set({"temporary-directory": scratch}):
        try:
            return _on_cluster(distributed, tasks, workers, address, scratch, on_row)
        finally:
            shutil.rmtree(scratch, ignore_errors=True)


def _on_cluster(distributed, tasks: Sequence[Task], workers: int, address: str | None,
                scratch: str, on_row: Callable[[BatchRow], None]) -> int:
    cluster = None
    if address is None:  # a cluster of `workers` processes on this machine, for this batch
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                           processes=True, host="127.0.0.1",
                                           dashboard_address=None, local_directory=scratch)
        address = cluster.scheduler_address
    try:
        try:
            client = distributed.Client(address, timeout="20s")
        except (OSError, TimeoutError) as e:
            raise BatchError(f"cannot reach the Dask scheduler at {address!r}: {e} (start one "
                             "with `dask scheduler` and workers with `dask worker ADDRESS`, "
                             "or leave --address out for a local cluster)") from None
        finished = False
        futures = []
        try:
            n = len(client.scheduler_info().get("workers", {}))
            token = secrets.token_hex(4)
            futures = [client.submit(process_file, *t, key=f"gdimitate-batch-{token}-{i}",
                                     pure=False) for i, t in enumerate(tasks)]
            task_of = {f.key: t for f, t in zip(futures, tasks)}
            for f in distributed.as_completed(futures):
                try:
                    row = f.result()
                except Exception as e:  # noqa: BLE001 — KilledWorker, lost connection
                    row = _failed(task_of[f.key], f"{type(e).__name__}: {e}")
                on_row(row)
            finished = True
        finally:
            if not finished and futures:
                with contextlib.suppress(Exception):
                    client.cancel(futures)
            client.close()
    finally:
        if cluster is not None:
            cluster.close()
    return n


# ------------------------------------------------------------------------- the batch
def _absolute_models(options: BatchOptions) -> BatchOptions:
    """Model files (``.urdf``/``.osim``) named by absolute path, so that workers started
    elsewhere (another folder, a cluster node) find them."""
    def absolute(spec: str) -> str:
        if spec and Path(spec).suffix.lower() in (".urdf", ".osim") and Path(spec).is_file():
            return str(Path(spec).expanduser().resolve())
        return spec

    demonstrator = options.demonstrator
    return dataclasses.replace(options, imitator=absolute(options.imitator),
                               demonstrator=None if demonstrator is None
                               else absolute(demonstrator))


def run_batch(input_dir: str | os.PathLike, out_dir: str | os.PathLike,
              options: BatchOptions, *, workers: int = 1, executor: str = "process",
              address: str | None = None, pattern: str = "*",
              progress: bool = True) -> BatchResult:
    """Adapt every demonstration file in ``input_dir`` (:func:`find_inputs`) for
    ``options.imitator`` and write the results and a summary table into ``out_dir``.

    - ``workers``: worker processes (``"process"``, and a local Dask cluster);
    - ``executor``: ``"process"`` (a pool on this machine) or ``"dask"`` (``address``:
      ``"tcp://host:port"`` of a running Dask scheduler, whose workers are used; ``None``: a
      local cluster of ``workers`` processes, started and stopped here);
    - resumable: a file whose output exists, is complete and was made with the same options
      is skipped (its row is kept, status ``"skipped"``); a file that fails becomes a
      ``"failed"`` row and the others go on; an interrupt (Ctrl-C) stops the workers, writes
      the summary of what finished and propagates;
    - ``progress``: a progress bar on stderr.

    Writes ``<input>.<imitator>.<method>.npz`` (+ ``.json`` record) per file and
    ``summary.csv``/``summary.json``. Raises :class:`BatchError` (no inputs, an output folder
    that is the input folder, a scheduler out of reach), :class:`UnknownNameError` (executor;
    :class:`~gdimitate.errors.UnknownRobotError` for the imitator, before any work),
    :class:`~gdimitate.errors.OutputError` (an output folder that cannot be written, or that
    another gdimitate run holds: :func:`~gdimitate.safety.output_lock`).
    """
    from ..safety import check_count, output_lock, prepare_output_dir

    if executor not in EXECUTORS:
        raise UnknownNameError("executor", executor, EXECUTORS)
    workers = check_count("workers", workers, 1, 1024)
    if address is not None and executor != "dask":
        raise BatchError(f"address= is for executor 'dask' (a Dask scheduler); executor "
                         f"{executor!r} runs on this machine")
    if executor == "dask":
        _dask()
    options = _absolute_models(options)
    for spec in (options.imitator, options.demonstrator):
        if spec:  # a wrong name or model fails here, before any worker starts
            load_robot(spec)
    files = find_inputs(input_dir, pattern)
    out = prepare_output_dir(out_dir)
    if out.resolve() == Path(input_dir).expanduser().resolve():
        raise BatchError(f"the output folder {out} is the input folder: give another --out "
                         "(the results would be read as inputs next time)")
    with output_lock(out):  # one batch (or command) at a time in this folder
        start = time.perf_counter()
        rows: dict[str, BatchRow] = {}
        bar = Progress(len(files), enabled=progress)
        tasks: list[Task] = []
        for f in files:
            row = read_finished(f, out, options)
            if row is None:
                tasks.append((str(f), str(out), options, f.name))
            else:
                rows[f.name] = row
                bar.update(row)

        def on_row(row: BatchRow) -> None:
            rows[row.file] = row
            bar.update(row)

        used = workers
        meta: dict[str, Any] = {"executor": executor, "address": address,
                                "workers": workers, "options": options.key(),
                                "inputs": len(files)}
        complete = False
        try:
            if tasks and executor == "process":
                used = _run_process(tasks, min(workers, len(tasks)), on_row)
            elif tasks:
                used = _run_dask(tasks, workers, address, on_row)
            complete = True
        finally:
            wall = time.perf_counter() - start
            ordered = tuple(rows[f.name] for f in files if f.name in rows)
            meta.update(workers=used, wall_s=wall, complete=complete)
            csv_path, json_path = write_summary(ordered, out, meta)
    return BatchResult(rows=ordered, summary_csv=csv_path, summary_json=json_path,
                       wall_s=wall, executor=executor, workers=used)
