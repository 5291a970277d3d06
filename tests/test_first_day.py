"""The papercuts of a first day (issue 24, item 6): a drawing's material file is no batch
job; progress in a log has no carriage returns; the compile notice is said once; plan
takes --material; printed coordinates carry no floating-point dust."""

from __future__ import annotations

import io
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from deformclosure import reports
from deformclosure.cli.common import lazy_progress
from deformclosure.cli.main import main
from deformclosure.log import COMPILE_NOTICE, PlainProgress, compile_notice, progress_bar

ROOT = Path(__file__).resolve().parents[1]
DRAWINGS = ROOT / "examples" / "drawings"


def test_batch_over_the_drawings_folder_runs_the_drawing_not_its_sidecar(tmp_path, capsys):
    from deformclosure.batch import load_jobs

    jobs = load_jobs(DRAWINGS, "mesh")
    assert [Path(j.part).name for j in jobs] == ["gasket.dxf"]
    db = tmp_path / "d.sqlite"
    assert main(["batch", str(DRAWINGS), "-o", str(db), "--command", "mesh",
                 "--scheduler", "inline", "-q"]) == 0
    capsys.readouterr()
    assert main(["results", str(db), "--format", "json", "-o", str(tmp_path / "d.json")]) == 0
    rows = json.loads((tmp_path / "d.json").read_text())
    rows = rows["rows"] if isinstance(rows, dict) else rows
    assert len(rows) == 1 and rows[0]["status"] == "ok"
    assert rows[0]["part"].endswith("gasket.dxf")
    # the material file travels with the drawing: it is part of the job's key
    shutil.copytree(DRAWINGS, tmp_path / "d")
    side = tmp_path / "d" / "gasket.material.json"
    mat = json.loads(side.read_text())
    mat["youngs_modulus"] *= 2
    side.write_text(json.dumps(mat))
    (other,) = load_jobs(tmp_path / "d", "mesh")
    assert other.key != jobs[0].key


def test_progress_in_a_log_is_plain_lines(capsys):
    """Standard error captured (not a terminal): one line per tenth, no ``\\r``."""
    progress, close, say = lazy_progress(False, "plan", "step")
    for k in range(0, 101):
        progress(k, 100)
        if k == 50:
            say("a note")
    close()
    err = capsys.readouterr().err
    assert "\r" not in err
    lines = err.splitlines()
    counts = [int(m.group(1)) for m in (re.match(r"plan: (\d+)/100 step", x) for x in lines) if m]
    assert counts == list(range(0, 101, 10))
    assert "a note" in lines


def test_batch_progress_in_a_log_has_no_carriage_return(tmp_path, capsys):
    assert main(["batch", str(DRAWINGS), "-o", str(tmp_path / "b.sqlite"), "--command", "mesh",
                 "--scheduler", "inline"]) == 0
    err = capsys.readouterr().err
    assert "\r" not in err and "batch: 1/1 job" in err


def test_a_terminal_gets_the_tqdm_bar():
    from tqdm import tqdm

    class Tty(io.StringIO):
        def isatty(self):
            return True

    bar = progress_bar(3, "x", "step", file=Tty())
    assert isinstance(bar, tqdm)
    bar.close()
    assert isinstance(progress_bar(3, "x", "step", file=io.StringIO()), PlainProgress)


def test_unknown_total_lines_double():
    out = io.StringIO()
    bar = PlainProgress(None, "check", "placements", file=out, clock=lambda: 0.0)
    for _ in range(20):
        bar.update(1)
    bar.close()
    assert [int(x.split()[1]) for x in out.getvalue().splitlines()] == [0, 1, 2, 4, 8, 16, 20]


def test_the_compile_notice_is_said_once_and_only_when_numba_compiles():
    """Fresh functions of this module compile on their first call (no cache): the notice
    comes once for both; a compiled one says nothing; outside the block, nothing."""
    from numba import njit

    @njit
    def f(x):
        return x + 1

    @njit
    def g(x):
        return 2 * x

    said: list[str] = []
    with compile_notice(said.append, package=__name__):
        assert f(1) == 2 and g(2) == 4
    assert said == [COMPILE_NOTICE]
    with compile_notice(said.append, package=__name__):
        f(3)                                  # compiled already
    assert said == [COMPILE_NOTICE]

    @njit
    def h(x):
        return x - 1

    assert h(1) == 0                          # no block: no notice
    assert said == [COMPILE_NOTICE]
    with compile_notice(said.append, package="someone_else"):
        f(2.5)                                # a new signature of ours, another package
    assert said == [COMPILE_NOTICE]


def test_plan_takes_material_and_the_quality_scales_with_E():
    """Linear elasticity: at the same jaws and separations every energy is ∝ E and σ_L
    does not depend on E, so Q* doubles with E and σ* stays."""
    part = str(ROOT / "examples" / "l_shape.json")
    base = reports.run("plan", part, {"model": "paper", "top": 3, "quiet": True}).data
    mat = json.loads(Path(part).read_text())["material"]
    mat = {**mat, "youngs_modulus": 2 * mat["youngs_modulus"],
           "units": json.loads(Path(part).read_text())["units"]}
    twice = reports.run("plan", part, {"model": "paper", "top": 3, "quiet": True,
                                       "material": json.dumps(mat)}).data
    best = base["pairs"][0]
    other = next(p for p in twice["pairs"] if (p["a"], p["b"]) == (best["a"], best["b"]))
    assert other["quality"] == pytest.approx(2 * best["quality"], rel=1e-6)
    assert other["sigma_star"] == pytest.approx(best["sigma_star"], rel=1e-6)


_DUST = re.compile(r"\d\.\d*(?:0{6,}|9{6,})\d")


@pytest.mark.parametrize("params", [
    {"axis": "0.3,10.1,0", "pad_radius": 1.0, "refine": 1},
    {"model": "paper", "at": ("0,10.3", "12,10.3")},
])
def test_printed_lines_have_no_floating_point_dust(params):
    rep = reports.run("optimize", str(ROOT / "examples" / "rectangle.json"),
                      {**params, "quiet": True})
    text = "\n".join(rep.lines + list(rep.warnings))
    assert not _DUST.search(text), _DUST.search(text)
    assert not re.search(r"(?<![\d.])-0(?:\.0+)?(?![\d.])", text)       # no "-0"
    assert np.isfinite(rep.data["sigma0"])
