"""BVH files written by the tests and the corpus benchmark (not tests themselves).

- :func:`write_bvh`: a hierarchy ``[(name, parent, offset, channels, ends)]`` and its frame
  values → a BVH text file (the synthetic skeletons of ``tests/io/test_bvh.py``).
- :func:`rewrite_bvh`: a parsed BVH clip (:func:`gdimitate.io.bvh.parse_bvh`) rewritten in
  other conventions — every joint's rotation channels in one order (e.g. ``"XYZ"``), another
  length unit (e.g. inches), the whole clip turned by a yaw about the vertical (or so that it
  walks along a chosen heading), cut to a time window at the file's own rate. The rotations
  are re-expressed, not relabelled: each joint's local rotation matrix (its channels composed
  in the file's order, :mod:`gdimitate.io.bvh.parse`) is decomposed again in the new order,
  so every joint lands where it did (turned, and in the new unit). It is how
  ``benchmarks/corpus.py --clips sfu`` makes an SFU-style walk (``LeftUpLeg``… names, XYZ
  channels, inches, 120 Hz, walking along −y: issue 32) from the shipped CMU walk.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from gdimitate.io.bvh import UNITS, BVHFile, channel_rotation
from gdimitate.io.bvh.skeleton import detect_scale, world_turn

__all__ = ["CMU_BVH", "SFU_STYLE", "write_bvh", "rewrite_bvh", "root_heading",
           "write_sfu_style"]

#: the shipped CMU walk (subject 02, trial 01: ZYX channels, CMU units, a T-pose first frame)
CMU_BVH = Path(__file__).resolve().parents[2] / "gdimitate" / "data" / "gait" / "cmu_02_01" / (
    "cmu_02_01.bvh")
#: the conventions of issue 32's SFU walk: XYZ channels, inches, walking along −y, 2.2 s,
#: numbers with 6 decimals (at the source's rate: the CMU clip's is 120 Hz, as SFU's)
SFU_STYLE = {"order": "XYZ", "unit": "inches", "heading": -np.pi / 2, "duration": 2.2,
             "decimals": 6}


def write_bvh(path, joints, root_channels, values, dt, tpose=False, fmt=None):
    """Write ``joints`` ``[(name, parent, offset, channels, ends)]`` (depth-first; the root's
    channels are ``root_channels``) and ``values`` ``(T, n)`` (file units, degrees) at frame
    time ``dt`` [s] to ``path``; ``tpose``: a first frame with every rotation at 0 (the root
    at its first position, as CMU's); ``fmt``: how a number is written (default ``repr``: every
    digit of the double). Returns the frame rows written."""
    num = fmt or (lambda x: repr(float(x)))
    lines = ["HIERARCHY"]
    depth = {}
    order = []
    kids = {}
    for j in joints:
        kids.setdefault(j[1], []).append(j)

    def emit(j, d):
        name, parent, off, ch, ends = j
        ch = root_channels if parent is None else ch
        ind = "\t" * d
        lines.append(f"{ind}{'ROOT' if parent is None else 'JOINT'} {name}")
        lines.append(f"{ind}{{")
        lines.append(f"{ind}\tOFFSET {' '.join(num(x) for x in off)}")
        lines.append(f"{ind}\tCHANNELS {len(ch)} {' '.join(ch)}")
        order.append(name)
        depth[name] = d
        for k in kids.get(name, []):
            emit(k, d + 1)
        for e in ends:
            lines.extend([f"{ind}\tEnd Site", f"{ind}\t{{",
                          f"{ind}\t\tOFFSET {' '.join(num(x) for x in e)}", f"{ind}\t}}"])
        lines.append(f"{ind}}}")

    emit(joints[0], 0)
    assert order == [j[0] for j in joints], "joints must be listed depth-first"
    rows = values
    if tpose:
        rows = np.vstack([np.where(np.arange(values.shape[1]) < 3, values[0], 0.0), values])
    lines += ["MOTION", f"Frames: {rows.shape[0]}", f"Frame Time: {dt!r}"]
    lines += [" ".join(num(x) for x in r) for r in rows]
    Path(path).write_text("\n".join(lines) + "\n")
    return rows


def _unit_scale(unit) -> float:
    """[m per file unit] of a unit name of :data:`gdimitate.io.bvh.UNITS` or a number."""
    if isinstance(unit, str):
        found = [s for n, s in UNITS if n == unit or n.split()[0] == unit]
        if not found:
            raise ValueError(f"unit {unit!r}: give one of {[n for n, _ in UNITS]} or metres "
                             "per unit")
        return float(found[0])
    return float(unit)


def _local_rotations(bvh: BVHFile, frames: np.ndarray, i: int) -> np.ndarray:
    """``(T, 3, 3)``: joint ``i``'s rotation channels composed in the file's order."""
    j = bvh.joints[i]
    R = np.tile(np.eye(3), (frames.shape[0], 1, 1))
    for k, c in enumerate(j.channels):
        if c.endswith("rotation"):
            R = R @ channel_rotation(c, np.deg2rad(frames[:, j.column + k]))
    return R


def _root_positions(bvh: BVHFile, frames: np.ndarray) -> np.ndarray:
    """``(T, 3)``: the root's OFFSET + position channels [file units, file axes]."""
    root = bvh.joints[0]
    p = np.tile(root.offset, (frames.shape[0], 1)).astype(float)
    for k, c in enumerate(root.channels):
        if c.endswith("position"):
            p[:, "XYZ".index(c[0])] += frames[:, root.column + k]
    return p


def root_heading(bvh: BVHFile, frames: np.ndarray, up: str = "y") -> float:
    """The yaw [rad] in our world (x forward, y left, z up) of the root's horizontal
    displacement from the first of ``frames`` to the last — what
    :func:`gdimitate.model.heading.walk_heading` finds for a clip that travels."""
    d = world_turn(up) @ (_root_positions(bvh, frames[[-1]])[0]
                          - _root_positions(bvh, frames[[0]])[0])
    return float(np.arctan2(d[1], d[0]))


def rewrite_bvh(bvh: BVHFile, path, *, order: str | None = "XYZ", unit="inches",
                scale: float | None = None, yaw: float = 0.0, heading: float | None = None,
                start: float = 0.0, duration: float | None = None, up: str = "y",
                decimals: int | None = None) -> Path:
    """Write ``bvh`` (parsed) to ``path`` in other conventions; returns ``path``.

    - ``order``: every joint's rotation channels as three channels in this order (``"XYZ"``:
      ``R = R_X · R_Y · R_Z``); the root's channels become ``Xposition Yposition Zposition``
      and its three rotations. A joint without rotation channels keeps none; position
      channels of other joints are kept (scaled). ``None``: each joint keeps its channels
      (the angles copied, the root's recomputed in its own order when the clip turns).
    - ``unit``: the new length unit, a name of :data:`gdimitate.io.bvh.UNITS` (``"m"``,
      ``"cm"``, ``"mm"``, ``"inches"``, ``"CMU"``) or metres per unit; ``scale`` the file's
      own [m per unit] (default: detected as the reader does,
      :func:`gdimitate.io.bvh.skeleton.detect_scale`).
    - ``yaw`` [rad]: the clip turned about the vertical (our z, the file's ``up`` axis)
      through the root's first kept position; ``heading`` [rad], when given, sets the yaw so
      that the root's displacement over the window points along it (−π/2: along −y).
    - ``start``, ``duration`` [s]: the window, on the file's clock (frame k at k · frame
      time); frames from the one nearest ``start`` for ``duration`` (default: to the end).
      The frame time is the file's.
    - ``up``: the file's up axis (``"y"`` or ``"z"``), kept in the new file.
    - ``decimals``: numbers written with this many decimals (``None``: every digit).
    """
    if order is not None and sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"order={order!r}: give a permutation of 'XYZ'")
    C = world_turn(up)
    s0 = float(scale) if scale is not None else detect_scale(bvh, C)[0]
    s1 = _unit_scale(unit)
    dt = bvh.frame_time
    k0 = int(round(start / dt))
    n = bvh.frames.shape[0] - k0 if duration is None else int(round(duration / dt)) + 1
    frames = bvh.frames[k0:k0 + n]
    if k0 < 0 or n < 2 or frames.shape[0] != n:
        raise ValueError(f"window {start} s + {duration} s does not fit the clip "
                         f"({bvh.frames.shape[0]} frames of {dt} s)")
    if heading is not None:
        yaw = float(heading) - root_heading(bvh, frames, up)
    c, s = np.cos(yaw), np.sin(yaw)
    turn = C.T @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ C  # file axes
    root = bvh.joints[0]
    if yaw != 0.0 and not any(ch.endswith("position") for ch in root.channels):
        raise ValueError("the root has no position channels: the clip cannot turn")
    p = _root_positions(bvh, frames)
    about = p[0] - (p[0] @ C[2]) * C[2]  # the vertical through the first position
    if yaw != 0.0:
        p = (p - about) @ turn.T + about
    k = s0 / s1  # new units per old unit
    joints, cols = [], []
    names = [j.name for j in bvh.joints]
    for i, j in enumerate(bvh.joints):
        rot = [c for c in j.channels if c.endswith("rotation")]
        if i == 0:  # the root's place: OFFSET + channels, turned
            channels = [f"{a}position" for a in "XYZ"] if order is not None else [
                c for c in j.channels if c.endswith("position")]
            cols += [k * (p[:, "XYZ".index(c[0])] - j.offset["XYZ".index(c[0])])
                     for c in channels]
        else:
            channels = [c for c in j.channels if c.endswith("position")]
            cols += [k * frames[:, j.column + j.channels.index(c)] for c in channels]
        if order is None and (i > 0 or yaw == 0.0):  # the angles as written
            channels += rot
            cols += [frames[:, j.column + j.channels.index(c)] for c in rot]
        elif rot:
            new_order = order or "".join(c[0] for c in rot)
            if len(new_order) < 3:
                raise ValueError(f"{j.name}: {len(rot)} rotation channels cannot hold a turn; "
                                 "give order=")
            R = _local_rotations(bvh, frames, i)
            if i == 0:
                R = turn @ R
            channels += [f"{a}rotation" for a in new_order]
            cols += list(Rotation.from_matrix(R).as_euler(new_order, degrees=True).T)
        parent = None if j.parent < 0 else names[j.parent]
        joints.append([j.name, parent, list(k * j.offset), channels,
                       [list(k * e) for e in j.end_sites]])
    values = np.column_stack(cols)
    fmt = None if decimals is None else (lambda x: f"{float(x):.{decimals}f}")
    write_bvh(path, joints, joints[0][3], values, dt, fmt=fmt)
    return Path(path)


def write_sfu_style(path, source=CMU_BVH) -> Path:
    """The SFU-style clip of issue 32 made from ``source`` (default the shipped CMU walk):
    :data:`SFU_STYLE`'s conventions, the 2.2 s around the middle of its motion (a reference
    first frame, :func:`gdimitate.io.bvh.is_reference_frame`, left out). Returns ``path``."""
    from gdimitate.io.bvh import is_reference_frame, parse_bvh

    bvh = parse_bvh(source)
    first = 1 if is_reference_frame(bvh) else 0
    mid = (first + bvh.frames.shape[0] - 1) / 2 * bvh.frame_time
    return rewrite_bvh(bvh, path, start=mid - SFU_STYLE["duration"] / 2, **SFU_STYLE)
