"""Body maps as data: the naming families live in ``gdimitate/data/bodymaps/*.json``, validated
on load. The families reproduce exactly the presets the Python tables gave before the move
(frozen in tests/data/bodymap_presets.json by the old code: every map, scale and offset, name,
warning and error, compared with ``==``); malformed files are refused with a
:class:`~gdimitate.errors.BodyMapError` saying what to fix; a user's family file passed as
``body_map=`` names a robot the shipped families do not."""

from __future__ import annotations

import functools
import json
import sys
import tempfile
import warnings
from pathlib import Path

import pytest

import gdimitate as gd
from gdimitate.errors import BodyMapError, GdimitateError, InvalidInputError, UnknownNameError
from gdimitate.retarget import BodyMap, body_map
from gdimitate.retarget import bodymap as bm
from tests.helpers import TESTS

HERE = TESTS  # the tests' root: its data/ and opensim_ref/
FROZEN = json.loads((HERE / "data" / "bodymap_presets.json").read_text())


@functools.cache
def _humans() -> dict:
    """The 3-D OpenSim walk's subject, the same with arms (tests/opensim_ref/with_arms.py) and
    the CMU BVH skeleton."""
    from gdimitate.io.bvh.reader import read_bvh
    from gdimitate.io.gait import human_walk_path

    sys.path.insert(0, str(HERE / "opensim_ref"))
    from with_arms import write_model

    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out["opensim_3d"] = gd.gait.human_walk_3d()[0]
        with tempfile.TemporaryDirectory() as tmp:
            p = write_model(gd.gait.human_walk_3d_folder() / "subject01.osim",
                            Path(tmp) / "armed.osim")
            out["opensim_armed"] = gd.Robot.from_osim(p)
        bvh = human_walk_path().parents[1] / "cmu_02_01" / "cmu_02_01.bvh"
        out["cmu_bvh"] = read_bvh(bvh)[0]
    return out


@pytest.fixture
def robots(robot):
    """Every robot of the frozen file: the library's (conftest's cache) and :func:`_humans`."""
    humans = _humans()
    return {n: humans[n] if n in humans else robot(n) for n in FROZEN["family"]}


def _record(d, i) -> dict:
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        try:
            m = body_map(d, i)
            rec = {"name": m.name,
                   "joints": [[a, b, s, o] for a, (b, s, o) in m.joints.items()],
                   "segments": [[a, b] for a, b in m.segments.items()]}
        except GdimitateError as e:
            rec = {"error": f"{type(e).__name__}: {e}"}
    rec["warnings"] = [f"{w.category.__name__}: {w.message}" for w in got]
    return rec


def test_the_json_families_give_the_frozen_presets(robots):
    """Each robot's family, arms-down and legs-down poses, and the preset of four
    demonstrators (3-D OpenSim, OpenSim with arms, CMU BVH, planar) onto every robot of the
    library — joint order, scales, offsets, segments, name, warnings and errors — equal the
    maps the tables of bodymap.py gave before the move, float for float."""
    for n, r in robots.items():
        fam = bm._family(r)
        assert (fam.name if fam else None) == FROZEN["family"][n], n
        assert [float(x) for x in bm.arms_down(r)] == FROZEN["arms_down"][n], n
        assert [float(x) for x in bm.legs_down(r)] == FROZEN["legs_down"][n], n
    assert len(FROZEN["maps"]) == 72
    for pair, want in FROZEN["maps"].items():
        d, i = pair.split("->")
        assert _record(robots[d], robots[i]) == want, pair


def test_the_shipped_families_load_in_the_old_order():
    """One file per family, named by it; tried in the tables' old order (priority)."""
    fams = bm.families()
    assert [f.name for f in fams] == ["opensim", "talos", "g1", "icub", "romeo", "planar",
                                      "bvh"]
    files = sorted(f.name for f in bm.FAMILY_DIR.iterdir() if f.name.endswith(".json"))
    assert files == sorted(f"{f.name}.json" for f in fams)
    for f in fams:
        assert set(f.roles) <= set(bm.ROLES) and f.description


def test_package_data_ships_the_family_files():
    """pyproject's package-data glob takes gdimitate/data/bodymaps/*.json into a wheel."""
    import fnmatch
    import re

    text = (HERE.parent / "pyproject.toml").read_text()
    section = text.split("[tool.setuptools.package-data]", 1)[1].split("\n[", 1)[0]
    globs = re.findall(r'"([^"]+)"', section.split("gdimitate", 1)[1])
    assert globs
    for f in bm.FAMILY_DIR.iterdir():
        rel = f"data/bodymaps/{f.name}"
        assert any(fnmatch.fnmatch(rel, g) for g in globs), rel


# ------------------------------------------------------------------ validation
def _g1() -> dict:
    return json.loads((Path(str(bm.FAMILY_DIR)) / "g1.json").read_text())


def _bad(**change) -> dict:
    d = _g1()
    for k, v in change.items():
        if v is None:
            del d[k]
        else:
            d[k] = v
    return d


def test_a_family_with_a_missing_or_unknown_key_is_refused():
    for key in ("family", "match", "sides", "roles"):
        with pytest.raises(BodyMapError, match=f"missing key.*'{key}'.*required"):
            bm.family_from_dict(_bad(**{key: None}))
    with pytest.raises(BodyMapError, match="unknown key 'joints'; valid keys: 'family'"):
        bm.family_from_dict(_bad(joints={}))
    with pytest.raises(BodyMapError, match="match names no joint and no frame"):
        bm.family_from_dict(_bad(match={}))


def test_an_unknown_role_or_joint_name_is_refused_with_the_valid_ones(robots):
    roles = dict(_g1()["roles"], hip_pich="{s}_hip_pitch_joint")
    with pytest.raises(UnknownNameError, match="'hip_pich'.*'hip_pitch', 'hip_roll'"):
        bm.family_from_dict(_bad(roles=roles))
    with pytest.raises(UnknownNameError, match="arms_down joint.*'left_shoulder_pich'.*valid"
                       ".*'left_shoulder_pitch_joint'"):
        bm.family_from_dict(_bad(arms_down={"left_shoulder_pich": 1.0}))
    # a user map's names are checked against the robots (UnknownNameError lists them)
    d, i = robots["case1_demonstrator"], robots["hoap2"]
    with pytest.raises(UnknownNameError, match="'nope'.*valid"):
        body_map(d, i, {"joints": {"left_knee": "nope"}})


def test_a_bad_number_is_refused():
    for v in ("1", float("nan"), True):
        with pytest.raises(BodyMapError, match="scale must be a finite number"):
            BodyMap.from_dict({"joints": {"knee_angle_r": ["right_knee_joint", v, 0.0]}})
    with pytest.raises(BodyMapError, match="offset .rad. must be a finite number"):
        BodyMap.from_dict({"joints": {"knee_angle_r": ["right_knee_joint", 1.0, "0"]}})
    with pytest.raises(BodyMapError, match="arms_down 'left_shoulder_pitch_joint': an angle"):
        bm.family_from_dict(_bad(arms_down={"left_shoulder_pitch_joint": "90"}))
    with pytest.raises(BodyMapError, match="priority must be an integer"):
        bm.family_from_dict(_bad(priority=1.5))
    assert issubclass(BodyMapError, InvalidInputError)  # callers catching that still do


def test_duplicate_entries_are_refused(tmp_path):
    text = json.dumps(_g1())
    p = tmp_path / "twice.json"
    p.write_text(text[:-1] + ', "priority": 5}')  # a key repeated: plain JSON keeps the last
    with pytest.raises(BodyMapError, match="'priority' appears twice"):
        bm.family_from_json(p)
    p.write_text('{"joints": {"knee_angle_r": "right_knee_joint", '
                 '"knee_angle_r": "left_knee_joint"}}')
    with pytest.raises(BodyMapError, match="'knee_angle_r' appears twice"):
        BodyMap.from_json(p)
    roles = dict(_g1()["roles"], hip_roll="{s}_hip_pitch_joint")
    with pytest.raises(BodyMapError, match="'left_hip_pitch' and 'left_hip_roll' both name "
                       "joint 'left_hip_pitch_joint'"):
        bm.family_from_dict(_bad(roles=roles))
    with pytest.raises(BodyMapError, match="match.joints lists 'a' twice"):
        bm.family_from_dict(_bad(match={"joints": ["a", "a"]}))
    with pytest.raises(BodyMapError, match="imitator joint 'right_knee_joint' is mapped from 2"):
        BodyMap.from_dict({"joints": {"knee_angle_r": "right_knee_joint",
                                      "knee_angle_l": "right_knee_joint"}})
    with pytest.raises(BodyMapError, match="two body-map family files name the family 'g1'"):
        bm._ordered([bm.family_from_dict(_g1()), bm.family_from_dict(_g1())])


def test_a_users_family_file_is_tried_first(robots, tmp_path):
    """``body_map="my_family.json"``: a naming family of the user's (here G1's under another
    name, without the ankles) pairs by role like a shipped one."""
    human, g1 = robots["opensim_3d"], robots["g1"]
    mine = _g1()
    mine.update(family="my_g1", priority=1)
    for role in ("ankle_pitch", "ankle_roll"):
        del mine["roles"][role]
    p = tmp_path / "my_g1.json"
    p.write_text(json.dumps(mine))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        preset, got = body_map(human, g1), body_map(human, g1, p)
        assert body_map(human, g1, mine).joints == got.joints  # the same as a dict
    assert got.name == "opensim→my_g1"
    left_out = {"ankle_angle_l", "ankle_angle_r", "subtalar_angle_l", "subtalar_angle_r"}
    assert dict(got.joints) == {k: v for k, v in preset.joints.items() if k not in left_out}
    assert got.segments == preset.segments
