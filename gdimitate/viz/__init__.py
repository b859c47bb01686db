"""Meshcat previews of robots and motions: live in the browser, inline in notebooks, or as one
self-contained HTML file that plays offline.

Typical use::

    from gdimitate.viz import compare
    v = compare(demonstrator, demo_motion, imitator, adapted, html="walk.html")
    print(v.url)      # live page
    v.display()       # in a notebook cell
    v.close()

Modules: :mod:`~.server` (our own meshcat server process, connection with timeouts),
:mod:`~.scene` (static drawing), :mod:`~.animate` (kinematics → animation tracks),
:mod:`~.export` (HTML files, notebook snippet), :mod:`~.track` (a robot over a motion: what
:meth:`Viewer.show` checks), :mod:`~.camera` (camera and ground framing), :mod:`~.viewer`
(:class:`Viewer`: the scene's lifecycle, drawing and animation),
:mod:`~.compare` (:func:`compare`), :mod:`~.browser` (headless Chromium screenshots).
"""

from .animate import MotionMismatchError
from .browser import BrowserNotFoundError, changed_fraction, find_chromium, screenshot_html
from .compare import compare
from .export import network_references
from .scene import Style, skeleton_geometry
from .server import MeshcatServer, PortInUseError
from .viewer import Track, Viewer, leg_length

__all__ = [
    "BrowserNotFoundError",
    "MeshcatServer",
    "MotionMismatchError",
    "PortInUseError",
    "Style",
    "Track",
    "Viewer",
    "changed_fraction",
    "compare",
    "find_chromium",
    "leg_length",
    "network_references",
    "screenshot_html",
    "skeleton_geometry",
]
