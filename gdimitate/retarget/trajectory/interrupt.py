"""Ctrl-C during a solve, and progress lines.

CasADi's IPOPT swallows SIGINT (the solve runs to its end and the process exits 0), and an
exception raised by a Python signal handler inside its callback is lost ("SystemError …
returned a result with an exception set"). Around each solve :func:`guard` installs SIGINT and
SIGTERM handlers that only set a flag; the solver's
iteration callback (:class:`Progress`, IPOPT's intermediate callback through CasADi's
``iteration_callback``) sees the flag and asks IPOPT to stop; :func:`guard` then passes
the signal on to the handler that was there before (``KeyboardInterrupt`` for Ctrl-C) after the
solver has returned, so nothing is half-written. The callback
also prints the iteration number, the objective and the largest constraint violation every
``every`` iterations when progress is on, and feeds each iterate to the stopping rule
(:class:`~.stopping.Plateau`) when one is given.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
from contextlib import contextmanager

import casadi as ca
import numpy as np

__all__ = ["Progress", "guard"]


class _State:
    interrupted = 0  # the signal number that asked the solve to stop
    verbose = False
    lbg: np.ndarray | None = None
    ubg: np.ndarray | None = None
    every = 10
    t0 = 0.0
    label = ""
    stopper = None
    solver: ca.Function | None = None


STATE = _State()


class Progress(ca.Callback):
    """IPOPT iteration callback: progress lines and the stop request (module docstring)."""

    def __init__(self, name: str, nx: int, ng: int, np_: int):
        ca.Callback.__init__(self)
        self._nx, self._ng, self._np = nx, ng, np_
        self._it = 0
        self.construct(name, {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        n = ca.nlpsol_out(i)
        size = {"f": 1, "x": self._nx, "lam_x": self._nx, "g": self._ng, "lam_g": self._ng,
                "p": self._np, "lam_p": self._np}[n]
        return ca.Sparsity.dense(size, 1)

    def reset(self) -> None:
        self._it = 0

    def eval(self, arg):
        self._it += 1
        out = ca.nlpsol_out()
        g = np.asarray(arg[out.index("g")]).ravel()
        f = float(arg[out.index("f")])
        stop = STATE.stopper is not None and STATE.stopper.update(
            f, np.asarray(arg[out.index("x")]), g, _barrier())
        if STATE.verbose and (self._it == 1 or self._it % STATE.every == 0):
            viol = 0.0
            if STATE.lbg is not None and g.size:
                viol = float(np.max(np.maximum(STATE.lbg - g, 0) + np.maximum(g - STATE.ubg, 0)))
            print(f"  {STATE.label} iter {self._it:4d}  cost {f:.4e}  constraint violation "
                  f"{viol:.2e}  ({time.perf_counter() - STATE.t0:.1f} s)", file=sys.stderr,
                  flush=True)
        return [1 if STATE.interrupted or stop else 0]


def _barrier() -> float:
    """IPOPT's barrier parameter μ at the current iterate (in its scaled objective's units),
    read from the running solver's statistics (CasADi records IPOPT's intermediate-callback
    values, ``mu`` among them, before it calls the iteration callback); 0 when no solver is
    set."""
    if STATE.solver is None:
        return 0.0
    mu = STATE.solver.stats().get("iterations", {}).get("mu", ())
    return float(mu[-1]) if len(mu) else math.inf


@contextmanager
def guard(verbose: bool, lbg: np.ndarray, ubg: np.ndarray, label: str = "", stopper=None,
          solver: ca.Function | None = None):
    """Run a solve with the flag handler of SIGINT and SIGTERM installed (main thread only),
    progress settings and an optional stopping rule, which is given IPOPT's barrier parameter
    of each iterate from ``solver`` (the nlpsol that runs). A signal that arrived during the
    solve is delivered after it (:func:`_deliver`): ``KeyboardInterrupt`` for Ctrl-C."""
    STATE.interrupted = 0
    STATE.stopper, STATE.solver = stopper, solver
    STATE.verbose, STATE.lbg, STATE.ubg, STATE.label = verbose, lbg, ubg, label
    STATE.t0 = time.perf_counter()
    main = threading.current_thread() is threading.main_thread()
    old: dict[int, object] = {}
    if main:
        def handler(signum: int, frame: object) -> None:
            STATE.interrupted = int(signum)

        for sig in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(sig) is not signal.SIG_IGN:
                old[sig] = signal.signal(sig, handler)
    try:
        yield STATE
    finally:
        STATE.solver = None
        for signum, previous in old.items():
            signal.signal(signum, previous)  # type: ignore[arg-type]
    if STATE.interrupted:
        _deliver(int(STATE.interrupted), old.get(int(STATE.interrupted)))


def _deliver(sig: int, previous: object) -> None:
    """Hand a signal that arrived during a solve to the handler that was there before (the
    command line's: Ctrl-C → exit 130, SIGTERM → exit 143), once the solver has returned;
    Python's own Ctrl-C handler → ``KeyboardInterrupt``; SIGTERM's default → the process ends
    by it."""
    STATE.interrupted = 0
    if callable(previous) and previous is not signal.default_int_handler:
        previous(sig, None)
    if sig == signal.SIGINT:
        raise KeyboardInterrupt("optimal adaptor: solve interrupted (Ctrl-C)")
    signal.raise_signal(sig)
