"""Motion: validation and file round trips."""

import numpy as np
import pytest

from gdimitate import InvalidInputError, Motion, TimeGridError, UnknownNameError, paper_case


def test_validation():
    t = np.linspace(0, 1, 5)
    with pytest.raises(TimeGridError, match="strictly increasing"):
        Motion(t[::-1], ("a",), np.zeros((5, 1)))
    with pytest.raises(TimeGridError, match="NaN"):
        Motion(np.array([0, np.nan, 1.0]), ("a",), np.zeros((3, 1)))
    with pytest.raises(InvalidInputError, match=r"shape \(T, nq\) = \(5, 2\)"):
        Motion(t, ("a", "b"), np.zeros((5, 3)))
    q = np.zeros((5, 1))
    q[2, 0] = np.inf
    with pytest.raises(InvalidInputError, match="frame 2"):
        Motion(t, ("a",), q)
    with pytest.raises(InvalidInputError, match="contact"):
        Motion(t, ("a",), np.zeros((5, 1)), contact={"left": np.ones(4, bool)})
    m = Motion(t, ("a",), np.zeros((5, 1)))
    with pytest.raises(UnknownNameError, match="'a'"):
        m.column("b")


def test_npz_and_csv_round_trip(tmp_path):
    _, _, m = paper_case("I")
    m.to_npz(tmp_path / "m.npz")
    m2 = Motion.from_npz(tmp_path / "m.npz")
    np.testing.assert_array_equal(m2.q, m.q)
    assert m2.joint_names == m.joint_names and m2.base_nq == 3
    np.testing.assert_array_equal(m2.contact["left"], m.contact["left"])
    m.to_csv(tmp_path / "m.csv")
    data = np.loadtxt(tmp_path / "m.csv", delimiter=",", skiprows=1)
    header = (tmp_path / "m.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "time" and "left_knee" in header
    np.testing.assert_allclose(data[:, header.index("left_knee")], m.column("left_knee"),
                               rtol=1e-8, atol=1e-12)
