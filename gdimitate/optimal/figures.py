"""Figures of the optimal adaptor (matplotlib; used by the notebook and for the README image).

``python -m gdimitate.optimal.figures docs/img/optimal_case2.png`` regenerates the README figure.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..adapt import AdaptedMotion, adapt
from ..cases import paper_case
from ..metrics import hip_height_ratio
from ..sagittal import leg_angles
from .targets import slice_motion

__all__ = ["case2_results", "plot_case2"]


def case2_results(subsample: int = 2) -> tuple[AdaptedMotion, AdaptedMotion, tuple]:
    """``(analytic, optimal, (demonstrator, imitator, demonstration))`` for the paper's Case II
    (every ``subsample``-th frame)."""
    d, i, m = paper_case("II")
    demo = slice_motion(m, slice(None, None, subsample))
    return (adapt(demo, d, i, method="analytic"), adapt(demo, d, i, method="optimal"),
            (d, i, demo))


def plot_case2(path: str | Path | None = None, results=None):
    """Case II, left leg: thigh angle and hip-height ratio of Eq. (1) (clipped where it cannot
    reach, shaded) and of the optimal adaptor, and the knee torque against its limit. Saves to
    ``path`` when given; returns the figure."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ana, opt, (d, i, demo) = results if results is not None else case2_results()
    t = demo.t
    s = "left"
    _, a_ana = leg_angles(i, ana.motion.q)
    _, a_opt = leg_angles(i, opt.motion.q)
    _, a_dem = leg_angles(d, demo.q)
    h_dem = hip_height_ratio(d, demo)[s]
    h_ana = hip_height_ratio(i, ana.motion)[s]
    h_opt = hip_height_ratio(i, opt.motion)[s]
    bad = ~ana.report.feasible[s]
    fig, ax = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True)

    def shade(a):
        for k in np.flatnonzero(bad):
            a.axvspan(t[k] - 0.5 * (t[1] - t[0]), t[k] + 0.5 * (t[1] - t[0]), color="0.9", lw=0)

    shade(ax[0])
    ax[0].plot(t, np.degrees(a_dem[s][:, 0]), "k:", label="demonstrator θ1")
    ax[0].plot(t, np.degrees(a_ana[s][:, 0]), "C1", label="Eq. (1) (clipped)")
    ax[0].plot(t, np.degrees(a_opt[s][:, 0]), "C0", label="optimal")
    ax[0].set_ylabel("thigh angle θ1 [deg]")
    ax[0].legend(loc="upper right", fontsize=8)
    shade(ax[1])
    ax[1].plot(t, h_dem, "k:", label="demonstrator")
    ax[1].plot(t, h_ana, "C1", label="Eq. (1)")
    ax[1].plot(t, h_opt, "C0", label="optimal")
    ax[1].set_ylabel("hip height / leg length")
    tau = opt.report.extra["torques"]
    drv = list(opt.report.extra["driven"])
    lim = i.model.effortLimit[i.idx_v("left_knee")]
    k = drv.index("left_knee")
    ax[2].plot(t, tau[:, k], "C0", label="optimal knee torque")
    ax[2].axhline(lim, color="C3", ls="--", lw=1, label="URDF limit")
    ax[2].axhline(-lim, color="C3", ls="--", lw=1)
    ax[2].set_ylabel("τ knee [N·m]")
    ax[2].set_xlabel("time [s]")
    ax[2].legend(loc="upper right", fontsize=8)
    fig.suptitle("Case II (demonstrator thigh 60 % of its leg → HOAP-2): grey = Eq. (1) cannot "
                 "reach\noptimal: force direction kept to "
                 f"{opt.report.force_direction_error_max:.0e} rad, no limit violated",
                 fontsize=10)
    fig.tight_layout()
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
    return fig


if __name__ == "__main__":
    plot_case2(sys.argv[1] if len(sys.argv) > 1 else "docs/img/optimal_case2.png")
