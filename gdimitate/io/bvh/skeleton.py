"""Geometry of a parsed BVH skeleton at its zero pose: the world turn, units, legs and feet.

The zero pose is every channel at 0 (the pose the OFFSETs describe — usually a T-pose). All
positions here are in the BVH file's axes and units unless a name says ``_m`` (metres) or
``_world`` (our world: x forward, y left, z up).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ...errors import BVHError, LegDetectionError
from ...model.anthropometry import match_segment, side_of
from .parse import BVHFile

__all__ = ["UP_TURNS", "UNITS", "world_turn", "zero_pose", "detect_scale", "hip_height_units",
           "LegChain", "find_legs", "Sole", "measure_sole", "leg_splay", "pitch_channel"]

#: Constant rotations ``C`` (x_ours = C · x_bvh) for the supported BVH up axes. ``"y"``: BVH Y
#: up and the subject facing +Z (the common convention: CMU, MotionBuilder, Mixamo) → our x
#: forward = BVH Z, y left = BVH X, z up = BVH Y. ``"z"``: BVH Z up, facing −Y (Blender's
#: convention) → x = −Y, y = X, z = Z.
UP_TURNS: dict[str, np.ndarray] = {
    "y": np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
    "z": np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
}

#: Candidate units [m per file unit] for ``scale=None``, tried in this order.
UNITS: tuple[tuple[str, float], ...] = (
    ("m", 1.0), ("cm", 0.01), ("mm", 0.001), ("inches", 0.0254),
    ("CMU units (0.056444 m, = inches / 0.45)", 0.056444),
)
#: Hip height [m] (root to the lowest point of the zero pose) that unit detection aims at, and
#: the range it accepts.
HIP_HEIGHT_M = 0.9
HIP_HEIGHT_RANGE_M = (0.55, 1.35)


def world_turn(up: str) -> np.ndarray:
    """The constant rotation ``C`` (3, 3) for ``up`` (``"y"`` or ``"z"``), see
    :data:`UP_TURNS`."""
    if up not in UP_TURNS:
        raise BVHError(f"up={up!r}: valid BVH up axes are {sorted(UP_TURNS)}")
    return UP_TURNS[up]


def zero_pose(bvh: BVHFile) -> tuple[np.ndarray, list[list[np.ndarray]]]:
    """Joint positions ``(J, 3)`` and, per joint, its End Site positions, at the zero pose,
    relative to the root joint (file axes and units)."""
    pos = np.zeros((len(bvh.joints), 3))
    for i, j in enumerate(bvh.joints):
        if j.parent >= 0:
            pos[i] = pos[j.parent] + j.offset
    ends = [[pos[i] + e for e in j.end_sites] for i, j in enumerate(bvh.joints)]
    return pos, ends


def _all_points(bvh: BVHFile) -> np.ndarray:
    pos, ends = zero_pose(bvh)
    extra = [e for es in ends for e in es]
    return np.vstack([pos, *extra]) if extra else pos


def hip_height_units(bvh: BVHFile, C: np.ndarray) -> float:
    """The zero pose's hip height: root to the lowest point along the up axis [file units]."""
    up = C.T @ np.array([0.0, 0.0, 1.0])
    h = float(-(_all_points(bvh) @ up).min())
    if not h > 0:
        raise BVHError(f"{bvh.path}: the skeleton's zero pose has nothing below the root along "
                       "the up axis; check up= (and pass scale= [m per file unit])")
    return h


def detect_scale(bvh: BVHFile, C: np.ndarray) -> tuple[float, str, float]:
    """Guess the file's unit from the zero pose's hip height (root to the lowest point along
    the up axis): the candidate of :data:`UNITS` that brings it closest (in ratio) to
    :data:`HIP_HEIGHT_M`. Returns ``(scale [m/unit], unit name, hip height [file units])``;
    :class:`BVHError` if no candidate lands in :data:`HIP_HEIGHT_RANGE_M` (pass ``scale=``)."""
    h = hip_height_units(bvh, C)
    best = min(UNITS, key=lambda u: abs(math.log(h * u[1] / HIP_HEIGHT_M)))
    lo, hi = HIP_HEIGHT_RANGE_M
    if not lo <= h * best[1] <= hi:
        raise BVHError(
            f"{bvh.path}: hip height {h:g} file units matches no known unit for an adult "
            f"({', '.join(f'{n}: {h * s:.3g} m' for n, s in UNITS)}; expected "
            f"{lo}–{hi} m); pass scale= [m per file unit]")
    return best[1], best[0], h


@dataclass(frozen=True)
class LegChain:
    """One leg's BVH joints: ``hip`` (turns the thigh), ``knee`` (the shank), ``ankle`` (the
    foot) and ``toe`` (``None`` where the foot has no toe joint); indices into
    :attr:`BVHFile.joints`."""

    side: str
    hip: int
    knee: int
    ankle: int
    toe: int | None


def _descendants(bvh: BVHFile, i: int) -> list[int]:
    out, todo = [], bvh.children(i)
    while todo:
        k = todo.pop(0)
        out.append(k)
        todo.extend(bvh.children(k))
    return out


def _is_ancestor(bvh: BVHFile, a: int, b: int) -> bool:
    while b >= 0:
        b = bvh.joints[b].parent
        if b == a:
            return True
    return False


def find_legs(bvh: BVHFile, legs: Mapping[str, Mapping[str, str]] | None = None
              ) -> dict[str, LegChain]:
    """The two legs, from ``legs`` (``{"left": {"hip": …, "knee": …, "ankle": …, "toe": …},
    "right": …}``, BVH joint names, ``toe`` optional) or from the segment names
    (:func:`gdimitate.model.anthropometry.match_segment`: the first thigh/shank/foot joint of each
    side in file order; the toe is the ankle's first foot-segment child)."""
    names = [j.name for j in bvh.joints]
    out = {}
    for s in ("left", "right"):
        if legs is not None:
            if s not in legs:
                raise LegDetectionError(f"legs= must give 'left' and 'right'; got {list(legs)}")
            d = dict(legs[s])
            idx: dict[str, int | None] = {}
            for role in ("hip", "knee", "ankle", "toe"):
                n = d.get(role)
                if n is None and role == "toe":
                    idx[role] = None
                    continue
                if n not in names:
                    from ...errors import UnknownNameError

                    raise UnknownNameError("BVH joint", n, names)
                idx[role] = names.index(n)
        else:
            idx = {}
            for role, seg in (("hip", "thigh"), ("knee", "shank"), ("ankle", "foot")):
                c = [i for i, n in enumerate(names) if side_of(n) == s and match_segment(n) == seg]
                if not c:
                    raise LegDetectionError(
                        f"{bvh.path}: no {s} {seg} joint found by name (joints: {names}); pass "
                        "legs={'left': {'hip': …, 'knee': …, 'ankle': …, 'toe': …}, 'right': …} "
                        "with BVH joint names")
                idx[role] = c[0]
            found = idx["ankle"]
            assert found is not None  # set in the loop
            toes = [k for k in bvh.children(found) if match_segment(names[k]) == "foot"]
            idx["toe"] = toes[0] if toes else None
        hip, knee, ankle, toe = idx["hip"], idx["knee"], idx["ankle"], idx["toe"]
        assert hip is not None and knee is not None and ankle is not None  # found above
        chain = [hip, knee, ankle] + ([toe] if toe is not None else [])
        for a, b in zip(chain, chain[1:]):
            if not _is_ancestor(bvh, a, b):
                raise LegDetectionError(
                    f"{bvh.path}: {s} leg: {names[b]!r} is not below {names[a]!r} in the "
                    "hierarchy; pass legs= with the hip, knee, ankle (and toe) joints in order")
        out[s] = LegChain(s, hip, knee, ankle, toe)
    return out


def pitch_channel(bvh: BVHFile, joint: int, C: np.ndarray) -> str:
    """The rotation channel of ``joint`` whose axis is closest to our lateral axis (y) at the
    zero pose (every link frame below the root then has the file's axes, turned by ``C``)."""
    j = bvh.joints[joint]
    rot = [c for c in j.channels if c.endswith("rotation")]
    if not rot:
        raise LegDetectionError(f"{bvh.path}: leg joint {j.name!r} has no rotation channel")
    lat = {c: abs(float((C @ np.eye(3)["XYZ".index(c[0])])[1])) for c in rot}
    return max(rot, key=lambda c: lat[c])


@dataclass(frozen=True)
class Sole:
    """A foot's sole at the zero pose, in the ankle link's frame (file axes, metres):
    ``centre`` ``(3,)`` of the sole rectangle, ``below_ankle`` ``(3,)`` the sole plane's point
    under the ankle (the rectangle's rear edge), ``rotation`` ``(3, 3)`` (columns: the sole's
    forward, left and up axes),
    ``length`` heel to toe tip [m], ``width`` [m] = :data:`SOLE_WIDTH_RATIO` × length,
    ``height`` ankle above the sole plane [m]."""

    centre: np.ndarray
    below_ankle: np.ndarray
    rotation: np.ndarray
    length: float
    width: float
    height: float


#: How far the heel lies behind the ankle, as a fraction of the ankle-to-toe-tip distance [-]:
#: a skeleton has no heel point, and in adult feet about a fifth of the foot's length (heel to
#: toe tip) lies behind the ankle joint centre, i.e. 0.25 of what lies ahead of it.
HEEL_RATIO = 0.25
#: Sole width / sole length [-] (an adult's foot: ~0.10 m wide at ~0.26 m long ≈ 0.38; the
#: rectangle's width is kept a little inside the forefoot's).
SOLE_WIDTH_RATIO = 0.35


def _turn(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix ``(3, 3)`` by ``angle`` [rad] about the unit ``axis`` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def leg_splay(bvh: BVHFile, leg: LegChain, up: np.ndarray, fwd: np.ndarray) -> float:
    """Frontal-plane angle [rad] of ``leg``'s hip→ankle line from the downward vertical at
    the zero pose (file axes; ``up``, ``fwd`` unit vectors, ``fwd`` horizontal; positive:
    turned about ``fwd`` from −``up`` towards ``up × fwd``). A rest pose may splay the legs
    (CMU's skeletons: ≈ ±20°); a standing subject's legs hang at 0."""
    pos, _ = zero_pose(bvh)
    v = pos[leg.ankle] - pos[leg.hip]
    return float(math.atan2(v @ np.cross(up, fwd), -(v @ up)))


def _forward(pts: list[np.ndarray], a: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The horizontal direction ``(3,)`` (not normalised) from the ankle ``a`` to the most
    distal of the foot's points ``pts``."""
    far = max(pts, key=lambda p: float(np.linalg.norm((p - a) - ((p - a) @ up) * up)))
    return (far - a) - ((far - a) @ up) * up


def measure_sole(bvh: BVHFile, leg: LegChain, C: np.ndarray, scale: float) -> Sole:
    """The sole rectangle of ``leg``, measured with the leg hanging — the foot turned about
    the subject's forward axis by −:func:`leg_splay` about the ankle, as the hip's roll would
    turn it: a foot flat under a splayed rest pose's leg stands on its edge once the leg hangs
    under the hip (CMU's by 20°), so the sole is the plane of the hanging foot — and expressed
    at the zero pose: the plane through the lowest point of the foot (ankle, toe joint, End
    Sites below the ankle), from the heel (:data:`HEEL_RATIO` of the ankle-to-toe-tip distance
    behind the ankle: a BVH skeleton has no heel point) to the foot's most distal point (the
    toe's End Site, else the toe joint, else the foot's own End Site), along the horizontal
    direction from the ankle to that point."""
    pos, ends = zero_pose(bvh)
    up = C.T @ np.array([0.0, 0.0, 1.0])
    a = pos[leg.ankle]
    foot = [leg.ankle] + [k for k in _descendants(bvh, leg.ankle)]
    pts = [pos[k] for k in foot] + [e for k in foot for e in ends[k]]
    if len(pts) < 2:
        raise BVHError(f"{bvh.path}: the {leg.side} foot {bvh.joints[leg.ankle].name!r} has no "
                       "toe joint or End Site to measure its length from")
    axis = C.T @ np.array([1.0, 0.0, 0.0])  # the subject's forward (file axes)
    back = _turn(axis, leg_splay(bvh, leg, up, axis))  # hanging pose -> zero pose
    pts = [a + back.T @ (p - a) for p in pts]
    fwd = _forward(pts, a, up)
    low = min(float(p @ up) for p in pts)
    length = float(np.linalg.norm(fwd))
    if length * scale < 0.02:
        raise BVHError(f"{bvh.path}: the {leg.side} foot is {length * scale:.3f} m long at the "
                       "zero pose; a sole needs a horizontal foot (toe End Site ahead of the "
                       "ankle)")
    fwd /= length
    below = a - (a @ up - low) * up
    heel, toe = below - fwd * HEEL_RATIO * length, below + fwd * length
    total = (1 + HEEL_RATIO) * length * scale
    R = np.column_stack([fwd, np.cross(up, fwd), up])
    return Sole(centre=back @ ((heel + toe) / 2 - a) * scale,
                below_ankle=back @ (below - a) * scale, rotation=back @ R, length=total,
                width=SOLE_WIDTH_RATIO * total, height=float(a @ up - low) * scale)
