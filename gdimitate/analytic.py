"""Deprecated: moved to :mod:`gdimitate.planar.analytic` (re-exported here, with a warning)."""

import warnings

from .planar.analytic import adapt_planar, check_pair

__all__ = ["adapt_planar", "check_pair"]

warnings.warn("gdimitate.analytic is deprecated: import adapt_planar and check_pair from "
              "gdimitate.planar", DeprecationWarning, stacklevel=2)
