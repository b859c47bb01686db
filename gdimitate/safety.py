"""Resource bounds and safe file handling, stated once and checked before any work starts.

Bounds (module constants, documented in ``docs/security.md``):

- URDF: at most :data:`MAX_URDF_BYTES` bytes, :data:`MAX_URDF_LINKS` links/joints and a
  kinematic chain at most :data:`MAX_URDF_DEPTH` joints deep (Pinocchio's parser crashes on a
  5000-deep chain and runs for minutes on 191 000 links; a 2000-link chain parses in 0.4 s);
  no ``<!DOCTYPE>``/``<!ENTITY>`` (entity expansion) in any encoding, no element nested deeper
  than :data:`MAX_XML_DEPTH` (:func:`parse_xml`).
- Motions: a median sample interval of at most :data:`MAX_SAMPLE_INTERVAL_S` and at least
  :data:`MIN_SAMPLE_INTERVAL_S`, a duration of at most :data:`MAX_MOTION_DURATION_S` (a time
  axis in milliseconds read as seconds is refused, not integrated for 2500 "seconds").
- NPZ files: at most :data:`MAX_NPZ_BYTES` unpacked, no pickled objects (:func:`open_npz`).
- Arrays built from user numbers (frame counts, frame rates, knot rates, bank shapes): at
  most :data:`MAX_ARRAY_BYTES` each, checked by :func:`check_array_size` before allocating.
- Optimal adaptor: a knot rate of at most :data:`MAX_KNOT_RATE`.
- Oscillators: at most :data:`MAX_HARMONICS` harmonics, :data:`MAX_CYCLES` teaching or free
  cycles, :data:`MAX_SIM_STEPS` integration steps per run and :data:`MAX_OUTPUT_SAMPLES`
  output frames, all checked before any array is allocated.

Files: :func:`atomic_write` writes through a temporary name in the target's folder and renames
it into place, so an interrupted run never leaves a half-written file; :func:`output_job` holds a
command's output folder (one run at a time) and undoes exactly the files a failed or interrupted
run wrote there — never a file that was there before or that another program wrote.
"""

from __future__ import annotations

import contextlib
import contextvars
import fcntl
import os
import secrets
import shutil
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np
from defusedxml import DefusedXmlException
from defusedxml import ElementTree as defused_et

from .errors import (
    FileFormatError,
    GdimitateError,
    InvalidInputError,
    OutputError,
    ResourceLimitError,
    URDFError,
    URDFLimitError,
)

__all__ = [
    "MAX_ARRAY_BYTES",
    "MAX_CYCLES",
    "MAX_HARMONICS",
    "MAX_KNOT_RATE",
    "MAX_MOTION_DURATION_S",
    "MAX_NPZ_BYTES",
    "MAX_OUTPUT_SAMPLES",
    "MAX_SAMPLE_INTERVAL_S",
    "MAX_SIM_STEPS",
    "MAX_TABLE_BYTES",
    "MAX_URDF_BYTES",
    "MAX_URDF_DEPTH",
    "MAX_URDF_LINKS",
    "MAX_XML_DEPTH",
    "MIN_SAMPLE_INTERVAL_S",
    "atomic_write",
    "check_array_size",
    "check_count",
    "check_positive",
    "check_steps",
    "check_time_axis",
    "check_urdf_bounds",
    "open_npz",
    "parse_xml",
    "prepare_output_dir",
    "read_text_bounded",
    "output_job",
    "output_lock",
]

#: Largest URDF file read [bytes] (example-robot-data's largest, TIAGo dual, is 0.2 MB).
MAX_URDF_BYTES = 16 * 2**20
#: Most links (and most joints) in a URDF (example-robot-data's largest has 130).
MAX_URDF_LINKS = 2000
#: Deepest kinematic chain, in joints from the root link (example-robot-data's deepest: 21).
MAX_URDF_DEPTH = 1000
#: Most degrees of freedom of a URDF's joints (revolute, continuous, prismatic: 1; planar: 3;
#: floating: 6; the free-flyer the loader adds not counted). Pinocchio's ``pin.Data``, which
#: every loaded robot builds, holds eight nv × nv × nv second-derivative tensors: about
#: 64·nv³ bytes. Measured through ``Robot.from_urdf``: nv = 212 → 0.70 GB peak RSS, 0.6 s;
#: 312 → 2.0 GB, 1.8 s; 412 → 4.5 GB, 8.7 s (a 500-joint chain: 5.2 GB and MemoryError).
#: 250 (nv 256 with the free-flyer: 1.2 GB) stays within 2 GB; example-robot-data's most:
#: 101 (TIAGo dual).
MAX_URDF_DOF = 250
#: Most ``<visual>`` plus ``<collision>`` elements of a URDF. Pinocchio's
#: ``buildGeomFromUrdfString`` takes time cubic in their number: 1000 boxes 1.0–1.6 s, 2000:
#: 8–14 s, 4000: 82 s (20 000 did not load in 150 s); example-robot-data's most: 223.
MAX_URDF_GEOMETRIES = 1000
#: Largest median time step of a motion [s]: slower than 1 Hz is not a sampled motion (a time
#: axis in milliseconds read as seconds gives 16.7 "s" for 60 Hz data).
MAX_SAMPLE_INTERVAL_S = 1.0
#: Smallest median time step of a motion [s] (100 kHz).
MIN_SAMPLE_INTERVAL_S = 1e-5
#: Longest motion, and longest replay [s].
MAX_MOTION_DURATION_S = 3600.0
#: Most harmonics of a Fourier teaching signal.
MAX_HARMONICS = 64
#: Most teaching cycles, and most free-running cycles, of the frequency adaptation.
MAX_CYCLES = 1000
#: Most fixed-step integration steps of one oscillator run (about 0.3 GB of states and
#: read-out features for the 7-joint sagittal network).
MAX_SIM_STEPS = 1_000_000
#: Most frames of a generated (replayed) motion.
MAX_OUTPUT_SAMPLES = 1_000_000
#: Largest array built from numbers a user gives (frames × channels of a BVH file, frames of
#: an export at a frame rate, knots of an adaptation, a bank's shape) [bytes]: 1 GiB.
MAX_ARRAY_BYTES = 2**30
#: Highest knot rate of the optimal adaptor [knots/s] (its default is 50; motion capture
#: rarely exceeds 1 kHz, and each knot is a whole-body state in one nonlinear program).
MAX_KNOT_RATE = 1000.0
#: Deepest element nesting of an XML file read (URDF, ``.osim``, ExternalLoads ``.xml``):
#: OpenSim models nest about 12 deep, URDFs 4.
MAX_XML_DEPTH = 256
#: Largest text table (``.mot``/``.sto``, ``.trc``) read [bytes]: reading needs at most 5.4
#: (``.mot``) and 8.4 (``.trc``) bytes of memory per byte of file (measured, one-digit
#: numbers; 2–4 for lab files), so 192 MiB stays under 2 GB.
MAX_TABLE_BYTES = 192 * 2**20
#: Largest unpacked content of an ``.npz`` file read [bytes] (a compressed archive can
#: unpack to far more than its size on disk).
MAX_NPZ_BYTES = 2 * 2**30
#: Largest BVH file read [bytes]. ``read_bvh`` peaks at about 5 bytes of memory per byte of
#: a motion-capture file (CMU's clip repeated: 80 MB → 0.57 GB, 11 s) and 16 per byte of the
#: densest text (one-digit values: 60 MB → 1.14 GB, 33 s; a 300 MB file hit MemoryError at
#: 5 GB): 64 MiB (12 minutes of a 96-channel skeleton at 120 Hz) stays within 1.2 GB.
MAX_BVH_BYTES = 64 * 2**20


# ---------------------------------------------------------------------------------- numbers
def check_positive(name: str, value: object, *, upper: float | None = None,
                   zero: bool = False,
                   error: type[GdimitateError] = InvalidInputError) -> float:
    """``value`` as a float if it is a finite real number > 0 (≥ 0 with ``zero=True``);
    else ``error`` naming ``name``. Above ``upper``: :class:`ResourceLimitError` stating the
    limit."""
    bad = isinstance(value, bool | str | bytes) or np.iscomplexobj(cast(Any, value))
    try:
        v = float(cast(Any, value))  # anything float() takes; the rest is refused below
    except (TypeError, ValueError):
        bad = True
    if bad:
        raise error(f"{name} must be a real number; got {value!r}")
    if not np.isfinite(v) or v < 0 or (v == 0 and not zero):
        raise error(f"{name} must be a finite number {'>=' if zero else '>'} 0; got {value!r}")
    if upper is not None and v > upper:
        raise ResourceLimitError(f"{name} = {v:g} exceeds the limit {upper:g}")
    return v


def check_count(name: str, value: object, lo: int, hi: int,
                error: type[GdimitateError] = InvalidInputError) -> int:
    """``value`` as an int if it is an integer in ``[lo, hi]``: else ``error`` (not an
    integer, below ``lo``) or :class:`ResourceLimitError` (above ``hi``) naming it."""
    integral = isinstance(value, int | np.integer) or (
        isinstance(value, float | np.floating) and float(value).is_integer())
    if isinstance(value, bool) or not integral:
        raise error(f"{name} must be an integer; got {value!r}")
    v = int(cast(Any, value))  # an integral int, numpy integer or float (checked above)
    if v < lo:
        raise error(f"{name} must be >= {lo}; got {v}")
    if v > hi:
        raise ResourceLimitError(f"{name} = {v} exceeds the limit {hi}")
    return v


def check_array_size(what: str, shape: Sequence[float], itemsize: int = 8) -> tuple[int, ...]:
    """``shape`` as ints if an array of that shape and ``itemsize`` [bytes] fits in
    :data:`MAX_ARRAY_BYTES`; else :class:`ResourceLimitError` naming ``what``, its size and the
    limit. Call it before allocating any array whose size comes from a user's numbers (the
    product is computed in Python integers: no overflow; NaN/inf/negative sizes are refused)."""
    dims = []
    for d in shape:
        try:
            x = float(d)
        except (TypeError, ValueError):
            raise InvalidInputError(f"{what}: size {d!r} is not a number") from None
        if not np.isfinite(x):
            raise ResourceLimitError(f"{what}: size {d!r} is not finite")
        if x < 0:
            raise InvalidInputError(f"{what}: size {d!r} is negative")
        dims.append(int(np.ceil(x)))
    total = itemsize
    for d in dims:
        total *= d
    if total > MAX_ARRAY_BYTES:
        shown = " × ".join(f"{d:,}" for d in dims)
        raise ResourceLimitError(
            f"{what} would need an array of {shown} values ({total / 2**30:.3g} GiB); the limit "
            f"is {MAX_ARRAY_BYTES / 2**30:g} GiB (gdimitate.safety.MAX_ARRAY_BYTES): check the "
            "frame count, rate or shape you gave")
    return tuple(dims)


def check_steps(steps: float, what: str) -> int:
    """Refuse a run of more than :data:`MAX_SIM_STEPS` integration steps (before allocating)."""
    if not np.isfinite(steps) or steps > MAX_SIM_STEPS:
        raise ResourceLimitError(
            f"{what} needs {steps:.3g} integration steps; the limit is {MAX_SIM_STEPS:,} "
            "(check the time axis's unit, the frequency, the cycle counts and dt)")
    return int(steps)


def check_time_axis(t: np.ndarray, what: str = "motion") -> None:
    """Refuse a time axis ``t (T,)`` [s] whose median step or duration is implausible
    (see :data:`MAX_SAMPLE_INTERVAL_S`, :data:`MIN_SAMPLE_INTERVAL_S`,
    :data:`MAX_MOTION_DURATION_S`)."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        return
    dt = float(np.median(np.diff(t)))
    span = float(t[-1] - t[0])
    if dt > MAX_SAMPLE_INTERVAL_S:
        raise ResourceLimitError(
            f"{what}: median time step {dt:g} s ({1 / dt:.3g} Hz) exceeds "
            f"{MAX_SAMPLE_INTERVAL_S:g} s; is the time axis in milliseconds? (divide by 1000)")
    if dt < MIN_SAMPLE_INTERVAL_S:
        raise ResourceLimitError(
            f"{what}: median time step {dt:g} s is below {MIN_SAMPLE_INTERVAL_S:g} s; is the "
            "time axis in the wrong unit?")
    if span > MAX_MOTION_DURATION_S:
        raise ResourceLimitError(
            f"{what}: duration {span:g} s exceeds the limit {MAX_MOTION_DURATION_S:g} s")


# ---------------------------------------------------------------------------------- XML
def read_text_bounded(path: Path, max_bytes: int, what: str,
                      error: type[GdimitateError] = URDFError,
                      limit_error: type[GdimitateError] = URDFLimitError) -> str:
    """The UTF-8 text of ``path`` if it holds at most ``max_bytes`` bytes (checked before
    reading); else ``limit_error`` (too large) or ``error`` (unreadable, not UTF-8) naming the
    file."""
    try:
        size = path.stat().st_size
    except OSError as e:
        raise error(f"cannot read {what} {path}: {e.strerror or e}") from None
    if size > max_bytes:
        raise limit_error(f"{what} {path} has {size:,} bytes; the limit is {max_bytes:,}")
    try:
        data = path.read_bytes()
    except OSError as e:
        raise error(f"cannot read {what} {path}: {e.strerror or e}") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise error(f"{what} {path} is not UTF-8 text (byte {e.start}); is it a binary "
                    "file?") from None


def parse_xml(text: str | bytes, source: object, error: type[GdimitateError] = URDFError
              ) -> ET.Element:
    """Parse XML ``text`` (from ``source``, for messages; bytes in any encoding the document
    declares, UTF-16 included) with ``defusedxml``, the hardened front of the standard
    library's parser: document type declarations, entities and external references are
    refused as the parser meets them, whatever the encoding (a scan of the raw bytes for
    ``<!DOCTYPE`` misses them in UTF-16), and elements nested deeper than
    :data:`MAX_XML_DEPTH` are refused (code that walks the tree recursively would hit Python's
    recursion limit)."""
    try:
        root = defused_et.fromstring(text, forbid_dtd=True, forbid_entities=True,
                                     forbid_external=True)
    except DefusedXmlException as e:
        raise error(f"cannot read {source}: <!DOCTYPE>/<!ENTITY> declarations and external "
                    f"references are not accepted ({type(e).__name__}); remove them (URDF "
                    "and OpenSim files need none)") from None
    except ET.ParseError as e:
        raise error(f"cannot read {source}: malformed XML ({e})") from None
    stack = [(root, 1)]
    while stack:
        el, depth = stack.pop()
        if depth > MAX_XML_DEPTH:
            raise error(f"cannot read {source}: <{el.tag}> is nested {depth} elements deep; "
                        f"the limit is {MAX_XML_DEPTH} (URDF and OpenSim files nest fewer "
                        "than 20)")
        stack.extend((c, depth + 1) for c in el)
    return root


def check_urdf_bounds(root: ET.Element, source: object) -> None:
    """Refuse a URDF tree with more than :data:`MAX_URDF_LINKS` links or joints, or a chain
    deeper than :data:`MAX_URDF_DEPTH` joints, or a joint graph with a loop — before Pinocchio
    parses it."""
    if root.tag != "robot":
        raise URDFError(f"{source}: the root element is <{root.tag}>, not <robot>")
    links = root.findall("link")
    joints = root.findall("joint")
    for kind, items in (("links", links), ("joints", joints)):
        if len(items) > MAX_URDF_LINKS:
            raise URDFLimitError(f"{source} has {len(items):,} {kind}; the limit is "
                                 f"{MAX_URDF_LINKS:,}")
    parent: dict[str, str] = {}
    for j in joints:
        c, p = j.find("child"), j.find("parent")
        if c is not None and p is not None and c.get("link") and p.get("link"):
            parent[str(c.get("link"))] = str(p.get("link"))
    depth: dict[str, int] = {}
    for start in parent:
        chain, link, seen = [], start, set()
        while link in parent and link not in depth:
            if link in seen:
                raise URDFError(f"{source}: the joints form a loop through link {link!r}")
            seen.add(link)
            chain.append(link)
            link = parent[link]
        d = depth.get(link, 0)
        for lk in reversed(chain):
            d += 1
            depth[lk] = d
        if d > MAX_URDF_DEPTH:
            raise URDFLimitError(f"{source}: link {start!r} is {d:,} joints deep; the limit is "
                                 f"{MAX_URDF_DEPTH:,}")


# ---------------------------------------------------------------------------------- files
def prepare_output_dir(path: str | os.PathLike) -> Path:
    """Create the output folder ``path`` (and parents) if needed and check that files can be
    created in it; :class:`OutputError` says why not (a file of that name, no permission)."""
    p = Path(path).expanduser()
    if p.exists() and not p.is_dir():
        raise OutputError(f"output folder {p} is an existing file; give a folder name")
    try:
        p.mkdir(parents=True, exist_ok=True)
        probe = p / f".gdimitate-write-test-{secrets.token_hex(4)}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as e:
        raise OutputError(f"cannot write to output folder {p}: {e.strerror or e}") from None
    return p


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike) -> Iterator[Path]:
    """Write a file all at once: yields a temporary path in the same folder (same suffix, so
    ``np.savez``/``savefig`` keep their format), renamed to ``path`` when the block ends
    normally and deleted when it raises (Ctrl-C included). ``path`` keeps its old content until
    the rename. Inside an :func:`output_job` on ``path``'s folder the write is recorded, so
    that a failure of the job removes this file (or puts back the one it replaced) and only
    this one.

    Example::

        with atomic_write(out / "report.json") as tmp:
            tmp.write_text(json.dumps(report))

    Raises:
        OutputError: ``path`` is a folder, its folder does not exist, or writing fails.
    """
    p = Path(path).expanduser()
    if p.is_dir():
        raise OutputError(f"cannot write {p}: it is a folder; give a file name")
    if not p.parent.is_dir():
        raise OutputError(f"cannot write {p}: folder {p.parent} does not exist")
    tmp = p.with_name(f".{p.name}.{secrets.token_hex(4)}.tmp{p.suffix}")
    try:  # created with the umask's permissions (mkstemp would make it 0600)
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    except OSError as e:
        raise OutputError(f"cannot write {p}: {e.strerror or e}") from None
    try:
        yield tmp
        job = _JOB.get()
        if job is not None and job.covers(p):
            job.replace(tmp, p)
        else:
            os.replace(tmp, p)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {p}: {e.strerror or e}") from e
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def save_figure(fig, path: str | os.PathLike | None):
    """``fig`` (a matplotlib figure) laid out tight and, where ``path`` is given, written there
    atomically (:func:`atomic_write`; PNG at 110 dpi for a ``.png``) and closed; returns
    ``fig``."""
    fig.tight_layout()
    if path is not None:
        import matplotlib.pyplot as plt

        with atomic_write(path) as tmp:
            fig.savefig(tmp, dpi=110)
        plt.close(fig)
    return fig


Stamp = tuple[int, int, int]
LOCK_NAME = ".gdimitate.lock"
"""The lock file an :func:`output_job` holds in its folder (``flock``; it names the run's
process id)."""


def _stamp(p: Path) -> Stamp | None:
    try:
        st = p.stat()
    except OSError:
        return None
    return (st.st_ino, st.st_mtime_ns, st.st_size)


class _Job:
    """The files one :func:`output_job` wrote (through :func:`atomic_write`): those it
    created, and those it replaced with the hard link that keeps their old content."""

    def __init__(self, root: Path):
        self.root = root.resolve()
        self.created: dict[Path, Stamp] = {}
        self.replaced: dict[Path, tuple[Path, Stamp]] = {}

    def covers(self, p: Path) -> bool:
        return p.parent.resolve().is_relative_to(self.root)

    def replace(self, tmp: Path, p: Path) -> None:
        """Rename ``tmp`` to ``p``, keeping what ``p`` held before the job first wrote it."""
        if p not in self.created and p not in self.replaced and p.exists():
            backup = p.with_name(f".{p.name}.{secrets.token_hex(4)}.before")
            try:
                os.link(p, backup)  # the old content stays reachable through the new name
            except OSError:
                shutil.copy2(p, backup)  # a file system without hard links
            os.replace(tmp, p)
            self.replaced[p] = (backup, cast(Stamp, _stamp(p)))
            return
        os.replace(tmp, p)
        stamp = cast(Stamp, _stamp(p))
        if p in self.replaced:
            self.replaced[p] = (self.replaced[p][0], stamp)
        else:
            self.created[p] = stamp

    def undo(self) -> None:
        """Remove what the job created and put back what it replaced, where nobody changed
        the file since the job wrote it (a file changed by another program stays)."""
        for p, stamp in self.created.items():
            if _stamp(p) == stamp:
                p.unlink(missing_ok=True)
        for p, (backup, stamp) in self.replaced.items():
            if _stamp(p) == stamp:
                os.replace(backup, p)
            else:
                backup.unlink(missing_ok=True)

    def commit(self) -> None:
        for backup, _ in self.replaced.values():
            backup.unlink(missing_ok=True)


_JOB: contextvars.ContextVar[_Job | None] = contextvars.ContextVar("gdimitate_job",
                                                                    default=None)


@contextlib.contextmanager
def output_lock(folder: str | os.PathLike) -> Iterator[Path]:
    """Hold ``folder``'s lock (:data:`LOCK_NAME`, an advisory ``flock`` that the system
    releases when the process ends, even by SIGKILL) for the block: a second gdimitate run on
    the same output folder is refused with :class:`OutputError` instead of mixing its files
    with this one's. ``folder`` must exist."""
    p = Path(folder).expanduser()
    lock = p / LOCK_NAME
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as e:
            raise OutputError(f"cannot write to output folder {p}: {e.strerror or e}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            owner = os.read(fd, 64).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise OutputError(f"output folder {p} is in use by another gdimitate run "
                              f"(process {owner}); wait for it to end or give another "
                              "output folder") from None
        if _stamp(lock) is not None and os.fstat(fd).st_ino == cast(Stamp, _stamp(lock))[0]:
            break  # not a lock file its last holder removed while we opened it
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        yield p
    finally:
        lock.unlink(missing_ok=True)
        os.close(fd)


@contextlib.contextmanager
def output_job(folder: str | os.PathLike) -> Iterator[Path]:
    """A command's writes into its output folder as one job: creates ``folder`` (and its
    parents) if needed, holds its :func:`output_lock`, and records every file the block
    writes there through :func:`atomic_write`. When the block raises (Ctrl-C and SIGTERM
    included), exactly those files are undone — the ones it created removed, the ones it
    replaced put back — unless another program changed them since; the folders it created are
    removed if left empty; nothing else is touched (files that were there, files others write
    meanwhile). Yields the folder."""
    p = Path(folder).expanduser()
    made = [p]  # p and the parents mkdir(parents=True) creates
    while not made[-1].parent.exists() and made[-1].parent != made[-1]:
        made.append(made[-1].parent)
    made = [d for d in made if not d.exists()]
    prepare_output_dir(p)
    job = _Job(p)
    try:
        with output_lock(p):
            before = {d for d in p.rglob("*") if d.is_dir()}
            token = _JOB.set(job)
            try:
                yield p
            except BaseException:
                job.undo()
                for d in sorted((d for d in p.rglob("*") if d.is_dir() and d not in before),
                                reverse=True):
                    with contextlib.suppress(OSError):
                        d.rmdir()
                raise
            finally:
                _JOB.reset(token)
            job.commit()
    except BaseException:
        for d in made:  # deepest first; a folder that is not empty stays
            with contextlib.suppress(OSError):
                d.rmdir()
        raise


def _looks_like(head: bytes) -> str:
    if head.startswith(b"\x93NUMPY"):
        return "a single NumPy .npy array"
    if head.startswith(b"\x80"):
        return "a Python pickle"
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError:
        return "binary data"
    return "text (a CSV or other table?)" if text.isprintable() or "\n" in text else "binary data"


def _check_member(p: Path, zf: zipfile.ZipFile, info: zipfile.ZipInfo) -> None:
    """Refuse an archive member whose ``.npy`` header promises more data than the member
    holds (NumPy would allocate what the header says: a shape of (10¹¹,) asks for 745 GiB)."""
    if not info.filename.endswith(".npy"):
        return
    with zf.open(info) as f:
        try:
            version = np.lib.format.read_magic(f)
            read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                    else np.lib.format.read_array_header_2_0)
            shape, _, dtype = read(f)
        except (ValueError, SyntaxError, TypeError, OverflowError) as e:
            raise FileFormatError(f"{p}: member {info.filename} has no valid .npy header "
                                  f"({e})") from None
        header = f.tell()
    if dtype.hasobject:
        return  # refused when read (no pickled objects)
    need = int(np.prod(shape, dtype=object)) * dtype.itemsize
    if need > info.file_size - header:
        raise FileFormatError(f"{p}: member {info.filename} claims shape {shape} of {dtype} "
                              f"({need:,} bytes) but holds {info.file_size - header:,}; the "
                              "archive is truncated or forged")


@contextlib.contextmanager
def open_npz(path: str | os.PathLike, required: Sequence[str] = ()
             ) -> Iterator[np.lib.npyio.NpzFile]:
    """Open an ``.npz`` archive for reading (no pickled objects) and check that it holds the
    ``required`` keys; errors while the block reads it become :class:`FileFormatError` naming
    the file (gdimitate's own errors pass through).

    Raises:
        FileFormatError: no such file, an empty file, not a zip archive (a CSV renamed
            ``.npz``, a ``.npy``), a corrupt archive, more than :data:`MAX_NPZ_BYTES`
            unpacked, pickled object arrays, missing keys.
    """
    p = Path(path).expanduser()
    if not p.is_file():
        raise FileFormatError(f"no such NPZ file: {p}")
    try:
        with open(p, "rb") as f:
            head = f.read(64)
        if not head:
            raise FileFormatError(f"{p} is empty (0 bytes); not an NPZ archive")
        if not head.startswith(b"PK"):
            raise FileFormatError(f"{p} is not an NPZ archive (a zip of .npy arrays, as written "
                                  f"by Motion.to_npz); it looks like {_looks_like(head)}")
        with zipfile.ZipFile(p) as zf:
            unpacked = sum(i.file_size for i in zf.infolist())
            if unpacked > MAX_NPZ_BYTES:
                raise FileFormatError(f"{p} unpacks to {unpacked:,} bytes; the limit is "
                                      f"{MAX_NPZ_BYTES:,}")
            for info in zf.infolist():
                _check_member(p, zf, info)
        z = np.load(p, allow_pickle=False)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as e:
        if isinstance(e, GdimitateError):
            raise
        raise FileFormatError(f"{p} is not a readable NPZ archive: {e}") from None
    with z:
        missing = [k for k in required if k not in z.files]
        if missing:
            raise FileFormatError(f"{p} lacks the keys {missing} (it has {sorted(z.files)}); "
                                  "was it written by Motion.to_npz?")
        try:
            yield z
        except GdimitateError:
            raise
        except ValueError as e:
            if "pickle" in str(e):
                raise FileFormatError(f"{p} holds pickled Python objects, which are not loaded "
                                      "(only plain arrays are)") from None
            raise FileFormatError(f"{p}: {e}") from None
        except (TypeError, KeyError, IndexError, zipfile.BadZipFile, OSError, EOFError) as e:
            raise FileFormatError(f"{p}: malformed content ({type(e).__name__}: {e})") from None
