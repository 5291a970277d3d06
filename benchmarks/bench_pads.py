"""Pad-model benchmark (SPEC §6) against the paper's model (SPEC §4) on the same part.

Run:  python benchmarks/bench_pads.py [--quick]

On the notched rubber bar (30 × 12 mm, V-notches) meshed to ~5 000 nodes it prints, side
by side in one run, warm (compiled kernels loaded first):

* optimize: pads seated in the notches (``pad_grasp``: start axis, release landscape over
  grasp axes, exact σ*, noise floor from a second mesh realisation) vs the paper's
  ``optimize_separation(method="exact")`` on the node pair at the notch roots (all pair
  stiffnesses, contact graph, exact σ*);
* refine 3: the pad grasp on three meshes (h halving, the finest ~5 000 nodes) vs the paper
  model on the same three meshes;
* plan: every grasp axis of the default grid (``plan_pads``) vs every jaw pair
  (``plan_grasps``, default ε), both with their top 5 refined exactly;
* the contact-energy kernel alone: grasp axes solved per second (exact curve U(σ)).

Targets (issue 9): optimize ≤ 5 s, refine 3 ≤ 60 s, plan ≤ 30 s.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import deformclosure as dc
from deformclosure.grasp.analysis import grasp_model, optimize_separation
from deformclosure.pads import GraspAxis, Pad, PadContact, pad_grasp
from deformclosure.mesh.generate import twin_mesh
from deformclosure.planning.pads import plan_pads

AXIS = GraspAxis.through([0.015, 0.0], [0.015, 0.012])
PAD = Pad(0.0, 0.002)


def timed(fn, *a, **k):
    t0 = time.perf_counter()
    out = fn(*a, **k)
    return time.perf_counter() - t0, out


def paper_optimize(part, area):
    mesh = dc.mesh_part(part, max_area=area, points=np.array([[0.015, 0.003], [0.015, 0.009]]))
    jaws = (mesh.find_node([0.015, 0.003]), mesh.find_node([0.015, 0.009]))
    return optimize_separation(mesh, jaws, method="exact", model=grasp_model(mesh))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="~1 400 nodes instead of ~5 000")
    args = ap.parse_args()
    area = 0.2e-6 if args.quick else 0.05e-6
    part = dc.notched_part(area * 1e6)
    mesh = dc.mesh_part(part)
    # Warm-up: compile/load the numba kernels of both models on a tiny mesh.
    small = dc.notched_part(2.0)
    pad_grasp(small, AXIS, PAD)
    paper_optimize(small, 2e-6)
    print(f"part: {part.name}, {mesh.n_nodes} nodes, {mesh.n_triangles} triangles, "
          f"{len(mesh.outer_loop)} outer-perimeter nodes")
    rows = []
    t_pads, r = timed(pad_grasp, part, AXIS, PAD, mesh=mesh)
    t_paper, rp = timed(paper_optimize, part, area)
    f = r.finest
    rows.append(("optimize (one mesh)", t_pads, t_paper,
                 f"pads: sigma* {f.sigma_star * 1e3:.4f} mm Q* {f.quality * 1e3:.3f} mJ, "
                 f"{f.n_axes} axes; paper: sigma* {rp.sigma_star * 1e3:.4f} mm"))
    coarse = dc.notched_part(area * 16 * 1e6)
    t_pads3, r3 = timed(pad_grasp, coarse, AXIS, PAD, refine=3)
    t_paper3, _ = timed(lambda: [paper_optimize(coarse, area * 16 / 4**k) for k in range(3)])
    rows.append(("refine 3 (to ~5k nodes)", t_pads3, t_paper3,
                 f"pads verdict {r3.verdict}, Q* ± {r3.error_estimate()['quality'] * 1e3:.3g} mJ"))
    pc = PadContact(mesh)
    t_plan, plan = timed(plan_pads, mesh, PAD, top=5, twin=PadContact(twin_mesh(part)), solver=pc)
    t_pplan, pplan = timed(dc.plan_grasps, mesh, top=5)
    best = plan.rows[0]
    rows.append(("plan (default grid / pairs)", t_plan, t_pplan,
                 f"{plan.grid.size} axes vs {len(pplan.pairs)} pairs; best axis "
                 f"{np.degrees(best['angle']):.0f} deg Q* {best['quality'] * 1e3:.3f} mJ"))
    print(f"{'task':<30} {'pads (s)':>9} {'paper (s)':>10} {'pads/paper':>11}  notes")
    for name, a, b, note in rows:
        print(f"{name:<30} {a:>9.2f} {b:>10.2f} {a / b:>10.1f}x  {note}")
    # The contact-energy kernel alone.
    axes = [GraspAxis(th, c, tuple(pc.centroid)) for th in np.linspace(0, np.pi, 24, endpoint=False)
            for c in np.linspace(-4e-3, 4e-3, 10)]
    t_k, curves = timed(lambda: [pc.curve(ax, PAD, 0.3 * 0.0077) for ax in axes])
    pieces = np.mean([len(c.path.delta) for c in curves if c.path is not None])
    print(f"contact kernel: {len(axes) / t_k:.0f} grasp axes/s (exact U(σ) down to 0.3·σ0, "
          f"{pieces:.0f} pieces each on average)")


if __name__ == "__main__":
    main()
