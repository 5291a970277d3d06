"""Benchmark: meshing and CST stiffness assembly against scikit-fem.

For rectangles meshed to about 1k, 10k and 100k nodes, prints the mesh time (Triangle),
our assembly time ``stiffness_matrix`` on a fresh mesh (best of 3; "cold": the sparsity
pattern is built too) and again on the same mesh (best of 3; "warm": the pattern is kept
in the mesh's cache, as for every later call), scikit-fem's assembly of the same
operator on the same mesh (best of 3; basis and assembly) and the ratio skfem / ours
(cold). It also checks that the two matrices agree. Targets (issue 2): 100k-node
assembly <= 0.5 s and >= 4x faster than scikit-fem.

Run: ``python benchmarks/bench_fem.py [--sizes 1000 10000 100000] [--repeat 3]``
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np
import scipy.sparse as sp

from deformclosure import Part, mesh_part, stiffness_matrix


def rectangle_part() -> Part:
    """A 200 × 100 mm rubber rectangle."""
    return Part.from_dict({
        "name": "bench-rectangle", "units": "mm",
        "outer": [[0, 0], [200, 0], [200, 100], [0, 100]],
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": "stress"},
    })


def best_of(fn, repeat: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def skfem_assembler(mesh, material):
    """A closure assembling K with scikit-fem (P1 vector basis, linear_elasticity)."""
    from skfem import Basis, ElementTriP1, ElementVector, MeshTri
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    lam, mu = lame_parameters(material.youngs_modulus, material.poisson_ratio)
    if material.plane == "stress":
        lam = 2 * lam * mu / (lam + 2 * mu)
    form = linear_elasticity(lam, mu)

    def assemble():
        # Building the basis is part of what a scikit-fem user pays per mesh.
        basis = Basis(MeshTri(mesh.nodes.T.copy(), mesh.triangles.T.copy()),
                      ElementVector(ElementTriP1()))
        return form.assemble(basis) * material.thickness, basis

    return assemble


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1_000, 10_000, 100_000],
                    help="approximate node counts")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    part = rectangle_part()
    # Triangle at min angle 30° gives about n ≈ 0.79 · area / max_area nodes.
    rows = []
    for n_target in args.sizes:
        max_area = 0.79 * part.area / n_target
        t_mesh, mesh = best_of(lambda: mesh_part(part, max_area=max_area), 1)
        stiffness_matrix(dataclasses.replace(mesh, _cache={}))  # warm up numpy/scipy
        t_ours, K = best_of(lambda: stiffness_matrix(dataclasses.replace(mesh, _cache={})),
                            args.repeat)
        stiffness_matrix(mesh)
        t_warm, _ = best_of(lambda: stiffness_matrix(mesh), args.repeat)
        t_sk, (Ks, basis) = best_of(skfem_assembler(mesh, part.material), args.repeat)
        perm = np.empty(2 * mesh.n_nodes, dtype=np.int64)
        perm[0::2], perm[1::2] = basis.nodal_dofs[0], basis.nodal_dofs[1]
        Ks = sp.csr_matrix(Ks)[perm][:, perm]
        err = abs(K - Ks).max() / abs(Ks).max()
        rows.append((mesh.n_nodes, mesh.n_triangles, t_mesh, t_ours, t_warm, t_sk,
                     t_sk / t_ours, err))

    head = (f"{'nodes':>8} {'triangles':>10} {'mesh (s)':>9} {'ours (s)':>9} "
            f"{'warm (s)':>9} {'skfem (s)':>10} {'skfem/ours':>11} {'max rel diff':>13}")
    print(head)
    print("-" * len(head))
    for n, m, tm, to, tw, ts, r, e in rows:
        print(f"{n:>8d} {m:>10d} {tm:>9.3f} {to:>9.4f} {tw:>9.4f} {ts:>10.4f} {r:>11.1f} "
              f"{e:>13.1e}")
    n, _, _, to, _, _, r, _ = rows[-1]
    print(f"\ntargets at {n} nodes: assembly <= 0.5 s: {'met' if to <= 0.5 else 'MISSED'} "
          f"({to:.3f} s); >= 4x faster than scikit-fem: {'met' if r >= 4 else 'MISSED'} ({r:.1f}x)")


if __name__ == "__main__":
    main()
