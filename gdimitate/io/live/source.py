"""A live source: frames as they arrive, the newest first, the ones the consumer could not
take counted — and a BVH file played at its own frame rate (the loop's test).

A source's :meth:`~BVHFileSource.newest` returns the newest frame that has arrived since the
previous call and how many arrived before it in that time (frames the consumer was too slow
for: dropped, never queued, so it never falls behind). A frame's ``arrived`` is when it became
available on the source's clock (:meth:`~BVHFileSource.now`): its latency is measured from
there.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from .layout import BVHLayout, Layout

__all__ = ["LiveFrame", "LiveSource", "BVHFileSource"]


@dataclass(frozen=True)
class LiveFrame:
    """One received frame: ``index`` (the source's count, 0 = the first it delivered or
    dropped), ``t`` [s] (its time stamp on the source's clock), ``sample`` ``(n,)`` (the
    numbers in the layout's channel order) and ``arrived`` [s] (when it became available, on
    the source's clock)."""

    index: int
    t: float
    sample: np.ndarray
    arrived: float


class LiveSource(Protocol):
    """What ``gdimitate stream`` reads (:class:`BVHFileSource`,
    :class:`~gdimitate.live.lsl.LSLSource`)."""

    layout: Layout
    #: the nominal frame rate [Hz]
    rate: float
    #: what it is, for the console (e.g. ``"cmu_02_01.bvh at 120 Hz"``)
    description: str

    def now(self) -> float:
        """The source's clock [s] (frames' ``arrived`` and ``t``)."""
        ...

    def newest(self, timeout: float) -> tuple[LiveFrame | None, int]:
        """``(the newest frame arrived since the last call or None after timeout [s], how many
        arrived before it since the last call: dropped)``."""
        ...

    @property
    def ended(self) -> str | None:
        """Why no frame will come any more (None while the stream goes on)."""
        ...

    def close(self) -> None:
        """Release what the source holds."""
        ...


class BVHFileSource:
    """A BVH file played at its own frame rate: frame k arrives ``k × frame_time`` after the
    first call to :meth:`newest`, whether or not the consumer is ready (as a mocap system
    sends); the stance is :func:`~gdimitate.bvh.read_bvh`'s (:attr:`.BVHLayout.file_samples`).
    ``frames``: play only the first ones."""

    def __init__(self, path: str | Path, frames: int | None = None):
        layout = BVHLayout(path)
        self.layout: Layout = layout
        samples = layout.file_samples
        self._samples = samples[:frames] if frames else samples
        self.rate = 1.0 / self.layout.frame_time
        self.description = (f"{Path(path).name} played at its own rate ({self.rate:.4g} Hz, "
                            f"{len(self._samples)} frames)")
        self._t0: float | None = None
        self._last = -1

    def now(self) -> float:
        """``time.perf_counter()`` [s]."""
        return time.perf_counter()

    @property
    def ended(self) -> str | None:
        """``"end of file"`` once its last frame was delivered or dropped."""
        return "end of file" if self._last >= len(self._samples) - 1 else None

    def newest(self, timeout: float) -> tuple[LiveFrame | None, int]:
        """The newest frame due (see :class:`LiveSource`); waits for the next one at most
        ``timeout`` [s]."""
        now = self.now()
        if self._t0 is None:
            self._t0 = now
        dt, last = self.layout.frame_time, len(self._samples) - 1
        if self._last >= last:
            return None, 0
        wait = self._t0 + (self._last + 1) * dt - now
        if wait > 0:
            time.sleep(min(wait, timeout))
            if wait > timeout:
                return None, 0
            now = self.now()
        due = min(int((now - self._t0) / dt), last)
        due = max(due, self._last + 1)
        skipped, self._last = due - self._last - 1, due
        return LiveFrame(due, due * dt, self._samples[due], self._t0 + due * dt), skipped

    def close(self) -> None:
        """Nothing to release."""
