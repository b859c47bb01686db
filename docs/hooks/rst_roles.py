"""A Griffe extension for the API reference (mkdocs.yml): gdimitate's docstrings are written
in reStructuredText's inline markup (``code``, :class:`~gdimitate.model.robot.Robot`,
:data:`X`), which Markdown would show with the role names; this turns each role into a code
span of its target (``~`` keeps the last name, as Sphinx does). Docstrings themselves are
unchanged: the rewrite happens on Griffe's copy when the site is built."""

from __future__ import annotations

import re
from typing import Any

import griffe

#: ``:role:`target``` and ``:role:`~dotted.target```
ROLE = re.compile(r":(?:py:)?\w+:`(~?)([^`]+)`")


def _role(m: re.Match[str]) -> str:
    target = m.group(2)
    return f"`{target.rsplit('.', 1)[-1]}`" if m.group(1) else f"`{target}`"


def markdown(text: str) -> str:
    """``text`` with reST roles as Markdown code spans."""
    return ROLE.sub(_role, text)


class RstRoles(griffe.Extension):
    """Rewrite reST roles in every docstring Griffe loads."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)
