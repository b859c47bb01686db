"""Resource bounds and safe file handling, stated once and checked before any work starts.

Bounds (module constants, documented in ``docs/security.md``):

- URDF: at most :data:`MAX_URDF_BYTES` bytes, :data:`MAX_URDF_LINKS` links/joints and a
  kinematic chain at most :data:`MAX_URDF_DEPTH` joints deep (Pinocchio's parser crashes on a
  5000-deep chain and runs for minutes on 191 000 links; a 2000-link chain parses in 0.4 s);
  no ``<!DOCTYPE>``/``<!ENTITY>`` (entity expansion).
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
it into place, so an interrupted run never leaves a half-written file; :func:`removed_on_failure`
undoes every file a failed or interrupted multi-file job wrote into its output folder.
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np

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
    "removed_on_failure",
]

#: Largest URDF file read [bytes] (example-robot-data's largest, TIAGo dual, is 0.2 MB).
MAX_URDF_BYTES = 16 * 2**20
#: Most links (and most joints) in a URDF (example-robot-data's largest has 130).
MAX_URDF_LINKS = 2000
#: Deepest kinematic chain, in joints from the root link (example-robot-data's deepest: 21).
MAX_URDF_DEPTH = 1000
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
#: Largest text table (``.mot``/``.sto``) read [bytes].
MAX_TABLE_BYTES = 512 * 2**20
#: Largest unpacked content of an ``.npz`` file read [bytes] (a compressed archive can
#: unpack to far more than its size on disk).
MAX_NPZ_BYTES = 2 * 2**30


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


_DTD = re.compile(r"<!\s*(DOCTYPE|ENTITY)", re.IGNORECASE)


def parse_xml(text: str, source: object, error: type[GdimitateError] = URDFError
              ) -> ET.Element:
    """Parse XML ``text`` (from ``source``, for messages) with the standard library, refusing
    document type declarations and entities (no entity expansion, no external references)."""
    if _DTD.search(text):
        raise error(f"cannot read {source}: <!DOCTYPE>/<!ENTITY> declarations are not "
                    "accepted")
    try:
        return ET.fromstring(text)
    except ET.ParseError as e:
        raise error(f"cannot read {source}: malformed XML ({e})") from None


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
    the rename.

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
        os.replace(tmp, p)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {p}: {e.strerror or e}") from e
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _snapshot(folder: Path) -> dict[Path, tuple[int, int]]:
    out = {}
    for f in folder.rglob("*") if folder.is_dir() else ():
        with contextlib.suppress(OSError):
            if f.is_file():
                st = f.stat()
                out[f] = (st.st_mtime_ns, st.st_size)
    return out


@contextlib.contextmanager
def removed_on_failure(folder: str | os.PathLike) -> Iterator[Path]:
    """Undo a multi-file job's output if it fails or is interrupted: on any exception
    (``KeyboardInterrupt`` included) every file under ``folder`` that the block created or
    changed is deleted (and ``folder`` too if the block created it and it is left empty, and
    the parent folders created on the way when left empty), then the exception propagates.
    Files that were there before and are unchanged stay."""
    p = Path(folder).expanduser()
    existed = p.is_dir()
    made = [p]  # p and the parents the block may create (mkdir(parents=True))
    while not made[-1].parent.exists() and made[-1].parent != made[-1]:
        made.append(made[-1].parent)
    before = _snapshot(p)
    try:
        yield p
    except BaseException:
        for f, stamp in _snapshot(p).items():
            if before.get(f) != stamp:
                f.unlink(missing_ok=True)
        if not existed:
            for d in sorted((d for d in p.rglob("*") if d.is_dir()), reverse=True):
                with contextlib.suppress(OSError):
                    d.rmdir()
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
