"""TRC headers as written in the wild, read by name: single tabs (OpenSim's own writer), runs
of tabs padded with spaces (the header the issue quotes: ``100.0\\t\\t  100.0\\t\\t    238 …``),
trailing tabs, an empty value, a path with spaces in the first line. Each synthetic file's
markers must come back as written (mm → m, Y up → our z up) and its header values by name."""

from __future__ import annotations

import numpy as np
import pytest

from gdimitate.errors import OpenSimDataError
from gdimitate.model.osim.trc import read_trc

KEYS = ["DataRate", "CameraRate", "NumFrames", "NumMarkers", "Units", "OrigDataRate",
        "OrigDataStartFrame", "OrigNumFrames"]
Y_UP = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # ours from OpenSim's lab axes


def _lab(T: int) -> np.ndarray:
    """(T, 3, 3) [mm] head, hip and heel of a person walking along X in a Y-up lab."""
    base = np.array([[0.0, 1700.0, 0.0], [0.0, 950.0, 100.0], [-50.0, 50.0, 100.0]])
    return base[None] + np.array([1200.0, 0, 0])[None, None] * (np.arange(T) / 100)[:, None, None]


def _write(path, keys_line: str, values_line: str, first: str, T: int):
    names = ["Top.Head", "R.ASIS", "R.Heel"]
    lab = _lab(T)
    rows = [f"{k + 1}\t{k / 100:.6f}\t" + "\t".join(f"{v:.4f}" for v in lab[k].ravel())
            for k in range(T)]
    head = [first, keys_line, values_line, "Frame#\tTime\t" + "\t\t\t".join(names),
            "\t\t" + "\t".join(f"{a}{i + 1}" for i in range(3) for a in "XYZ"), ""]
    path.write_text("\n".join(head + rows) + "\n")
    return lab / 1000 @ Y_UP.T


LAYOUTS = {
    "single tabs": ("\t".join(KEYS), "100.0\t100.0\t{T}\t3\tmm\t100.0\t1\t{T}"),
    "doubled tabs and spaces": (
        "\t".join(KEYS), "100.0\t\t  100.0\t\t    {T}\t\t     3\t\t mm\t\t100.0\t\t1\t\t{T}"),
    "trailing tabs": ("\t".join(KEYS) + "\t", "100.0\t100.0\t{T}\t3\tmm\t100.0\t1\t{T}\t\t\t"),
    "empty value": ("\t".join(KEYS), "100.0\t100.0\t{T}\t3\tmm\t\t1\t{T}"),
    "spaces only": ("  ".join(KEYS), "100.0   100.0   {T}   3   mm   100.0   1   {T}"),
}


@pytest.mark.parametrize("layout", list(LAYOUTS))
@pytest.mark.parametrize("first", ["PathFileType\t4\t(X/Y/Z)\twalk.trc",
                                   "PathFileType\t4\t(X/Y/Z)\tC:\\My Data\\walk 1.trc"])
def test_trc_header_layouts(tmp_path, layout, first):
    T = 9
    keys, vals = LAYOUTS[layout]
    want = _write(tmp_path / "m.trc", keys, vals.format(T=T), first, T)
    mk = read_trc(tmp_path / "m.trc")
    assert mk.names == ("Top.Head", "R.ASIS", "R.Heel")
    assert "units mm" in mk.frame_note and "Y up" in mk.frame_note
    np.testing.assert_allclose(mk.xyz, want, atol=1e-9)
    assert mk.rate == pytest.approx(100.0)


def test_trc_header_units_by_name_not_position(tmp_path):
    """The issue's failure: the values' 5th tab field is NumFrames under doubled tabs; read by
    position it gave Units='238'. By name it is 'mm' (else the markers would be 1000× off)."""
    T = 238
    _write(tmp_path / "m.trc", "\t".join(KEYS),
           "100.0\t\t  100.0\t\t    238\t\t     3\t\t mm\t\t100.0\t\t1\t\t238", "PathFileType", T)
    mk = read_trc(tmp_path / "m.trc")
    assert mk.t.size == 238 and 1.6 < mk["Top.Head"][0, 2] < 1.8


def test_trc_header_key_value_mismatch(tmp_path):
    _write(tmp_path / "m.trc", "\t".join(KEYS), "100.0\t\t100.0\t\t9\t\t3\t\tmm\t\t100\t\t1\t\t9"
           "\t\t7\t\t8", "PathFileType", 9)
    with pytest.raises(OpenSimDataError, match="one value per key"):
        read_trc(tmp_path / "m.trc")
