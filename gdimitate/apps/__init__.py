"""The command line and scenario code — NOT API: the stories told with the library, not the
library.

``cli`` (the ``gdimitate`` command: its parser, signals and errors; one module per command in
``commands/``), ``figures`` (the paper's and the demo's matplotlib figures), ``demo``
(``gdimitate demo``), ``paper`` (``gdimitate paper``: the paper's figures and numbers),
``cases`` (the paper's three planar cases: robots and the generated walk), ``examples`` (named
demonstration/adaptation pairs for ``gdimitate view`` and the notebooks), ``baselines`` (the
kinematic retargeters the benchmarks compare against) and ``scenarios`` (small plans for the
physics check's tests), ``viewer_picture`` (the README's picture of the viewer), ``stream``
(``gdimitate stream``: a live source adapted frame by frame), ``repair`` (``gdimitate repair``:
a motion file repaired on its own robot) and ``outputs`` (the files ``adapt``, ``stream`` and
``repair`` write). Their names may change between releases without a deprecation period.

Only the command line (:mod:`gdimitate.apps.cli`), ``benchmarks/``, ``notebooks/``, ``docs/``
and ``tests/`` import this package; nothing in the library below it does
(``tests/project/test_architecture.py`` checks, docs/design.md §8). The one documented public
name defined here, :func:`gdimitate.paper_case`, is re-exported lazily by ``gdimitate/__init__``.
"""
