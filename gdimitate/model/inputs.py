"""Checks of what a caller hands the library: argument types, the ``legs=``/``contacts=``
options, and JSON option text (files or strings), so that a wrong type or a hostile file
raises a :class:`~gdimitate.errors.GdimitateError` naming the argument and what to give,
never a bare ``TypeError``, ``RecursionError`` or ``JSONDecodeError`` (issue 33).

JSON (:func:`loads_json`, :func:`read_json`): at most :data:`MAX_JSON_BYTES` of UTF-8 text,
nested at most :data:`MAX_JSON_DEPTH` deep (checked before parsing: Python's parser recurses),
integers of at most :data:`MAX_JSON_DIGITS` digits (Python refuses to convert more than 4300
with a ``ValueError``), no ``NaN``/``Infinity`` and no number that overflows to infinity.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import GdimitateError, InvalidInputError

__all__ = ["MAX_FRICTION", "MAX_JSON_BYTES", "MAX_JSON_DEPTH", "MAX_JSON_DIGITS",
           "MAX_SOLE_HALF_SIZE_M", "check_contacts", "check_legs", "loads_json", "path_arg",
           "read_json"]

#: Largest JSON option text (``--legs``, ``--contacts``, a body map, a motion file's recorded
#: legs) [bytes]: these are a few hundred bytes; 1 MiB is a thousand times more.
MAX_JSON_BYTES = 2**20
#: Deepest nesting of JSON arrays/objects (the options are two levels deep).
MAX_JSON_DEPTH = 32
#: Most digits of a JSON integer.
MAX_JSON_DIGITS = 30
#: Largest sole half-length or half-width [m] (a 4 m foot; feet of legged robots are
#: 0.1–0.3 m).
MAX_SOLE_HALF_SIZE_M = 2.0
#: Largest friction coefficient of a sole (rubber on concrete is about 1).
MAX_FRICTION = 10.0


def path_arg(name: str, value: object) -> Path:
    """``value`` as a :class:`~pathlib.Path` if it is a ``str`` or ``os.PathLike``; else
    :class:`InvalidInputError` naming the argument ``name``."""
    if isinstance(value, bytes) or not isinstance(value, str | os.PathLike):
        raise InvalidInputError(f"{name} must be a file path (str or pathlib.Path); got "
                                f"{type(value).__name__} {value!r:.80}")
    text = os.fspath(value)
    if not isinstance(text, str) or not text or "\0" in text:
        raise InvalidInputError(f"{name} must be a non-empty file path without NUL bytes; got "
                                f"{value!r:.80}")
    return Path(text)


def _depth(text: str) -> int:
    """Deepest bracket nesting of JSON ``text``, outside strings (no parsing)."""
    depth = deepest = 0
    in_str = esc = False
    for ch in text:
        if in_str:
            if esc:
                esc = False
            elif ch == "\\":
                esc = True
            elif ch == '"':
                in_str = False
        elif ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth -= 1
    return deepest


def loads_json(text: str | bytes, where: str,
               error: type[GdimitateError] = InvalidInputError, unique_keys: bool = False
               ) -> Any:
    """The JSON value of ``text`` (from ``where``, for messages), within the bounds of the
    module docstring; else ``error`` naming ``where`` and what is wrong (with ``unique_keys``,
    an object that repeats a key too: plain JSON keeps the last silently)."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as e:
            raise error(f"{where}: not UTF-8 text (byte {e.start}); JSON must be UTF-8"
                        ) from None
    if not isinstance(text, str):
        raise error(f"{where}: expected JSON text; got {type(text).__name__}")
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as e:  # a lone surrogate: bytes that were not UTF-8
        raise error(f"{where}: not UTF-8 text (character {e.start}); JSON must be UTF-8"
                    ) from None
    if len(text) > MAX_JSON_BYTES:
        raise error(f"{where}: {len(text):,} characters of JSON; the limit is "
                    f"{MAX_JSON_BYTES:,} (gdimitate.model.inputs.MAX_JSON_BYTES)")
    d = _depth(text)
    if d > MAX_JSON_DEPTH:
        raise error(f"{where}: JSON nested {d:,} deep; the limit is {MAX_JSON_DEPTH} "
                    "(gdimitate.model.inputs.MAX_JSON_DEPTH)")

    def number(s: str) -> float:
        v = float(s)
        if not math.isfinite(v):
            raise ValueError(f"the number {s[:40]} overflows (its magnitude exceeds 1.8e308)")
        return v

    def integer(s: str) -> int:
        if len(s.lstrip("-")) > MAX_JSON_DIGITS:
            raise ValueError(f"an integer of {len(s.lstrip('-')):,} digits (the limit is "
                             f"{MAX_JSON_DIGITS})")
        return int(s)

    def constant(s: str) -> float:
        raise ValueError(f"{s} is not a number JSON allows (give a finite number)")

    def unique(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        seen: dict[str, Any] = {}
        for k, v in pairs:
            if k in seen:
                raise ValueError(f"the key {k!r:.80} appears twice in one object (give it once)")
            seen[k] = v
        return seen

    try:
        return json.loads(text, parse_float=number, parse_int=integer,
                          parse_constant=constant, object_pairs_hook=unique if unique_keys
                          else None)
    except json.JSONDecodeError as e:
        raise error(f"{where}: not valid JSON ({e})") from None
    except (ValueError, RecursionError) as e:
        raise error(f"{where}: {e}") from None


def read_json(path: str | os.PathLike, what: str,
              error: type[GdimitateError] = InvalidInputError, unique_keys: bool = False
              ) -> Any:
    """The JSON value in file ``path`` (``what`` names it in messages, e.g. ``"--legs"``):
    at most :data:`MAX_JSON_BYTES` (checked before reading), then :func:`loads_json`."""
    p = path_arg(what, path)
    try:
        size = p.stat().st_size
        if size > MAX_JSON_BYTES:
            raise error(f"{what} {p}: {size:,} bytes; the limit for a JSON option file is "
                        f"{MAX_JSON_BYTES:,} (gdimitate.model.inputs.MAX_JSON_BYTES)")
        data = p.read_bytes()
    except OSError as e:
        raise error(f"{what} {p}: cannot read it ({e.strerror or e})") from None
    return loads_json(data, f"{what} {p}", error, unique_keys)


def _per_side(value: object, where: str, shape: str) -> list[tuple[object, object]]:
    """The ``(side, entry)`` items of a per-foot option ``{"left": …, "right": …}``, or
    :class:`InvalidInputError` (``shape``: what one entry looks like, for the message)."""
    if not isinstance(value, Mapping):
        raise InvalidInputError(f"{where} must be a dict {{'left': {shape}, 'right': {{…}}}}; "
                                f"got {type(value).__name__} {value!r:.80}")
    bad = [k for k in value if k not in ("left", "right")]
    if bad:
        raise InvalidInputError(f"{where}: keys must be 'left' and 'right'; got {bad[:5]!r:.120}")
    return list(value.items())


def check_legs(legs: object, where: str = "legs=") -> None:
    """Refuse a ``legs=`` value that is not ``None`` or ``{"left": {...}, "right": {...}}`` of
    role (``hip``, ``knee``, ``ankle``, ``sole``) → name (``str``; ``ankle`` may be
    ``None``)."""
    if legs is None:
        return
    for side, d in _per_side(legs, where, "{'hip': …, 'knee': …, 'ankle': …, 'sole': …}"):
        if not isinstance(d, Mapping):
            raise InvalidInputError(f"{where}[{side!r}] must be a dict of hip, knee, ankle, "
                                    f"sole names; got {type(d).__name__} {d!r:.80}")
        for role, name in d.items():
            if role not in ("hip", "knee", "ankle", "sole"):
                raise InvalidInputError(f"{where}[{side!r}]: unknown role {role!r:.60}; valid: "
                                        "hip, knee, ankle, sole")
            if not (isinstance(name, str) or (name is None and role == "ankle")):
                raise InvalidInputError(f"{where}[{side!r}][{role!r}] must be a joint or frame "
                                        f"name (str); got {type(name).__name__} {name!r:.80}")


def check_contacts(contacts: object, where: str = "contacts=") -> None:
    """Refuse a ``contacts=`` value that is not ``None`` or ``{side: SoleContact | {...}}``
    whose ``half_length``, ``half_width`` [m] are real numbers in (0,
    :data:`MAX_SOLE_HALF_SIZE_M`], ``mu`` in (0, :data:`MAX_FRICTION`] and ``frame`` a name
    (JSON ``true`` is not a size)."""
    from .contact import SoleContact

    if contacts is None:
        return
    for side, g in _per_side(contacts, where, "{'half_length': m, 'half_width': m, …}"):
        if isinstance(g, SoleContact):
            g = {k: getattr(g, k) for k in ("frame", "half_length", "half_width", "mu")}
        if not isinstance(g, Mapping):
            raise InvalidInputError(f"{where}[{side!r}] must be a SoleContact or a dict with "
                                    f"half_length, half_width [m]; got {type(g).__name__} "
                                    f"{g!r:.80}")
        for key, v in g.items():
            if key == "frame":
                if v is not None and not isinstance(v, str):
                    raise InvalidInputError(f"{where}[{side!r}]['frame'] must be a frame name "
                                            f"(str); got {type(v).__name__} {v!r:.80}")
                continue
            if key not in ("half_length", "half_width", "mu"):
                continue  # unknown keys: named by the contact module
            hi, unit, bound = ((MAX_FRICTION, "", "MAX_FRICTION") if key == "mu" else
                               (MAX_SOLE_HALF_SIZE_M, " m", "MAX_SOLE_HALF_SIZE_M"))
            real = isinstance(v, int | float) and not isinstance(v, bool)
            try:
                real = real or (hasattr(v, "dtype") and v.dtype.kind in "fiu" and v.ndim == 0)
            except AttributeError:
                real = False
            if not real:
                raise InvalidInputError(f"{where}[{side!r}][{key!r}] must be a number; got "
                                        f"{type(v).__name__} {v!r:.80}")
            x = float(v)
            if not (math.isfinite(x) and 0 < x <= hi):
                raise InvalidInputError(
                    f"{where}[{side!r}][{key!r}] = {v!r:.40} must be a finite number in (0, "
                    f"{hi:g}]{unit} (gdimitate.model.inputs.{bound}): is the unit right?")
