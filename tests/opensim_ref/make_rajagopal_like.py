"""Writes tests/data/osim/rajagopal_like.osim (the committed file; rerun after editing)."""

from pathlib import Path

import numpy as np


def v(*x):
    return " ".join(f"{float(a):.10g}" for a in x)


def coord(name, lo, hi, default=0.0):
    return (
        f'<Coordinate name="{name}"><default_value>{default}</default_value>'
        f"<range>{v(lo, hi)}</range><clamped>false</clamped><locked>false</locked></Coordinate>"
    )


def frame(name, parent, t=(0, 0, 0), o=(0, 0, 0)):
    return (
        f'<PhysicalOffsetFrame name="{name}"><socket_parent>{parent}</socket_parent>'
        f"<translation>{v(*t)}</translation><orientation>{v(*o)}</orientation>"
        "</PhysicalOffsetFrame>"
    )


def lin(s=1.0, b=0.0):
    return f"<LinearFunction><coefficients>{v(s, b)}</coefficients></LinearFunction>"


def const(c):
    return f"<Constant><value>{c}</value></Constant>"


def spline(kind, x, y):
    return f"<{kind}><x>{v(*x)}</x><y>{v(*y)}</y></{kind}>"


def ta(name, coord_, axis, func):
    return (
        f'<TransformAxis name="{name}"><function>{func}</function>'
        f"<coordinates>{coord_}</coordinates><axis>{v(*axis)}</axis></TransformAxis>"
    )


def custom(
    name, parent, child, coords, axes, pt=(0, 0, 0), po=(0, 0, 0), ct=(0, 0, 0), co=(0, 0, 0)
):
    pf, cf = f"{parent.split('/')[-1]}_offset_{name}", f"{child}_offset_{name}"
    return (
        f'<CustomJoint name="{name}"><socket_parent_frame>{pf}</socket_parent_frame>'
        f"<socket_child_frame>{cf}</socket_child_frame>"
        f"<coordinates>{''.join(coords)}</coordinates>"
        f"<frames>{frame(pf, parent, pt, po)}{frame(cf, '/bodyset/' + child, ct, co)}</frames>"
        f"<SpatialTransform>{''.join(axes)}</SpatialTransform></CustomJoint>"
    )


def simple(
    kind, name, parent, child, coords, pt=(0, 0, 0), po=(0, 0, 0), ct=(0, 0, 0), co=(0, 0, 0)
):
    pf, cf = f"{parent.split('/')[-1]}_offset_{name}", f"{child}_offset_{name}"
    return (
        f'<{kind} name="{name}"><socket_parent_frame>{pf}</socket_parent_frame>'
        f"<socket_child_frame>{cf}</socket_child_frame>"
        f"<coordinates>{''.join(coords)}</coordinates>"
        f"<frames>{frame(pf, parent, pt, po)}{frame(cf, '/bodyset/' + child, ct, co)}"
        f"</frames></{kind}>"
    )


def body(name, m, com, I):
    return (
        f'<Body name="{name}"><mass>{m}</mass><mass_center>{v(*com)}</mass_center>'
        f"<inertia>{v(*I)}</inertia></Body>"
    )


Z3 = [
    ta("translation1", "", (1, 0, 0), const(0)),
    ta("translation2", "", (0, 1, 0), const(0)),
    ta("translation3", "", (0, 0, 1), const(0)),
]
kx = np.linspace(0, 2.0944, 7)
bodies = [
    body("pelvis", 11.0, (-0.07, 0, 0), (0.10, 0.09, 0.06, 0, 0, 0)),
    body("femur_r", 9.0, (0, -0.17, 0), (0.15, 0.04, 0.16, 0, 0, 0)),
    body("tibia_r", 3.6, (0, -0.18, 0), (0.05, 0.005, 0.05, 0, 0, 0)),
    body("patella_r", 0.0862, (0, 0, 0), (2e-6, 2e-6, 2e-6, 0, 0, 0)),
    body("talus_r", 0.1, (0, 0, 0), (1e-3, 1e-3, 1e-3, 0, 0, 0)),
    body("calcn_r", 1.25, (0.1, 0.03, 0), (0.0014, 0.004, 0.004, 0, 0, 0)),
    body("toes_r", 0.2, (0.035, 0.006, -0.018), (1e-4, 2e-4, 1e-4, 0, 0, 0)),
    body("femur_l", 9.0, (0, -0.17, 0), (0.15, 0.04, 0.16, 0, 0, 0)),
    body("tibia_l", 3.6, (0, -0.18, 0), (0.05, 0.005, 0.05, 0, 0, 0)),
    body("talus_l", 0.1, (0, 0, 0), (1e-3, 1e-3, 1e-3, 0, 0, 0)),
    body("calcn_l", 1.25, (0.1, 0.03, 0), (0.0014, 0.004, 0.004, 0, 0, 0)),
    body("toes_l", 0.2, (0.035, 0.006, 0.018), (1e-4, 2e-4, 1e-4, 0, 0, 0)),
    body("torso", 30.0, (-0.03, 0.32, 0), (1.4, 0.7, 1.4, 0.01, 0, 0)),
    body("humerus_r", 2.0, (0, -0.16, 0), (0.012, 0.004, 0.013, 0, 0, 0)),
    body("ulna_r", 1.2, (0, -0.12, 0), (0.006, 0.001, 0.006, 0, 0, 0)),
    body("hand_r", 0.45, (0, -0.07, 0), (9e-4, 5e-4, 1e-3, 0, 0, 0)),
]
joints = [
    custom(
        "ground_pelvis",
        "/ground",
        "pelvis",
        [
            coord("pelvis_tilt", -1.57, 1.57),
            coord("pelvis_list", -1.57, 1.57),
            coord("pelvis_rotation", -1.57, 1.57),
            coord("pelvis_tx", -5, 5),
            coord("pelvis_ty", -1, 2, 0.95),
            coord("pelvis_tz", -3, 3),
        ],
        [
            ta("rotation1", "pelvis_tilt", (0, 0, 1), lin()),
            ta("rotation2", "pelvis_list", (1, 0, 0), lin()),
            ta("rotation3", "pelvis_rotation", (0, 1, 0), lin()),
            ta("translation1", "pelvis_tx", (1, 0, 0), lin()),
            ta("translation2", "pelvis_ty", (0, 1, 0), lin()),
            ta("translation3", "pelvis_tz", (0, 0, 1), lin()),
        ],
    ),
    custom(
        "hip_r",
        "/bodyset/pelvis",
        "femur_r",
        [
            coord("hip_flexion_r", -0.79, 2.09),
            coord("hip_adduction_r", -0.87, 0.52),
            coord("hip_rotation_r", -0.7, 0.7),
        ],
        [
            ta("rotation1", "hip_flexion_r", (0, 0, 1), lin()),
            ta("rotation2", "hip_adduction_r", (1, 0, 0), lin()),
            ta("rotation3", "hip_rotation_r", (0, 1, 0), lin()),
        ]
        + Z3,
        pt=(-0.056, -0.078, 0.077),
    ),
    # walker knee: knee_angle_r positive in flexion (about -z); rotations 2, 3 and translations
    # 1, 2 are splines of it, translation3 piecewise linear
    custom(
        "walker_knee_r",
        "/bodyset/femur_r",
        "tibia_r",
        [coord("knee_angle_r", 0, 2.0944)],
        [
            ta("rotation1", "knee_angle_r", (0, 0, -1), lin()),
            ta(
                "rotation2",
                "knee_angle_r",
                (1, 0, 0),
                spline("SimmSpline", kx, 0.05 * np.sin(kx / 1.3)),
            ),
            ta("rotation3", "knee_angle_r", (0, 1, 0), spline("SimmSpline", kx, 0.1 * kx / 2.0944)),
            ta(
                "translation1",
                "knee_angle_r",
                (1, 0, 0),
                spline("SimmSpline", kx, 0.005 * np.cos(1.6 * kx) - 0.002),
            ),
            ta(
                "translation2",
                "knee_angle_r",
                (0, 1, 0),
                spline("SimmSpline", kx, -0.396 - 0.012 * (kx / 2.0944) ** 2),
            ),
            ta(
                "translation3",
                "knee_angle_r",
                (0, 0, 1),
                spline("PiecewiseLinearFunction", (0, 0.8, 2.0944), (0.002, 0.004, 0.001)),
            ),
        ],
        pt=(-0.0045, 0, 0),
        po=(0, 0, 0.05),
        co=(0.02, 0, 0),
    ),
    custom(
        "patellofemoral_r",
        "/bodyset/femur_r",
        "patella_r",
        [coord("knee_angle_r_beta", 0, 2.0944)],
        [
            ta(
                "rotation1",
                "knee_angle_r_beta",
                (0, 0, 1),
                "<MultiplierFunction><function>"
                + spline("SimmSpline", kx, 0.3 * kx - 0.05 * kx**2)
                + "</function><scale>-1</scale></MultiplierFunction>",
            ),
            ta("rotation2", "", (1, 0, 0), const(0)),
            ta("rotation3", "", (0, 1, 0), const(0)),
            ta(
                "translation1",
                "knee_angle_r_beta",
                (1, 0, 0),
                spline("SimmSpline", kx, 0.05 - 0.02 * kx / 2.0944),
            ),
            ta(
                "translation2",
                "knee_angle_r_beta",
                (0, 1, 0),
                "<PolynomialFunction><coefficients>0.004 -0.012 -0.38</coefficients>"
                "</PolynomialFunction>",
            ),
            ta("translation3", "", (0, 0, 1), const(0.002)),
        ],
    ),
    simple(
        "PinJoint",
        "ankle_r",
        "/bodyset/tibia_r",
        "talus_r",
        [coord("ankle_angle_r", -0.7, 0.7)],
        pt=(-0.01, -0.40, 0),
        po=(0.175, -0.105, 0),
        co=(0.175, -0.105, 0),
    ),
    simple(
        "PinJoint",
        "subtalar_r",
        "/bodyset/talus_r",
        "calcn_r",
        [coord("subtalar_angle_r", -0.35, 0.35)],
        pt=(-0.049, -0.042, 0.008),
        po=(-1.768, 0.906, 1.819),
        co=(-1.768, 0.906, 1.819),
    ),
    simple("WeldJoint", "mtp_r", "/bodyset/calcn_r", "toes_r", [], pt=(0.18, -0.002, 0.001)),
    custom(
        "hip_l",
        "/bodyset/pelvis",
        "femur_l",
        [
            coord("hip_flexion_l", -0.79, 2.09),
            coord("hip_adduction_l", -0.87, 0.52),
            coord("hip_rotation_l", -0.7, 0.7),
        ],
        [
            ta("rotation1", "hip_flexion_l", (0, 0, 1), lin()),
            ta("rotation2", "hip_adduction_l", (1, 0, 0), lin(-1, 0.05)),
            ta("rotation3", "hip_rotation_l", (0, 1, 0), lin(-1, 0)),
        ]
        + Z3,
        pt=(-0.056, -0.078, -0.077),
    ),
    custom(
        "knee_l",
        "/bodyset/femur_l",
        "tibia_l",
        [coord("knee_angle_l", -2.0944, 0.17)],
        [
            ta("rotation1", "", (1, 0, 0), const(0)),
            ta("rotation2", "", (0, 1, 0), const(0)),
            ta("rotation3", "knee_angle_l", (0, 0, 1), lin()),
            ta(
                "translation1",
                "knee_angle_l",
                (1, 0, 0),
                spline("NaturalCubicSpline", -kx[::-1], -0.005 * np.cos(1.6 * kx[::-1]) + 0.002),
            ),
            ta(
                "translation2",
                "knee_angle_l",
                (0, 1, 0),
                spline("NaturalCubicSpline", -kx[::-1], -0.396 - 0.012 * (kx[::-1] / 2.0944) ** 2),
            ),
            ta("translation3", "", (0, 0, 1), const(0)),
        ],
    ),
    simple(
        "PinJoint",
        "ankle_l",
        "/bodyset/tibia_l",
        "talus_l",
        [coord("ankle_angle_l", -0.7, 0.7)],
        pt=(-0.01, -0.40, 0),
        po=(-0.175, 0.105, 0),
        co=(-0.175, 0.105, 0),
    ),
    simple(
        "PinJoint",
        "subtalar_l",
        "/bodyset/talus_l",
        "calcn_l",
        [coord("subtalar_angle_l", -0.35, 0.35)],
        pt=(-0.049, -0.042, -0.008),
        po=(1.768, -0.906, 1.819),
        co=(1.768, -0.906, 1.819),
    ),
    simple("WeldJoint", "mtp_l", "/bodyset/calcn_l", "toes_l", [], pt=(0.18, -0.002, -0.001)),
    custom(
        "back",
        "/bodyset/pelvis",
        "torso",
        [
            coord("lumbar_extension", -1.57, 1.57),
            coord("lumbar_bending", -1.57, 1.57),
            coord("lumbar_rotation", -1.57, 1.57),
        ],
        [
            ta("rotation1", "lumbar_extension", (0, 0, 1), lin(1, 0.1)),
            ta("rotation2", "lumbar_bending", (1, 0, 0), lin()),
            ta("rotation3", "lumbar_rotation", (0, 1, 0), lin()),
        ]
        + Z3,
        pt=(-0.1, 0.08, 0),
    ),
    simple(
        "BallJoint",
        "acromial_r",
        "/bodyset/torso",
        "humerus_r",
        [
            coord("arm_flex_r", -1.57, 1.57),
            coord("arm_add_r", -2.09, 1.57),
            coord("arm_rot_r", -1.57, 1.57),
        ],
        pt=(0.003, 0.37, 0.17),
    ),
    # an elbow whose rotation is half its coordinate (slope 0.5: not representable, held)
    custom(
        "elbow_r",
        "/bodyset/humerus_r",
        "ulna_r",
        [coord("elbow_flex_r", 0, 0.5, 0.2)],
        [ta("rotation1", "elbow_flex_r", (0.05, 0, 0.99875), lin(0.5, 0))] + Z3,
        pt=(0.013, -0.286, -0.01),
    ),
    simple(
        "UniversalJoint",
        "radius_hand_r",
        "/bodyset/ulna_r",
        "hand_r",
        [coord("wrist_flex_r", -1.2, 1.2), coord("wrist_dev_r", -0.4, 0.4)],
        pt=(0, -0.25, 0),
    ),
]
markers = [
    ("R.Heel", "calcn_r", (-0.01, 0.02, -0.005)),
    ("R.Toe", "calcn_r", (0.22, 0.02, 0.01)),
    ("R.Toe.Lat", "calcn_r", (0.17, 0.02, 0.05)),
    ("L.Heel", "calcn_l", (-0.01, 0.02, 0.005)),
    ("L.Toe", "calcn_l", (0.22, 0.02, -0.01)),
    ("R.Knee", "tibia_r", (0, 0, 0.05)),
    ("R.Patella", "patella_r", (0.01, 0, 0)),
    ("R.Hand", "hand_r", (0, -0.1, 0)),
    ("Sternum", "torso", (0.12, 0.3, 0)),
]
mk = "".join(
    f'<Marker name="{n}"><socket_parent_frame>/bodyset/{b}</socket_parent_frame>'
    f"<location>{v(*p)}</location><fixed>false</fixed></Marker>"
    for n, b, p in markers
)
doc = f"""<?xml version="1.0" encoding="UTF-8" ?>
<!-- Synthetic Rajagopal-2016-like model for gdimitate's tests (written by a script, CC0): walker
     knee with spline-coupled rotations/translations (knee positive in flexion), a patella on a
     coupled coordinate, PinJoint ankles/subtalar, WeldJoint toes, a BallJoint shoulder, a
     slope-0.5 elbow, a UniversalJoint wrist, slope -1 and intercepts on the left hip and back. -->
<OpenSimDocument Version="40000">
<Model name="rajagopal_like">
<gravity>0 -9.8065 0</gravity>
<Ground name="ground"/>
<BodySet name="bodyset"><objects>
{chr(10).join(bodies)}
</objects></BodySet>
<JointSet name="jointset"><objects>
{chr(10).join(joints)}
</objects></JointSet>
<MarkerSet name="markerset"><objects>{mk}</objects></MarkerSet>
</Model>
</OpenSimDocument>
"""
Path(__file__).resolve().parents[1].joinpath("data/osim/rajagopal_like.osim").write_text(doc)
