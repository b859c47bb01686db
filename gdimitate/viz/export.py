"""Self-contained HTML: writing meshcat's ``static_html()`` to a file, and notebook display.

meshcat's static page embeds the viewer's JavaScript and every drawing command (meshes
included, base64) so it plays offline; :func:`network_references` lists anything in a page
that would still reach out to the network (it should find nothing).
"""

from __future__ import annotations

import html as _html
import os
import re
from collections.abc import Callable
from pathlib import Path

from ..errors import OutputError, ViewerError
from ..safety import atomic_write

__all__ = ["LEGEND_ID", "check_writable", "inline_html", "network_references",
           "notebook_display", "with_legend", "write_html"]

#: The ``id`` of the legend box a saved page carries (:func:`with_legend`).
LEGEND_ID = "gdimitate-legend"

# Attributes and JS/CSS constructs that make a browser fetch a URL when the page loads.
_FETCHING = re.compile(
    r"""(?:\b(?:src|href|data|poster|srcset)\s*=\s*["']?\s*(?:https?:)?//"""
    r"""|@import\s+(?:url\()?\s*["']?\s*(?:https?:)?//"""
    r"""|\burl\(\s*["']?\s*(?:https?:)?//"""
    r"""|\bimport\s*\(?\s*["']\s*(?:https?:)?//"""
    r"""|\bfrom\s+["']\s*(?:https?:)?//"""
    r"""|\bfetch\(\s*["']\s*(?:https?:)?//)""",
    re.IGNORECASE,
)


def network_references(html: str) -> list[str]:
    """Snippets of ``html`` that would load something over the network when the page opens
    (``<script src="https://...">``, ``<link href="//...">``, CSS ``url(http...)``, ES
    ``import ... from "https://..."``, ``fetch("http...")``). Empty for a self-contained page.

    URLs that only appear inside strings (licence headers, error messages) are not counted.
    """
    return [html[max(m.start() - 40, 0): m.end() + 60] for m in _FETCHING.finditer(html)]


def with_legend(page: str, title: str,
                entries: list[tuple[str, tuple[float, float, float] | None]]) -> str:
    """meshcat's static ``page`` with the ``title`` (meshcat's own is "MeshCat") and a legend
    box in the top-left corner (the viewer's controls are top-right): one line per
    ``(label, rgb)`` entry, a colour swatch (``rgb`` in [0, 1]; None: the model's own colours,
    drawn grey) before its label, so that a reader can tell the demonstrator from the plan
    and the simulation."""
    rows = "".join(
        f'<div><span style="display:inline-block;width:0.9em;height:0.9em;margin-right:0.4em;'
        f'vertical-align:-0.1em;border:1px solid #555;background:{_css(rgb)}"></span>'
        f"{_html.escape(label)}</div>" for label, rgb in entries)
    box = (f'<div id="{LEGEND_ID}" style="position:fixed;top:10px;left:10px;z-index:10;'
           "padding:8px 12px;background:rgba(255,255,255,0.88);border:1px solid #888;"
           'border-radius:4px;font:15px/1.5 sans-serif;color:#111">'
           f"<div style=\"font-weight:bold\">{_html.escape(title)}</div>{rows}</div>")
    page = re.sub(r"<title>.*?</title>", lambda _: f"<title>{_html.escape(title)}</title>",
                  page, count=1, flags=re.DOTALL)
    return re.sub(r"<body>", lambda m: m.group(0) + box, page, count=1)


def _css(rgb: tuple[float, float, float] | None) -> str:
    if rgb is None:
        return "linear-gradient(135deg,#ddd,#777)"
    r, g, b = (int(round(255 * min(max(c, 0.0), 1.0))) for c in rgb)
    return f"rgb({r},{g},{b})"


def check_writable(path: str | os.PathLike) -> Path:
    """``path`` as a ``Path`` if a file can be written there (an existing file is left as it
    is); else :class:`ViewerError` saying why."""
    p = Path(path).expanduser()
    if p.is_dir():
        raise ViewerError(f"cannot write HTML to {p}: it is a folder; give a file name")
    if not p.parent.is_dir():
        raise ViewerError(f"cannot write HTML to {p}: folder {p.parent} does not exist")
    existed = p.exists()
    try:
        with open(p, "ab"):
            pass
    except OSError as e:
        raise ViewerError(f"cannot write HTML to {p}: {e.strerror or e}") from e
    if not existed:
        p.unlink(missing_ok=True)
    return p


def write_html(html: str, path: str | os.PathLike) -> Path:
    """Write ``html`` to ``path`` (UTF-8) through a temporary file in the same folder that is
    renamed into place once complete; return the absolute path.

    Raises:
        ViewerError: if the folder does not exist or the file cannot be written.
    """
    p = check_writable(path)
    try:  # a temporary name, renamed when complete: Ctrl-C never leaves half a page
        with atomic_write(p) as tmp:
            tmp.write_text(html, encoding="utf-8")
    except OutputError as e:
        raise ViewerError(f"cannot write HTML to {p}: {e}") from e
    return p.resolve()


def inline_html(html: str, height: int = 480) -> str:
    """An ``<iframe srcdoc=...>`` snippet that shows the self-contained page ``html`` inside
    a notebook cell of ``height`` pixels (needs no server and no network)."""
    return (
        f'<div style="height: {int(height)}px; width: 100%; overflow: hidden; resize: both">'
        f'<iframe srcdoc="{_html.escape(html, quote=True)}" '
        'style="width: 100%; height: 100%; border: none"></iframe></div>'
    )


def notebook_display(html: Callable[[], str], url: str, height: int = 480,
                     live: bool = False) -> object:
    """Show a scene in a Jupyter cell and return the ``IPython.display.HTML`` object.

    ``live=False``: the self-contained page ``html()`` embedded (works with a remote kernel
    and offline, frozen at this moment); ``live=True``: the server's page ``url`` in an iframe
    (follows later changes; the browser must reach it). Outside a notebook nothing is
    displayed and nothing blocks; the object is just returned."""
    from IPython.display import HTML

    if live:
        obj = HTML(
            f'<div style="height: {int(height)}px; width: 100%; resize: both; '
            f'overflow: hidden"><iframe src="{url}" style="width: 100%; '
            'height: 100%; border: none"></iframe></div>')
    else:
        obj = HTML(inline_html(html(), height))
    try:
        from IPython import get_ipython

        shell = get_ipython()
    except ImportError:  # pragma: no cover
        shell = None
    if shell is not None and getattr(shell, "kernel", None) is not None:
        from IPython.display import display

        display(obj)
    return obj
