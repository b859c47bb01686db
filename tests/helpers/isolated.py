"""Run one call of the library in a child process under a time and memory cap, so that a
crash (a segfault inside a compiled reader), a hang or a huge allocation fails the test that
provoked it instead of the whole suite (issue 33).

``call("gdimitate.io.c3d:read_c3d", "trial.c3d")`` imports the function in a fresh interpreter,
calls it with the (JSON-able) arguments and reports what happened as an :class:`Outcome`.
The child's address space is capped with ``RLIMIT_AS`` (``mem`` bytes) and its wall time
with ``timeout`` seconds; BLAS and OpenMP run one thread so that their per-thread reserves
do not count against the cap.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from dataclasses import dataclass

__all__ = ["Outcome", "call", "MEM", "TIMEOUT"]

MEM = 2 * 2**30 + 2**30  # 2 GiB for the work, plus what the imports map (≈ 0.9 GiB virtual)
TIMEOUT = 30.0

_CHILD = r"""
import json, sys, warnings
warnings.simplefilter("ignore")
spec, args, kwargs = json.loads(sys.argv[1])
mod, _, name = spec.partition(":")
import importlib
fn = importlib.import_module(mod)
for part in name.split("."):
    fn = getattr(fn, part)
from gdimitate.errors import GdimitateError
try:
    fn(*args, **kwargs)
    out = {"ok": True}
except BaseException as e:
    out = {"ok": False, "type": type(e).__name__, "message": str(e)[:2000],
           "ours": isinstance(e, GdimitateError),
           "mro": [c.__name__ for c in type(e).__mro__]}
print("\n@@OUTCOME@@" + json.dumps(out))
"""


@dataclass(frozen=True)
class Outcome:
    """What one isolated call did: ``returncode`` (negative: killed by that signal),
    ``elapsed`` [s], ``ok`` (returned normally), the exception's ``type``, ``message`` and
    ``ours`` (a :class:`~gdimitate.errors.GdimitateError`), and the child's ``stderr``."""

    returncode: int
    elapsed: float
    timed_out: bool
    ok: bool = False
    type: str = ""
    message: str = ""
    ours: bool = False
    mro: tuple[str, ...] = ()
    stderr: str = ""

    def handled(self) -> bool:
        """Returned normally or raised one of the library's errors, without a crash."""
        return (self.returncode == 0 and not self.timed_out) and (self.ok or self.ours)

    def __str__(self) -> str:
        if self.timed_out:
            return f"timed out after {self.elapsed:.0f} s"
        if self.returncode != 0:
            return f"exit {self.returncode}: {self.stderr[-800:]}"
        return "ok" if self.ok else f"{self.type}: {self.message}"


def _limit(mem: int):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (mem, mem))
    return apply


def call(spec: str, *args, timeout: float = TIMEOUT, mem: int = MEM, **kwargs) -> Outcome:
    """Call ``spec`` (``"module:function"``, or ``"module:Class.method"``) with ``args`` and
    ``kwargs`` (JSON-able: give paths as strings) in a child process; see the module
    docstring."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "PYTHONWARNINGS": "ignore"}
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-c", _CHILD, json.dumps([spec, args, kwargs])],
                           capture_output=True, text=True, timeout=timeout, env=env,
                           preexec_fn=_limit(mem))
    except subprocess.TimeoutExpired as e:
        err = e.stderr.decode(errors="replace") if isinstance(e.stderr, bytes) else ""
        return Outcome(-9, time.perf_counter() - t0, True, stderr=err)
    dt = time.perf_counter() - t0
    tail = p.stdout.rpartition("@@OUTCOME@@")[2]
    if p.returncode != 0 or not tail.strip():
        return Outcome(p.returncode or -1, dt, False, stderr=p.stderr)
    o = json.loads(tail)
    return Outcome(p.returncode, dt, False, ok=o["ok"], type=o.get("type", ""),
                   message=o.get("message", ""), ours=o.get("ours", False),
                   mro=tuple(o.get("mro", ())), stderr=p.stderr)
