"""Live mocap in: frames as they arrive, for ``gdimitate stream`` (docs/guide/streaming.md).

Modules: :mod:`.layout` (a sample's channels → the demonstrator's configuration and stance:
a BVH skeleton's channels and two stance channels), :mod:`.coordinates` (an OpenSim model's
coordinates as the channels), :mod:`.source` (what a live source gives: the newest frame and
the count of those dropped; a BVH file played at its own rate), :mod:`.lsl` (Lab Streaming
Layer: an inlet, and frames played out as an outlet; pylsl is imported only there, when used).
"""

from .coordinates import OpenSimLayout
from .layout import CONTACT_LABELS, BVHLayout, Layout, LiveSourceError
from .source import BVHFileSource, LiveFrame, LiveSource

__all__ = ["CONTACT_LABELS", "BVHFileSource", "BVHLayout", "Layout", "LiveFrame", "LiveSource",
           "LiveSourceError", "OpenSimLayout"]
