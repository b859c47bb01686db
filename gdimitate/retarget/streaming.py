"""Streaming mode (placeholder while the trajectory mode is brought up)."""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["StreamingAdaptor", "FrameResult", "adapt_per_frame"]


class FrameResult(NamedTuple):
    q: object


class StreamingAdaptor:
    pass


def adapt_per_frame(*a, **k):
    raise NotImplementedError
