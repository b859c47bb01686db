"""Deprecated alias of :mod:`gdimitate.apps.baselines` (scenario code, not API): import that.

Importing ``gdimitate.baselines`` warns (DeprecationWarning) and binds the same module object, so
every name (and any monkeypatching) is shared; there is no second implementation.
"""

import sys
import warnings

from .apps import baselines as _moved

warnings.warn("gdimitate.baselines moved to gdimitate.apps.baselines (scenario code, not API); "
              "import it from there", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _moved
