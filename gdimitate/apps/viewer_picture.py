"""``python -m gdimitate.apps.viewer_picture screenshot PNG`` — render the README picture of the
viewer (a figure script: scenario code, not API).

Builds a Talos (example-robot-data) walking next to a Unitree G1 that performs the adapted
walk, exports the scene as self-contained HTML, and screenshots it in headless Chromium.
``... html FILE`` writes only the HTML;
``... screenshot PNG --html PAGE`` screenshots an existing page.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from ..errors import ViewerError


def demo_html(path: str | Path, demonstrator: str = "talos", imitator: str = "g1") -> Path:
    """Write the demo scene to ``path``: ``demonstrator`` walking (the generated human-like
    gait) next to ``imitator`` performing the analytically adapted walk, with force-direction
    arrows, centres of mass and foot paths."""
    from ..adaptation.adaptor import adapt
    from ..assess.metrics import force_direction
    from ..model.robot import Robot
    from ..planar.walking import walking_motion
    from ..viz.compare import compare

    demo = Robot.from_library(demonstrator)
    imit = Robot.from_library(imitator)
    walk = walking_motion(demo)
    adapted = adapt(walk, demo, imit, "analytic")
    v = compare(demo, walk, imit, adapted, layout="side", gap=1.2,
                demo_force=force_direction(demo, walk),
                imitator_force=force_direction(imit, adapted.motion))
    try:
        frames = v.tracks["imitator"].frames
        if frames is None:  # compare() animates every track
            raise ViewerError("the imitator's track was not animated")
        com = frames.com
        target = np.array([com[:, 0].mean(), 0.0, 0.75])
        v.set_camera(target + np.array([1.9, -2.3, 0.8]), target)
        return v.save_html(path)
    finally:
        v.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m gdimitate.apps.viewer_picture",
                                     description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("screenshot", help="write the demo scene's screenshot (PNG)")
    s.add_argument("png")
    s.add_argument("--size", default="1200x800", help="WIDTHxHEIGHT in pixels")
    s.add_argument("--html", default=None,
                   help="screenshot this existing page (e.g. gdimitate-demo/demo.html) instead")
    h = sub.add_parser("html", help="write the demo scene as self-contained HTML")
    h.add_argument("path")
    args = parser.parse_args(argv)
    if args.cmd == "html":
        print(demo_html(args.path))
        return 0
    from ..viz.browser import screenshot_html

    w, hgt = (int(x) for x in args.size.lower().split("x"))
    if args.html:
        print(screenshot_html(args.html, args.png, size=(w, hgt), virtual_time_ms=3000))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        page = demo_html(Path(tmp) / "demo.html")
        print(screenshot_html(page, args.png, size=(w, hgt), virtual_time_ms=3000))
    return 0


if __name__ == "__main__":
    sys.exit(main())
