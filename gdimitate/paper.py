"""Deprecated alias of :mod:`gdimitate.apps.paper` (scenario code, not API): import that.

Importing ``gdimitate.paper`` warns (DeprecationWarning) and binds the same module object, so
every name (and any monkeypatching) is shared; there is no second implementation.
"""

import sys
import warnings

from .apps import paper as _moved

warnings.warn("gdimitate.paper moved to gdimitate.apps.paper (scenario code, not API); "
              "import it from there", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _moved
