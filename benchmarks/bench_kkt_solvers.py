"""qdldl vs SuperLU for the Newton systems of the finite-strain contact solve (SPEC §8).

The Newton matrix of :class:`deformclosure.contact.large_deformation.FiniteStrainContact`
is symmetric and indefinite: ``[[K_T − Σλ∇²g, −Jᵀ, −Gᵀ], [−J, D, 0], [−G, 0, 0]]``, its
tangent block only positive *semi*-definite on its own (the gauge removes the rigid
modes), its pattern fixed along a squeeze. This records (through SuperLU) the Newton
systems of one neo-Hookean U(σ) curve of the notched bar (~5k nodes, round pads r 2 mm,
first touch to 40 % squeeze) and times, on the same matrices:

- ``superlu``: the solver's fallback (and its only path without qdldl),
  ``splu(KKT, permc_spec="NATURAL")`` on the METIS nested-dissection order (partial
  pivoting), one fresh factorisation per Newton step;
- ``superlu (COLAMD)``: SuperLU in its own column order;
- ``qdldl``: a symmetric LDLᵀ without pivoting (AMD order) — unshifted (it meets zero
  pivots), and shifted by ``±ε`` (ε = 1e-12 × the tangent's mean diagonal, in a pattern
  fixed along the curve) with iterative refinement on the true matrix to a residual of
  1e-13: the first factorisation (symbolic + numeric), then ``Solver.update`` (numeric
  only) — what the solver does when qdldl is installed;

each with the relative residual ``‖A x − b‖∞ / ‖b‖∞`` of its solution.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_kkt_solvers.py [--max-area MM2]
[--smoke]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from deformclosure import Part, mesh_part
from deformclosure.contact import large_deformation as LD
from deformclosure.pads.geometry import GraspAxis, Pad
from deformclosure.pads.large_deformation import FiniteStrainPads

MM = 1e-3
#: Static regularisation of the qdldl variant, relative to the tangent's mean diagonal.
EPS = 1e-12


def record(max_area_mm2: float, n_sep: int, keep: int = 200):
    """The first ``keep`` Newton systems ``(A, b)`` of one curve, and the time of that
    curve (s, recording included)."""
    mesh = mesh_part(Part.from_file("examples/notched_bar.json"), max_area=max_area_mm2 * MM * MM)
    systems = []
    real = LD.spla.splu

    class Recording:
        def __init__(self, A, **kw):
            self.A, self.lu = A, real(A, **kw)

        def solve(self, b):
            if len(systems) < keep:
                systems.append((self.A.copy(), np.array(b)))
            return self.lu.solve(b)

    LD.spla.splu = Recording
    backend, LD.LINEAR_SOLVER = LD.LINEAR_SOLVER, "superlu"      # every system via splu
    try:
        t0 = time.perf_counter()
        c = FiniteStrainPads(mesh).curve(GraspAxis.through([15 * MM, 0.0], [15 * MM, 12 * MM]),
                                         Pad(0.0, 2 * MM))
        for s in np.linspace(c.sigma0, 0.6 * c.sigma0, n_sep + 1)[1:]:
            c.energy_at(float(s))
        seconds = time.perf_counter() - t0
    finally:
        LD.spla.splu, LD.LINEAR_SOLVER = real, backend
    return mesh.n_nodes, systems, seconds


def residual(A, x, b) -> float:
    return float(np.abs(A @ x - b).max() / np.abs(b).max())


def qdldl_regularised(solver, A, b, tol: float = 1e-13, most: int = 10):
    """Solve with the factor of ``A + diag(+ε on u, −ε on the multipliers)`` and
    iterative refinement on ``A`` until the relative residual is ``≤ tol`` (at most
    ``most`` sweeps); returns the solution and the sweeps taken."""
    x = solver.solve(b)
    k = 0
    while k < most and residual(A, x, b) > tol:
        x = x + solver.solve(b - A @ x)
        k += 1
    return x, k


def regularised(A: sp.csc_matrix, n_u: int, eps: float) -> sp.csc_matrix:
    """``A + diag(+ε on the first n_u, −ε on the rest)`` in a pattern that is the same
    for every value of ``A`` (its stored entries, zeros included, and the diagonal):
    ``qdldl.Solver.update`` needs the pattern of the first factorisation."""
    n = A.shape[0]
    C = A.tocoo()
    d = np.concatenate([np.full(n_u, eps), np.full(n - n_u, -eps)])
    i = np.concatenate([C.row, np.arange(n)])
    out = sp.coo_matrix((np.concatenate([C.data, d]), (i, np.concatenate([C.col, np.arange(n)]))),
                        shape=A.shape).tocsc()
    out.sort_indices()
    return out


def factored(solver, A):
    """``(solver, first)``: a new qdldl factorisation of ``A`` (symbolic and numeric) when
    ``solver`` is None, else ``solver`` refactorised numerically on the same pattern."""
    import qdldl

    if solver is None:
        return qdldl.Solver(A), True
    solver.update(A)
    return solver, False


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-area", type=float, default=0.055, help="mm² (0.055: ~5k nodes)")
    ap.add_argument("--separations", type=int, default=16)
    ap.add_argument("--smoke", action="store_true", help="a coarse mesh, 3 separations")
    args = ap.parse_args()
    if args.smoke:
        args.max_area, args.separations = 0.5, 3
    n_nodes, systems, t_curve = record(args.max_area, args.separations)
    n = systems[0][0].shape[0]
    n_u = 2 * n_nodes
    print(f"notched bar, {n_nodes} nodes: {len(systems)} Newton systems of size {n} "
          f"(nnz {systems[0][0].nnz}), curve of {args.separations} separations "
          f"{t_curve:.2f} s with SuperLU")
    rows = {}

    def add(name, t, res):
        rows.setdefault(name, ([], []))
        rows[name][0].append(t)
        rows[name][1].append(res)

    solver = solver_reg = pattern = None
    failures, sweeps = 0, []
    for A, b in systems:
        A = A.tocsc()
        t0 = time.perf_counter()
        x = spla.splu(A, permc_spec="NATURAL").solve(b)
        add("superlu (ND order, NATURAL)", time.perf_counter() - t0, residual(A, x, b))
        t0 = time.perf_counter()
        x = spla.splu(A, permc_spec="COLAMD").solve(b)
        add("superlu (COLAMD)", time.perf_counter() - t0, residual(A, x, b))
        # qdldl, no regularisation: fresh, then numeric update on the fixed pattern
        try:
            t0 = time.perf_counter()
            solver, first = factored(solver, A)
            name = "qdldl first (symbolic+numeric)" if first else "qdldl update (numeric)"
            x = solver.solve(b)
            add(name, time.perf_counter() - t0, residual(A, x, b))
        except Exception:                             # a zero pivot
            failures += 1
            solver = None
        eps = EPS * float(np.abs(A.diagonal()[:n_u]).mean())
        Ar = regularised(A, n_u, eps)
        same = pattern is not None and np.array_equal(Ar.indices, pattern)
        if not same:
            solver_reg, pattern = None, Ar.indices.copy()
        t0 = time.perf_counter()
        solver_reg, first = factored(solver_reg, Ar)
        name = f"qdldl ±eps + refinement, {'first' if first else 'update'}"
        x, k = qdldl_regularised(solver_reg, A, b)
        sweeps.append(k)
        add(name, time.perf_counter() - t0, residual(A, x, b))
    print(f"{'method':36} {'calls':>5} {'median ms':>10} {'total s':>8} {'max resid':>10}")
    for name, (ts, rs) in rows.items():
        print(f"{name:36} {len(ts):>5} {1e3 * np.median(ts):>10.1f} {sum(ts):>8.2f} "
              f"{max(rs):>10.1e}")
    print(f"qdldl ±eps (eps = {EPS:g} x mean |diag K|): refinement sweeps per system "
          f"median {np.median(sweeps):.0f}, max {max(sweeps)}")
    if failures:
        print(f"qdldl without regularisation failed (zero pivot) on {failures} of "
              f"{len(systems)} systems")


if __name__ == "__main__":
    main()
