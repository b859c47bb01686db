"""How long ``import gdimitate`` and ``gdimitate --help`` take, and which engines they load
(issue 19).

Run: ``python benchmarks/import_time.py [--repeat 5] [--baseline-rev eac54a4]``.

Each figure is the median wall time [s] of ``--repeat`` fresh interpreters
(``python -c "import gdimitate"``; ``python -c "from gdimitate.apps.cli import main;
main(['--help'])"``,
what the console script runs), with the engines each leaves in ``sys.modules``. The same-run
baseline is the tree of ``--baseline-rev`` (by default the revision before the lazy
``gdimitate/__init__``), extracted with ``git archive`` into a temporary folder and put first
on ``PYTHONPATH``. Both rows run in the same environment and the same minute, so the load of
the machine (printed) touches both alike.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from results import add_flag, recording
from revision import checkout as extract

ROOT = Path(__file__).resolve().parents[1]
ENGINES = ("mujoco", "meshcat", "dask", "numba", "pink", "matplotlib", "casadi", "pinocchio",
           "scipy")
CASES = {
    "import gdimitate": "import gdimitate",
    "gdimitate --help": ("import contextlib, io\nfrom gdimitate.apps.cli import main\n"
                         "with contextlib.redirect_stdout(io.StringIO()):\n"
                         "    try:\n        main(['--help'])\n    except SystemExit:\n"
                         "        pass"),
}



def measure(tree: Path, code: str, repeat: int) -> tuple[float, list[str]]:
    """``(median wall time [s], engines loaded)`` of ``code`` in fresh interpreters whose
    ``gdimitate`` is the one under ``tree``."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    probe = code + f"\nimport sys\nprint([m for m in {ENGINES!r} if m in sys.modules])"
    times, loaded = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", probe], env=env, cwd=tree,
                             capture_output=True, text=True, check=True).stdout
        times.append(time.perf_counter() - t0)
        loaded = eval(out.strip().splitlines()[-1])  # a list literal printed by the probe
    return statistics.median(times), loaded


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--baseline-rev", default="eac54a4")
    add_flag(ap)
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs; "
          f"median of {a.repeat} fresh interpreters")
    print("| case | tree | median [s] | engines loaded |\n|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        trees = {f"baseline {a.baseline_rev}": extract(a.baseline_rev, tmp), "this tree": ROOT}
        for case, code in CASES.items():
            for label, tree in trees.items():
                t, loaded = measure(tree, code, a.repeat)
                print(f"| {case} | {label} | {t:.2f} | {', '.join(loaded) or '—'} |")


if __name__ == "__main__":
    with recording("import_time", "--results" in sys.argv[1:]):
        main()
