"""``--max-area`` on every command that meshes a part (SPEC §6 "Accuracy by default"):
the starting mesh without editing files, in the part's units²; refused for mesh files and
for values that are not areas."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import deformclosure as dc
from deformclosure import reports
from deformclosure.errors import DeformClosureError
from deformclosure.reports.inputs import read_inputs

ROOT = Path(__file__).resolve().parents[1]
RECT = str(ROOT / "examples" / "rectangle.json")


def test_the_starting_mesh_follows_max_area():
    part = dc.Part.from_file(RECT)
    coarse = read_inputs(RECT, max_area=4.0).mesh
    fine = read_inputs(RECT, max_area=0.5).mesh
    assert coarse.areas.max() <= 4.0e-6 * (1 + 1e-12)      # mm² → m²
    assert fine.areas.max() <= 0.5e-6 * (1 + 1e-12)
    assert fine.n_nodes > 3 * coarse.n_nodes
    # the part's own mesh options are replaced, so refinement starts there
    assert read_inputs(RECT, max_area=0.5).part.mesh_options.max_area == pytest.approx(0.5e-6)
    assert part.mesh_options.max_area != pytest.approx(0.5e-6)


@pytest.mark.parametrize("command", ["optimize", "check", "plan", "slice"])
def test_every_command_has_max_area(command):
    from deformclosure.reports.options import OPTIONS

    assert any(o.name == "max_area" and "--max-area" in o.flags for o in OPTIONS[command])


def test_optimize_report_uses_it():
    one = {"at": ("0,10", "12,10"), "pad_radius": 1.0, "grid_angles": 8, "grid_offsets": 8,
           "refine": 1}
    a = reports.run("optimize", RECT, {**one, "max_area": 2.0})
    b = reports.run("optimize", RECT, {**one, "max_area": 0.5})
    assert b.data["nodes"] > 2 * a.data["nodes"]
    # an adaptive run starts there too: its first level is no coarser than the option
    c = reports.run("optimize", RECT, {**one, "refine": None, "rtol": 0.2, "max_area": 0.5})
    assert c.data["convergence"][0]["max_area"] <= 0.5e-6 * (1 + 1e-9)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_values_are_one_line_errors(bad):
    with pytest.raises(DeformClosureError, match=r"--max-area"):
        read_inputs(RECT, max_area=bad)


def test_mesh_files_are_used_as_they_are(tmp_path):
    mesh = dc.mesh_part(dc.Part.from_file(RECT))
    path = tmp_path / "m.json"
    dc.write_mesh(mesh, path)
    with pytest.raises(DeformClosureError, match=r"--max-area: applies to part files"):
        read_inputs(str(path), max_area=1.0)
    assert json.loads(path.read_text())["format"].startswith("deformclosure-mesh")
