"""Masses and inertias of a BVH skeleton's links from de Leva's (1996) segment table.

Each BVH joint's link is the segment from the joint to its children (joints and End Sites).
Links are grouped by table segment (:func:`gdimitate.model.anthropometry.match_segment`, one group
per side for the limbs). A group's mass is its table fraction of the body mass, renormalised
over the groups the skeleton has; inside a group the mass is shared in proportion to the links'
lengths. A group of one link puts the centre of mass at the table's fraction along the segment
and uses the table's radii of gyration times the segment length; a group of several links
(e.g. the trunk of ``Hips``, ``LowerBack``, ``Spine``, ``Spine1``) puts each link's centre of
mass at its midpoint, with the group's radii times the link's length. Links whose names match
no segment get a share of the body mass equal to their share of the skeleton's total link
length, as rods with the shank's radii of gyration (a warning names them). Zero-length links
and the intermediate links of multi-channel joints get :data:`TINY_MASS` and
:data:`TINY_INERTIA` (MuJoCo needs positive masses for moving bodies); the rest is scaled so
that the total is exactly the body mass.

The inertia's principal axes: the segment's direction (longitudinal), the antero-posterior
axis (the skeleton's forward, orthogonalised; the table's "sagittal" radius is read as the
radius about it) and the medio-lateral axis ("transverse"), at the zero pose.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ...errors import BVHError
from ...model.anthropometry import DE_LEVA_MALE, match_segment, side_of
from .parse import BVHFile

__all__ = ["TINY_MASS", "TINY_INERTIA", "LinkInertia", "segment_inertias"]

#: Mass [kg] of massless links (zero-length segments, intermediate channel links).
TINY_MASS = 1e-6
#: Principal moment [kg·m²] of massless links.
TINY_INERTIA = 1e-9


@dataclass(frozen=True)
class LinkInertia:
    """A link's ``mass`` [kg], ``com`` ``(3,)`` [m] and ``inertia`` ``(3, 3)`` [kg·m²] about the
    centre of mass, both in the link's frame; ``segment``: the table row used (``None``:
    unmatched, or a massless link)."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    segment: str | None


def tiny() -> LinkInertia:
    """A massless link's inertia (:data:`TINY_MASS`, :data:`TINY_INERTIA`)."""
    return LinkInertia(TINY_MASS, np.zeros(3), np.eye(3) * TINY_INERTIA, None)


def _axes(d: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Longitudinal, antero-posterior and medio-lateral unit axes (file axes) of a segment
    along ``d``."""
    up = C.T @ np.array([0.0, 0.0, 1.0])
    fwd = C.T @ np.array([1.0, 0.0, 0.0])
    n = np.linalg.norm(d)
    e = d / n if n > 0 else up
    ap = fwd - (fwd @ e) * e
    if np.linalg.norm(ap) < 1e-6:
        ap = up - (up @ e) * e
    ap /= np.linalg.norm(ap)
    return e, ap, np.cross(e, ap)


def segment_inertias(bvh: BVHFile, C: np.ndarray, scale: float, mass: float,
                     n_tiny_extra: int = 0) -> tuple[list[LinkInertia], tuple[str, ...]]:
    """One :class:`LinkInertia` per BVH joint (file order) and the names of the unmatched
    links. ``n_tiny_extra``: how many other massless links the URDF has (their
    :data:`TINY_MASS` is taken out of ``mass`` so that the total stays ``mass``)."""
    J = len(bvh.joints)
    vecs = []
    for i, j in enumerate(bvh.joints):
        v = [bvh.joints[k].offset for k in bvh.children(i)] + list(j.end_sites)
        vecs.append(np.array(v) * scale if v else np.zeros((0, 3)))
    length = np.array([np.linalg.norm(v, axis=1).max() if len(v) else 0.0 for v in vecs])
    seg = [match_segment(j.name) for j in bvh.joints]
    unmatched_idx = [i for i in range(J) if seg[i] is None and length[i] > 0]
    unmatched = tuple(bvh.joints[i].name for i in unmatched_idx)
    if unmatched:
        warnings.warn(f"{bvh.path}: segments not in the anthropometric table (mass by length "
                      f"instead): {list(unmatched)}", stacklevel=3)
    groups: dict[tuple[str, str | None], list[int]] = {}
    for i, s in enumerate(seg):
        if s is not None and length[i] > 0:
            key = (s, side_of(bvh.joints[i].name) if DE_LEVA_MALE[s].paired else None)
            groups.setdefault(key, []).append(i)
    if not groups and not unmatched:
        raise BVHError(f"{bvh.path}: every link has zero length; no mass can be placed")
    n_massless = int(np.sum(length == 0))
    budget = mass - TINY_MASS * (n_massless + n_tiny_extra)
    L_unmatched = float(length[unmatched_idx].sum())
    m_unmatched = budget * L_unmatched / float(length.sum())
    fsum = sum(DE_LEVA_MALE[k[0]].mass for k in groups)
    out: list[LinkInertia] = [tiny() for _ in range(J)]
    for key, members in groups.items():
        row = DE_LEVA_MALE[key[0]]
        M = (budget - m_unmatched) * row.mass / fsum
        L = length[members]
        single = len(members) == 1
        for i, Li in zip(members, L):
            out[i] = _link(vecs[i], M * Li / L.sum(), row.com if single else 0.5,
                           (row.r_sagittal, row.r_transverse, row.r_longitudinal), Li, C, key[0])
    rod = DE_LEVA_MALE["shank"]  # unmatched links: limb-like rods
    for i in unmatched_idx:
        out[i] = _link(vecs[i], m_unmatched * length[i] / L_unmatched, 0.5,
                       (rod.r_sagittal, rod.r_transverse, rod.r_longitudinal), length[i], C, None)
    return out, unmatched


def _link(v: np.ndarray, m: float, com_frac: float, radii: tuple[float, float, float],
          L: float, C: np.ndarray, segment: str | None) -> LinkInertia:
    d = v.mean(axis=0) if len(v) > 1 else v[0]
    if len(v) > 1 and np.linalg.norm(d) < 0.25 * L:
        # children spread around the joint (the hips → legs and spine): their centroid
        com = np.vstack([np.zeros(3), v]).mean(axis=0)
    else:
        com = com_frac * d
    e, ap, ml = _axes(d, C)
    rs, rt, rl = radii
    inertia = _principal(m * (rs * L) ** 2, m * (rt * L) ** 2, m * (rl * L) ** 2, ap, ml, e)
    return LinkInertia(float(m), com, inertia, segment)


def _principal(i_ap: float, i_ml: float, i_long: float, ap: np.ndarray, ml: np.ndarray,
               e: np.ndarray) -> np.ndarray:
    """The tensor with moments ``i_ap``, ``i_ml``, ``i_long`` about the orthonormal axes
    ``ap``, ``ml``, ``e``."""
    R = np.column_stack([ap, ml, e])
    return R @ np.diag([i_ap, i_ml, i_long]) @ R.T
