"""Plain JSON values, written once for every report the package writes to JSON (the audit's
:meth:`~gdimitate.audit.AuditReport.to_json`, the physics check's
:meth:`~gdimitate.sim.SimMetrics.to_dict`, the walk's ``walk.json``). Imports NumPy only."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields, is_dataclass
from typing import Any

import numpy as np

__all__ = ["jsonable"]


def jsonable(x: object) -> Any:
    """A JSON-safe copy of ``x``: mappings → dicts with ``str`` keys, named tuples and dataclass
    instances → dicts of their fields, NumPy arrays, lists and tuples → lists, NumPy scalars →
    ``bool``/``int``/``float``, NaN and ±inf → ``None`` (JSON has neither); anything else as
    it is. Recursive."""
    if isinstance(x, Mapping):
        return {str(k): jsonable(v) for k, v in x.items()}
    if hasattr(x, "_asdict"):
        return jsonable(x._asdict())
    if is_dataclass(x) and not isinstance(x, type):
        return {f.name: jsonable(getattr(x, f.name)) for f in fields(x)}
    if isinstance(x, np.ndarray):
        return [jsonable(v) for v in x.tolist()]
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x
