"""Lab Streaming Layer (``pylsl``, whose wheel carries ``liblsl``): a mocap stream in
(:class:`LSLSource`) and frames played out as one (:class:`LayoutOutlet`, :class:`BVHOutlet`:
a stand-in for a lab's mocap system, the tests' sender).

The stream: ``channel_count`` numbers per sample in a layout's channels
(:class:`~gdimitate.live.layout.BVHLayout`, :class:`~gdimitate.live.coordinates.OpenSimLayout`;
any order), labelled in the stream's description as XDF does it
(``<desc><channels><channel><label>Hips.Xposition</label>…``; pylsl's
``StreamInfo.set_channel_labels``), any numeric channel format (``double64`` keeps a BVH
line's digits), content type ``MoCap`` by convention. Time stamps are the sender's
(``local_clock()`` at the push by default); the inlet maps them onto this machine's clock
(``proc_clocksync``), so a frame's latency is measured from its push.

:func:`configure` with ``loopback=True`` keeps discovery on this machine (liblsl's
``ResolveScope = machine``: queries only to 127.0.0.1, the multicast listener on 127.0.0.1,
``KnownPeers = {127.0.0.1}``, IPv6 off); it must come before any other LSL call of the process.
liblsl has no setting for the address its outlets' TCP data server and UDP time server bind
(all interfaces, port 16572 up): a firewall keeps them local where that matters. Without it,
liblsl reads its own configuration (``LSLAPICFG``, ``lsl_api.cfg``; the lab's network).

pylsl is imported when first used, never by ``import gdimitate``.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from .layout import BVHLayout, Layout, LiveSourceError
from .source import LiveFrame

__all__ = ["LOOPBACK_CONFIG", "configure", "LSLSource", "LayoutOutlet", "BVHOutlet"]

#: liblsl's configuration (INI) that keeps discovery on this machine
LOOPBACK_CONFIG = """[ports]
IPv6 = disable
[multicast]
ResolveScope = machine
ListenAddress = 127.0.0.1
[lab]
KnownPeers = {127.0.0.1}
[log]
level = -3
"""

_configured: list[bool] = []  # [loopback] once configure() ran in this process


def _pylsl() -> ModuleType:
    try:
        import pylsl
    except ImportError as e:  # a dependency: say what to install
        raise LiveSourceError(f"Lab Streaming Layer needs pylsl (pip install pylsl): {e}"
                              ) from None
    return pylsl


def configure(loopback: bool = False) -> None:
    """Choose liblsl's configuration for this process, once, before any other LSL call:
    ``loopback`` → :data:`LOOPBACK_CONFIG`; else liblsl's own (its ``LSLAPICFG`` file or
    ``lsl_api.cfg``). A second call with another choice raises :class:`LiveSourceError`."""
    if _configured:
        if _configured[0] != loopback:
            raise LiveSourceError("liblsl is configured once per process; it already is "
                                  f"(loopback={_configured[0]})")
        return
    pylsl = _pylsl()
    if loopback:
        pylsl.set_config_content(LOOPBACK_CONFIG)
    _configured.append(bool(loopback))


class LSLSource:
    """The newest frames of the LSL stream called ``name`` in ``layout``'s channels
    (:class:`~gdimitate.live.source.LiveSource`). ``timeout`` [s]: how long to look for the
    stream, and how long the stream may stay silent before it counts as ended.
    ``loopback``: :func:`configure`'s."""

    def __init__(self, name: str, layout: Layout, *, timeout: float = 10.0,
                 loopback: bool = False):
        configure(loopback)
        pylsl = _pylsl()
        self.layout, self.timeout, self._pylsl = layout, float(timeout), pylsl
        found = pylsl.resolve_byprop("name", name, 1, self.timeout)
        if not found:
            where = "on this machine" if loopback else "on the network"
            raise LiveSourceError(f"no LSL stream called {name!r} {where} within "
                                  f"{self.timeout:g} s")
        info = found[0]
        self._inlet = pylsl.StreamInlet(info, max_buflen=60, recover=False,
                                        processing_flags=pylsl.proc_clocksync)
        full = self._inlet.info(self.timeout)
        labels = full.get_channel_labels() or []
        self._columns = layout.columns([str(x) for x in labels])
        self._given = self._columns >= 0  # the stance's two: -1 where it is detected
        srate = float(full.nominal_srate())
        self.rate = srate if srate > 0 else 1.0 / layout.frame_time
        self.description = (f"LSL stream {name!r} ({full.type()}, {full.channel_count()} "
                            f"channels, {srate:g} Hz nominal) from {full.hostname()}"
                            + ("" if self._given.all() else ", stance detected from the feet"))
        self._opened = False  # the data flows from the first newest(): a reader that gets
        self._count = 0  # ready after finding the stream finds no backlog
        self._last_seen: float | None = None
        self._ended: str | None = None

    def now(self) -> float:
        """liblsl's ``local_clock()`` [s] (the frames' time stamps are on it)."""
        return float(self._pylsl.local_clock())

    @property
    def ended(self) -> str | None:
        """Why the stream is over: its outlet gone, or silent for ``timeout`` s."""
        return self._ended

    def _pull(self, timeout: float) -> tuple[list[Any], list[float]]:
        from pylsl.util import LostError

        try:
            rows, stamps = self._inlet.pull_chunk(timeout=0.0, max_samples=4096)
            if not stamps:
                row, stamp = self._inlet.pull_sample(timeout=timeout)
                rows, stamps = ([row], [stamp]) if row is not None else ([], [])
        except LostError:
            self._ended = "the LSL outlet is gone"
            return [], []
        return rows, stamps

    def _open(self) -> None:
        from pylsl.util import LostError

        try:
            self._inlet.time_correction(self.timeout)  # the clock sync's first probes (~0.5
            self._inlet.open_stream(self.timeout)  # s), before the data flows: no backlog
        except (TimeoutError, LostError) as e:
            raise LiveSourceError(f"the LSL stream found did not open within {self.timeout:g} "
                                  f"s: {e}") from None
        self._opened = True

    def newest(self, timeout: float) -> tuple[LiveFrame | None, int]:
        """Every sample received since the last call is drained: the newest is returned, the
        others counted as dropped; waits at most ``timeout`` [s] for one. The first call
        opens the data stream (after the clock synchronisation's first probes)."""
        if not self._opened:
            self._open()
        rows, stamps = self._pull(timeout)
        now = self.now()
        if not stamps:
            if self._ended is None and now - (self._last_seen or now) > self.timeout:
                self._ended = f"no frame for {self.timeout:g} s"
            if self._last_seen is None:
                self._last_seen = now
            return None, 0
        self._last_seen = now
        self._count += len(stamps)
        x = np.full(self._columns.size, np.nan)
        x[self._given] = np.asarray(rows[-1], float)[self._columns[self._given]]
        ts = float(stamps[-1])
        return LiveFrame(self._count - 1, ts, x, ts), len(stamps) - 1

    def close(self) -> None:
        """Close the inlet."""
        if self._opened:
            self._inlet.close_stream()


class LayoutOutlet:
    """Frames ``samples`` ``(T, len(layout.labels))`` in a layout's channels (a
    :class:`~gdimitate.live.layout.Layout`: BVH or OpenSim coordinates) sent as an LSL stream
    called ``name`` (``double64``, type ``MoCap``, the labels in its description), from a
    thread: :meth:`start` waits for a consumer (at most ``wait`` [s]) and then pushes one frame
    every ``1 / rate`` s (time stamps: ``local_clock()`` at each push) — a stand-in for a mocap
    system. ``sent`` counts the frames pushed; :meth:`stop` ends it early."""

    def __init__(self, layout: Layout, samples: np.ndarray, name: str, rate: float, *,
                 wait: float = 60.0, loopback: bool = False, stance: bool = True):
        configure(loopback)
        pylsl = _pylsl()
        self.layout, self.samples, self.rate = layout, np.asarray(samples, float), float(rate)
        if self.samples.ndim != 2 or self.samples.shape[1] != len(layout.labels):
            raise LiveSourceError(f"samples of shape {self.samples.shape}: expected (T, "
                                  f"{len(layout.labels)}) in the layout's channels")
        labels = list(layout.labels) if stance else list(layout.labels[:-2])
        if not stance:  # ``stance=False``: the stance channels left out (the reader detects it)
            self.samples = self.samples[:, :-2]
        info = pylsl.StreamInfo(name, "MoCap", len(labels), self.rate,
                                pylsl.cf_double64, f"gdimitate-{name}")
        info.set_channel_labels(labels)
        self._outlet: Any = pylsl.StreamOutlet(info)
        self._pylsl, self._wait = pylsl, float(wait)
        self.sent = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"lsl-{name}", daemon=True)

    def start(self) -> LayoutOutlet:
        """Start sending (in a thread); returns self."""
        self._thread.start()
        return self

    def _run(self) -> None:
        if not self._outlet.wait_for_consumers(self._wait):
            return
        period, t0 = 1.0 / self.rate, time.perf_counter()
        for k, row in enumerate(self.samples):
            lag = t0 + k * period - time.perf_counter()
            if lag > 0 and self._stop.wait(lag):
                return
            self._outlet.push_sample(row.tolist(), self._pylsl.local_clock())
            self.sent = k + 1
            if self._stop.is_set():
                return

    def join(self, timeout: float | None = None) -> None:
        """Wait for the last frame to be sent."""
        self._thread.join(timeout)

    def stop(self) -> None:
        """Stop sending and close the outlet (consumers then see it gone); after the last
        frame, 0.2 s later (destroyed at once, liblsl dropped the last frame of 343 in a
        measured run)."""
        if self._outlet is None:
            return
        finished = self.sent == len(self.samples)
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5.0)
        if finished:
            time.sleep(0.2)
        self._outlet = None  # liblsl's outlet is destroyed with its last reference


class BVHOutlet(LayoutOutlet):
    """A BVH file's frames (:attr:`~gdimitate.live.layout.BVHLayout.file_samples`: its
    stance as :func:`~gdimitate.bvh.read_bvh` detects it) sent as the LSL stream ``name``
    in :class:`~gdimitate.live.layout.BVHLayout`'s channels at ``rate`` (default: the file's
    frame rate), its first ``frames`` (default: all) — :class:`LayoutOutlet`."""

    def __init__(self, path: str | Path, name: str, *, rate: float | None = None,
                 frames: int | None = None, wait: float = 60.0, loopback: bool = False,
                 stance: bool = True):
        layout = BVHLayout(path)
        samples = layout.file_samples
        super().__init__(layout, samples[:frames] if frames else samples, name,
                         float(rate) if rate else 1.0 / layout.frame_time, wait=wait,
                         loopback=loopback, stance=stance)
