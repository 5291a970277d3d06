"""Time to a stated accuracy (SPEC §6 "Accuracy by default", issue 20): adaptive vs uniform.

Run:  python benchmarks/bench_accuracy.py [--quick]

For each grasp it prints, side by side in one run, the time ``pad_grasp(..., rtol=0.05)``
takes to meet the accuracy with adaptive refinement (the default) and with uniform
refinement (every element halved per level), the levels, the finest node count, Q* with
its error estimate, and the ratio uniform / adaptive. Then the default ``optimize`` of the
examples (target ≤ 20 s each) and ``plan`` with verification of 5 on a ~5 000-node part
(target ≤ 60 s).

Grasps: the demo's notched bar (round pads in the V-notches), the README rectangle
(a convex block: the answer is "not held"), and the notched bar meshed to ~5 000 nodes.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import deformclosure as dc
from deformclosure import reports
from deformclosure.pads import GraspAxis, Pad, pad_grasp
from deformclosure.planning.pads import plan_pads

ROOT = Path(__file__).resolve().parents[1]
MM = 1e-3


def timed(fn, *a, **k):
    t0 = time.perf_counter()
    out = fn(*a, **k)
    return time.perf_counter() - t0, out


def _fmt_q(run) -> str:
    e = run.error_estimate()["quality"]
    return f"{run.finest.quality * 1e3:.4g} ± {e * 1e3:.2g} mJ" if e is not None else "-"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="skip the 5 000-node grasp and plan")
    args = ap.parse_args()
    rect = dc.Part.from_file(str(ROOT / "examples" / "rectangle.json"))
    bar = dc.notched_part()
    grasps = [("demo notched bar, rho 2 mm", bar, GraspAxis(math.pi / 2, -0.015), Pad(0.0, 2 * MM), None),
              ("README rectangle, rho 1 mm", rect, GraspAxis.through([0, 0.010], [0.012, 0.010]),
               Pad(0.0, 1 * MM), None)]
    if not args.quick:
        grasps.append(("notched bar, ~5k nodes", bar, GraspAxis(math.pi / 2, -0.015),
                       Pad(0.0, 2 * MM), 0.05e-6))
    pad_grasp(dc.notched_part(2.0), grasps[0][2], grasps[0][3], refine=1)      # warm-up
    print("time to rtol 0.05 on Q* and U_A (mesh and landscape)")
    print(f"{'grasp':30} {'mode':9} {'time (s)':>9} {'levels':>6} {'nodes':>7} "
          f"{'Q*':>20} {'verdict':>10} {'uniform/adaptive':>17}")
    for name, part, axis, pad, area in grasps:
        rows = {}
        for mode in ("adaptive", "uniform"):
            t, run = timed(pad_grasp, part, axis, pad, rtol=0.05, max_area=area,
                           adaptive=mode == "adaptive", max_seconds=600)
            rows[mode] = (t, run)
        for mode, (t, run) in rows.items():
            ratio = f"{rows['uniform'][0] / rows['adaptive'][0]:.2f}" if mode == "uniform" else ""
            print(f"{name:30} {mode:9} {t:9.1f} {len(run.levels):6d} {run.finest.n_nodes:7d} "
                  f"{_fmt_q(run):>20} {run.verdict:>10} {ratio:>17}"
                  + ("" if run.converged else "  (not converged)"))
    print()
    print("optimize at default settings (--rtol 0.05, adaptive), target <= 20 s")
    cases = [("notched_bar.json", {"at": ("15,0", "15,12"), "pad_radius": 2.0}),
             ("rectangle.json", {"at": ("0,10", "12,10"), "pad_radius": 1.0})]
    for fname, params in cases:
        full = {**reports.defaults("optimize"), **params}
        t, rep = timed(reports.run, "optimize", str(ROOT / "examples" / fname), full)
        d = rep.data
        print(f"  {fname:20} {t:6.1f} s  levels {len(d['convergence'])}  verdict {d['verdict']}"
              f"  converged {d['converged']}")
    if not args.quick:
        part = dc.notched_part(0.05)
        mesh = dc.mesh_part(part)
        t, plan = timed(plan_pads, mesh, Pad(0.0, 2 * MM), top=5, part=part)
        held = [r for r in plan.rows if r["verdict"] == "held"]
        print(f"\nplan with verification of 5 on {mesh.n_nodes} nodes: {t:.1f} s (target <= 60 s), "
              f"{len(held)} held, best {np.round(np.array(plan.rows[0]['point']) * 1e3, 2)} mm")


if __name__ == "__main__":
    main()
