"""Every notebook runs top to bottom in a Jupyter kernel (nbclient), shows at least one figure
(a PNG display output: matplotlib inline) and stays small on disk once executed."""

from __future__ import annotations

import shutil

import pytest

from tests.helpers import ROOT

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
#: An executed notebook must stay under this size [bytes] (embedded 3-D scenes are ~25 MB).
MAX_EXECUTED_BYTES = 3_000_000


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_shows_figures_and_stays_small(tmp_path, path, monkeypatch):
    # the kernel must use Jupyter's inline backend, as a user's would: a non-interactive
    # MPLBACKEND inherited from the test process (e.g. Agg) would swallow every figure
    monkeypatch.delenv("MPLBACKEND", raising=False)
    work = tmp_path / path.name  # run in a scratch copy: files a notebook writes land there
    shutil.copy(path, work)
    nb = nbformat.read(work, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    figures = [o for o in outputs if o.get("output_type") in ("display_data", "execute_result")
               and "image/png" in o.get("data", {})]
    assert figures, f"{path.name}: no figure output (image/png)"
    errors = [o for o in outputs if o.get("output_type") == "error"]
    assert not errors
    out = tmp_path / f"executed_{path.name}"
    nbformat.write(nb, out)
    size = out.stat().st_size
    assert size < MAX_EXECUTED_BYTES, f"{path.name}: {size / 1e6:.1f} MB executed"
