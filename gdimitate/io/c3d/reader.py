"""Read a C3D file with ``ezc3d`` → :class:`C3DTrial` (markers and force plates, SI units).

* Markers: the ``POINT`` group's labels (``LABELS``, ``LABELS2`` …), minus the points a
  lab's software stores there that are not markers (those named in ``POINT:ANGLES``,
  ``FORCES``, ``MOMENTS``, ``POWERS``, ``SCALARS``); ``POINT:UNITS`` (``mm``, ``cm``, ``m``) →
  metres; a marker not seen in a frame (negative residual) is NaN. Positions stay in the lab
  frame of the file, which gait labs set Z up (checked: the markers must spread most along
  Z, as a standing person does; a Y-up file is turned as OpenSim's ``.trc`` files are,
  x = X, y = −Z, z = Y, and the note says so).
* Force plates: ``ezc3d``'s own reading (``extract_forceplat_data=True``: the calibration
  matrix, the plate's corners and origin, every plate type it supports) at the analog rate:
  ``force`` the ground's reaction on the subject (its vertical component up under load: a
  plate whose largest vertical force points down is turned and the note says so), ``cop`` the
  centre of pressure (NaN where the vertical force is at most ``threshold``), ``free_moment``
  about it, ``corners`` of the plate's surface, all in the same frame as the markers.

Time: frame k of the markers is at ``k / POINT:RATE`` [s], analog sample k at
``k / ANALOG:RATE`` (OpenSim's ``C3DFileAdapter`` does the same).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import C3DFormatError, FileFormatError, ForceDataError, UnitError
from ...model.osim.joints import ground_to_world
from ...model.osim.trc import Markers, check_marker_values
from ..opensim.grf import CONTACT_THRESHOLD

__all__ = ["C3DTrial", "ForcePlate", "read_c3d"]

_LENGTH = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}
_MOMENT = {"nmm": 1e-3, "n.mm": 1e-3, "n*mm": 1e-3, "nm": 1.0, "n.m": 1.0, "n*m": 1.0}
_NOT_MARKERS = ("ANGLES", "FORCES", "MOMENTS", "POWERS", "SCALARS", "REACTIONS")


@dataclass(frozen=True)
class ForcePlate:
    """One force platform: ``t`` ``(T,)`` [s]; ``force`` ``(T, 3)`` [N] the ground's reaction
    on the subject; ``cop`` ``(T, 3)`` [m] centre of pressure (NaN where unloaded);
    ``free_moment`` ``(T, 3)`` [N·m] about the centre of pressure; ``corners`` ``(4, 3)`` [m]
    of the plate's surface (the file's order); ``index`` (1-based, the file's numbering)."""

    t: np.ndarray
    force: np.ndarray
    cop: np.ndarray
    free_moment: np.ndarray
    corners: np.ndarray
    index: int = 1
    threshold: float = CONTACT_THRESHOLD

    @property
    def loaded(self) -> np.ndarray:
        """``(T,)`` bool: vertical force above :attr:`threshold` [N]."""
        return self.force[:, 2] > self.threshold

    @property
    def rate(self) -> float:
        """Sample rate [Hz]."""
        return float((self.t.size - 1) / (self.t[-1] - self.t[0]))


@dataclass(frozen=True)
class C3DTrial:
    """A C3D trial: ``markers`` (:class:`~gdimitate.opensim.Markers`, metres, lab frame Z
    up), ``plates`` (one :class:`ForcePlate` per platform), ``source`` and ``note`` (units and
    axes as read)."""

    markers: Markers
    plates: tuple[ForcePlate, ...]
    source: str = ""
    note: str = field(default="")

    def contact_forces(self, robot, motion, *, threshold: float = CONTACT_THRESHOLD):
        """The plates' forces on ``robot``'s feet along ``motion`` (same lab frame) →
        :class:`~gdimitate.contact.ContactForces` on ``motion.t``; see
        :func:`gdimitate.io.c3d.plates.assign_plates`."""
        from .plates import assign_plates

        return assign_plates(self.plates, robot, motion, threshold=threshold,
                             source=self.source)


def _labels(group: dict, count: int) -> list[str]:
    out: list[str] = []
    for key in ["LABELS"] + [f"LABELS{k}" for k in range(2, 100)]:
        if key not in group or len(out) >= count:
            break
        out += [str(v).strip() for v in group[key]["value"]]
    return out[:count]


def _markers(c, path: Path) -> tuple[Markers, np.ndarray, str]:
    par = c["parameters"]["POINT"]
    pts = np.asarray(c["data"]["points"], dtype=float)  # (4, n, T)
    names = _labels(par, pts.shape[1])
    skip = {str(v).strip() for g in _NOT_MARKERS if g in par for v in par[g]["value"]}
    keep = [i for i, n in enumerate(names) if n and n not in skip]
    if not keep:
        raise FileFormatError(f"{path}: the C3D file holds no markers (POINT:USED "
                              f"{pts.shape[1]}, labels {names[:5]})")
    units = list(par["UNITS"]["value"]) if "UNITS" in par else []
    rate = _rate(par, "POINT", path)
    raw = pts[:3, keep].transpose(2, 1, 0)  # (T, n, 3) in the file's unit
    res = c["data"]["meta_points"]["residuals"][0][keep].T if keep else None
    if res is not None:
        raw[res < 0] = np.nan
    if raw.shape[0] < 2:
        raise FileFormatError(f"{path}: the C3D file holds {raw.shape[0]} frame(s) of markers; "
                              "at least 2 are needed for a motion")
    t = np.arange(raw.shape[0]) / rate
    if not units or not str(units[0]).strip():
        raise UnitError(f"{path}: POINT:UNITS is empty; set it to 'mm', 'cm' or 'm' "
                        f"(the markers span {_extent(raw):g} in the file's numbers)")
    unit = str(units[0]).strip().lower()
    if unit not in _LENGTH:
        raise UnitError(f"{path}: POINT:UNITS={unit!r}; expected one of {sorted(_LENGTH)}")
    raw = raw * _LENGTH[unit]
    check_marker_values(raw, [names[i] for i in keep], t, path, unit, _LENGTH[unit],
                        "POINT:UNITS")
    up = "Z"
    seen = np.isfinite(raw).all(axis=2).sum(axis=1) >= 2  # frames with 2+ markers
    if seen.any():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # markers unseen in a frame
            spread = np.nanmax(raw[seen], axis=1) - np.nanmin(raw[seen], axis=1)
        up = "XYZ"[int(np.argmax(np.nanmedian(spread, axis=0)))]
    if up == "X":
        raise FileFormatError(f"{path}: the markers spread most along the lab's X axis; "
                              "cannot tell which axis is up (labs use Z, sometimes Y)")
    R = ground_to_world(up)
    note = f"markers {unit} → m; lab {up} up" + (" → x = X, y = −Z, z = Y" if up == "Y" else "")
    mk = Markers(t, tuple(names[i] for i in keep), raw @ R.T, source=str(path), frame_note=note)
    return mk, R, note


def _extent(raw: np.ndarray) -> float:
    """Median over frames of the markers' largest spread along an axis (file units)."""
    seen = np.isfinite(raw).all(axis=2).sum(axis=1) >= 1
    if not seen.any():
        return float("nan")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        X = raw[seen]
        ext = np.nanmax(np.nanmax(X, axis=1) - np.nanmin(X, axis=1), axis=1)
    return float(np.median(ext))


def _rate(par: dict, group: str, path: Path) -> float:
    """``group:RATE`` [Hz], a finite number > 0 (else :class:`C3DFormatError`)."""
    v = list(par["RATE"]["value"]) if "RATE" in par else []
    x = float(v[0]) if v else float("nan")
    if not (np.isfinite(x) and x > 0):
        raise C3DFormatError(f"{path}: {group}:RATE = {v[0] if v else 'nothing'}; it must be "
                             f"the {'marker' if group == 'POINT' else 'analog'} sample rate, a "
                             "finite number of Hz > 0")
    return x


def _plate(p: dict, k: int, rate: float, R: np.ndarray, threshold: float, path: Path
           ) -> tuple[ForcePlate, str]:
    units = {u: str(p[f"unit_{u}"]).strip().lower() for u in ("force", "moment", "position")}
    if units["force"] != "n" or units["moment"] not in _MOMENT or \
            units["position"] not in _LENGTH:
        raise UnitError(f"{path}: force plate {k} has units {units}; expected N, N·mm or N·m, "
                        "and mm, cm or m")
    L, M = _LENGTH[units["position"]], _MOMENT[units["moment"]]
    f = np.asarray(p["force"], float).T @ R.T
    if len(f) < 2:
        raise ForceDataError(f"{path}: force plate {k} has {len(f)} analog samples (ANALOG:RATE"
                             f" {rate:g} Hz, ANALOG:USED channels): at least 2 are needed; "
                             "check the ANALOG group or drop FORCE_PLATFORM:USED to 0")
    cop = np.asarray(p["center_of_pressure"], float).T * L @ R.T
    tz = np.asarray(p["Tz"], float).T * M @ R.T
    note = ""
    if -f[:, 2].min() > max(f[:, 2].max(), threshold):  # the push on the plate: turn it
        f, tz = -f, -tz
        note = f"plate {k}: force read as the push on the plate, negated; "
    if not np.all(np.isfinite(f)):
        raise ForceDataError(f"{path}: force plate {k} has NaN/inf forces")
    cop = cop.copy()
    cop[f[:, 2] <= threshold] = np.nan
    corners = np.asarray(p["corners"], float).T * L @ R.T
    if not np.all(np.isfinite(corners)):
        raise ForceDataError(f"{path}: force plate {k} has NaN/inf corners "
                             "(FORCE_PLATFORM:CORNERS); give its four corners")
    t = np.arange(len(f)) / rate
    return ForcePlate(t, f, cop, tz, corners, k, threshold), note


def read_c3d(path: str | Path, *, threshold: float = CONTACT_THRESHOLD) -> C3DTrial:
    """Read a C3D file → :class:`C3DTrial` (see the module docstring).

    ``threshold`` [N]: a plate is loaded where its vertical force exceeds it (centre of
    pressure NaN elsewhere). Raises :class:`~gdimitate.errors.FileFormatError` (no such file,
    not a C3D file, no markers, no vertical axis; :class:`~gdimitate.errors.C3DFormatError`,
    one of them, for a truncated or corrupt file, checked before ezc3d reads it:
    :func:`gdimitate.io.c3d.layout.check_c3d`), :class:`~gdimitate.errors.ResourceLimitError`
    (too large), :class:`~gdimitate.errors.OpenSimDataError` (marker values no body has),
    :class:`~gdimitate.errors.UnitError` (units not understood) and
    :class:`~gdimitate.errors.ForceDataError` (NaN forces, plates without samples)."""
    import ezc3d

    from .layout import check_c3d

    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"no such C3D file: {path}")
    check_c3d(path)  # truncated or corrupt layouts crash or hang ezc3d: refused before it
    try:
        c = ezc3d.c3d(str(path), extract_forceplat_data=True)
    except Exception as e:  # ezc3d raises RuntimeError/IOError on a malformed file
        raise FileFormatError(f"{path}: not a readable C3D file ({e})") from None
    markers, R, note = _markers(c, path)
    if not markers.names:
        raise FileFormatError(f"{path}: the C3D file holds no markers")
    plates, notes = [], [note]
    if c["data"]["platform"]:
        rate = _rate(c["parameters"]["ANALOG"], "ANALOG", path)
        for k, p in enumerate(c["data"]["platform"], start=1):
            plate, n = _plate(p, k, rate, R, threshold, path)
            plates.append(plate)
            notes.append(n)
    notes.append(f"{len(plates)} force plate(s), loaded where vertical force > {threshold:g} N")
    return C3DTrial(markers, tuple(plates), str(path), "; ".join(n for n in notes if n))
