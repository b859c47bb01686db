"""``gdimitate paper``: the paper's figures (:mod:`gdimitate.apps.paper`)."""

from __future__ import annotations

import argparse

__all__ = ["add", "run"]


def add(sub) -> None:
    """``gdimitate paper``: the paper's figures (:mod:`gdimitate.apps.paper`)."""
    pp = sub.add_parser("paper", help="the paper's Figs. 4–13 (in spirit) + summary.json")
    pp.add_argument("--out", default="paper-out", help="output folder (default: %(default)s)")
    pp.set_defaults(func=run)


def run(a: argparse.Namespace) -> None:
    from ..paper import run_paper

    run_paper(a.out)
