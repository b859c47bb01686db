"""Figures draw what the numbers say: the centre-of-pressure plot's points are the CoP of the
given wrenches (closed form −τ_y/f_z, τ_x/f_z), inside the drawn sole outline."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from gdimitate.apps.figures import plot_sole_cop  # noqa: E402
from gdimitate.model.contact import SoleContact  # noqa: E402


def test_sole_cop_points_are_the_wrenches_cop(tmp_path):
    rng = np.random.default_rng(0)
    T = 40
    cs = {s: SoleContact(s, f"{s}_sole", 0.1, 0.05, 0.8) for s in ("left", "right")}
    cop = {s: rng.uniform([-0.09, -0.045], [0.09, 0.045], (T, 2)) for s in cs}
    stance = {"left": np.arange(T) < 25, "right": np.arange(T) >= 15}
    W = {}
    for s in cs:
        fz = rng.uniform(50, 500, T)
        w = np.zeros((T, 6))
        w[:, 2] = fz
        w[:, 3], w[:, 4] = cop[s][:, 1] * fz, -cop[s][:, 0] * fz  # τ_x = y f_z, τ_y = −x f_z
        W[s] = w
    fig = plot_sole_cop(W, cs, stance, path=tmp_path / "cop.png")
    assert (tmp_path / "cop.png").stat().st_size > 10_000
    fig = plot_sole_cop(W, cs, stance)
    for ax, s in zip(fig.axes, ("left", "right"), strict=True):
        outline, points = ax.lines[:2]
        x, y = points.get_data()
        np.testing.assert_allclose(y, 100 * cop[s][stance[s], 0], rtol=1e-12)
        np.testing.assert_allclose(x, -100 * cop[s][stance[s], 1], rtol=1e-12)
        ox, oy = outline.get_data()
        assert np.max(np.abs(oy)) == 10.0 and np.max(np.abs(ox)) == 5.0
