"""A same-run baseline from an earlier revision of this repository: its tree extracted with
``git archive`` into a temporary folder (nothing in the working folder changes). Shared by the
benchmark scripts (``adaptor.py``, ``streaming.py``, ``import_time.py``)."""

from __future__ import annotations

import subprocess
import tarfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def checkout(rev: str, into: str) -> Path:
    """The tree of ``rev`` extracted into ``into``; returns the tree's folder."""
    tar = Path(into) / "tree.tar"
    with open(tar, "wb") as fh:
        subprocess.run(["git", "-C", str(ROOT), "archive", rev], stdout=fh, check=True)
    with tarfile.open(tar) as t:
        t.extractall(Path(into) / "tree", filter="data")
    return Path(into) / "tree"
