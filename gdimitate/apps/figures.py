"""Matplotlib figures of demonstrator vs imitator(s), normalised by leg length.

The module leaves matplotlib's backend alone: in Jupyter figures show inline, on a machine
without a display matplotlib falls back to Agg by itself (or set ``MPLBACKEND=Agg``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..assess import metrics
from ..assess.metrics import ForceDirection
from ..model.contact import SoleContact, centre_of_pressure
from ..model.motion import Motion
from ..model.robot import Robot
from ..model.sagittal import leg_angles
from ..safety import save_figure

__all__ = ["Track", "plot_heights", "plot_angles", "plot_paths", "plot_com", "plot_eq1_argument",
           "plot_force_directions", "plot_sole_cop"]

Track = tuple[str, Robot, Motion]  # (label, robot, motion)
STYLES = ["-", "--", ":", "-."]


def _L(robot: Robot) -> float:
    return robot.legs["left"].length



def plot_heights(tracks: list[Track], title: str = "", path: Path | None = None):
    """Hip height, foot (sole) heights and foot distance over time, each / leg length
    (paper Figs. 4–6, 10–11 in spirit)."""
    fig, ax = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for k, (label, r, m) in enumerate(tracks):
        L, ls = _L(r), STYLES[k % 4]
        ax[0].plot(m.t, metrics.hip_height(r, m) / L, ls, label=label)
        fh = metrics.foot_heights(r, m)
        ax[1].plot(m.t, fh["left"] / L, ls, color=f"C{k}", label=f"{label} left")
        ax[1].plot(m.t, fh["right"] / L, ls, color=f"C{k}", alpha=0.5)
        ax[2].plot(m.t, metrics.foot_distance(r, m) / L, ls, label=label)
    ax[0].set_ylabel("hip height / L")
    ax[1].set_ylabel("sole height / L\n(left dark, right light)")
    ax[2].set_ylabel("ankles along the walk:\nleft − right / L")
    ax[2].set_xlabel("time [s]")
    ax[0].legend(fontsize=8)
    ax[0].set_title(title)
    return save_figure(fig, path)


def plot_gait(demonstrator: Robot, demo: Motion, adapted, path: Path | None = None):
    """The paper's Fig. 4 for an adaptation (``adapted``: an
    :class:`~gdimitate.AdaptedMotion` of ``demo``): :func:`plot_heights` of the
    demonstrator and the imitator, each over its own leg length — the demonstrator scaled to
    the imitator's legs — titled with the travel ratio (docs/design.md §13)."""
    g = adapted.gait
    kept = f" — travel ratio {g.travel_ratio:.2f}" if g is not None else ""
    name = adapted.robot.name
    return plot_heights([(f"{demonstrator.name} (demonstrator)", demonstrator, demo),
                         (name, adapted.robot, adapted.motion)],
                        f"{demonstrator.name} → {name}, each over its leg length{kept}", path)


def plot_angles(tracks: list[Track], title: str = "", path: Path | None = None):
    """Left-leg planar angles θ1 (thigh, absolute), θ2 (knee) and the shank angle θ1+θ2 [deg]."""
    fig, ax = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for k, (label, r, m) in enumerate(tracks):
        _, a = leg_angles(r, m.q)
        a = np.degrees(a["left"])
        ls = STYLES[k % 4]
        ax[0].plot(m.t, a[:, 0], ls, label=label)
        ax[1].plot(m.t, a[:, 1], ls, label=label)
        ax[2].plot(m.t, a[:, 0] + a[:, 1], ls, label=label)
    for a_, lab in zip(ax, ["θ1 thigh [deg]", "θ2 knee [deg]", "θ1+θ2 shank [deg]"]):
        a_.set_ylabel(lab)
    ax[2].set_xlabel("time [s]")
    ax[0].legend(fontsize=8)
    ax[0].set_title(title)
    return save_figure(fig, path)


def plot_paths(tracks: list[Track], title: str = "", path: Path | None = None):
    """x–z paths of the hip and both soles, / leg length (paper Figs. 7–8, 12–13 in spirit)."""
    fig, ax = plt.subplots(len(tracks), 1, figsize=(9, 2.2 * len(tracks) + 0.6), squeeze=False)
    for k, (label, r, m) in enumerate(tracks):
        L = _L(r)
        h = metrics.hip_path(r, m) / L
        s = metrics.sole_paths(r, m)
        a = ax[k, 0]
        a.plot(h[:, 0], h[:, 2], "k-", label="hip")
        a.plot(s["left"][:, 0] / L, s["left"][:, 2] / L, "C1-", label="left sole")
        a.plot(s["right"][:, 0] / L, s["right"][:, 2] / L, "C0--", label="right sole")
        a.set_aspect("equal")
        a.set_ylabel(f"{label}\nz / L")
    ax[-1, 0].set_xlabel("x / L")
    ax[0, 0].legend(fontsize=8, ncol=3)
    ax[0, 0].set_title(title)
    return save_figure(fig, path)


def plot_com(tracks: list[Track], title: str = "", path: Path | None = None):
    """Whole-body centre of mass (Pinocchio): x–z path and height over time, / leg length."""
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.5))
    for k, (label, r, m) in enumerate(tracks):
        c = metrics.com_path(r, m) / _L(r)
        ax[0].plot(c[:, 0], c[:, 2], STYLES[k % 4], label=label)
        ax[1].plot(m.t, c[:, 2], STYLES[k % 4], label=label)
    ax[0].set_xlabel("x / L")
    ax[0].set_ylabel("CoM z / L")
    ax[1].set_xlabel("time [s]")
    ax[1].set_ylabel("CoM z / L")
    ax[1].legend(fontsize=8)
    ax[0].set_title(title)
    return save_figure(fig, path)


def plot_eq1_argument(t: np.ndarray, arguments: dict[str, np.ndarray], title: str = "",
                      path: Path | None = None):
    """Eq. (1)'s arccos argument per leg; outside ±1 the imitator cannot reach (paper Fig. 9)."""
    fig, ax = plt.subplots(figsize=(8, 3))
    for s, a in arguments.items():
        ax.plot(t, a, label=s)
    ax.axhspan(-1, 1, color="0.9", zorder=-1, label="reachable |arg| ≤ 1")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("Eq. (1) argument")
    ax.legend(fontsize=8)
    ax.set_title(title)
    return save_figure(fig, path)


def plot_force_directions(t: np.ndarray, directions: Mapping[str, Mapping[str, ForceDirection]],
                          contact: Mapping[str, np.ndarray] | None = None, title: str = "",
                          path: Path | None = None,
                          times: Mapping[str, np.ndarray] | None = None):
    """Sagittal and frontal force-direction angles [deg] of each foot over time ``t`` ``(T,)``
    [s]: ``directions`` maps a label (e.g. "measured", "dynamics", "imitator") to
    :func:`gdimitate.assess.metrics.force_direction`'s result on that time grid (``times``: a
    label's
    own time grid where it differs, e.g. an adaptor's knots). ``contact`` (``{side: (T,)
    bool}`` on ``t``) shades single support."""
    fig, ax = plt.subplots(2, 2, figsize=(10, 6), sharex=True)
    for j, side in enumerate(("left", "right")):
        for i, (what, label) in enumerate((("sagittal", "sagittal [deg] (+ forward)"),
                                           ("frontal", "frontal [deg] (+ left)"))):
            a = ax[i, j]
            for k, (name, fd) in enumerate(directions.items()):
                tk = (times or {}).get(name, t)
                a.plot(tk, np.degrees(getattr(fd[side], what)), STYLES[k % len(STYLES)],
                       label=name)
            if contact is not None:
                other = "right" if side == "left" else "left"
                ss = np.asarray(contact[side], bool) & ~np.asarray(contact[other], bool)
                a.fill_between(t, 0, 1, where=ss, color="0.9", transform=a.get_xaxis_transform(),
                               zorder=0, label="single support" if i == j == 0 else None)
            a.set_ylabel(label)
            a.set_title(f"{side} foot" if i == 0 else "")
            a.grid(alpha=0.3)
        ax[1, j].set_xlabel("t [s]")
    ax[0, 0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    return save_figure(fig, path)


def plot_sole_cop(wrenches: Mapping[str, np.ndarray], contacts: Mapping[str, SoleContact],
                  stance: Mapping[str, np.ndarray], title: str = "", path: Path | None = None):
    """Each foot's centre of pressure [cm] inside its sole rectangle, seen from above in the
    sole frame (x forward, y left): ``wrenches`` ``{side: (T, 6)}`` [N, N·m] in the sole frame
    (an :class:`~gdimitate.AdaptedMotion`'s), ``contacts`` the sole rectangles,
    ``stance`` ``{side: (T,) bool}`` (only stance knots with a positive normal force are
    drawn). The drawn points are :func:`gdimitate.model.contact.centre_of_pressure`'s."""
    fig, ax = plt.subplots(1, 2, figsize=(8, 4.5))
    for a, side in zip(ax, ("left", "right"), strict=True):
        c = contacts[side]
        X, Y = 100 * c.half_length, 100 * c.half_width
        a.plot([-Y, Y, Y, -Y, -Y], [-X, -X, X, X, -X], "k-", lw=1.5, label="sole")
        cop = 100 * centre_of_pressure(np.asarray(wrenches[side])[np.asarray(stance[side], bool)])
        ok = np.all(np.isfinite(cop), axis=1)
        # drawn with x (forward) up the page and y (left) to the left, as seen from above
        a.plot(-cop[ok, 1], cop[ok, 0], "C0.-", ms=3, lw=0.6, label="centre of pressure")
        a.set_aspect("equal")
        a.set_xlim(-1.4 * Y, 1.4 * Y)
        a.set_ylim(-1.2 * X, 1.2 * X)
        a.set_title(f"{side} sole")
        a.set_xlabel("← left  y [cm]  right →")
        a.set_ylabel("x [cm] (forward)")
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8, loc="lower left")
    if title:
        fig.suptitle(title)
    return save_figure(fig, path)
