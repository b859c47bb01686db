"""One generator for our planar biped URDFs (``urdf/*.urdf``).

A planar biped is a torso on a planar floating base — prismatic ``base_x`` (axis +x), prismatic
``base_z`` (axis +z) and revolute ``base_pitch`` — and two legs, each with revolute ``*_hip``,
``*_knee``, ``*_ankle`` joints and a foot ending in a ``*_sole`` frame directly below the
ankle. Every revolute joint turns about **−y**, so a positive angle moves the distal end
forward (+x): the joint angle *is* docs/design.md §4's planar angle (hip: thigh relative to the
torso;
knee: negative in flexion; ankle: positive in dorsiflexion), and ``base_pitch`` has the sign of
OpenSim's ``pelvis_tilt``. The base origin is the midpoint between the hips.

Mass distribution (Winter, *Biomechanics and Motor Control of Human Movement*, 4th ed., 2009,
Table 4.1): per leg thigh 10.0 %, shank 4.65 %, foot 1.45 % of the total mass; the torso
(head, arms, trunk) carries the rest (67.8 %). Centres of mass sit 43.3 % down the thigh and
shank from their proximal joint; segments are modelled as slender rods (thigh, shank, torso) and
a box (foot) for their inertias. Visual geometry: boxes and cylinders, so the models draw in
meshcat without meshes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["PlanarBipedSpec", "PLANAR_MODELS", "planar_biped_urdf", "write_planar_models",
           "MASS_FRACTIONS", "PLANAR_BASE"]

#: Joint names of our planar floating base (x, z, pitch), in q order.
PLANAR_BASE = ("base_x", "base_z", "base_pitch")

#: Winter (2009) Table 4.1 mass fractions of the whole body.
MASS_FRACTIONS = {"thigh": 0.100, "shank": 0.0465, "foot": 0.0145}
COM_FRACTION = 0.433  # thigh and shank CoM from the proximal joint (Winter 2009)


@dataclass(frozen=True)
class PlanarBipedSpec:
    """Dimensions [m], mass [kg] and limits of one planar biped.

    ``foot``: ankle-to-sole height; ``toe``/``heel``: sole extent in front of/behind the ankle;
    ``hip_width``: distance between the two hip joints; ``torso``: torso length above the hips.
    Limits: hip/knee/ankle ``(lower, upper)`` [rad], ``velocity`` [rad/s], ``effort`` [N·m].
    """

    name: str
    thigh: float
    shank: float
    foot: float
    mass: float
    hip_width: float
    torso: float
    toe: float
    heel: float
    hip_limits: tuple[float, float] = (-1.57, 1.57)
    knee_limits: tuple[float, float] = (-2.4, 0.0)
    ankle_limits: tuple[float, float] = (-0.8, 0.8)
    velocity: float = 10.0
    effort: float = 100.0
    note: str = ""

    @property
    def leg_length(self) -> float:
        """Thigh + shank [m] (docs/design.md §4's L)."""
        return self.thigh + self.shank


def _spec(name: str, thigh: float, shank: float, mass: float, note: str, **kw) -> PlanarBipedSpec:
    L = thigh + shank
    defaults: dict[str, Any] = dict(foot=0.16 * L, hip_width=0.2 * L, torso=0.9 * L,
                                    toe=0.25 * L, heel=0.07 * L)
    defaults.update(kw)
    return PlanarBipedSpec(name=name, thigh=thigh, shank=shank, mass=mass, note=note, **defaults)


#: The models committed in ``urdf/`` (name → spec). The paper's lengths (docs/design.md §4).
PLANAR_MODELS: dict[str, PlanarBipedSpec] = {
    s.name: s
    for s in [
        _spec("case1_demonstrator", 0.40, 0.60, 70.0, "paper Case I demonstrator (40/60 cm)",
              effort=400.0),
        _spec("case2_demonstrator", 0.06, 0.04, 1.5, "paper Case II demonstrator (6/4 cm)",
              effort=5.0),
        _spec("humanoid_demonstrator", 0.3325, 0.30, 50.0,
              "paper humanoid-case demonstrator (33.25/30 cm)", effort=300.0),
        _spec("humanoid_imitator", 0.4325, 0.20, 50.0,
              "paper humanoid-case imitator (43.25/20 cm)", effort=300.0),
        _spec("hoap2", 0.10, 0.10, 7.0, "HOAP-2-sized imitator (Fujitsu HOAP-2: ~50 cm, 7 kg)",
              foot=0.035, hip_width=0.078, torso=0.26, toe=0.06, heel=0.035,
              hip_limits=(-1.57, 1.57), knee_limits=(-2.36, 0.0), ankle_limits=(-1.05, 1.05),
              velocity=6.0, effort=3.0),
    ]
}


def _f(x: float) -> str:
    """Fixed, platform-independent number formatting (so regenerated files compare equal)."""
    s = f"{x:.6g}"
    return "0" if s == "-0" else s


def _inertial(mass: float, com: tuple[float, float, float], ixx: float, iyy: float,
              izz: float) -> str:
    return (
        f'    <inertial>\n      <origin xyz="{" ".join(_f(c) for c in com)}" rpy="0 0 0"/>\n'
        f'      <mass value="{_f(mass)}"/>\n'
        f'      <inertia ixx="{_f(ixx)}" ixy="0" ixz="0" iyy="{_f(iyy)}" iyz="0" '
        f'izz="{_f(izz)}"/>\n'
        "    </inertial>\n"
    )


def _rod(mass: float, length: float, com_z: float, radius: float, color: str) -> str:
    """A link modelled as a slender rod along z (inertia about its CoM) with a cylinder visual."""
    i_t = mass * length**2 / 12.0
    i_a = 0.5 * mass * radius**2
    return _inertial(mass, (0.0, 0.0, com_z), i_t, i_t, i_a) + (
        f'    <visual>\n      <origin xyz="0 0 {_f(-length / 2 if com_z < 0 else length / 2)}" '
        f'rpy="0 0 0"/>\n      <geometry><cylinder radius="{_f(radius)}" '
        f'length="{_f(length)}"/></geometry>\n'
        f'      <material name="{color}"/>\n    </visual>\n'
    )


def planar_biped_urdf(spec: PlanarBipedSpec) -> str:
    """The URDF text of one planar biped (deterministic: same spec, same bytes)."""
    L = spec.leg_length
    m = spec.mass
    r = 0.04 * L  # visual radius of leg segments
    foot_len = spec.toe + spec.heel
    out = [
        '<?xml version="1.0"?>\n',
        "<!-- Generated by gdimitate.model.urdfgen.planar_biped_urdf; do not edit. "
        f"{spec.note} -->\n",
        f'<robot name="{spec.name}">\n',
        '  <material name="torso"><color rgba="0.55 0.6 0.7 1"/></material>\n',
        '  <material name="left"><color rgba="0.85 0.45 0.2 1"/></material>\n',
        '  <material name="right"><color rgba="0.25 0.5 0.85 1"/></material>\n',
        '  <link name="world"/>\n  <link name="base_x_link"/>\n  <link name="base_z_link"/>\n',
    ]
    lim = 'effort="0" velocity="100"'
    out.append(
        '  <joint name="base_x" type="prismatic">\n    <parent link="world"/>'
        '<child link="base_x_link"/>\n    <axis xyz="1 0 0"/>'
        f'<limit lower="-100" upper="100" {lim}/>\n  </joint>\n'
        '  <joint name="base_z" type="prismatic">\n    <parent link="base_x_link"/>'
        '<child link="base_z_link"/>\n    <axis xyz="0 0 1"/>'
        f'<limit lower="-10" upper="10" {lim}/>\n  </joint>\n'
        '  <joint name="base_pitch" type="revolute">\n    <parent link="base_z_link"/>'
        '<child link="torso"/>\n    <axis xyz="0 -1 0"/>'
        f'<limit lower="-1.57" upper="1.57" {lim}/>\n  </joint>\n'
    )
    m_torso = m * (1.0 - 2.0 * sum(MASS_FRACTIONS.values()))
    torso = _rod(m_torso, spec.torso, spec.torso / 2, 0.1 * L, "torso")
    out.append(f'  <link name="torso">\n{torso}  </link>\n')
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        y = sgn * spec.hip_width / 2
        limits = {"hip": spec.hip_limits, "knee": spec.knee_limits, "ankle": spec.ankle_limits}
        parents = {"hip": ("torso", f"0 {_f(y)} 0"),
                   "knee": (f"{side}_thigh", f"0 0 {_f(-spec.thigh)}"),
                   "ankle": (f"{side}_shank", f"0 0 {_f(-spec.shank)}")}
        children = {"hip": f"{side}_thigh", "knee": f"{side}_shank", "ankle": f"{side}_foot"}
        for joint in ("hip", "knee", "ankle"):
            parent, xyz = parents[joint]
            lo, hi = limits[joint]
            out.append(
                f'  <joint name="{side}_{joint}" type="revolute">\n'
                f'    <parent link="{parent}"/><child link="{children[joint]}"/>\n'
                f'    <origin xyz="{xyz}" rpy="0 0 0"/>\n    <axis xyz="0 -1 0"/>\n'
                f'    <limit lower="{_f(lo)}" upper="{_f(hi)}" effort="{_f(spec.effort)}" '
                f'velocity="{_f(spec.velocity)}"/>\n  </joint>\n'
            )
        for seg, length in (("thigh", spec.thigh), ("shank", spec.shank)):
            mass = m * MASS_FRACTIONS[seg]
            body = _inertial(mass, (0.0, 0.0, -COM_FRACTION * length), mass * length**2 / 12,
                             mass * length**2 / 12, 0.5 * mass * r**2)
            body += (
                f'    <visual>\n      <origin xyz="0 0 {_f(-length / 2)}" rpy="0 0 0"/>\n'
                f'      <geometry><cylinder radius="{_f(r)}" length="{_f(length)}"/></geometry>\n'
                f'      <material name="{side}"/>\n    </visual>\n'
            )
            out.append(f'  <link name="{side}_{seg}">\n{body}  </link>\n')
        mf = m * MASS_FRACTIONS["foot"]
        cx = (spec.toe - spec.heel) / 2
        w = 0.5 * spec.hip_width
        foot = _inertial(mf, (cx, 0.0, -spec.foot / 2), mf * (w**2 + spec.foot**2) / 12,
                         mf * (foot_len**2 + spec.foot**2) / 12, mf * (foot_len**2 + w**2) / 12)
        foot += (
            f'    <visual>\n      <origin xyz="{_f(cx)} 0 {_f(-spec.foot / 2)}" rpy="0 0 0"/>\n'
            f'      <geometry><box size="{_f(foot_len)} {_f(w)} {_f(spec.foot)}"/></geometry>\n'
            f'      <material name="{side}"/>\n    </visual>\n'
        )
        out.append(f'  <link name="{side}_foot">\n{foot}  </link>\n')
        out.append(
            f'  <link name="{side}_sole"/>\n'
            f'  <joint name="{side}_sole_joint" type="fixed">\n'
            f'    <parent link="{side}_foot"/><child link="{side}_sole"/>\n'
            f'    <origin xyz="0 0 {_f(-spec.foot)}" rpy="0 0 0"/>\n  </joint>\n'
        )
    out.append("</robot>\n")
    return "".join(out)


def human_spec(height: float = 1.75, mass: float = 70.0, name: str = "human_planar"
               ) -> PlanarBipedSpec:
    """A planar human demonstrator with Winter's (2009, Fig. 4.1) segment-length ratios.

    Thigh 0.245·H, shank 0.246·H, ankle height 0.039·H, foot length 0.152·H (ankle at about a
    quarter of it from the heel), hip-joint separation 0.1·H (about half the 0.191·H hip width),
    torso (hips to head top) 0.47·H. ``height`` [m], ``mass`` [kg].
    """
    if not (math.isfinite(height) and 0.2 <= height <= 3.0):
        from ..errors import InvalidInputError

        raise InvalidInputError(f"height must be a body height in metres (0.2–3), got {height!r}")
    foot_len = 0.152 * height
    return PlanarBipedSpec(
        name=name, thigh=0.245 * height, shank=0.246 * height, foot=0.039 * height, mass=mass,
        hip_width=0.1 * height, torso=0.47 * height, toe=0.75 * foot_len, heel=0.25 * foot_len,
        hip_limits=(-2.0, 2.0), knee_limits=(-2.6, 0.1), ankle_limits=(-0.9, 0.9),
        velocity=15.0, effort=300.0,
        note=f"planar human demonstrator, height {height:g} m (Winter 2009 ratios)",
    )


def write_planar_models(folder: str | Path) -> list[Path]:
    """Write every model of :data:`PLANAR_MODELS` as ``folder/<name>.urdf``; return the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, spec in PLANAR_MODELS.items():
        p = folder / f"{name}.urdf"
        p.write_text(planar_biped_urdf(spec))
        paths.append(p)
    return paths


if __name__ == "__main__":  # python -m gdimitate.model.urdfgen [folder]
    import sys

    for p in write_planar_models(sys.argv[1] if len(sys.argv) > 1 else "urdf"):
        print(p)
