"""Helpers of the tests that compare what a command printed with what it wrote (issue 34:
every printed number equals the report's and the audit's)."""

from __future__ import annotations

import re
from typing import Any

#: a number as the console prints it (``nan`` included), not part of a name (``hoap2``,
#: ``base_x``, ``subject01``) or a term (``3-D``)
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:nan|inf|\d+\.\d*|\.\d+|\d+)(?:e[-+]?\d+)?"
                    r"(?![\w.]|-[A-Za-z])")


def numbers(text: str) -> list[str]:
    """Every number printed in ``text``, in order, as printed."""
    return NUMBER.findall(text)


def flat(d: Any, path: str = "") -> dict[str, Any]:
    """A nested JSON value as ``{path: leaf}`` (for ``pytest.approx``)."""
    if isinstance(d, dict):
        return {k: v for key, x in d.items() for k, v in flat(x, f"{path}/{key}").items()}
    if isinstance(d, (list, tuple)):
        return {k: v for i, x in enumerate(d) for k, v in flat(x, f"{path}/{i}").items()}
    return {path: d}
