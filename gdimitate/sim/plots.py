"""Matplotlib figures of a :class:`~gdimitate.sim.simulate.SimResult`.

Each function returns the figure (and writes it to ``path`` when given). The backend is left
alone: figures show inline in Jupyter; without a display matplotlib falls back to Agg.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..assess.metrics import angle_down
from ..model.robot import SIDES
from ..safety import save_figure
from .metrics import frontal_angle, stance_intervals
from .simulate import SimResult

__all__ = ["plot_forces", "plot_force_directions", "plot_cop", "plot_tracking", "plot_summary"]



def _shade_single(ax, res: SimResult, side: str) -> None:
    other = "right" if side == "left" else "left"
    single = res.plan_stance[side] & ~res.plan_stance[other]
    for i, j in stance_intervals(single):
        ax.axvspan(res.t[i], res.t[j], color="0.9", zorder=0)


def _mark_fall(ax, res: SimResult) -> None:
    if res.metrics.fell:
        ax.axvline(res.metrics.fall_time, color="k", ls=":", lw=1)


def plot_forces(res: SimResult, path: str | Path | None = None):
    """Ground reaction force on each foot [N], world x/y/z: simulated (solid) vs plan
    (dashed) vs demonstrator (dotted, where given); single support shaded."""
    fig, ax = plt.subplots(3, 2, figsize=(10, 7), sharex=True)
    for c, s in enumerate(SIDES):
        for r, comp in enumerate("xyz"):
            a = ax[r, c]
            _shade_single(a, res, s)
            a.plot(res.t, res.contact_forces[s][:, r], "C0-", lw=1, label="simulated")
            a.plot(res.t, res.plan_forces[s][:, r], "C1--", lw=1, label="plan")
            if res.demo_forces is not None:
                a.plot(res.t, res.demo_forces[s][:, r], "C2:", lw=1, label="demonstrator")
            _mark_fall(a, res)
            a.set_ylabel(f"{s} f_{comp} [N]")
    ax[0, 0].legend(fontsize=8)
    for a in ax[-1]:
        a.set_xlabel("t [s]")
    return save_figure(fig, path)


def plot_force_directions(res: SimResult, path: str | Path | None = None):
    """Direction of each foot's push on the ground [deg from the downward vertical]:
    sagittal (+forward) and frontal (+left), simulated vs plan vs demonstrator, shown where
    the foot is loaded; single support shaded."""
    fig, ax = plt.subplots(2, 2, figsize=(10, 6), sharex=True)
    thr = 0.01 * max(1.0, float(np.nanmax([np.abs(res.contact_forces[s][:, 2]).max()
                                           for s in SIDES])))
    series = [("simulated", res.contact_forces, "C0-"), ("plan", res.plan_forces, "C1--")]
    if res.demo_forces is not None:
        series.append(("demonstrator", res.demo_forces, "C2:"))
    for c, s in enumerate(SIDES):
        for r, (name, fn) in enumerate((("sagittal", angle_down), ("frontal", frontal_angle))):
            a = ax[r, c]
            _shade_single(a, res, s)
            for label, forces, style in series:
                f = forces[s]
                ang = np.degrees(fn(-f))
                ang[f[:, 2] < thr] = np.nan
                a.plot(res.t, ang, style, lw=1, label=label)
            _mark_fall(a, res)
            a.set_ylabel(f"{s} {name} [deg]")
    ax[0, 0].legend(fontsize=8)
    for a in ax[-1]:
        a.set_xlabel("t [s]")
    return save_figure(fig, path)


def plot_cop(res: SimResult, path: str | Path | None = None):
    """Centre of pressure of each foot in its sole frame [cm] over time, with the sole
    rectangle's edges, and its margin inside the sole [mm]."""
    fig, ax = plt.subplots(3, 2, figsize=(10, 7), sharex=True)
    for c, s in enumerate(SIDES):
        for r, comp in enumerate("xy"):
            a = ax[r, c]
            a.plot(res.t, 100 * res.cop[s][:, r], "C0-", lw=1)
            _mark_fall(a, res)
            a.set_ylabel(f"{s} CoP {comp} [cm]")
        a = ax[2, c]
        a.plot(res.t, 1000 * res.cop_margin[s], "C3-", lw=1)
        a.axhline(0.0, color="k", lw=0.8)
        a.set_ylabel(f"{s} margin [mm]")
        a.set_xlabel("t [s]")
    return save_figure(fig, path)


def plot_tracking(res: SimResult, path: str | Path | None = None):
    """Tracking: per actuated joint RMSE [deg] (bars), and the largest |torque|/limit over
    the run per joint."""
    mt = res.metrics
    names = list(mt.joint_rmse_per_joint)
    fig, ax = plt.subplots(2, 1, figsize=(max(6, 0.25 * len(names)), 6), sharex=True)
    ax[0].bar(range(len(names)), np.degrees([mt.joint_rmse_per_joint[n] for n in names]))
    ax[0].set_ylabel("joint RMSE [deg]")
    peak = np.abs(res.tau).max(axis=0) if res.tau.size else np.zeros(len(names))
    ax[1].bar(range(len(names)), peak / res.effort)  # unlimited joints: 0
    ax[1].axhline(1.0, color="k", lw=0.8)
    ax[1].set_ylabel("max |τ| / limit")
    ax[1].set_xticks(range(len(names)), names, rotation=90, fontsize=7)
    return save_figure(fig, path)


def plot_summary(res: SimResult, path: str | Path | None = None):
    """One page: vertical force per foot (simulated vs plan), base height and tilt with the
    fall thresholds, and the feet's horizontal drift from their stance start."""
    mt = res.metrics
    fig, ax = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for k, s in enumerate(SIDES):
        ax[0].plot(res.t, res.contact_forces[s][:, 2], f"C{k}-", lw=1, label=f"{s} simulated")
        ax[0].plot(res.t, res.plan_forces[s][:, 2], f"C{k}--", lw=1, label=f"{s} plan")
    ax[0].set_ylabel("f_z [N]")
    ax[0].legend(fontsize=8, ncol=2)
    ax[1].plot(res.t, res.base_height, "C0-", lw=1, label="base height")
    ax[1].plot(res.t, res.plan_base_height, "C1--", lw=1, label="plan")
    ax[1].plot(res.t, mt.criteria.min_height_ratio * res.plan_base_height, "k:", lw=1,
               label="fall threshold")
    ax[1].set_ylabel("height [m]")
    ax[1].legend(fontsize=8)
    tw = ax[1].twinx()
    tw.plot(res.t, np.degrees(res.tilt), "C3-", lw=0.8)
    tw.set_ylabel("tilt [deg]", color="C3")
    for s in SIDES:
        ax[2].plot([x.start for x in mt.slip if x.side == s],
                   [100 * x.slip for x in mt.slip if x.side == s], "o", label=f"{s}")
    ax[2].set_ylabel("slip per stance [cm]")
    ax[2].set_xlabel("t [s] (stance start)")
    ax[2].legend(fontsize=8)
    title = (f"fell at {mt.fall_time:.2f} s ({mt.fall_reason})" if mt.fell else "stayed up")
    ax[0].set_title(f"{title}; slip max {100 * mt.slip_max:.1f} cm; joint RMSE "
                    f"{np.degrees(mt.joint_rmse):.2f} deg; saturation "
                    f"{100 * mt.torque_saturation:.1f} %")
    for a in ax:
        _mark_fall(a, res)
    return save_figure(fig, path)
