"""A signal whose handler's exception Python drops (raised inside a weakref callback, as the
import system's module locks run them) is sent again and stops the block
(:func:`gdimitate.apps.signals.handling_signals`): ``gdimitate demo`` sent SIGTERM while it
imported its modules once printed "Exception ignored in: <function _get_module_lock.<locals>.cb>"
and ran to its end (tests/apps/test_security.py's terminated demo, one fresh-clone run in three)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import os, signal, sys, time, weakref
    from gdimitate.apps.signals import handling_signals

    class Stop(BaseException):
        pass

    def handler(signum, frame):
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        raise Stop

    class Body:
        pass

    def callback(ref):  # a weakref callback: an exception raised here is dropped
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(50):
            time.sleep(0.001)  # the handler runs here, inside the callback

    try:
        with handling_signals(handler):
            body = Body()
            ref = weakref.ref(body, callback)
            del body
            print("after the callback", flush=True)
            for _ in range(300):
                time.sleep(0.01)  # 3 s: the signal sent again ends it before
            print("finished", flush=True)
    except Stop:
        print("stopped", flush=True)
        sys.exit(143)
""")


def test_a_dropped_signal_exception_is_delivered_again():
    run = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                         timeout=60)
    assert "Exception ignored" not in run.stderr, run.stderr
    assert run.stdout.split() == ["after", "the", "callback", "stopped"], run.stdout + run.stderr
    assert run.returncode == 143
