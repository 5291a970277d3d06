"""Cost of friction (SPEC §9, issue 22): ``optimize`` with ``--friction 0.5`` against the
frictionless run on the examples, through the command's own code path (``reports.run``).

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_friction.py [--quick]

For each grasp it prints the time of the frictionless ``optimize`` (default accuracy,
``--rtol 0.05``), the time of the same run with ``μ = 0.5`` (the frictionless levels and
then every level read with friction: release work ``U_A^μ`` on the level's landscape, the
sampled σ*-search, the hold at σ*), their ratio (goal ≤ 3×), both verdicts and Q*, and the
hold force across the axis. ``--quick`` solves one mesh per grasp (``--refine 1``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from deformclosure import reports

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


def run(part: str, params: dict) -> tuple[float, dict]:
    t0 = time.perf_counter()
    rep = reports.run("optimize", str(ROOT / "examples" / part), params)
    return time.perf_counter() - t0, rep.data


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="one mesh per grasp (--refine 1)")
    ap.add_argument("--smoke", action="store_true",
                    help="the first grasp only, one mesh (the benchmarks' smoke test)")
    args = ap.parse_args()
    extra = {"refine": 1} if args.quick or args.smoke else {}
    head = (f"{'grasp':<28} {'t mu=0':>8} {'t mu=0.5':>9} {'ratio':>6} {'Q* mu=0 (J)':>12} "
            f"{'Q* mu=0.5 (J)':>13} {'verdict mu=0':>13} {'verdict mu=0.5':>15} {'hold (N)':>9}")
    print(head)
    print("-" * len(head))
    for name, part, params in (GRASPS[:1] if args.smoke else GRASPS):
        t0, d0 = run(part, {**params, **extra})
        t1, d1 = run(part, {**params, **extra, "friction": 0.5})
        hold = d1.get("hold") or {}
        f = hold.get("force")
        if f is not None and None in f:
            f = hold["slide"]["force"]
        hs = "-" if f is None else f"{min(abs(f[0]), abs(f[1])):.3g}"
        print(f"{name:<28} {t0:>7.1f}s {t1:>8.1f}s {t1 / t0:>5.1f}x {d0['quality']:>12.4g} "
              f"{d1['quality']:>13.4g} {d0['verdict']:>13} {d1['verdict']:>15} {hs:>9}",
              flush=True)


if __name__ == "__main__":
    main()
