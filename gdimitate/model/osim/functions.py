"""OpenSim's one-variable functions (``Constant``, ``LinearFunction``, ``SimmSpline``,
``NaturalCubicSpline``, ``PiecewiseLinearFunction``, ``PolynomialFunction`` (also read under
the name ``Polynomial``), ``MultiplierFunction``),
evaluated as OpenSim evaluates them.

``SimmSpline`` is the cubic spline of Forsythe, Malcolm & Moler (*Computer Methods for
Mathematical Computations*, 1977, routine ``spline``): end conditions match the third
derivatives of the cubics through the first and last four points; outside its knots it
extrapolates linearly with the end slopes (opensim-core ``SimmSpline.cpp``). OpenSim reads a
``NaturalCubicSpline`` element as a ``SimmSpline`` (the older name), so both evaluate alike here.
``PiecewiseLinearFunction`` extrapolates with its end segments' slopes; a polynomial's
coefficients are in descending powers. The test suite compares these against OpenSim itself
through the joint kinematics they drive.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from ...errors import OsimError

__all__ = ["Function", "parse_function", "SUPPORTED_FUNCTIONS"]

SUPPORTED_FUNCTIONS = ("Constant", "LinearFunction", "SimmSpline", "NaturalCubicSpline",
                       "PiecewiseLinearFunction", "PolynomialFunction", "MultiplierFunction")


@dataclass(frozen=True)
class Function:
    """One OpenSim function of a single variable.

    ``kind``: ``"Constant"``, ``"LinearFunction"``, ``"SimmSpline"`` (also for
    ``NaturalCubicSpline``), ``"PiecewiseLinearFunction"``, ``"Polynomial"`` or
    ``"MultiplierFunction"``; ``x``, ``y``: knots (splines, piecewise linear); ``coefficients``:
    ``(slope, intercept)`` of a ``LinearFunction``, descending powers of a ``Polynomial``, or
    ``(value,)`` of a ``Constant``; ``scale`` and ``inner`` for a ``MultiplierFunction``.
    """

    kind: str
    x: tuple[float, ...] = ()
    y: tuple[float, ...] = ()
    coefficients: tuple[float, ...] = ()
    scale: float = 1.0
    inner: Function | None = None

    @property
    def is_constant(self) -> bool:
        return self.kind == "Constant"

    def linear(self) -> tuple[float, float] | None:
        """``(slope, intercept)`` if the function is exactly linear (a ``LinearFunction``, a
        degree ≤ 1 ``Polynomial`` or a multiple of one), else ``None``."""
        if self.kind == "LinearFunction":
            return self.coefficients[0], self.coefficients[1]
        if self.kind == "Polynomial" and len(self.coefficients) <= 2:
            c = (0.0,) * (2 - len(self.coefficients)) + self.coefficients
            return c[0], c[1]
        if self.kind == "MultiplierFunction" and self.inner is not None:
            lin = self.inner.linear()
            return None if lin is None else (self.scale * lin[0], self.scale * lin[1])
        return None

    def __call__(self, x: float | np.ndarray) -> np.ndarray:
        """Value at ``x`` (any shape) → same shape."""
        x = np.asarray(x, dtype=float)
        k = self.kind
        if k == "Constant":
            return np.full_like(x, self.coefficients[0])
        if k == "LinearFunction":
            return self.coefficients[0] * x + self.coefficients[1]
        if k == "Polynomial":
            return np.polyval(np.asarray(self.coefficients), x)
        if k == "MultiplierFunction":
            if self.inner is None:
                raise OsimError("a MultiplierFunction without its inner function")
            return self.scale * self.inner(x)
        if k == "PiecewiseLinearFunction":
            return _piecewise_linear(np.asarray(self.x), np.asarray(self.y), x)
        return _simm_spline(np.asarray(self.x), np.asarray(self.y), x)


def _piecewise_linear(xs: np.ndarray, ys: np.ndarray, x: np.ndarray) -> np.ndarray:
    if len(xs) == 1:
        return np.full_like(x, ys[0])
    slope = np.diff(ys) / np.diff(xs)
    i = np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 2)
    return ys[i] + slope[i] * (x - xs[i])


def _fmm_coefficients(x: np.ndarray, y: np.ndarray):
    """b, c, d of the Forsythe–Malcolm–Moler spline: y_i + b_i t + c_i t² + d_i t³."""
    n = len(x)
    b, c, d = np.zeros(n), np.zeros(n), np.zeros(n)
    if n == 2:
        b[:] = (y[1] - y[0]) / (x[1] - x[0])
        return b, c, d
    nm1, nm2 = n - 1, n - 2
    d[0] = x[1] - x[0]
    c[1] = (y[1] - y[0]) / d[0]
    for i in range(1, nm1):
        d[i] = x[i + 1] - x[i]
        b[i] = 2.0 * (d[i - 1] + d[i])
        c[i + 1] = (y[i + 1] - y[i]) / d[i]
        c[i] = c[i + 1] - c[i]
    b[0], b[nm1] = -d[0], -d[nm2]
    c[0] = c[nm1] = 0.0
    if n > 3:
        d31, d20 = x[3] - x[1], x[2] - x[0]
        d1, d2 = x[nm1] - x[n - 3], x[nm2] - x[n - 4]
        d30, d3 = x[3] - x[0], x[nm1] - x[n - 4]
        c[0] = (c[2] / d31 - c[1] / d20) * d[0] * d[0] / d30
        c[nm1] = -(c[nm2] / d1 - c[n - 3] / d2) * d[nm2] * d[nm2] / d3
    for i in range(1, n):
        t = d[i - 1] / b[i - 1]
        b[i] -= t * d[i - 1]
        c[i] -= t * c[i - 1]
    c[nm1] /= b[nm1]
    for i in range(nm2, -1, -1):
        c[i] = (c[i] - d[i] * c[i + 1]) / b[i]
    b[nm1] = (y[nm1] - y[nm2]) / d[nm2] + d[nm2] * (c[nm2] + 2.0 * c[nm1])
    for i in range(nm1):
        b[i] = (y[i + 1] - y[i]) / d[i] - d[i] * (c[i + 1] + 2.0 * c[i])
        d[i] = (c[i + 1] - c[i]) / d[i]
        c[i] *= 3.0
    c[nm1] *= 3.0
    d[nm1] = d[nm2]
    return b, c, d


def _simm_spline(xs: np.ndarray, ys: np.ndarray, x: np.ndarray) -> np.ndarray:
    if len(xs) == 1:
        return np.full_like(x, ys[0])
    b, c, d = _fmm_coefficients(xs, ys)
    i = np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 1)
    t = x - xs[i]
    inside = ys[i] + t * (b[i] + t * (c[i] + t * d[i]))
    below = ys[0] + (x - xs[0]) * b[0]
    above = ys[-1] + (x - xs[-1]) * b[-1]
    return np.where(x < xs[0], below, np.where(x > xs[-1], above, inside))


def _numbers(el: ET.Element | None, where: str) -> tuple[float, ...]:
    if el is None or el.text is None:
        raise OsimError(f"{where}: missing numbers")
    try:
        return tuple(float(v) for v in el.text.split())
    except ValueError:
        raise OsimError(f"{where}: {el.text.strip()!r} is not a list of numbers") from None


def parse_function(el: ET.Element, where: str) -> Function:
    """A :class:`Function` from an OpenSim function element (the child of ``<function>``).

    Raises :class:`~gdimitate.errors.OsimError` for an unsupported type or malformed knots.
    """
    kind = el.tag
    if kind == "Constant":
        return Function("Constant", coefficients=_numbers(el.find("value"), f"{where} Constant"))
    if kind == "LinearFunction":
        c = _numbers(el.find("coefficients"), f"{where} LinearFunction")
        if len(c) != 2:
            raise OsimError(f"{where}: LinearFunction needs 2 coefficients (slope intercept), "
                            f"got {len(c)}")
        return Function("LinearFunction", coefficients=c)
    if kind in ("PolynomialFunction", "Polynomial"):
        c = _numbers(el.find("coefficients"), f"{where} {kind}")
        if not c:
            raise OsimError(f"{where}: Polynomial has no coefficients")
        return Function("Polynomial", coefficients=c)
    if kind == "MultiplierFunction":
        holder = el.find("function")
        inner = None if holder is None else next(iter(holder), None)
        if inner is None:
            raise OsimError(f"{where}: MultiplierFunction without an inner <function>")
        scale_el = el.find("scale")
        scale = _numbers(scale_el, f"{where} MultiplierFunction scale")[0] if scale_el is not None \
            else 1.0
        return Function("MultiplierFunction", scale=scale,
                        inner=parse_function(inner, f"{where} (inner)"))
    if kind in ("SimmSpline", "NaturalCubicSpline", "PiecewiseLinearFunction"):
        x = _numbers(el.find("x"), f"{where} {kind} x")
        y = _numbers(el.find("y"), f"{where} {kind} y")
        if len(x) != len(y) or len(x) < 1:
            raise OsimError(f"{where}: {kind} needs as many x as y knots (got {len(x)} x, "
                            f"{len(y)} y)")
        if np.any(np.diff(x) <= 0):
            raise OsimError(f"{where}: {kind} knots x must increase strictly: {x}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise OsimError(f"{where}: {kind} has NaN/inf knots")
        return Function("PiecewiseLinearFunction" if kind == "PiecewiseLinearFunction"
                        else "SimmSpline", x=x, y=y)
    raise OsimError(
        f"{where}: unsupported function type <{kind}>; supported: {', '.join(SUPPORTED_FUNCTIONS)}"
        ". Replace it (e.g. by a SimmSpline sampled from it) in the .osim file.")
