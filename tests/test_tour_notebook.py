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
    assert "verdict: held" in out and "deform closure: True" in out and "3 of 3 jobs ok" in out
    code = [c.source for c in nb.cells if c.cell_type == "code"]
    tour = (ROOT / "examples" / "tour.py").read_text()
    assert all(c in tour for c in code)          # one tour: the notebook is tour.py's cells


def _builder():
    import importlib.util

    spec = importlib.util.spec_from_file_location("build_tour_notebook",
                                                  ROOT / "tools" / "build_tour_notebook.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
def test_the_committed_notebooks_are_built_from_tour_py():
    """``examples/tour.ipynb`` is what ``tools/build_tour_notebook.py`` builds from
    ``tour.py`` (cell by cell), and the rendered ``docs/tour.ipynb`` has the same cells
    with their outputs: the figures and the held, converged grasp."""
    nbformat = pytest.importorskip("nbformat")
    built = _builder().notebook_of((ROOT / "examples" / "tour.py").read_text())
    for path in (ROOT / "examples" / "tour.ipynb", ROOT / "docs" / "tour.ipynb"):
        nb = nbformat.read(path, as_version=4)
        assert [(c.cell_type, c.source) for c in nb.cells] == \
            [(c.cell_type, c.source) for c in built.cells], f"{path}: rebuild it"
    rendered = nbformat.read(ROOT / "docs" / "tour.ipynb", as_version=4)
    outs = [o for c in rendered.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert sum("image/png" in o.get("data", {}) for o in outs) >= 3
    text = "".join(o.get("text", "") for o in outs)
    assert "verdict: held" in text and "3 of 3 jobs ok" in text and "/tmp/" not in text
