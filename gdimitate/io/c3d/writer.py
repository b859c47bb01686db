"""Write markers and force plates as a C3D file (``ezc3d``): :func:`write_c3d`.

The reverse of :func:`~gdimitate.c3d.read_c3d`, for synthetic trials and for turning other
lab exports (a ``.trc`` with its forces) into the format labs exchange. Markers are written in
millimetres, lab frame Z up (our world frame). Each plate is a type-2 platform (six channels
Fx Fy Fz Mx My Mz, identity calibration) whose surface is the axis-aligned rectangle around its
``corners``, its axes the usual AMTI ones (plate x = lab x, y = −y, z = −z, down), its origin
at the surface centre; the channels hold the reaction on the subject in those axes, N and
N·mm about the surface centre, at the analog rate (the plates resampled linearly onto it).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ...errors import InvalidInputError
from ...model.osim.trc import Markers
from .reader import ForcePlate

__all__ = ["write_c3d"]

_R = np.diag([1.0, -1.0, -1.0])  # lab from plate axes (and its own inverse)


def _corners(plate: ForcePlate) -> np.ndarray:
    """(3, 4) [mm] corners in C3D order: 1 (+x, +y), 2 (−x, +y), 3 (−x, −y), 4 (+x, −y) of
    the plate's axes."""
    lo, hi = plate.corners.min(axis=0), plate.corners.max(axis=0)
    z = float(plate.corners[:, 2].mean())
    c = [(hi[0], lo[1]), (lo[0], lo[1]), (lo[0], hi[1]), (hi[0], hi[1])]
    return np.array([[x, y, z] for x, y in c]).T * 1000.0


def _channels(plate: ForcePlate, t: np.ndarray) -> np.ndarray:
    """(6, len(t)) Fx Fy Fz [N] and Mx My Mz [N·mm] in plate axes about the surface centre."""
    centre = plate.corners.mean(axis=0)
    cop = np.where(np.isnan(plate.cop), centre, plate.cop)
    F, P, Tq = (np.column_stack([np.interp(t, plate.t, x[:, k]) for k in range(3)])
                for x in (plate.force, cop, plate.free_moment))
    M = np.cross(P - centre, F) + Tq
    return np.vstack([(F @ _R).T, (M @ _R).T * 1000.0])


def write_c3d(path: str | Path, markers: Markers, plates: Sequence[ForcePlate] = (), *,
              analog_rate: float | None = None) -> Path:
    """Write ``markers`` (our world frame, metres) and ``plates`` to a C3D file at ``path``.

    ``analog_rate`` [Hz]: the plates' sample rate in the file (default: the first plate's,
    rounded to a whole multiple of the marker rate, as C3D requires). Returns ``path``. Raises
    :class:`~gdimitate.errors.InvalidInputError` for an analog rate that is not a multiple
    of the marker rate."""
    import ezc3d

    path = Path(path)
    rate = markers.rate
    T = markers.t.size
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = np.array([rate])
    c["parameters"]["POINT"]["LABELS"]["value"] = list(markers.names)
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    pts = np.ones((4, len(markers.names), T))
    pts[:3] = markers.xyz.transpose(2, 1, 0) * 1000.0
    c["data"]["points"] = pts
    if plates:
        ratio = round((analog_rate or plates[0].rate) / rate)
        if ratio < 1 or (analog_rate and abs(ratio * rate - analog_rate) > 1e-6):
            raise InvalidInputError(f"analog_rate must be a whole multiple of the marker rate "
                                    f"{rate:g} Hz; got {analog_rate or plates[0].rate:g}")
        t = markers.t[0] + np.arange(T * ratio) / (ratio * rate)
        t = np.clip(t, max(p.t[0] for p in plates), min(p.t[-1] for p in plates))
        c["parameters"]["ANALOG"]["RATE"]["value"] = np.array([ratio * rate])
        n = 6 * len(plates)
        labels = [f"{a}{k}" for k in range(1, len(plates) + 1)
                  for a in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")]
        c["parameters"]["ANALOG"]["LABELS"]["value"] = labels
        c["parameters"]["ANALOG"]["UNITS"]["value"] = ["N", "N", "N", "Nmm", "Nmm", "Nmm"] * \
            len(plates)
        c["data"]["analogs"] = np.vstack([_channels(p, t) for p in plates])[None]
        fp = c["parameters"]["FORCE_PLATFORM"]
        fp["USED"]["value"] = np.array([len(plates)])
        fp["TYPE"]["value"] = np.array([2] * len(plates))
        fp["ZERO"]["value"] = np.array([1, 0])
        fp["CORNERS"]["value"] = np.stack([_corners(p) for p in plates], axis=-1)
        fp["ORIGIN"]["value"] = np.zeros((3, len(plates)))
        fp["CHANNEL"]["value"] = np.arange(1, n + 1).reshape(len(plates), 6).T
    c.write(str(path))
    return path
