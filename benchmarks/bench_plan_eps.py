"""Planner benchmark: every jaw pair within ε of its optimum (issue 12).

Run:  python benchmarks/bench_plan_eps.py [--quick]

Two runs of :func:`deformclosure.plan_grasps` (paper model, point jaws), each timed end
to end (stiffness, contact graph, factorisation, elastic limits, shared lattice, per-pair
refinement, the exact top 10):

* the L-shape of ``examples/l_shape.json`` meshed to p ≈ 130 perimeter nodes with
  ``ε = 1e-3 · max Q*`` — target ≤ 60 s;
* a 12 × 20 mm rectangle at p ≈ 240 with the default ε — target ≤ 10 s.

For comparison, the old planner: one shared lattice ``σ_j = j·ε/λ`` with the global
``λ = max k σ0`` for every pair (no per-pair guarantee across the jumps of ``U_A``). It
refused lattices over 200 000 values ("refused"); otherwise it is timed here with the
same steps as it had (elastic limits, lattice sweeps, the exact top 10).

The table: part, p, pairs, ε (J), wall and CPU seconds (CPU counts every thread; on a
busy machine wall ≫ CPU), rows settled zero / by bounds / exactly, escape-level
evaluations of the refinement, and the old planner's wall time.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

import deformclosure as dc
from deformclosure.grasp.analysis import grasp_model, optimize_separation
from deformclosure.grasp.release import release_energies
from deformclosure.grasp.separation import lipschitz_constant, vertex_energies
from deformclosure.planning.plan import _workers, pair_elastic_limits

ROOT = Path(__file__).resolve().parents[1]
MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
       "elastic_limit_strain": 0.8, "plane": "stress"}
OLD_MAX_SIGMA = 200_000


def l_shape_mesh(max_area: float):
    raw = json.loads((ROOT / "examples" / "l_shape.json").read_text())
    raw["mesh"]["max_area"] = max_area
    return dc.mesh_part(dc.Part.from_dict(raw))


def rectangle_mesh(p_target: int):
    """12 × 20 mm rubber rectangle whose outer loop has about ``p_target`` nodes."""
    h = 64.0 / p_target
    return dc.mesh_part(dc.Part.from_dict({"units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
                                           "material": MAT,
                                           "mesh": {"max_area": 0.45 * h * h, "min_angle": 25}}))


def old_plan_seconds(mesh, eps: float | None, n_sigma: int = 400, top: int = 10) -> str:
    """The old planner (shared λ-lattice, exact top 10), timed; "refused" where it
    refused the lattice."""
    t0 = time.perf_counter()
    model = grasp_model(mesh)
    g, s0, k = model.graph, model.stiffness.sigma0, model.stiffness.k
    idx = np.arange(g.n_vertices)
    e_max, sigma_L = pair_elastic_limits(model, idx, mesh.material.elastic_limit_strain)
    lo, hi = float(sigma_L.min()), float(s0.max())
    lam = lipschitz_constant(s0, k, hi)
    if eps is None:
        eps = lam * (hi - lo) / n_sigma
    step = eps / lam
    j0, j1 = math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9)
    if j1 - j0 + 1 > OLD_MAX_SIGMA:
        return f"refused ({j1 - j0 + 1:.3g} σ)"
    grid = np.arange(j0, j1 + 1) * step
    UsL = 0.5 * k * (s0 - sigma_L) ** 2
    best = np.zeros(len(idx))

    def sweep(sig):
        U = vertex_energies(sig, s0, k)
        return release_energies(U, g), UsL - U

    with ThreadPoolExecutor(_workers()) as pool:
        for sig, (R, UL) in zip(grid, pool.map(sweep, grid)):
            Q = np.where((sig >= sigma_L) & (sig <= s0), np.minimum(R, UL), -np.inf)
            best = np.maximum(best, Q)
    for v in np.argsort(-best, kind="stable")[:top]:
        optimize_separation(mesh, tuple(int(x) for x in g.pairs[v]), method="exact", model=model)
    return f"{time.perf_counter() - t0:.1f}"


def run(label: str, mesh, rel_eps: float | None, limit: float) -> None:
    eps = None
    if rel_eps is not None:                       # ε relative to the best pair's exact Q*
        ref = dc.plan_grasps(mesh, top=1, allow_pulling=True)    # the best pair, exact
        eps = rel_eps * float(ref.refined[0].quality)
    t0, c0 = time.perf_counter(), time.process_time()
    plan = dc.plan_grasps(mesh, eps=eps, top=10)
    dt, cpu = time.perf_counter() - t0, time.process_time() - c0
    c = plan.settled_counts()
    old = old_plan_seconds(mesh, eps)
    ok = "ok" if dt <= limit else f"OVER {limit:.0f} s"
    print(f"{label:<24} {len(mesh.outer_loop):>4} {len(plan.pairs):>7} {plan.epsilon:>10.3g} "
          f"{dt:>8.2f} {cpu:>8.2f} {ok:>9} {c['zero']:>7} {c['bounds']:>7} {c['exact']:>6} "
          f"{plan.n_evaluations:>7} {old:>20}")
    print(f"{'':<24} timings (s): " + ", ".join(f"{k} {v:.2f}" for k, v in plan.timings.items()
                                               if v >= 0.01))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="the p ≈ 130 run only")
    args = ap.parse_args()
    dc.plan_grasps(rectangle_mesh(24), top=1, n_sigma=20)      # JIT warm-up, not timed
    print(f"{'part':<24} {'p':>4} {'pairs':>7} {'eps (J)':>10} {'time (s)':>8} {'cpu (s)':>8} "
          f"{'target':>9} "
          f"{'zero':>7} {'bounds':>7} {'exact':>6} {'evals':>7} {'old planner (s)':>20}")
    run("L-shape, eps=1e-3 Q*", l_shape_mesh(0.2), 1e-3, 60.0)
    if not args.quick:
        run("rectangle, default eps", rectangle_mesh(240), None, 10.0)


if __name__ == "__main__":
    main()
