"""The CLI's inputs: a robot as a library name or a URDF path (with --legs/--contacts JSON),
each demonstration format, NPZ files that carry their robot, the export command, defaults and
help texts, and no URL printed for a server that is gone."""

from __future__ import annotations

import argparse
import json
import re

import numpy as np
import pytest

from gdimitate.apps.cli import build_parser, main
from gdimitate.export.writers import read_csv
from gdimitate.io.demonstration import load_demonstration
from gdimitate.io.gait import human_walk_3d_folder, human_walk_path
from gdimitate.model.motion import RobotRecord
from gdimitate.model.urdfgen import PLANAR_MODELS, planar_biped_urdf

D3 = human_walk_3d_folder()
SAG = human_walk_path()
SAG_GRF = SAG.parent / "walk_gait1018_subject01_grf.mot"
BVH = SAG.parents[1] / "cmu_02_01" / "cmu_02_01.bvh"
MINE = ("demo", "paper", "adapt", "view", "entrain", "export")


def _subparsers(p: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    (sub,) = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def test_default_method_is_optimal_and_every_option_has_help():
    subs = _subparsers(build_parser())
    for cmd in ("demo", "adapt", "view", "entrain"):
        method = next(a for a in subs[cmd]._actions if a.dest == "method")
        assert method.default == "optimal", cmd
    for cmd in MINE:
        for a in subs[cmd]._actions:
            if not isinstance(a, argparse._HelpAction):
                assert a.help and a.help.strip(), (cmd, a.dest)
    assert "lafan1_csv" in subs["export"].format_help()


def _hoap_urdf(tmp_path):
    p = tmp_path / "robots" / "hoap.urdf"
    p.parent.mkdir()
    p.write_text(planar_biped_urdf(PLANAR_MODELS["hoap2"]))
    return p


def test_urdf_imitator_with_legs_and_contacts_json(tmp_path):
    urdf = _hoap_urdf(tmp_path)
    legs = {s: {"hip": f"{s}_hip", "knee": f"{s}_knee", "ankle": f"{s}_ankle",
                "sole": f"{s}_sole"} for s in ("left", "right")}
    contacts = {s: {"half_length": 0.06, "half_width": 0.025} for s in ("left", "right")}
    (tmp_path / "legs.json").write_text(json.dumps(legs))
    (tmp_path / "contacts.json").write_text(json.dumps(contacts))
    out = tmp_path / "a"
    assert main(["adapt", str(SAG), "--grf", str(SAG_GRF), "--imitator", str(urdf),
                 "--package-dir", str(urdf.parent), "--legs", str(tmp_path / "legs.json"),
                 "--contacts", str(tmp_path / "contacts.json"), "--method", "analytic",
                 "--out", str(out)]) == 3  # written; HOAP-2's knee limit (0 rad) is exceeded
    rec = RobotRecord.from_npz(out / "imitator_motion.npz")
    assert rec.kind == "urdf" and rec.source == str(urdf.resolve())
    assert json.loads(rec.contacts) == contacts and json.loads(rec.legs) == legs
    d = load_demonstration(out / "imitator_motion.npz")  # the robot comes from the file
    assert d.robot.contacts["left"].half_length == 0.06 and d.motion.T == 151
    # the CSV export holds the same motion
    back = read_csv(out / "imitator_joints.csv", d.robot)
    assert np.max(np.abs(back.q - d.motion.q)) < 1e-12
    # a bad JSON file is an error that names it
    (tmp_path / "bad.json").write_text("[1, 2]")
    assert main(["adapt", "--imitator", str(urdf), "--legs", str(tmp_path / "bad.json"),
                 "--method", "copy", "--out", str(tmp_path / "b")]) == 2


@pytest.mark.parametrize("args, frames", [
    ([str(SAG), "--grf", str(SAG_GRF)], 151),
    ([str(D3 / "subject01.osim"), "--coordinates", str(D3 / "subject01_walk1_ik.mot"),
      "--grf", str(D3 / "subject01_walk1_grf.mot")], 211),
    ([str(D3 / "subject01_walk1_ik.mot"), "--osim", str(D3 / "subject01.osim")], 211),
    ([str(BVH)], None),
], ids=["mot-sagittal+grf", "osim+coordinates+grf", "mot-full-body+osim", "bvh"])
def test_each_demonstration_format(tmp_path, capsys, args, frames):
    out = tmp_path / "out"
    status = main(["adapt", *args, "--method", "copy", "--out", str(out)])
    rep = json.loads((out / "report.json").read_text())
    assert status == (0 if rep["verdict"]["ok"] else 3)  # exit 3: written, not feasible
    n = frames or len(load_demonstration(BVH).motion.t)
    assert rep["frames"] == n
    assert np.loadtxt(out / "imitator_joints.csv", delimiter=",", skiprows=1).shape[0] == n
    assert "read " in capsys.readouterr().out  # what was read, and how, is said
    # the result is itself a demonstration: its NPZ is read back without naming hoap2
    again = tmp_path / "again"
    status = main(["adapt", str(out / "imitator_motion.npz"), "--imitator",
                   "case1_demonstrator", "--method", "copy", "--out", str(again)])
    assert status == (0 if json.loads((again / "report.json").read_text())["verdict"]["ok"]
                      else 3)


def test_errors_name_what_to_fix(tmp_path, capsys):
    assert main(["adapt", str(tmp_path / "walk.c3d"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert all(ext in err for ext in (".mot", ".sto", ".osim", ".bvh", ".npz"))
    assert main(["adapt", str(D3 / "subject01_walk1_ik.mot"), "--method", "copy",
                 "--out", str(tmp_path / "o")]) == 2
    assert "--osim" in capsys.readouterr().err
    assert main(["adapt", "--imitator", "no_such_robot", "--out", str(tmp_path / "o")]) == 2
    assert "hoap2" in capsys.readouterr().err


def test_export_command_and_changed_robot(tmp_path, capsys):
    urdf = _hoap_urdf(tmp_path)
    out = tmp_path / "a"
    assert main(["adapt", str(SAG), "--grf", str(SAG_GRF), "--imitator", str(urdf),
                 "--method", "analytic", "--out", str(out)]) == 3  # HOAP-2's knee limit
    npz = out / "imitator_motion.npz"
    for fmt, name in (("csv", "imitator_motion.csv"), ("mujoco", "imitator_motion.mujoco.npz"),
                      ("npz", "imitator_motion.export.npz")):
        assert main(["export", str(npz), "--format", fmt]) == 0
        assert (out / name).is_file()
    capsys.readouterr()
    assert main(["export", str(npz), "--format", "lafan1_csv"]) == 2  # a planar base
    assert "free-floating base" in capsys.readouterr().err
    # the URDF changed after the motion was written: refused, with both fingerprints named
    text = urdf.read_text()
    m = re.search(r'<mass value="([0-9.eE+-]+)"', text)
    urdf.write_text(text[:m.start(1)] + str(2 * float(m.group(1))) + text[m.end(1):])
    assert main(["export", str(npz), "--format", "csv", "--out", str(tmp_path / "x.csv")]) == 2
    assert "fingerprint" in capsys.readouterr().err and not (tmp_path / "x.csv").exists()


def test_view_html_prints_no_url_of_a_gone_server(tmp_path, capsys):
    out = tmp_path / "a"
    assert main(["adapt", "--method", "copy", "--out", str(out)]) == 0
    capsys.readouterr()
    page = tmp_path / "walk.html"
    assert main(["view", str(out / "imitator_motion.npz"), "--html", str(page)]) == 0
    printed = capsys.readouterr().out
    assert page.stat().st_size > 10_000 and str(page) in printed
    assert "http://" not in printed and "https://" not in printed
