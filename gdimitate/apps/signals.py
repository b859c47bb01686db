"""SIGINT and SIGTERM handled by a function of the command's for the length of a block (the
command line's statuses 130 and 143, the live stream's stop-and-write), the previous handlers
back afterwards.

A handler that stops the command raises (``KeyboardInterrupt``, the command line's own
``BaseException``). Where the signal lands in code whose exceptions Python cannot propagate —
a weakref callback such as the import system's module locks, a ``__del__`` — Python prints
"Exception ignored in …" and drops it: a SIGTERM sent while ``gdimitate demo`` imported its
modules was lost, and the demo ran to its end. Within the block such a dropped exception of the
handler's is taken as undelivered: the signal is sent again :data:`RETRY_S` later, from a timer
thread, and handled where the main thread is then."""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = ["handling_signals", "RETRY_S"]

#: seconds after a dropped handler exception until its signal is sent again
RETRY_S = 0.02


@contextmanager
def handling_signals(handler: Callable[[int, object], None]) -> Iterator[None]:
    """Within the block, Ctrl-C (SIGINT) and SIGTERM call ``handler(signum, frame)``; outside
    the main thread (where Python cannot install handlers) nothing changes."""
    previous: dict = {}
    handled: list[int] = []

    def recorded(signum: int, frame: object) -> None:
        handled.append(signum)
        handler(signum, frame)

    def redeliver(unraisable) -> None:
        exc = unraisable.exc_value
        if handled and exc is not None and not isinstance(exc, Exception):
            signum = handled[-1]  # the handler's exception, dropped: send its signal again
            signal.signal(signum, recorded)
            threading.Timer(RETRY_S, signal.raise_signal, (signum,)).start()
            return
        hook(unraisable)

    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, recorded)
    except ValueError:  # not the main thread: signals are left alone
        pass
    hook = sys.unraisablehook
    if previous:
        sys.unraisablehook = redeliver
    try:
        yield
    finally:
        if previous:
            sys.unraisablehook = hook
        for sig, old in previous.items():
            signal.signal(sig, old)
