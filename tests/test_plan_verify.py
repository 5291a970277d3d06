"""The pad planner verifies before it says "held" (SPEC §6 "Plan", issue 20).

Contact-mechanics facts, not mesh values: a convex part between frictionless pads is never
held (a lateral shift keeps the chord); round pads seated in a part's notches hold it. A
screened (lattice) row is a candidate by construction.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, strategies as st

import deformclosure as dc
from deformclosure import reports
from deformclosure.pads import Pad
from deformclosure.planning.pads import plan_pads, screened_verdict

MM = 1e-3
ROOT = Path(__file__).resolve().parents[1]


@given(st.floats(allow_nan=False, allow_infinity=True, min_value=-1.0))
def test_a_screened_row_is_never_held(quality):
    assert screened_verdict(quality) in ("candidate", "not held")
    assert (screened_verdict(quality) == "candidate") == (quality > 0)


def _plan(part, radius_mm: float, verify: int = 3):
    mesh = dc.mesh_part(part)
    return plan_pads(mesh, Pad(0.0, radius_mm * MM), n_angles=12, n_offsets=24, top=verify,
                     part=part), mesh


def _ellipse(a: float, b: float, n: int = 40, max_area: float = 1.5) -> dc.Part:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return dc.Part.from_dict({
        "name": "ellipse", "units": "mm",
        "outer": np.c_[a * np.cos(t), b * np.sin(t)].round(6).tolist(), "holes": [],
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": "stress"},
        "mesh": {"max_area": max_area, "min_angle": 30}})


@pytest.mark.parametrize("part", [_ellipse(12.0, 7.0), _ellipse(12.0, 7.0, 72, 0.8)],
                         ids=["coarse-ellipse", "ellipse"])
def test_a_convex_part_has_no_held_row(part):
    plan, _ = _plan(part, 1.5)
    assert not any(r["verdict"] == "held" for r in plan.rows)
    assert plan.held == [] and plan.to_dict()["top"] == []
    # every row either was verified or is a screened candidate / not held
    for r in plan.rows:
        assert r["verified"] or r["verdict"] in ("candidate", "not held")


def test_the_best_verified_row_of_a_notched_part_goes_through_the_notches():
    part = dc.notched_part(1.0)
    plan, mesh = _plan(part, 2.0)
    best = plan.rows[0]
    assert best["verified"] and best["verdict"] == "held"
    # the notch roots are at (15, 3) and (15, 9) mm: the axis is the line x = 15 mm, vertical
    assert abs(math.sin(best["axis"]["angle"])) == pytest.approx(1.0, abs=1e-9)
    assert best["axis"]["point"][0] == pytest.approx(15 * MM, abs=1e-6 * MM)
    assert best["error_estimate"]["quality"] is not None
    assert best["error_estimate"]["quality"] < best["quality"]
    top = plan.to_dict()["top"]
    assert top and top[0] is best
    # verified rows rank first
    flags = [r["verified"] for r in plan.rows]
    assert flags == sorted(flags, reverse=True)


def test_plan_report_rows_carry_a_pasteable_axis():
    rep = reports.run("plan", str(ROOT / "examples" / "notched_bar.json"),
                      {"pad_radius": 2.0, "grid_angles": 6, "grid_offsets": 16, "verify": 1})
    rows = rep.data["axes"]
    assert all({"axis", "verified", "verdict"} <= set(r) for r in rows)
    best = rows[0]
    assert best["verified"]
    line = next(l for l in rep.lines if l.startswith("best verified grasp: optimize --axis "))
    x, y, deg = (float(v) for v in line.split("--axis ")[1].split()[0].split(","))
    assert (x * MM, y * MM) == pytest.approx(tuple(best["axis"]["point"]), abs=1e-8)
    assert math.radians(deg) == pytest.approx(best["axis"]["angle"] % (2 * math.pi), abs=1e-6)
    assert rep.data["top"] and rep.data["top"][0]["verdict"] == "held"


def test_a_barrier_on_a_blind_mesh_is_no_hold():
    """optimize on the README block (convex: frictionless pads cannot hold it): on the
    part's own coarse mesh the boundary nodes are farther apart than the pads' reach and
    a node-noise barrier appears — the verdict is 'undecided', never 'held'; on a mesh
    that resolves the pads it is 'not held'."""
    from deformclosure.pads.optimize import mesh_is_blind

    rect = str(ROOT / "examples" / "rectangle.json")
    coarse = reports.run("optimize", rect,
                         {"at": ("0,10", "12,10"), "grid_angles": 12, "grid_offsets": 16})
    part = dc.Part.from_file(rect)
    assert mesh_is_blind(dc.mesh_part(part), Pad(0.0, coarse.data["pad"]["radius"]))
    assert coarse.data["verdict"] in ("undecided", "not held")
    fine = reports.run("optimize", rect,
                       {"at": ("0,10", "12,10"), "max_area": 0.3, "grid_angles": 12,
                        "grid_offsets": 16})
    assert fine.data["verdict"] == "not held"
