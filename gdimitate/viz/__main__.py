"""``python -m gdimitate.viz screenshot PNG`` — render the README picture of the viewer.

Builds a Talos (example-robot-data) stepping in place next to a scaled translucent ghost of
itself, exports the scene as self-contained HTML, and screenshots it in headless Chromium.
``python -m gdimitate.viz html FILE`` writes only the HTML.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin


@dataclass
class _Leg:
    sole: str
    hip: str
    knee: str
    ankle: str


@dataclass
class _Robot:
    name: str
    model: pin.Model
    visual_model: pin.GeometryModel | None
    legs: dict[str, _Leg] = field(default_factory=dict)


@dataclass
class _Motion:
    t: np.ndarray
    q: np.ndarray
    joint_names: list[str]
    contact: dict[str, np.ndarray]


def talos_demo(duration: float = 2.0, rate: float = 50.0) -> tuple[_Robot, _Motion]:
    """A Talos marching on the spot (knees and hips bend in turn), feet on z = 0.

    Returns plain objects with the fields of ``gdimitate.Robot`` and ``gdimitate.Motion`` that
    the viewer uses: ``t`` (T,) [s], ``q`` (T, 39).
    """
    from ..library import library_entry

    path, pkg = library_entry("talos")
    model, _, visual = pin.buildModelsFromUrdf(str(path), str(pkg), pin.JointModelFreeFlyer())
    legs = {side: _Leg(f"{side}_sole_link", f"leg_{side}_3_joint", f"leg_{side}_4_joint",
                       f"leg_{side}_5_joint") for side in ("left", "right")}
    robot = _Robot("talos", model, visual, legs)
    t = np.arange(0.0, duration, 1.0 / rate)
    q = np.tile(pin.neutral(model), (len(t), 1))
    data = model.createData()
    for i, ti in enumerate(t):
        for side, phase in (("left", 0.0), ("right", np.pi)):
            lift = max(0.0, np.sin(2 * np.pi * ti / duration * 2 + phase))
            bend = 0.25 + 0.7 * lift
            q[i, model.idx_qs[model.getJointId(f"leg_{side}_3_joint")]] = -bend / 2
            q[i, model.idx_qs[model.getJointId(f"leg_{side}_4_joint")]] = bend
            q[i, model.idx_qs[model.getJointId(f"leg_{side}_5_joint")]] = -bend / 2
        pin.framesForwardKinematics(model, data, q[i])
        low = min(data.oMf[model.getFrameId(f"{s}_sole_link")].translation[2]
                  for s in ("left", "right"))
        q[i, 2] -= low
        q[i, 0] = 0.15 * ti
    contact = {s: np.ones(len(t), dtype=bool) for s in ("left", "right")}
    return robot, _Motion(t, q, list(model.names)[1:], contact)


def demo_html(path: str | Path) -> Path:
    """Write the demo scene (Talos + scaled ghost, arrows, CoM, foot paths) to ``path``."""
    from .compare import compare

    robot, motion = talos_demo()
    n = len(motion.t)
    push = {"left": np.full(n, 0.15), "right": np.where(np.arange(n) % 50 < 25, -0.1, np.nan)}
    v = compare(robot, motion, robot, motion, layout="side", gap=1.0, demo_force=push,
                imitator_force=push, html=path, camera=(2.4, -3.0, 1.4))
    v.close()
    return Path(path).resolve()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m gdimitate.viz", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("screenshot", help="write the demo scene's screenshot (PNG)")
    s.add_argument("png")
    s.add_argument("--size", default="1200x800", help="WIDTHxHEIGHT in pixels")
    h = sub.add_parser("html", help="write the demo scene as self-contained HTML")
    h.add_argument("path")
    args = parser.parse_args(argv)
    if args.cmd == "html":
        print(demo_html(args.path))
        return 0
    from .browser import screenshot_html

    w, hgt = (int(x) for x in args.size.lower().split("x"))
    with tempfile.TemporaryDirectory() as tmp:
        page = demo_html(Path(tmp) / "demo.html")
        print(screenshot_html(page, args.png, size=(w, hgt), virtual_time_ms=3000))
    return 0


if __name__ == "__main__":
    sys.exit(main())
