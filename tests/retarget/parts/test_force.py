"""The ``segment`` force model on a leg whose shank is not in the robot's x–z plane.

``retarget.parts.force`` divides the imitator's shank vector (ankle → knee) by the shank's
3-D length, so that it is a unit vector for any leg axes. The robot is
``tests/adaptation/test_any_leg_axes.py``'s biped with knees tilted 30° from the lateral axis, its
ankles moved 6 cm outwards below the knees (the shank splayed: 3-D length √(0.3² + 0.06²) m, x–z
extent 0.3 m at the neutral pose). Reference: Pinocchio's forward kinematics of the same model
at random configurations; with ``d`` the unit vector from ankle to knee, the rows
``e1·c, e2·c, d·c`` are exactly ``0, 0, 1`` (``d·c`` was 1.0198 with the x–z length).
"""

from __future__ import annotations

import re

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

import gdimitate as gd
from gdimitate.model.robot import SIDES
from gdimitate.retarget import parts as P
from gdimitate.retarget.knot import Flags, Knot
from gdimitate.retarget.trajectory.problem import symbolic_model
from tests.adaptation.test_any_leg_axes import LEG, biped_urdf

SPLAY = 0.06  # [m] each ankle's lateral offset from its knee


def _splayed(tmp_path):
    text = biped_urdf("tilted")
    for s, y in (("left", SPLAY), ("right", -SPLAY)):
        pat = (rf'(<joint name="{s}_ankle" type="revolute"><parent link="{s}_shank"/>'
               rf'<child link="{s}_ankle_link"/><origin xyz=")0 0 ')
        text, n = re.subn(pat, rf"\g<1>0 {y} ", text)
        assert n == 1
    path = tmp_path / "splayed.urdf"
    path.write_text(text)
    return gd.Robot.from_urdf(path, name="test_knee_tilted_splayed_shank")


@pytest.mark.parametrize("cone", [False, True])
def test_segment_vector_is_a_unit_vector_for_a_splayed_shank(tmp_path, cone):
    r = _splayed(tmp_path)
    shank = float(np.hypot(LEG, SPLAY))
    for s in SIDES:  # the leg's measurements: 3-D length vs x–z extent
        assert r.legs[s].segments[1] == pytest.approx(shank, abs=1e-12)
        assert r.legs[s].shank == pytest.approx(LEG, abs=1e-12)
    part = P.ForceDirection()
    sym = symbolic_model(r)
    k = Knot(r, sym, Flags(goal="segment", cone=cone))
    k.add_slacks(0)
    f = ca.Function("rows", [k.x, k.p], [part.rows(k)])
    m, d = r.model, r.model.createData()
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = pin.randomConfiguration(m, np.maximum(m.lowerPositionLimit, -1.0),
                                    np.minimum(m.upperPositionLimit, 1.0))
        pin.framesForwardKinematics(m, d, q)
        x = np.zeros(k.var.size)
        x[k.var["q"]] = q
        p = rng.uniform(0.1, 1.0, size=k.par.size)
        ref = []
        for s in SIDES:
            leg = r.legs[s]
            u = (d.oMf[m.getFrameId(leg.knee)].translation
                 - d.oMf[m.getFrameId(leg.ankle)].translation)
            assert np.linalg.norm(u) == pytest.approx(shank, abs=1e-12)  # rigid
            u = u / np.linalg.norm(u)
            e1 = np.cross(u, rng.normal(size=3))
            e1 /= np.linalg.norm(e1)
            p[k.par[f"d_{s}"]], p[k.par[f"e1_{s}"]], p[k.par[f"e2_{s}"]] = u, e1, np.cross(u, e1)
            ref += [-p[k.par["tan2"]][0], 1.0] if cone else [0.0, 0.0, 1.0]
        np.testing.assert_allclose(np.array(f(x, p)).ravel(), ref, atol=1e-12)
