"""Mesh convergence of the two-jaw quantities: point jaws vs finite-width jaws.

Run:  python benchmarks/convergence.py

The 12 × 20 mm rubber rectangle, jaws at the mid-points of the long sides, meshes
refined by halving max_area. Point jaws load one node: in 2-D a point force has
unbounded energy under refinement, so k01 → 0 and e_max → ∞ (logarithmically for k01).
Flat jaws of width 2 mm tie the normal displacement of their contact patch and converge.
"""

from __future__ import annotations

import numpy as np

import deformclosure as dc
from deformclosure.grasp.analysis import grasp_model, optimize_separation


def run(max_area_mm2: float, width_m: float):
    part = dc.Part.from_dict({
        "units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": "stress"},
        "mesh": {"max_area": max_area_mm2, "min_angle": 30,
                 "points": [[0, 9], [0, 10], [0, 11], [12, 9], [12, 10], [12, 11]]}})
    mesh = dc.mesh_part(part)
    jaws = (mesh.find_node([0, 0.010]), mesh.find_node([0.012, 0.010]))
    model = grasp_model(mesh, jaw_width=width_m)
    res = optimize_separation(mesh, jaws, model=model, jaw_width=width_m)
    return mesh, res


def main() -> None:
    print(f"{'jaws':<12} {'max_area':>9} {'nodes':>6} {'p':>4} {'k01 (N/m)':>10} "
          f"{'e_max (1/m)':>11} {'sigma_L (mm)':>12} {'sigma* (mm)':>11} {'Q* (mJ)':>9}")
    for width, label in ((0.0, "point"), (2e-3, "flat 2 mm")):
        for area in (2.0, 1.0, 0.5, 0.25, 0.125, 0.0625):
            mesh, r = run(area, width)
            ss = "-" if r.sigma_star is None else f"{r.sigma_star * 1e3:.4f}"
            print(f"{label:<12} {area:>9.4f} {mesh.n_nodes:>6} {len(mesh.outer_loop):>4} "
                  f"{r.limit.k01:>10.2f} {r.limit.e_max:>11.2f} {r.limit.sigma_L * 1e3:>12.4f} "
                  f"{ss:>11} {r.quality * 1e3:>9.5f}")


if __name__ == "__main__":
    main()
