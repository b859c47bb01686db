"""Deprecated: ``python -m gdimitate.viz`` runs the README-picture script, which moved to
:mod:`gdimitate.apps.viewer_picture` (scenario code, not API); run that instead."""

import sys
import warnings

if __name__ == "__main__":
    from ..apps.viewer_picture import main

    warnings.warn("python -m gdimitate.viz moved to python -m gdimitate.apps.viewer_picture",
                  DeprecationWarning, stacklevel=1)
    sys.exit(main())
