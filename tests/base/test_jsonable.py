"""``gdimitate.jsonable``: the one conversion to plain JSON values that the audit's report,
the physics check's metrics and the walk's ``walk.json`` use. Reference: the expected plain
values written out by hand, and ``json.dumps(..., allow_nan=False)`` accepting the result."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from gdimitate.jsonable import jsonable


class _Pair(NamedTuple):
    a: float
    b: int


@dataclass(frozen=True)
class _Box:
    x: np.ndarray
    y: object


def test_plain_values_by_hand():
    value = {1: np.float32(0.5), "nan": float("nan"), "inf": np.float64(-np.inf),
             "ints": (np.int64(3), 4), "flags": np.array([True, False]),
             "pair": _Pair(np.float64(1.5), np.int32(2)),
             "box": _Box(np.arange(4).reshape(2, 2), {"z": [np.nan, 2.0]}),
             "text": "s", "none": None, "bool": np.bool_(True)}
    want = {"1": 0.5, "nan": None, "inf": None, "ints": [3, 4], "flags": [True, False],
            "pair": {"a": 1.5, "b": 2}, "box": {"x": [[0, 1], [2, 3]], "y": {"z": [None, 2.0]}},
            "text": "s", "none": None, "bool": True}
    got = jsonable(value)
    assert got == want
    assert json.loads(json.dumps(got, allow_nan=False)) == want
    assert type(got["bool"]) is bool and type(got["ints"][0]) is int
    assert type(got["1"]) is float


def test_the_reports_use_it():
    """The audit's report and the physics check's metrics take the one function (no copy of
    the conversion is left in them)."""
    import importlib
    import inspect

    for name in ("assess.audit.report", "sim.simulate", "walker.result"):
        module = importlib.import_module(f"gdimitate.{name}")
        assert module.jsonable is jsonable
        assert "isfinite(x) else None" not in inspect.getsource(module)
