"""Condensation onto the boundary against one sparse factorisation of the same ``K`` (issue 25).

Run:  python benchmarks/bench_condense.py [--nodes 5000 20000 80000] [--repeat 3] [--quick]

The pads solver's first step is :class:`deformclosure.elasticity.condense.CondensedCompliance`:
one LU of the pinned stiffness in nested-dissection order with the boundary last, then the
boundary compliance ``C = S⁻¹`` from the LU's trailing block (``SuperLU.L``, the diagonal,
LAPACK ``dpotri``). Issue 25 asks for the condensation within 1.3× one CHOLMOD Cholesky
of ``K``; scikit-sparse (CHOLMOD) has no wheel here, so the baselines are the sparse
factorisations that are installed, each of the same pinned ``K``:

* ``SuperLU``: ``scipy.sparse.linalg.splu`` with its default COLAMD order (what a user
  would call), and with the condensation's own order (the factorisation inside it);
* ``qdldl``: the symmetric LDLᵀ (AMD order) the finite-strain solver uses — the closest
  installed relative of a Cholesky.

For the notched bar meshed to about each size (one BLAS thread, best of ``--repeat``) the
table prints the times and the ratio condensation / qdldl with the target 1.3.
``--quick``: 2 500 nodes, the target not judged.

Measured (2 cores, one BLAS thread, best of 2; NOT met)::

      nodes    DOFs boundary  condense  LU (own order)  splu COLAMD  qdldl LDLt  cond/qdldl
      5,094  10,185      255      0.08            0.04         0.05        0.02        4.44
     20,015  40,027      530      0.43            0.24         0.29        0.12        3.50
     79,667 159,331    1,048      3.07            1.67         2.11        1.39        2.22

The condensation is about twice its own LU: reading the factor out of SuperLU
(``SuperLU.L`` builds CSC copies of both factors, 1.7-3 s at 80 000 nodes inside a
running ``optimize``) is most of the rest, a step a Cholesky with a Schur-complement
interface (CHOLMOD, MUMPS) would not need; ``dpotri`` on the ~2 000 boundary DOFs is
0.12 s.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402

import deformclosure as dc  # noqa: E402
from bench_threads import print_target  # noqa: E402
from deformclosure.elasticity.condense import CondensedCompliance, _interior_first_order, pinned_dofs_among  # noqa: E402
from deformclosure.elasticity.stiffness import stiffness_matrix  # noqa: E402

TARGET = 1.3
AREA_MM2 = 342.0 * 1.6      # the notched bar: about 1.6 triangles of this area per node


def best(f, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, nargs="+", default=[5000, 20000, 80000])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="2 500 nodes, target not judged")
    args = ap.parse_args()
    if args.quick:
        args.nodes, args.repeat = [2500], 1
    import qdldl

    part = dc.notched_part(1.0)
    print(f"{'nodes':>7} {'DOFs':>7} {'boundary':>8} {'condense':>9} {'LU (own order)':>15} "
          f"{'splu COLAMD':>12} {'qdldl LDLt':>11} {'cond/qdldl':>11} {'target':>7}  met")
    all_met = True
    for n in args.nodes:
        mesh = dc.mesh_part(part, max_area=AREA_MM2 / (2.0 * n) * 1e-6)
        K = stiffness_matrix(mesh)
        nodes, tri, boundary = mesh.nodes, mesh.triangles, mesh.perimeter_nodes
        pins = pinned_dofs_among(nodes, boundary)
        free = np.setdiff1d(np.arange(K.shape[0]), pins)
        Kf = sp.csc_matrix(K)[free][:, free].tocsc()
        order = _interior_first_order(tri, len(nodes), boundary, pins)
        Ko = sp.csc_matrix(K)[order][:, order].tocsc()
        t_cond = best(lambda: CondensedCompliance(K, nodes, tri, boundary), args.repeat)
        t_own = best(lambda: spla.splu(Ko, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                       options={"SymmetricMode": True, "Equil": False}),
                     args.repeat)
        t_colamd = best(lambda: spla.splu(Kf), args.repeat)
        Kt = sp.triu(Kf, format="csc")
        t_ldl = best(lambda: qdldl.Solver(Kt, upper=True), args.repeat)
        ratio = t_cond / t_ldl
        met = ratio <= TARGET
        all_met &= met
        print(f"{mesh.n_nodes:>7,} {Kf.shape[0]:>7,} {len(boundary):>8,} {t_cond:>9.2f} "
              f"{t_own:>15.2f} {t_colamd:>12.2f} {t_ldl:>11.2f} {ratio:>11.2f} {TARGET:>7.1f}  "
              f"{'-' if args.quick else ('yes' if met else 'NO')}", flush=True)
    print_target(args.quick, f"condensation within {TARGET}x one symmetric factorisation of K",
                 all_met)


if __name__ == "__main__":
    main()
