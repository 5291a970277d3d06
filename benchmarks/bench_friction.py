"""Cost of friction (SPEC §9, issue 22): ``optimize`` with ``--friction 0.5`` against the
frictionless run on the examples, through the command's own code path (``reports.run``).

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_friction.py [--quick]

For each grasp it prints the time of the frictionless ``optimize`` (default accuracy,
``--rtol 0.05``), the time of the same run with ``μ = 0.5`` (the frictionless levels and
then every level read with friction: release work ``U_A^μ`` on the level's landscape, the
sampled σ*-search, the hold at σ*), their ratio (goal ≤ 3×), both verdicts and Q*, and the
hold force across the axis, and whether the ratio meets the goal. Then ``plan`` with
``μ = 0.5`` on the notched bar meshed to about 5 000 nodes (``--max-area 0.055``; goal
≤ 90 s), against the frictionless plan. Wall time and this process's CPU time are both
printed; the goals are judged on the CPU time (one BLAS thread, no parallel kernels: what
the wall time is on an idle machine; on a shared one the wall time measures the load). ``--quick`` solves one mesh per grasp (``--refine 1``) and skips the plan.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from deformclosure import Part, mesh_part, reports

ROOT = Path(__file__).resolve().parents[1]

#: (name, part file, optimize parameters): the README's grasps and a few of the examples.
GRASPS = [
    ("rectangle (README)", "rectangle.json", {"axis": "6,10,0", "pad_radius": 1, "pad_width": 4}),
    ("notched bar (README)", "notched_bar.json", {"at": ("15,0", "15,12"), "pad_radius": 2}),
    ("L-shape, round pads", "l_shape.json", {"axis": "4,10,0", "pad_radius": 1}),
    ("ring, expanding (README)", "ring.json",
     {"at": ("1.5,0", "-1.5,0"), "expanding": True, "pad_radius": 0.3}),
    ("rectangle, flat pads 36 mm", "rectangle.json",
     {"axis": "6,10,90", "pad_radius": 0.5, "pad_width": 36}),
]


#: Goals (issue 22): time ratio of optimize with μ = 0.5 over μ = 0; plan at 5k nodes (s).
RATIO_GOAL, PLAN_GOAL = 3.0, 90.0

#: The plan row: the notched bar at about 5 000 nodes (mesh.max_area in mm²).
PLAN_PART, PLAN_AREA = "notched_bar.json", 0.055


def run(part: str, params: dict, command: str = "optimize") -> tuple[float, float, dict]:
    """Wall and CPU seconds of one command through ``reports.run``, and its report."""
    t0, c0 = time.perf_counter(), time.process_time()
    rep = reports.run(command, str(ROOT / "examples" / part), params)
    return time.perf_counter() - t0, time.process_time() - c0, rep.data


def met(ok: bool) -> str:
    return "met" if ok else "NOT MET"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="one mesh per grasp (--refine 1)")
    ap.add_argument("--smoke", action="store_true",
                    help="the first grasp only, one mesh (the benchmarks' smoke test)")
    args = ap.parse_args()
    extra = {"refine": 1} if args.quick or args.smoke else {}
    head = (f"{'grasp':<28} {'t mu=0':>8} {'t mu=0.5':>9} {'ratio':>6} {'cpu ratio':>9} "
            f"{'Q* mu=0 (J)':>12} {'Q* mu=0.5 (J)':>13} {'verdict mu=0':>13} "
            f"{'verdict mu=0.5':>15} {'hold (N)':>9} {'goal':>8}")
    print(f"optimize, mu = 0.5 against mu = 0 (goal: time ratio <= {RATIO_GOAL:g}x)")
    print(head)
    print("-" * len(head))
    for name, part, params in (GRASPS[:1] if args.smoke else GRASPS):
        t0, c0, d0 = run(part, {**params, **extra})
        t1, c1, d1 = run(part, {**params, **extra, "friction": 0.5})
        hold = d1.get("hold") or {}
        f = hold.get("force")
        if f is not None and None in f:
            f = hold["slide"]["force"]
        hs = "-" if f is None else f"{min(abs(f[0]), abs(f[1])):.3g}"
        print(f"{name:<28} {t0:>7.1f}s {t1:>8.1f}s {t1 / t0:>5.1f}x {c1 / c0:>8.1f}x "
              f"{d0['quality']:>12.4g} {d1['quality']:>13.4g} {d0['verdict']:>13} "
              f"{d1['verdict']:>15} {hs:>9} {met(c1 / c0 <= RATIO_GOAL):>8}", flush=True)
    if args.quick or args.smoke:
        return
    print(f"\nplan, notched bar at --max-area {PLAN_AREA} (goal: mu = 0.5 within "
          f"{PLAN_GOAL:g} s)")
    head = (f"{'mu':>4} {'nodes':>6} {'wall (s)':>9} {'cpu (s)':>8} {'best Q (J)':>11} "
            f"{'verified held':>14} {'goal':>8}")
    print(head)
    print("-" * len(head))
    part = Part.from_file(ROOT / "examples" / PLAN_PART)
    nodes = mesh_part(part, max_area=PLAN_AREA * 1e-6).n_nodes       # mm² -> m²
    for mu in (0.0, 0.5):
        t, c, d = run(PLAN_PART, {"max_area": PLAN_AREA, "friction": mu}, "plan")
        top = d.get("top") or []
        held = sum(1 for r in top if r.get("verdict") == "held")
        best = max((r["quality"] for r in top if r.get("quality") is not None), default=0.0)
        goal = met(c <= PLAN_GOAL) if mu > 0 else "-"
        print(f"{mu:>4g} {nodes:>6} {t:>9.1f} {c:>8.1f} {best:>11.4g} "
              f"{held:>14} {goal:>8}", flush=True)


if __name__ == "__main__":
    main()
