"""Per-knot functions compiled once per robot and kept on disk (docs/design.md §6, "the
solver").

CasADi's SX virtual machine evaluates the per-knot derivatives several times slower than the
same expressions compiled to C. :func:`compiled_functions` generates C for a set of
``casadi.Function`` objects, compiles it with the system C compiler into a shared library in the
user's cache folder (:func:`cache_dir`: ``$GDIMITATE_CACHE_DIR``, else
``$XDG_CACHE_HOME/gdimitate``, else ``~/.cache/gdimitate``) under a key the caller derives from
everything the expressions depend on (the robot's fingerprint, the list of parts, the code's
own version), and loads it with ``casadi.external``. A later process with the same key loads
the library without building or compiling anything; processes that miss the same library
together compile it once (a build lock; the others wait and load it); nothing is written to
the working folder.
A machine without a C compiler (or a failed compilation) keeps CasADi's virtual machine and
says so once in a :class:`SlowDerivativesWarning`.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import casadi as ca
import numpy as np

__all__ = ["cache_dir", "compiled_functions", "library", "mode", "MODE_ENV",
           "SlowDerivativesWarning", "source_digest", "COMPILE_COUNT", "split_rows", "pieces",
           "PIECE_SIZE", "OVERLAP", "INSTRUCTIONS_PER_S"]

ENV = "GDIMITATE_CACHE_DIR"
MODE_ENV = "GDIMITATE_COMPILE"
"""How a cache miss is compiled: ``background`` (the default) — the first run solves with
CasADi's virtual machine while a detached process compiles the library for later runs
(G1's derivatives take about a minute to compile on two cores, its stride's solve 20 s
uncompiled against 9 s compiled: the first result comes sooner); ``wait`` — compiled first,
then the solve (the test suite's setting: every run then times the same code)."""
CFLAGS = ("-O1", "-fPIC", "-fno-math-errno")
COMPILE_COUNT = 0
"""How many libraries this process has compiled, or started compiling in the background (a
disk-cache hit leaves it unchanged)."""
PIECE_SIZE = 120_000
"""SX instructions above which :func:`split_rows` cuts a function into pieces: the C
compiler's time grows faster than the size of one function body (its register allocation
over one basic block; docs/design.md §6, "the solver")."""
INSTRUCTIONS_PER_S = 5500.0
"""SX instructions the system compiler turns into code per second on two cores at
:data:`CFLAGS` (measured: G1's walking problem, 0.54 M instructions, 73 s; Talos's, 0.88 M,
191 s): the first run's announced estimate, within a factor of about 1.5."""
OVERLAP = 1.15
"""A cut is kept when its two pieces together take at most this many times the instructions
of the whole (what they recompute both)."""
BACKGROUND_DELAY = 60.0
"""Seconds the background build waits for the run that started it to end before it starts
compiling anyway [s]. A compiler beside the run slows it more than its niceness says: on 2
cores, the first `gdimitate demo` took 47 s with no compiler beside it (numba compiling the
oscillators' kernels in 21 s) and 72–89 s with one (the kernels 44–58 s), one compiler job or
two. A short run is over first; a batch gets its library a minute later."""
_WARNED = False


class SlowDerivativesWarning(UserWarning):
    """No C compiler: the adaptor's derivatives run in CasADi's virtual machine (slower)."""


def cache_dir() -> Path:
    """The folder compiled libraries are kept in (module docstring)."""
    if os.environ.get(ENV):
        return Path(os.environ[ENV]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "gdimitate"


def source_digest(*modules) -> str:
    """A digest of the source files of ``modules`` (packages: every ``.py`` below them), so
    that a library compiled by another version of the code is never loaded."""
    h = hashlib.sha1(str(ca.CasadiMeta.version()).encode())
    for mod in modules:
        p = Path(mod.__file__)
        files = sorted(p.parent.rglob("*.py")) if p.name == "__init__.py" else [p]
        for f in files:
            h.update(f.read_bytes())
    return h.hexdigest()


def _compiler() -> str | None:
    return os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc")


def _warn(why: str) -> None:
    global _WARNED
    if not _WARNED:
        warnings.warn(f"the optimal adaptor's derivatives run in CasADi's virtual machine "
                      f"(several times slower): {why}", SlowDerivativesWarning, stacklevel=3)
        _WARNED = True


def _write_sources(funcs: list[ca.Function], folder: Path) -> None:
    """One C file per function in ``folder``, the functions' names in ``names`` and the
    files' compile ``order`` (largest first: the compiler's longest job starts first)."""
    stems = []
    for f in sorted(funcs, key=lambda f: -f.n_instructions()):
        cg = ca.CodeGenerator(f"{f.name()}.c", {"with_header": False})
        cg.add(f)
        cg.generate(str(folder) + os.sep)
        stems.append(f.name())
    (folder / "names").write_text("\n".join(f.name() for f in funcs))
    (folder / "order").write_text("\n".join(stems))


def _compile_sources(folder: Path, lib: Path, cc: str, done: Callable[[int], None],
                     jobs: int) -> None:
    """Compile :func:`_write_sources`' files in ``folder``, ``jobs`` compilers at a time
    (separate files also bound the compiler's memory), link them into ``lib`` (atomically: a
    concurrent process sees the whole library or none) and its names file; ``done(n)`` after
    each file. Raises :class:`subprocess.CalledProcessError` when the compiler fails."""
    stems = (folder / "order").read_text().split()
    objs: list[str] = []
    procs: list[subprocess.Popen] = []

    def running() -> list[subprocess.Popen]:
        failed = next((p for p in procs if p.poll()), None)
        if failed is not None:  # stop at the first failure, not after every file
            for p in procs:
                if p.poll() is None:
                    p.kill()
            err = (folder / f"{stems[procs.index(failed)]}.err").read_text()
            raise subprocess.CalledProcessError(failed.returncode, failed.args, stderr=err)
        return [p for p in procs if p.poll() is None]

    for stem in stems:
        obj = folder / f"{stem}.o"
        objs.append(str(obj))
        while len(running()) >= jobs:
            running()[0].wait()
            done(len(procs) - len(running()))
        with open(folder / f"{stem}.err", "w") as err:  # the child keeps its own descriptor
            procs.append(subprocess.Popen([cc, *CFLAGS, "-c", str(folder / f"{stem}.c"),
                                           "-o", str(obj)], stderr=err))
    for p in procs:
        p.wait()
        done(len(procs) - len(running()))
    out = folder / lib.name
    subprocess.run([cc, "-shared", *objs, "-o", str(out), "-lm"], check=True,
                   capture_output=True, text=True)
    os.replace(folder / "names", lib.with_suffix(".names"))
    os.replace(out, lib)


def _build(funcs: list[ca.Function], lib: Path, cc: str, label: str = "") -> None:
    """Compile ``funcs`` into ``lib`` now (:data:`MODE_ENV` ``wait``). Says on stderr what it
    compiles, about how long it takes (:data:`INSTRUCTIONS_PER_S`) and how far it is (a
    progress bar over the files), then how long it took."""
    global COMPILE_COUNT
    from tqdm import tqdm

    lib.parent.mkdir(parents=True, exist_ok=True)
    total = sum(f.n_instructions() for f in funcs)
    t0 = time.perf_counter()
    print(f"gdimitate: compiling {label or 'the'} optimal-adaptor derivatives to C, once for "
          f"this robot and problem ({total / 1e6:.2f} M instructions in {len(funcs)} files, "
          f"roughly {_minutes(total / INSTRUCTIONS_PER_S)}; kept in {lib.parent}) …",
          file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory(dir=lib.parent, prefix=".build-") as tmp, \
            tqdm(total=len(funcs), unit="file", file=sys.stderr, leave=False) as bar:
        _write_sources(funcs, Path(tmp))
        _compile_sources(Path(tmp), lib, cc, lambda n: bar.update(n - bar.n),
                         os.cpu_count() or 1)
    COMPILE_COUNT += 1
    print(f"gdimitate: compiled in {time.perf_counter() - t0:.0f} s; later runs load it",
          file=sys.stderr, flush=True)


def _minutes(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.0f} min"


def split_rows(name: str, n: int, weight: np.ndarray,
               make: Callable[[int, int], list[ca.SX]], inputs: list[ca.SX],
               cuts: tuple[int, ...] = (), limit: int | None = None) -> list[ca.Function]:
    """One function's rows ``[0, n)`` as pieces ``name0, name1, …`` (rows ``[a, b)`` each:
    ``make(a, b)`` its outputs, of ``inputs``), so that the compiler sees smaller function
    bodies. A piece over ``limit`` (default :data:`PIECE_SIZE`) SX instructions is halved at
    the ``weight`` ``(n,)`` median — at the nearest of ``cuts`` (e.g. the parts' first rows)
    inside it, else at any row — unless its halves together take more than
    :data:`OVERLAP` times its instructions (rows that share a subexpression, as the
    dynamics rows share the inverse dynamics, stay together). The pieces' outputs, stacked or
    summed as ``make`` defines them, are the whole function's."""
    cum = np.r_[0.0, np.cumsum(np.asarray(weight, float))]
    limit = PIECE_SIZE if limit is None else limit

    def size(out: list[ca.SX]) -> int:
        return ca.Function(name, inputs, out).n_instructions()

    def split(a: int, b: int, out: list[ca.SX], n_out: int) -> list[list[ca.SX]]:
        if b - a < 2 or n_out <= limit:
            return [out]
        mid = np.searchsorted(cum, (cum[a] + cum[b]) / 2)
        inside = [c for c in cuts if a < c < b]
        m = min(inside, key=lambda c: abs(c - mid)) if inside else int(min(max(mid, a + 1),
                                                                             b - 1))
        lo, hi = make(a, m), make(m, b)
        n_lo, n_hi = size(lo), size(hi)
        if n_lo + n_hi > OVERLAP * n_out:
            return [out]
        return split(a, m, lo, n_lo) + split(m, b, hi, n_hi)

    whole = make(0, n)
    return [ca.Function(f"{name}{i}", inputs, out)
            for i, out in enumerate(split(0, n, whole, size(whole)))]


def pieces(fun: dict[str, ca.Function], name: str) -> list[ca.Function]:
    """The pieces ``name0, name1, …`` of :func:`split_rows` in ``fun``."""
    out: list[ca.Function] = []
    while f"{name}{len(out)}" in fun:
        out.append(fun[f"{name}{len(out)}"])
    return out


def compiled_functions(key: str, make: Callable[[], list[ca.Function]], label: str = ""
                       ) -> tuple[dict[str, ca.Function], bool]:
    """``({name: function}, compiled)`` for the functions ``make()`` builds: loaded from the
    cached library of ``key`` when it exists (``make`` is then not called; ``compiled``
    True). On a miss, by :func:`mode`: ``background`` — ``make()``'s own functions (CasADi's
    virtual machine; ``compiled`` False) while a detached process compiles the library for
    later calls (:func:`_in_background`); ``wait`` — built, compiled and cached now.
    ``label``, e.g. ``"g1's"``, names them in the message that says so; ``make()``'s own
    functions when no C compiler is available."""
    background = mode() == "background"  # a misspelt setting is said on every call
    lib = library(key)
    cached = _load(lib)
    if cached is not None:
        return cached, True
    if background:
        return _in_background(lib, make, label)
    with _building(lib):  # another process building the same library: wait, then load it
        cached = _load(lib)
        return (cached, True) if cached is not None else _compile(lib, make, label)


def library(key: str) -> Path:
    """The cached library of ``key`` (it may not exist yet)."""
    return cache_dir() / f"knot-{key[:24]}.so"


def mode() -> str:
    """:data:`MODE_ENV`'s value, ``background`` (the default) or ``wait``."""
    value = os.environ.get(MODE_ENV, "background").strip().lower() or "background"
    if value not in ("background", "wait"):
        from ...errors import InvalidInputError

        raise InvalidInputError(f"{MODE_ENV}={value!r}: use 'background' (the default: the "
                                "first run solves while the compiler works) or 'wait'")
    return value


def _in_background(lib: Path, make: Callable[[], list[ca.Function]], label: str
                   ) -> tuple[dict[str, ca.Function], bool]:
    """A cache miss in ``background`` mode: ``make()``'s functions, run by CasADi's virtual
    machine this time, and — unless another process is compiling ``lib`` already (it holds
    ``<lib>.lock``) or an earlier build failed (``<lib>.failed`` holds why) — their C files
    written into a build folder in the cache and a detached process (:func:`_spawn`) that
    compiles them into ``lib``, holding the lock until it is done."""
    global COMPILE_COUNT
    funcs = make()
    own = {f.name(): f for f in funcs}
    cc = _compiler()
    if cc is None:
        _warn("no C compiler found (set CC or install gcc)")
        return own, False
    failed = lib.with_suffix(".failed")
    if failed.exists():
        _warn(f"compiling the derivatives failed ({failed.read_text().strip()[:200]}; "
              f"delete {failed} to try again)")
        return own, False
    try:
        import fcntl

        lib.parent.mkdir(parents=True, exist_ok=True)
        lock = open(lib.with_suffix(".lock"), "a")  # noqa: SIM115 — handed to the builder
    except ImportError:  # no flock to hand over (Windows): compile now
        return _compile(lib, lambda: funcs, label)
    except OSError as e:  # a cache folder that cannot be written
        _warn(f"the cache folder {lib.parent} cannot be written ({e})")
        return own, False
    with lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:  # another process is compiling it
            print(f"gdimitate: another process is compiling {label or 'the'} derivatives; "
                  "this run uses CasADi's virtual machine (slower)", file=sys.stderr,
                  flush=True)
            return own, False
        cached = _load(lib)  # finished between our miss and the lock
        if cached is not None:
            return cached, True
        for stale in lib.parent.glob(f".build-{lib.stem}-*"):  # a builder that was killed
            shutil.rmtree(stale, ignore_errors=True)  # (we hold its lock: none is running)
        try:
            folder = Path(tempfile.mkdtemp(dir=lib.parent, prefix=f".build-{lib.stem}-"))
            _write_sources(funcs, folder)
            _spawn(folder, lib, cc, lock.fileno())
        except (OSError, subprocess.CalledProcessError) as e:  # a full disk, no /bin/sh
            _warn(f"the background build could not start ({e})")
            return own, False
    COMPILE_COUNT += 1
    total = sum(f.n_instructions() for f in funcs)
    print(f"gdimitate: {label or 'the'} optimal-adaptor derivatives run in CasADi's virtual "
          f"machine this time (slower: one thread per core); the C compiler builds them in the "
          f"background once this run has ended, for later runs ({total / 1e6:.2f} M "
          f"instructions, roughly {_minutes(total / INSTRUCTIONS_PER_S)}; kept in "
          f"{lib.parent})", file=sys.stderr, flush=True)
    return own, False


def _spawn(folder: Path, lib: Path, cc: str, lock_fd: int) -> None:
    """Start ``python -m gdimitate.retarget.trajectory.codegen FOLDER LIB CC`` detached: in a
    session of its own, through a shell that exits at once (so it is nobody's child: a batch's
    or a test's process tree does not hold it, Ctrl-C in the terminal does not stop it), at
    niceness 10, its output into ``FOLDER/log``; it starts compiling when this process has
    ended or after :data:`BACKGROUND_DELAY` s. It inherits ``lock_fd``, the build lock, and
    holds it until it ends."""
    args = " ".join(shlex.quote(a) for a in (sys.executable, "-m", __name__, str(folder),
                                              str(lib), cc, str(os.getpid()),
                                              str(BACKGROUND_DELAY)))
    subprocess.run(["/bin/sh", "-c", f"{args} </dev/null >{shlex.quote(str(folder / 'log'))} "
                    "2>&1 &"], pass_fds=(lock_fd,), start_new_session=True, check=True)


def _main(folder: str, lib: str, cc: str, parent: str, delay: str) -> int:
    """The detached builder (:func:`_spawn`): once process ``parent`` has ended or ``delay``
    seconds have passed, compile ``folder``'s sources into ``lib`` (every core when the
    parent is gone, all but one beside it) and remove ``folder``; on failure write why into
    ``<lib>.failed``."""
    os.nice(10)
    pid, deadline = int(parent), time.monotonic() + float(delay)
    while pid > 1 and _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.2)
    cores = os.cpu_count() or 1
    jobs = max(1, cores - 1) if pid > 1 and _alive(pid) else cores
    out = Path(lib)
    try:
        _compile_sources(Path(folder), out, cc, lambda n: None, jobs)
    except (OSError, subprocess.CalledProcessError) as e:
        detail = getattr(e, "stderr", "") or str(e)
        with contextlib.suppress(OSError):
            out.with_suffix(".failed").write_text(detail.strip()[:2000] or repr(e))
        return 1
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return 0


def _load(lib: Path) -> dict[str, ca.Function] | None:
    """The functions of the cached library ``lib`` (None: not there, or damaged)."""
    names_file = lib.with_suffix(".names")
    if not (lib.exists() and names_file.exists()):
        return None
    try:
        return {n: ca.external(n, str(lib)) for n in names_file.read_text().split()}
    except RuntimeError:
        return None  # a damaged library: rebuild it


@contextlib.contextmanager
def _building(lib: Path) -> Iterator[None]:
    """Hold the build lock of ``lib`` (an exclusive ``flock`` on ``<lib>.lock``; the system
    releases it when its process ends): the processes of a batch or of a parallel test run
    that miss the same library compile it once, the others waiting to load it. Without
    ``fcntl`` (Windows) or a writable cache, no lock."""
    try:
        import fcntl

        lib.parent.mkdir(parents=True, exist_ok=True)
        f = open(lib.with_suffix(".lock"), "a")  # noqa: SIM115 — held across the yield
    except (ImportError, OSError):
        yield
        return
    with f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _compile(lib: Path, make: Callable[[], list[ca.Function]], label: str
             ) -> tuple[dict[str, ca.Function], bool]:
    """:func:`compiled_functions` on a cache miss: build, compile and cache ``make()``'s
    functions into ``lib`` (its own, uncompiled, without a working C compiler)."""
    funcs = make()
    cc = _compiler()
    if cc is None:
        _warn("no C compiler found (set CC or install gcc)")
        return {f.name(): f for f in funcs}, False
    try:
        _build(funcs, lib, cc, label)
    except (OSError, subprocess.CalledProcessError) as e:
        detail = getattr(e, "stderr", "") or str(e)
        _warn(f"compiling the derivatives failed ({detail.strip()[:200]})")
        return {f.name(): f for f in funcs}, False
    return {f.name(): ca.external(f.name(), str(lib)) for f in funcs}, True


def _alive(pid: int) -> bool:
    """Whether process ``pid`` (> 1) still exists."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


if __name__ == "__main__":
    sys.exit(_main(*sys.argv[1:6]))
