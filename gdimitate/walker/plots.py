"""The walk's figures: the oscillators' phase portraits, the network's frequency over time,
and the force directions per step (simulated vs the demonstrator's measured)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..model.robot import SIDES  # noqa: E402
from ..safety import save_figure  # noqa: E402

__all__ = ["plot_walk"]


def plot_walk(res, out: Path) -> list[str]:
    """Write ``walk_phase_portraits.png``, ``walk_frequency.png`` and
    ``walk_force_directions.png`` into ``out``; return their names."""
    names = []
    for fn in (_portraits, _frequency, _forces):
        names.append(fn(res, out))
    return names


def _portraits(res, out: Path) -> str:
    tr = res.trace
    names = res.network.result.joint_names
    pick = np.argsort(-np.ptp(tr.y, axis=0))[:4] if tr.y.size else np.zeros(0, int)
    fig, axes = plt.subplots(1, max(len(pick), 1), figsize=(3.2 * max(len(pick), 1), 3.2))
    axes = np.atleast_1d(axes)
    dt = np.gradient(tr.t) if tr.t.size > 1 else np.ones(1)
    for ax, j in zip(axes, pick):
        y = tr.y[:, j]
        ax.plot(y, np.gradient(y) / dt, lw=0.6)
        ax.set_title(names[j], fontsize=8)
        ax.set_xlabel("y")
        ax.set_ylabel("dy/dt [1/s]")
    fig.suptitle(f"oscillator phase portraits (feedback gain {res.feedback_gain:g})")
    save_figure(fig, out / "walk_phase_portraits.png")
    return "walk_phase_portraits.png"


def _frequency(res, out: Path) -> str:
    tr = res.trace
    fig, ax = plt.subplots(figsize=(8, 3.5))
    f_cycle = 1.0 / res.reference.period
    if tr.t.size > 200:
        w = 200  # 0.2 s windows
        f = (tr.cycles[w:] - tr.cycles[:-w]) / (tr.t[w:] - tr.t[:-w])
        ax.plot(tr.t[w:], f, lw=1, label="network (0.2 s window)")
    ts, fs = res.step_times(), res.step_frequencies()
    if fs:
        ax.step(ts[1:], fs, where="pre", label="per step")
    ax.axhline(f_cycle, color="k", ls="--", lw=0.8, label="cycle")
    ax.axhspan(0.99 * f_cycle, 1.01 * f_cycle, color="0.85", label="±1 %")
    if tr.push_window:
        ax.axvspan(*tr.push_window, color="r", alpha=0.3, label="push")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("stride frequency [Hz]")
    ax.legend(fontsize=8)
    save_figure(fig, out / "walk_frequency.png")
    return "walk_frequency.png"


def _forces(res, out: Path) -> str:
    tr = res.trace
    fig, ax = plt.subplots(2, 1, figsize=(9, 6))
    mg = res.robot.mass * 9.81
    for k, s in enumerate(SIDES):
        f = tr.force[s]
        ang = np.where(f[:, 2] > 0.01 * mg, np.degrees(np.arctan2(f[:, 0], f[:, 2])), np.nan)
        ax[0].plot(tr.t, ang, f"C{k}-", lw=0.8, label=f"{s} simulated")
        if res.forces is not None:
            pr = res.reference
            td = pr.t0 + (tr.cycles % 1.0) * pr.period
            ft = res.forces.feet[s]
            fx = np.interp(td, res.forces.t, ft.force[:, 0])
            fz = np.interp(td, res.forces.t, ft.force[:, 2])
            on = ft.contact[np.clip(np.searchsorted(res.forces.t, td), 0, ft.contact.size - 1)]
            ax[0].plot(tr.t, np.where(on, np.degrees(np.arctan2(fx, fz)), np.nan), f"C{k}--",
                       lw=0.8, label=f"{s} measured (same phase)")
    ax[0].set_ylabel("sagittal force angle [deg]")
    ax[0].legend(fontsize=7, ncol=2)
    r = res.force_rmse_deg()
    ax[1].bar(np.arange(len(r)), r)
    ax[1].axhline(5.0, color="r", ls="--", lw=0.8, label="5°")
    ax[1].set_xlabel("step")
    ax[1].set_ylabel("RMS angle vs measured [deg]")
    ax[1].legend(fontsize=8)
    save_figure(fig, out / "walk_force_directions.png")
    return "walk_force_directions.png"
