"""Body-segment parameters of an adult human, matched to skeleton segment names.

The table is de Leva's adjustment of Zatsiorsky–Seluyanov's data for adult males
(P. de Leva, "Adjustments to Zatsiorsky-Seluyanov's segment inertia parameters",
J. Biomechanics 29(9):1223–1230, 1996, Table 4): for each segment its mass as a fraction of
the body mass, the position of its centre of mass as a fraction of the segment length from the
proximal joint, and its radii of gyration about the centre of mass as fractions of the segment
length — about the sagittal (antero-posterior) axis, the transverse (medio-lateral) axis and the
longitudinal axis. The fractions of one trunk, one head and two of each limb segment sum to 1.

:func:`match_segment` assigns a skeleton segment name to a table row by name patterns covering
the common motion-capture conventions: CMU's ASF names (``root``, ``lhipjoint``, ``lfemur``,
``ltibia``, ``lfoot``, ``ltoes``, ``lowerback``, ``thorax``, ``lclavicle``, ``lhumerus``,
``lradius``, ``lwrist``, ``lhand``, ``lthumb`` …), the MotionBuilder/SFU/Mixamo names
(``Hips``, ``LeftUpLeg``, ``LeftLeg``, ``LeftFoot``, ``LeftToeBase``, ``Spine1``,
``LeftShoulder``, ``LeftArm``, ``LeftForeArm``, ``LeftHand`` …, with or without a
``mixamorig:`` style prefix) and plain anatomical names (``pelvis``, ``thigh``, ``shank``,
``knee``, ``ankle``, ``upperarm``, ``elbow`` …).
"""

from __future__ import annotations

import re
from typing import NamedTuple

__all__ = ["Segment", "DE_LEVA_MALE", "match_segment", "side_of"]


class Segment(NamedTuple):
    """One row of the segment table.

    ``mass``: fraction of the body mass [-]; ``com``: centre of mass along the segment from the
    proximal joint, fraction of the segment length [-]; ``r_sagittal``, ``r_transverse``,
    ``r_longitudinal``: radii of gyration about the centre of mass, about the antero-posterior,
    medio-lateral and longitudinal axes, fractions of the segment length [-]; ``paired``: one
    per side (limbs) or one per body (head, trunk)."""

    mass: float
    com: float
    r_sagittal: float
    r_transverse: float
    r_longitudinal: float
    paired: bool


#: de Leva (1996), Table 4, males. Trunk: the whole trunk between the hip joint centres'
#: midpoint and the cervicale (it includes the pelvis and the shoulder girdle); head: head and
#: neck (cervicale to vertex); foot: heel to toe tip; hand: wrist to the third metacarpal. The
#: centre-of-mass fractions of the head and the trunk are counted from their lower end (the
#: table counts them from the top: 50.02 % and 51.38 %), the end a skeleton's chain reaches
#: first from the hips.
DE_LEVA_MALE: dict[str, Segment] = {
    "head": Segment(0.0694, 0.4998, 0.303, 0.315, 0.261, False),
    "trunk": Segment(0.4346, 0.4862, 0.328, 0.306, 0.169, False),
    "upper_arm": Segment(0.0271, 0.5772, 0.285, 0.269, 0.158, True),
    "forearm": Segment(0.0162, 0.4574, 0.276, 0.265, 0.121, True),
    "hand": Segment(0.0061, 0.7900, 0.628, 0.513, 0.401, True),
    "thigh": Segment(0.1416, 0.4095, 0.329, 0.329, 0.149, True),
    "shank": Segment(0.0433, 0.4459, 0.255, 0.249, 0.103, True),
    "foot": Segment(0.0137, 0.4415, 0.257, 0.245, 0.124, True),
}

# Order matters: the first pattern that matches wins (e.g. "upleg" before "leg", "forearm"
# before "arm", "hipjoint" → trunk before "hip" → thigh).
_PATTERNS: tuple[tuple[str, str], ...] = (
    ("hand", r"hand|wrist|finger|thumb|index|middle|ring|pinky|carpal|palm"),
    ("forearm", r"fore.?arm|radius|ulna|elbow|lower.?arm"),
    ("upper_arm", r"up.?arm|upper.?arm|humerus|^arm"),
    ("trunk", r"hips?joint|hip_?joint|hips$|^root$|pelvis|spine|back|chest|torso|thorax|abdomen"
              r"|waist|clavicle|collar|shoulder|lumbar|sternum"),
    ("head", r"head|neck|skull|jaw|eye|nose"),
    ("thigh", r"up.?leg|upper.?leg|femur|thigh|^hip$"),
    ("foot", r"foot|ankle|toe|heel|talus|calcn|ball"),
    ("shank", r"leg|tibia|shin|knee|calf|shank"),
)

_LEFT = re.compile(r"^(left|l(?=[_\W]|[A-Z]|femur|tibia|foot|toes|hipjoint|clavicle|humerus"
                   r"|radius|wrist|hand|fingers|thumb|shoulder|thigh|shin|arm|leg|up|fore))",
                   re.I)
_RIGHT = re.compile(r"^(right|r(?=[_\W]|[A-Z]|femur|tibia|foot|toes|hipjoint|clavicle|humerus"
                    r"|radius|wrist|hand|fingers|thumb|shoulder|thigh|shin|arm|leg|up|fore))",
                    re.I)


def _bare(name: str) -> str:
    """The name without an exporter prefix (``mixamorig:LeftUpLeg`` → ``LeftUpLeg``,
    ``Bip01 L Thigh`` → ``L Thigh``, ``Character1_LeftFoot`` → ``LeftFoot``)."""
    n = re.split(r"[:|]", name)[-1]
    n = re.sub(r"^(bip0?1|character\d*|root_?)[ _]?", "", n, flags=re.I) or n
    return n.strip()


def side_of(name: str) -> str | None:
    """``"left"``, ``"right"`` or ``None`` from a segment name's side token (``Left…``,
    ``L…`` before a capital, ``l_``, CMU's ``lfemur``/``rtibia``; also ``…_l``/``…_r`` and
    ``.L``/``.R`` suffixes)."""
    n = _bare(name)
    if _LEFT.match(n) and not re.match(r"^(leg|lower|lumbar)", n, re.I):
        return "left"
    if _RIGHT.match(n) and not re.match(r"^(ring|root|radius)", n, re.I):
        return "right"
    if re.search(r"[_.\s]l$|_left$", n, re.I):
        return "left"
    if re.search(r"[_.\s]r$|_right$", n, re.I):
        return "right"
    return None


def match_segment(name: str) -> str | None:
    """The :data:`DE_LEVA_MALE` row (``"thigh"``, ``"shank"``, ``"foot"``, ``"trunk"``,
    ``"head"``, ``"upper_arm"``, ``"forearm"``, ``"hand"``) whose name pattern the segment's
    name matches, or ``None``. The side token is removed first (``LeftLeg`` → ``Leg`` →
    shank, ``LeftUpLeg`` → thigh, ``lfemur`` → thigh, ``LHipJoint`` → trunk)."""
    n = _bare(name)
    if side_of(name) is not None:
        stripped = re.sub(r"^(left|right)[_\s]?", "", n, flags=re.I)
        if stripped == n:
            stripped = re.sub(r"^[lr][_\s]?", "", n, flags=re.I)
        if re.search(r"([_.\s][lr]|_left|_right)$", n, re.I):
            stripped = re.sub(r"([_.\s][lr]|_left|_right)$", "", n, flags=re.I)
        n = stripped
    for segment, pattern in _PATTERNS:
        if re.search(pattern, n, re.I):
            return segment
    return None
