"""Error estimates against a reference two uniform mesh levels finer (issue 20), opt-in.

The claim of ``tests/test_accuracy.py`` — the reported error of ``quality``, ``U_A`` and
``sigma_star`` bounds the difference to a much finer answer in at least 90 % of the
quantities, for rtol 0.2, 0.1 and 0.05 on three parts — checked against the reference the
issue names: the finest level's own mesh refined *twice* uniformly (every element's area /
16, its twin alike; 37k–51k nodes) and the landscape around the saddles two levels finer
(factor × 4), by the levels' own rule (:func:`~deformclosure.pads.refine.solve_level`).

Marked ``reference``: it takes 10–15 minutes and several GB on 2 cores (the critical-distance
averaging over 100k elements), beyond CI's budget, so neither the README's test command
nor ``-m slow`` runs it. Run it with::

    python -m pytest -q -p no:cacheprovider -m reference tests/test_accuracy_reference.py
"""

from __future__ import annotations

import functools

import pytest

import deformclosure as dc
from deformclosure.mesh.generate import twin_mesh
from deformclosure.mesh.sizing import Sizing
from deformclosure.pads import Pad
from deformclosure.pads.refine import solve_level

from test_accuracy import GRID, MM, PARTS, _axis, _quantities, _run

pytestmark = pytest.mark.reference


@functools.lru_cache(maxsize=None)
def _reference(name: str):
    part, (p, q), rho = PARTS[name]
    run = _run(name, 0.05)
    mesh = run.finest.solver.mesh
    default = float(mesh.areas.max()) / 16.0
    sizing = Sizing(default, points=mesh.nodes[mesh.triangles].mean(axis=1),
                    areas=mesh.areas / 16.0)
    ref_mesh = dc.mesh_part(part, max_area=default, sizing=sizing)
    twin = twin_mesh(part, max_area=default, sizing=sizing)
    return solve_level(ref_mesh, twin, _axis(p, q), Pad(0.0, rho * MM), len(run.levels) + 1,
                       list(run.saddles), None, GRID)


def test_error_estimates_bound_the_difference_to_a_reference_two_levels_finer():
    checked, failures = 0, []
    for name in PARTS:
        ref = _quantities(_reference(name))
        assert ref["quality"] > 0, name
        for rtol in (0.2, 0.1, 0.05):
            run = _run(name, rtol)
            err, val = run.error_estimate(), _quantities(run.finest)
            for key in ("quality", "U_A", "sigma_star"):
                checked += 1
                e = err[key]
                print(f"{name:20} rtol {rtol:<4} {key:10} {val[key]:.6g} ± {e:.3g}  "
                      f"reference {ref[key]:.6g}")           # the table, with -s
                if e is None or abs(val[key] - ref[key]) > e:
                    failures.append((name, rtol, key, val[key], ref[key], e))
    assert len(failures) <= 0.1 * checked, failures
