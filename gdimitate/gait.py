"""Demonstrations from files: OpenSim coordinate files (``.mot``) and the shipped real walk."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np

from .errors import InvalidInputError

__all__ = ["read_mot", "human_walk_path"]


def human_walk_path() -> Path:
    """Path of the shipped OpenSim walk (``walk_gait1018_state_reference.mot``, 60 Hz, degrees)."""
    folder = resources.files("gdimitate") / "data" / "gait" / "opensim_subject01_walk"
    return Path(str(folder / "walk_gait1018_state_reference.mot"))


def read_mot(path: str | Path) -> dict[str, np.ndarray]:
    """Read an OpenSim ``.mot``/``.sto`` table into ``{column: (T,) array}``, values as stored.

    Column names are shortened to their coordinate name (``/jointset/hip_r/hip_flexion_r/value``
    → ``hip_flexion_r``). Angles stay in the file's unit (the header's ``inDegrees`` tells);
    the key ``"__in_degrees__"`` holds that flag as a 0-d boolean array.
    """
    path = Path(path)
    if not path.is_file():
        raise InvalidInputError(f"no such OpenSim file: {path}")
    lines = path.read_text().splitlines()
    try:
        end = next(i for i, line in enumerate(lines) if line.strip().lower() == "endheader")
    except StopIteration:
        raise InvalidInputError(f"{path}: no 'endheader' line; not an OpenSim .mot/.sto") from None
    in_degrees = any(
        line.replace(" ", "").lower() == "indegrees=yes" for line in lines[:end]
    )
    names = lines[end + 1].split("\t") if "\t" in lines[end + 1] else lines[end + 1].split()
    names = [n.strip() for n in names if n.strip()]
    short = [n.split("/")[-2] if n.endswith("/value") else n.split("/")[-1] for n in names]
    try:
        data = np.loadtxt(lines[end + 2 :], ndmin=2)
    except ValueError as e:
        raise InvalidInputError(f"{path}: malformed numeric table ({e})") from None
    if data.shape[1] != len(short):
        raise InvalidInputError(
            f"{path}: {len(short)} column names but {data.shape[1]} columns of numbers"
        )
    out = {n: data[:, i].copy() for i, n in enumerate(short)}
    out["__in_degrees__"] = np.asarray(in_degrees)
    return out
