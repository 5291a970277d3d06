"""The tour notebook (``examples/tour.py``, jupytext percent format) runs as written
(issue 13, item 3): every cell, in a scratch folder holding a copy of ``examples/``."""

from __future__ import annotations

import runpy
import shutil
from pathlib import Path

import matplotlib
import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]


def test_tour_runs(tmp_path, monkeypatch, capsys):
    matplotlib.use("Agg")
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(tmp_path / "examples" / "tour.py"), run_name="__tour__")
    out = capsys.readouterr().out
    assert "verdict: held" in out and "deform closure: True" in out
    cells = (ROOT / "examples" / "tour.py").read_text().count("# %%")
    assert cells >= 8
