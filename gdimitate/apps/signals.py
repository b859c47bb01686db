"""SIGINT and SIGTERM handled by a function of the command's for the length of a block (the
command line's statuses 130 and 143, the live stream's stop-and-write), the previous handlers
back afterwards."""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = ["handling_signals"]


@contextmanager
def handling_signals(handler: Callable[[int, object], None]) -> Iterator[None]:
    """Within the block, Ctrl-C (SIGINT) and SIGTERM call ``handler(signum, frame)``; outside
    the main thread (where Python cannot install handlers) nothing changes."""
    previous = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, handler)
    except ValueError:  # not the main thread: signals are left alone
        pass
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
