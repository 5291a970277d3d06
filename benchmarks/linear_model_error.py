"""When to trust the linear model: ``(linear − neo-Hookean) / neo-Hookean`` of U and F
against the squeeze, on the example parts (SPEC §8, docs/large_deformation.md).

For each example part and a grasp on it: one mesh (the part's own ``max_area``, at most
0.1 mm², so that the node spacing resolves pads of 1–2 mm radius: a coarser mesh touches
a round pad only at squeezes of ~ h²/(8r)), the
linear pads curve (SPEC §6, ``PadContact``) and the neo-Hookean one with the exact pad gap
(``FiniteStrainPads``) on the same axis and pad, compared at squeezes of 5 … 40 % of the
first-touch width σ0: the relative differences of the stored energy U and of the pad force
F, and the finite-strain strain measure e (SPEC §8) there. "unreached": the finite-strain
solver could not squeeze that far (``delta_unreachable``).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/linear_model_error.py [--smoke]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from deformclosure import Part, mesh_part
from deformclosure.pads.contact import PadContact
from deformclosure.pads.geometry import GraspAxis, Pad
from deformclosure.pads.large_deformation import FiniteStrainPads

MM = 1e-3
#: (name, part file, two points on the axis (mm), pad width, pad radius (mm)).
CASES = [
    ("notched bar, round r 2", "examples/notched_bar.json", ((15, 0), (15, 12)), 0.0, 2.0),
    ("rectangle, flat W 4 r 1", "examples/rectangle.json", ((0, 10), (12, 10)), 4.0, 1.0),
    ("dogbone, round r 1.5", "examples/dogbone.json", ((10, 0), (10, 10)), 0.0, 1.5),
    ("plate with hole, round r 2", "examples/plate_with_hole.json", ((15, 0), (15, 20)), 0.0, 2.0),
    ("L-shape (plane strain, nu .45), r 1", "examples/l_shape.json", ((0, 14), (8, 14)), 0.0, 1.0),
    ("C-shape, round r 1", "examples/c_shape.json", ((3, 0), (3, 20)), 0.0, 1.0),
]
SQUEEZES = (0.05, 0.10, 0.20, 0.30, 0.40)
#: Largest triangle area (m²) of the meshes.
MAX_AREA = 0.1 * MM * MM


def rel(a: float, b: float) -> str:
    if not (math.isfinite(a) and math.isfinite(b)) or b == 0:
        return "unreached"
    return f"{100 * (a - b) / abs(b):+.1f} %"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--smoke", action="store_true", help="one part, coarse mesh")
    args = ap.parse_args()
    cases = CASES[:1] if args.smoke else CASES
    print("| part, pads | nodes | squeeze δ/σ0 | e (finite strain) | U lin vs neo | "
          "F lin vs neo |")
    print("|---|---|---|---|---|---|")
    for name, path, (p, q), width, radius in cases:
        part = Part.from_file(path)
        a = min(part.mesh_options.max_area or math.inf, MAX_AREA)
        mesh = mesh_part(part, max_area=a * 8 if args.smoke else a)
        axis = GraspAxis.through(np.array(p) * MM, np.array(q) * MM)
        pad = Pad(width * MM, radius * MM)
        t0 = time.perf_counter()
        lin = PadContact(mesh).curve(axis, pad, 0.0)
        neo = FiniteStrainPads(mesh).curve(axis, pad)
        for f in SQUEEZES:
            s = (1 - f) * neo.sigma0
            e = neo.strain(s)
            print(f"| {name} | {mesh.n_nodes} | {100 * f:.0f} % | "
                  f"{'-' if not math.isfinite(e) else f'{e:.2f}'} | "
                  f"{rel(lin.energy_at(s), neo.energy_at(s))} | "
                  f"{rel(lin.axial_force(s), neo.axial_force(s))} |", flush=True)
        print(f"<!-- {name}: sigma0 = {neo.sigma0 / MM:.3f} mm, "
              f"{time.perf_counter() - t0:.1f} s -->", flush=True)


if __name__ == "__main__":
    main()
