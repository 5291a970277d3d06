"""`deformclosure optimize` end to end: report keys/units, graph export, bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from deformclosure.cli.main import main

EX = Path(__file__).resolve().parents[1] / "examples"

SPEC_KEYS = {"sigma_star", "quality", "U_A", "U_L", "sigma_L", "sigma0", "k01", "e_max", "jaws",
             "method", "epsilon", "units", "curve", "U_A_infinite"}


def _small_part(tmp_path, outer, holes=(), max_area=3.0, units="mm"):
    p = tmp_path / "part.json"
    p.write_text(json.dumps({"units": units, "outer": outer, "holes": list(holes),
                             "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1,
                                          "thickness": 1.0, "elastic_limit_strain": 0.8},
                             "mesh": {"max_area": max_area, "min_angle": 28}}))
    return p


def test_optimize_report_is_si_and_complete(tmp_path):
    part = _small_part(tmp_path, [[0, 0], [12, 0], [12, 20], [0, 20]], max_area=4.0)
    out = tmp_path / "r.json"
    graph = tmp_path / "g.json"
    assert main(["optimize", str(part), "--model", "paper", "--at", "0,10", "12,10", "-o", str(out),
                 "--export-graph", str(graph)]) == 0
    r = json.loads(out.read_text())
    assert SPEC_KEYS <= set(r)
    assert r["units"] == {**r["units"], "length": "m", "energy": "J", "stiffness": "N/m",
                          "strain_per_length": "1/m"}
    assert r["sigma0"] == pytest.approx(0.012, rel=1e-12)           # metres, not mm
    assert 0 <= r["sigma_L"] < r["sigma0"]
    assert r["sigma_L"] == pytest.approx(max(0.0, 0.012 - 0.8 / r["e_max"]), rel=1e-12)
    if r["sigma_star"] is not None:
        assert r["sigma_L"] <= r["sigma_star"] <= r["sigma0"]
        assert r["quality"] == pytest.approx(min(r["U_A"] if r["U_A"] is not None else np.inf,
                                                 r["U_L"]), rel=1e-9)
    assert set(r["curve"]) >= {"sigma", "U_A", "U_L", "Q"}
    g = json.loads(graph.read_text())
    assert {"vertices", "edges"} <= set(g)
    v0 = g["vertices"][0]
    assert {"a", "b", "sigma0", "k"} <= set(v0)
    assert all(set(e["kinds"]) <= {"slide", "swing"} and e["kinds"] for e in g["edges"])
    # every edge shares a jaw node between its two vertices
    assert all(len(set(e["u"]) & set(e["v"])) == 1 for e in g["edges"])
    k01 = [v["k"] for v in g["vertices"] if sorted([v["a"], v["b"]]) == sorted(r["jaws"])]
    assert k01 and k01[0] == pytest.approx(r["k01"], rel=1e-12)


def test_expanding_grasp_on_ring(tmp_path):
    import math
    outer = [[10 * math.cos(2 * math.pi * i / 16), 10 * math.sin(2 * math.pi * i / 16)] for i in range(16)]
    hole = [[5 * math.cos(2 * math.pi * i / 8), 5 * math.sin(2 * math.pi * i / 8)] for i in range(8)]
    part = _small_part(tmp_path, outer, [hole], max_area=6.0)
    out = {}
    for method in ("exact", "paper"):
        o = tmp_path / f"{method}.json"
        assert main(["optimize", str(part), "--model", "paper", "--at", "5,0", "-5,0", "--expanding",
                     "--method", method, "-o", str(o)]) == 0
        out[method] = json.loads(o.read_text())
    r = out["exact"]
    assert r["mode"] == "expanding"
    assert r["sigma_L"] > r["sigma0"] == pytest.approx(0.010, rel=1e-12)
    if r["sigma_star"] is not None:
        assert r["sigma0"] <= r["sigma_star"] <= r["sigma_L"]
    assert r["quality"] == pytest.approx(out["paper"]["quality"], rel=1e-9, abs=1e-15)


def test_approx_default_eps_is_documented_and_guaranteed(tmp_path):
    """--method approx without --eps uses ε = 1e-3 · ½ k01 (σ0 − σ_L)² and stays within
    that ε of the exact optimum."""
    part = _small_part(tmp_path, [[0, 0], [12, 0], [12, 20], [0, 20]], max_area=4.0)
    out = {}
    for method in ("approx", "exact"):
        o = tmp_path / f"{method}.json"
        assert main(["optimize", str(part), "--model", "paper", "--at", "0,10", "12,10", "--method", method, "-o", str(o)]) == 0
        out[method] = json.loads(o.read_text())
    a, e = out["approx"], out["exact"]
    eps = 1e-3 * 0.5 * a["k01"] * (a["sigma0"] - a["sigma_L"]) ** 2
    assert a["epsilon"] == pytest.approx(eps, rel=1e-12)
    assert e["quality"] - eps <= a["quality"] <= e["quality"] * (1 + 1e-12)


BAD = [
    (["--jaws", "3", "3"], "same node|both jaws"),
    (["--at", "6,10", "12,10"], "interior"),
    (["--at", "50,50", "12,10"], "outside"),
    (["--at", "0,10", "12,10", "--method", "approx", "--eps", "0"], "eps"),
    (["--at", "0,10", "12,10", "--method", "approx", "--eps", "-1e-3"], "eps"),
    (["--at", "0,10", "12,10", "--jaw-width", "-1"], "width"),
    (["--jaws", "0", "99999"], "node"),
    (["--at", "0,10"], ""),
    (["--at", "0;10", "12,10"], "--at"),
    ([], "jaws"),
]


@pytest.mark.parametrize("args,pattern", BAD)
def test_bad_optimize_input_is_one_line_exit_2(tmp_path, args, pattern):
    part = _small_part(tmp_path, [[0, 0], [12, 0], [12, 20], [0, 20]], max_area=8.0)
    proc = subprocess.run([sys.executable, "-m", "deformclosure", "optimize", str(part),
                           "--model", "paper", *args],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert "Traceback" not in proc.stderr
    if pattern:
        assert len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
        import re
        assert re.search(pattern, lines[0], re.I), lines[0]


def test_approx_default_eps_bounds_the_number_of_samples(tmp_path):
    """A small e_L makes the range σ0 − σ_L tiny against λ = max k σ0: the default ε is
    raised to λ·|σ0 − σ_L| / 20 000 and the run completes (it once failed with
    'needs 1558309 evaluations')."""
    p = tmp_path / "stiff.json"
    p.write_text(json.dumps({"units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
                             "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
                                          "elastic_limit_strain": 1e-4},
                             "mesh": {"max_area": 4.0}}))
    out = tmp_path / "r.json"
    assert main(["optimize", str(p), "--model", "paper", "--at", "0,10", "12,10", "--method", "approx", "-o", str(out)]) == 0
    r = json.loads(out.read_text())
    span = r["sigma0"] - r["sigma_L"]
    formula = 1e-3 * 0.5 * r["k01"] * span ** 2
    raised = r["lipschitz"] * span / 20_000
    assert raised > formula                      # the case this test is about
    assert r["epsilon"] == pytest.approx(raised, rel=1e-12)
    assert r["n_evaluations"] <= 20_000 + 1000
