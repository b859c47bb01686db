"""Live mocap in: frames as they arrive, for ``gdimitate stream`` (docs/guide/streaming.md).

Modules: :mod:`.layout` (a sample's channels → the demonstrator's configuration and stance:
a BVH skeleton's channels and two stance channels), :mod:`.source` (what a live source gives:
the newest frame and the count of those dropped; a BVH file played at its own rate),
:mod:`.lsl` (Lab Streaming Layer: an inlet, and a BVH file played out as an outlet; pylsl is
imported only there, when used).
"""

from .layout import CONTACT_LABELS, BVHLayout, LiveSourceError
from .source import BVHFileSource, LiveFrame, LiveSource

__all__ = ["CONTACT_LABELS", "BVHFileSource", "BVHLayout", "LiveFrame", "LiveSource",
           "LiveSourceError"]
