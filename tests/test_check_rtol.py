"""``check --rtol``: the release energy over placements refined on meshes (SPEC §6 "Accuracy
by default", §7), and its refusals.

A 12 × 20 mm block squeezed between two half-planes (walls) 11 mm apart cannot leave: the
walls are infinite, so the part is caged on every mesh — ``U_A`` is infinite on each level,
its estimate 0, and the run converges on its second level. ``--rtol 0.05`` is the default
(``--refine 1`` is one mesh); point fingers pressing the part stop the refinement after two
levels, unconverged, because a point force in 2-D has no finite stiffness (the quality of the
README's L-shape falls level after level). A mesh file is solved once, with a warning, and a
bad ``--rtol``, ``--refine`` or ``--max-seconds`` is a one-line error.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from deformclosure import reports
from deformclosure.errors import DeformClosureError

ROOT = Path(__file__).resolve().parents[1]
RECT = ROOT / "examples" / "rectangle.json"
WALLS = ROOT / "examples" / "fingers" / "rectangle_squeeze.json"
L_SHAPE = ROOT / "examples" / "l_shape.json"
L_FINGERS = ROOT / "examples" / "fingers" / "l_shape.json"


def _check(**extra):
    params = {"fingers": str(WALLS), "grid_steps": 8, "saddle_levels": 0, "max_area": 4.0,
              **extra}
    return reports.run("check", str(RECT), params)


@pytest.mark.slow
def test_a_caged_block_converges_on_the_second_level():
    rep = _check(rtol=0.05)
    d = rep.data
    conv = d["convergence"]
    assert len(conv) == 2 and conv[1]["nodes"] > 2 * conv[0]["nodes"]       # h halved
    assert all(row["U_A_infinite"] for row in conv)
    assert d["converged"] is True and d["error_estimate"]["U_A"] == 0.0
    assert any("converged: yes" in line for line in rep.lines)
    # the default is the same rtol 0.05; --refine 1 is one mesh and no convergence keys
    default = _check().data
    assert default["rtol"] == 0.05 and default["convergence"] == conv
    one = _check(refine=1)
    assert "convergence" not in one.data and one.data["U_A_infinite"]
    two = _check(refine=2).data
    assert two["rtol"] is None and [r["nodes"] for r in two["convergence"]] == \
        [r["nodes"] for r in conv]


def test_point_fingers_stop_the_default_refinement_unconverged():
    rep = reports.run("check", str(L_SHAPE), {"fingers": str(L_FINGERS), "grid_steps": 8,
                                               "saddle_levels": 0})
    d = rep.data
    q = [row["quality"] for row in d["convergence"]]
    assert len(q) == 2 and q[1] < 0.9 * q[0]           # the point loads' energy follows h
    assert d["converged"] is False and d["error_estimate"]["quality"] >= q[0] - q[1]
    assert any("point fingers press the part" in w for w in rep.warnings)


def test_a_mesh_file_is_checked_once_with_a_warning(tmp_path):
    from deformclosure import mesh_part
    from deformclosure.mesh.io import write_mesh
    from deformclosure.part import Part

    path = tmp_path / "rect.mesh.json"
    write_mesh(mesh_part(Part.from_file(RECT), max_area=4.0), path)
    rep = reports.run("check", str(path), {"fingers": str(WALLS), "grid_steps": 8,
                                            "saddle_levels": 0})
    assert "convergence" not in rep.data
    assert any("a mesh file cannot be refined" in w for w in rep.warnings)
    with pytest.raises(DeformClosureError, match="--rtol: needs a part file"):
        reports.run("check", str(path), {"fingers": str(WALLS), "rtol": 0.1})


@pytest.mark.parametrize("bad, match", [({"rtol": 0.0}, "--rtol"), ({"rtol": 1.5}, "--rtol"),
                                        ({"rtol": math.nan}, "--rtol"),
                                        ({"rtol": 0.1, "max_seconds": -1.0}, "--max-seconds"),
                                        ({"refine": 0}, "--refine"), ({"refine": 9}, "--refine"),
                                        ({"refine": 2, "rtol": 0.1}, "--refine and --rtol")])
def test_bad_accuracy_options_are_one_line_errors(bad, match):
    with pytest.raises(DeformClosureError, match=match) as err:
        _check(**bad)
    assert "\n" not in str(err.value)
