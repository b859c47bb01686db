"""Headless Chromium: screenshots of a self-contained HTML page, and comparing them.

Chromium's plain ``--headless`` mode renders WebGL with its software rasteriser
(SwiftShader); ``--use-gl=swiftshader`` and ``--disable-software-rasterizer`` break it
(docs/design.md §10). A static page needs no driver: ``--screenshot`` with ``--virtual-time-budget``
lets the page's scripts run (and the first animation frames play) before the capture. Every
call has a timeout and the whole process group is killed when it expires.

Regenerate the README picture with ``python -m gdimitate.apps.viewer_picture screenshot PNG``.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import ViewerError

__all__ = ["BrowserNotFoundError", "changed_fraction", "find_chromium", "screenshot_html"]

_CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


class BrowserNotFoundError(ViewerError):
    """No Chromium executable was found."""


def find_chromium() -> str:
    """Path of a Chromium executable: ``$GDIMITATE_CHROMIUM`` if set, else the first of
    ``chromium``, ``chromium-browser``, ``google-chrome`` on ``PATH``.

    Raises:
        BrowserNotFoundError: none found (on Debian: ``apt-get install -y chromium``).
    """
    env = os.environ.get("GDIMITATE_CHROMIUM")
    if env:
        if shutil.which(env):
            return str(shutil.which(env))
        raise BrowserNotFoundError(f"GDIMITATE_CHROMIUM={env!r} is not an executable")
    for name in _CANDIDATES:
        found = shutil.which(name)
        if found:
            return found
    raise BrowserNotFoundError(
        f"no Chromium found on PATH (looked for {', '.join(_CANDIDATES)}); on Debian/Ubuntu "
        "install it with `apt-get install -y chromium`, or set GDIMITATE_CHROMIUM"
    )


def _kill_group(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    proc.wait(timeout=10)


def screenshot_html(html_path: str | os.PathLike, png_path: str | os.PathLike,
                    size: tuple[int, int] = (1024, 768), virtual_time_ms: int = 4000,
                    timeout_s: float = 60.0, chromium: str | None = None,
                    extra_args: Sequence[str] = ()) -> Path:
    """Render the local page ``html_path`` in headless Chromium and save a PNG.

    Args:
        html_path: a self-contained HTML file (e.g. from ``Viewer.save_html``).
        png_path: where the screenshot goes.
        size: window ``(width, height)`` in pixels.
        virtual_time_ms: virtual time the page runs before the capture [ms].
        timeout_s: wall-clock limit [s]; the browser is killed when it is reached.
        chromium: executable; default :func:`find_chromium`.
        extra_args: more command-line flags.

    Raises:
        BrowserNotFoundError: no Chromium.
        ViewerError: the page does not exist, the browser failed or timed out, or wrote no
            image.
    """
    exe = chromium or find_chromium()
    page = Path(html_path).resolve()
    if not page.is_file():
        raise ViewerError(f"no HTML file at {page}")
    out = Path(png_path).resolve()
    out.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="gdimitate-chromium-") as profile:
        args = [
            exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
            "--no-first-run", "--no-default-browser-check", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--disable-extensions",
            "--hide-scrollbars", "--mute-audio", f"--user-data-dir={profile}",
            # Without these two, virtual time stalls on a loaded machine: 2 of 4 renders of
            # an 11 MB scene hung past 60 s with three busy processes beside them, 0 of 6 with
            # them (Chromium 156). Small /dev/shm in containers is the other known cause.
            "--run-all-compositor-stages-before-draw", "--disable-dev-shm-usage",
            f"--window-size={int(size[0])},{int(size[1])}",
            f"--virtual-time-budget={int(virtual_time_ms)}",
            f"--screenshot={out}", *extra_args, page.as_uri(),
        ]
        proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            _, err = proc.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            _kill_group(proc)
            raise ViewerError(f"chromium did not finish within {timeout_s:g} s rendering "
                              f"{page}") from None
        finally:
            # Helpers (zygote, GPU process) may outlive the browser: end the whole group.
            if proc.poll() is not None:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except (ProcessLookupError, PermissionError):
                    pass
    if not out.is_file():
        tail = err.decode(errors="replace")[-1500:]
        raise ViewerError(f"chromium (exit {proc.returncode}) wrote no screenshot of {page}: "
                          f"{tail}")
    return out


def changed_fraction(png_a: str | os.PathLike, png_b: str | os.PathLike,
                     tolerance: int = 24) -> float:
    """Fraction of pixels (in [0, 1]) whose colour differs by more than ``tolerance`` (0–255,
    max over RGB channels) between two screenshots of the same size."""
    from PIL import Image

    a = np.asarray(Image.open(png_a).convert("RGB"), dtype=np.int16)
    b = np.asarray(Image.open(png_b).convert("RGB"), dtype=np.int16)
    if a.shape != b.shape:
        raise ViewerError(f"screenshots differ in size: {a.shape} vs {b.shape}")
    return float(np.mean(np.abs(a - b).max(axis=2) > tolerance))
