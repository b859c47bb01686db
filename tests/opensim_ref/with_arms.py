"""A synthetic full-body OpenSim model: the shipped subject01 (gait2354, no arms) with two
Rajagopal-style arms added to its torso — ``acromial_{r,l}`` (``arm_flex`` about Z, ``arm_add``
about ±X, ``arm_rot`` about ±Y) and ``elbow_{r,l}`` (``elbow_flex`` about Rajagopal's tilted
axis), upper arm 2.03 kg, forearm and hand 1.6 kg, the torso lighter by the same (total mass
unchanged) — and a walk for it: subject01's IK angles with arms that swing against the legs.
Test helper (no OpenSim needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

ARM = 2.03
FOREARM = 1.6


def _coord(name: str, lo: float, hi: float) -> str:
    return (f'<Coordinate name="{name}"><motion_type> rotational </motion_type>'
            f"<default_value> 0 </default_value><range> {lo} {hi} </range>"
            "<clamped> false </clamped><locked> false </locked></Coordinate>")


def _axis(name: str, coord: str | None, axis) -> str:
    f = ('<LinearFunction name=""><coefficients> 1 0 </coefficients></LinearFunction>'
         if coord else '<Constant name=""><value> 0 </value></Constant>')
    return (f'<TransformAxis name="{name}"><function>{f}</function>'
            f"<coordinates> {coord or ''} </coordinates><axis> {' '.join(map(str, axis))} "
            "</axis></TransformAxis>")


def _body(name, mass, com, inertia, joint, parent, loc, coords, rots) -> str:
    axes = [_axis(f"rotation{i + 1}", c, a) for i, (c, a) in enumerate(rots)]
    axes += [_axis(f"rotation{i + 1}", None, a) for i, a in
             enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1))) if i >= len(rots)]
    axes += [_axis(f"translation{i + 1}", None, a) for i, a in
             enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1)))]
    ixx, iyy, izz = inertia
    return (f'<Body name="{name}"><mass> {mass} </mass><mass_center> {" ".join(map(str, com))} '
            f"</mass_center><inertia_xx> {ixx} </inertia_xx><inertia_yy> {iyy} </inertia_yy>"
            f"<inertia_zz> {izz} </inertia_zz><inertia_xy> 0 </inertia_xy><inertia_xz> 0 "
            "</inertia_xz><inertia_yz> 0 </inertia_yz><Joint>"
            f'<CustomJoint name="{joint}"><parent_body> {parent} </parent_body>'
            f"<location_in_parent> {' '.join(map(str, loc))} </location_in_parent>"
            "<orientation_in_parent> 0 0 0 </orientation_in_parent><location> 0 0 0 "
            "</location><orientation> 0 0 0 </orientation>"
            f'<CoordinateSet name=""><objects>{"".join(coords)}</objects></CoordinateSet>'
            f'<SpatialTransform name="">{"".join(axes)}</SpatialTransform></CustomJoint>'
            "</Joint></Body>")


def arms_xml() -> str:
    out = []
    for s, m in (("r", 1), ("l", -1)):
        out.append(_body(
            f"humerus_{s}", ARM, (0, -0.164502, 0), (0.011946, 0.004121, 0.013409),
            f"acromial_{s}", "torso", (0.003155, 0.3715, m * 0.17),
            [_coord(f"arm_flex_{s}", -1.57, 1.57), _coord(f"arm_add_{s}", -2.09, 1.57),
             _coord(f"arm_rot_{s}", -1.57, 1.57)],
            [(f"arm_flex_{s}", (0, 0, 1)), (f"arm_add_{s}", (m, 0, 0)),
             (f"arm_rot_{s}", (0, m, 0))]))
        out.append(_body(
            f"ulna_{s}", FOREARM, (0, -0.15, 0), (0.0104, 0.0021, 0.0110),
            f"elbow_{s}", f"humerus_{s}", (0.013144, -0.286273, -m * 0.009595),
            [_coord(f"elbow_flex_{s}", 0, 2.618)],
            [(f"elbow_flex_{s}", (m * 0.0494, m * 0.0366, 0.9981))]))
    return "".join(out)


def write_model(subject: Path, out: Path) -> Path:
    """subject01.osim with arms → ``out``."""
    text = subject.read_text()
    start = text.index('<Body name="torso">')
    end = text.index("</Body>", start) + len("</Body>")
    torso = text[start:end]
    m0 = torso.split("<mass>")[1].split("</mass>")[0]
    torso = torso.replace(f"<mass>{m0}</mass>",
                          f"<mass> {float(m0) - 2 * (ARM + FOREARM):.8f} </mass>", 1)
    out.write_text(text[:start] + torso + arms_xml() + text[end:])
    return out


def arm_swing(robot, motion, amplitude: float = 0.6):
    """``motion`` (subject01's walk on the armed model) with arms that swing against the legs:
    ``arm_flex_s = −amplitude · (hip_flexion_s − its mean)`` [rad], elbows at
    0.3 + 0.5 · that swing (flexing as the arm swings forward), ``arm_add`` −0.1 rad (the
    hands clear of the hips)."""
    q = motion.q.copy()
    for s in ("r", "l"):
        hip = q[:, robot.idx_q(f"hip_flexion_{s}")]
        swing = -amplitude * (hip - hip.mean())
        q[:, robot.idx_q(f"arm_flex_{s}")] = swing
        q[:, robot.idx_q(f"elbow_flex_{s}")] = 0.3 + 0.5 * np.clip(swing, 0, None)
        q[:, robot.idx_q(f"arm_add_{s}")] = -0.1
    return motion.replace(q=q)
