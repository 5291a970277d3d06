"""``examples/tour.ipynb`` runs as a notebook (nbclient, a Jupyter kernel) from the folder
Jupyter starts in, ``examples/`` itself (issue 24, item 5), and matches ``tour.py``."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]


def test_the_notebook_runs_from_examples(tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    nb = nbformat.read(tmp_path / "examples" / "tour.ipynb", as_version=4)
    # the kernel inherits this environment: the package of this checkout, no display
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT / "src"),
                                                      os.environ.get("PYTHONPATH", "")]))
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path / "examples")}})
    client.execute()
    out = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                  for o in c.get("outputs", []))
    assert "verdict: held" in out and "deform closure: True" in out
    code = [c.source for c in nb.cells if c.cell_type == "code"]
    tour = (ROOT / "examples" / "tour.py").read_text()
    assert all(c in tour for c in code)          # one tour: the notebook is tour.py's cells
