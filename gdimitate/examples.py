"""Deprecated alias of :mod:`gdimitate.apps.examples` (scenario code, not API): import that.

Importing ``gdimitate.examples`` warns (DeprecationWarning) and binds the same module object, so
every name (and any monkeypatching) is shared; there is no second implementation.
"""

import sys
import warnings

from .apps import examples as _moved

warnings.warn("gdimitate.examples moved to gdimitate.apps.examples (scenario code, not API); "
              "import it from there", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _moved
