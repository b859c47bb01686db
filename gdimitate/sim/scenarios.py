"""Deprecated alias of :mod:`gdimitate.apps.scenarios` (scenario code, not API): import that.

Importing ``gdimitate.sim.scenarios`` warns (DeprecationWarning) and binds the same module
object, so every name is shared; there is no second implementation.
"""

import sys
import warnings

from ..apps import scenarios as _moved

warnings.warn("gdimitate.sim.scenarios moved to gdimitate.apps.scenarios (scenario code, not "
              "API); import it from there", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _moved
