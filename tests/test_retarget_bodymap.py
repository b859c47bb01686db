"""Body maps: presets pair joints whose axes agree (checked against Pinocchio's joint axes
and the robots' own leg sign conventions), user maps from dicts and JSON files, unknown names
listed, unmapped joints warned about."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from gdimitate.errors import InvalidInputError, UnknownNameError
from gdimitate.retarget import BodyMap, UnmappedJointsWarning, body_map


def _axis(robot, joint):
    m = robot.model
    jid = m.getJointId(joint)
    pin.computeJointJacobians(m, robot.data, robot.neutral)
    J = pin.getJointJacobian(m, robot.data, jid, pin.LOCAL_WORLD_ALIGNED)
    return J[3:, m.joints[jid].idx_v]


@pytest.mark.parametrize("name", ["talos", "g1", "icub", "hoap2"])
def test_planar_preset_signs_follow_the_leg_conventions(robot, name):
    d, i = robot("case1_demonstrator"), robot(name)
    with pytest.warns(UnmappedJointsWarning) if name != "hoap2" else _nowarn():
        bm = body_map(d, i)
    for s in ("left", "right"):
        dl, il = d.legs[s], i.legs[s]
        for k, (dj, ij) in enumerate(zip((dl.hip, dl.knee, dl.ankle), (il.hip, il.knee,
                                                                          il.ankle))):
            target, scale, offset = bm.joints[dj]
            assert target == ij and offset == 0.0
            # the planar angle sign·q is the same physical angle on both robots
            assert scale == dl.signs[k] * il.signs[k]
            a, b = _axis(d, dj), _axis(i, ij)
            assert np.sign(a @ b) == scale


class _nowarn:
    def __enter__(self):
        import warnings

        self._c = warnings.catch_warnings()
        self._c.__enter__()
        warnings.simplefilter("error", UnmappedJointsWarning)

    def __exit__(self, *exc):
        self._c.__exit__(*exc)
        return False


def test_user_maps_dict_and_json(robot, tmp_path):
    d, i = robot("case1_demonstrator"), robot("hoap2")
    spec = {"joints": {"left_knee": "left_knee", "right_knee": ["right_knee", -1.0, 0.1]},
            "segments": {"torso": "torso"}}
    with pytest.warns(UnmappedJointsWarning, match="left_hip"):
        bm = body_map(d, i, spec)
    assert bm.joints["right_knee"] == ("right_knee", -1.0, 0.1)
    p = tmp_path / "map.json"
    p.write_text(json.dumps(spec))
    with pytest.warns(UnmappedJointsWarning):
        assert body_map(d, i, p).joints == bm.joints


def test_unknown_names_are_listed(robot):
    d, i = robot("case1_demonstrator"), robot("hoap2")
    with pytest.raises(UnknownNameError, match="left_knee"):
        body_map(d, i, {"joints": {"left_knee": "nope"}})
    with pytest.raises(UnknownNameError, match="torso"):
        body_map(d, i, {"segments": {"nope": "torso"}})
    with pytest.raises(InvalidInputError):
        BodyMap.from_dict({"bones": {}})
