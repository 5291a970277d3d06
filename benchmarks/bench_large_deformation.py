"""Linear vs neo-Hookean pads (SPEC §8) at the same grasp, side by side in one run.

For each example part and grasp: one mesh (the part's own ``max_area``), the linear model
(``optimize_pads``) and its finite-strain twin (``optimize_finite_strain`` on the same mesh,
grid and escape path); time of each and the relative differences
``(linear − neo-Hookean) / neo-Hookean`` of U and F at the neo-Hookean σ*, of σ* and Q*.
Then one finite-strain U(σ) curve (16 separations from first touch to 40 % squeeze) on a
finer mesh of the notched bar against the exact linear curve.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_large_deformation.py [--quick]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from deformclosure import Part, mesh_part
from deformclosure.contact.large_deformation import LINEAR_SOLVER
from deformclosure.pads.contact import PadContact
from deformclosure.pads.finite_strain_grasp import optimize_finite_strain
from deformclosure.pads.geometry import GraspAxis, Pad
from deformclosure.pads.large_deformation import FiniteStrainPads
from deformclosure.pads.optimize import optimize_pads

MM = 1e-3
CASES = [
    ("notched bar, round pads r 2", "examples/notched_bar.json", ((15, 0), (15, 12)), 0.0, 2.0),
    ("rectangle, flat pads W 4 r 1", "examples/rectangle.json", ((0, 10), (12, 10)), 4.0, 1.0),
    ("dogbone, round pads r 1.5", "examples/dogbone.json", ((10, 0), (10, 10)), 0.0, 1.5),
]


def pct(x) -> str:
    return "     -" if x is None else f"{100 * x:+6.1f}%"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="coarser meshes")
    ap.add_argument("--smoke", action="store_true",
                    help="one coarse case and a 4-point curve (the benchmarks' smoke test)")
    args = ap.parse_args()
    args.quick = args.quick or args.smoke
    grow = 4.0 if args.quick else 1.0
    print(f"Newton systems factorised by {LINEAR_SOLVER} (benchmarks/bench_kkt_solvers.py)")
    print(f"{'case':32} {'nodes':>6} {'t lin':>7} {'t neo':>7} {'ratio':>6} "
          f"{'dU':>7} {'dF':>7} {'dsig*':>7} {'dQ*':>7}  Q* neo (J)")
    for name, path, (p, q), width, radius in (CASES[:1] if args.smoke else CASES):
        part = Part.from_file(path)
        a = part.mesh_options.max_area
        mesh = mesh_part(part, max_area=a * grow if a else None)
        axis = GraspAxis.through(np.array(p) * MM, np.array(q) * MM)
        pad = Pad(width * MM, radius * MM)
        t0 = time.perf_counter()
        lin = optimize_pads(mesh, axis, pad, noise=False)
        t1 = time.perf_counter()
        neo = optimize_finite_strain(mesh, lin)
        t2 = time.perf_counter()
        e = neo.linear_model_error()
        print(f"{name:32} {mesh.n_nodes:>6} {t1 - t0:>7.2f} {t2 - t1:>7.2f} "
              f"{(t2 - t1) / (t1 - t0):>6.1f} {pct(e['U'])} {pct(e['F'])} "
              f"{pct(e['sigma_star'])} {pct(e['quality'])}  {neo.quality:.4g}")

    part = Part.from_file("examples/notched_bar.json")
    for area in ((0.05, 0.02) if not args.quick else (0.4 if args.smoke else 0.1,)):
        mesh = mesh_part(part, max_area=area * MM * MM)
        axis, pad = GraspAxis.through([15 * MM, 0.0], [15 * MM, 12 * MM]), Pad(0.0, 2 * MM)
        t0 = time.perf_counter()
        lin = PadContact(mesh).curve(axis, pad, 0.0)
        t1 = time.perf_counter()
        c = FiniteStrainPads(mesh).curve(axis, pad)
        sig = np.linspace(c.sigma0, 0.6 * c.sigma0, 5 if args.smoke else 17)[1:]
        U = [c.energy_at(float(s)) for s in sig]
        t2 = time.perf_counter()
        reached = int(np.isfinite(U).sum())
        print(f"U(σ) curve, notched bar, {mesh.n_nodes} nodes: linear {t1 - t0:.2f} s (exact "
              f"path), neo-Hookean {t2 - t1:.2f} s for {len(sig)} separations ({reached} reached, "
              f"{c.n_solves} Newton solves); U_lin/U_neo at 40 % squeeze "
              f"{lin.energy_at(float(sig[-1])) / U[-1] if np.isfinite(U[-1]) else float('nan'):.3f}")


if __name__ == "__main__":
    main()
