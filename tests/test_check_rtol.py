"""``check --rtol``: the release energy over placements refined on meshes (SPEC §6 "Accuracy
by default", §7), and its refusals.

A 12 × 20 mm block squeezed between two half-planes (walls) 11 mm apart cannot leave: the
walls are infinite, so the part is caged on every mesh — ``U_A`` is infinite on each level,
its estimate 0, and the run converges on its second level. A mesh file cannot be re-meshed,
and a bad ``--rtol`` or ``--max-seconds`` is a one-line error.
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
    # without --rtol: one mesh and no convergence keys, as before
    one = _check()
    assert "convergence" not in one.data and one.data["U_A_infinite"]


@pytest.mark.parametrize("bad, match", [({"rtol": 0.0}, "--rtol"), ({"rtol": 1.5}, "--rtol"),
                                        ({"rtol": math.nan}, "--rtol"),
                                        ({"rtol": 0.1, "max_seconds": -1.0}, "--max-seconds")])
def test_bad_accuracy_options_are_one_line_errors(bad, match):
    with pytest.raises(DeformClosureError, match=match) as err:
        _check(**bad)
    assert "\n" not in str(err.value)
