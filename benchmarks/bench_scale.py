"""The scale targets of issue 25: ``optimize`` at 20k and 80k nodes, ``plan`` at 20k.

Run:  python benchmarks/bench_scale.py [--repeat 1] [--only optimize plan] [--quick]

On the notched rubber bar (``examples/notched_bar.json``, pads r 2 mm) meshed to about
the given number of nodes (``--max-area`` from the part's area), each case runs in a fresh
interpreter, twice per repeat, alternated so the machine's other load falls on both:

* ``1 thread``: ``OPENBLAS_NUM_THREADS=1`` for the whole process;
* ``default``: OpenBLAS' default threads (the package caps them itself inside its loops
  over small problems, ``limits.blas_threads``).

The cases (``reports.run``, the library call of the CLI, so exactly the CLI's work):

* ``optimize --axis 15,6,90 --pad-radius 2 --refine 1`` at ~20 000 and ~80 000 nodes: one
  mesh, its release landscape, σ*, the elastic limit and the noise floor from a second
  mesh realisation (targets 6 s and 25 s);
* ``plan --pad-radius 2 --verify 1`` at ~20 000 nodes: the default grid of grasp axes
  screened, one candidate verified with ``optimize``'s code path (target 25 s).

Times are in-process seconds (imports and the compiled kernels' loading excluded: a
warm-up on a coarse mesh comes first), the median of ``--repeat`` runs; the ratio is
default / 1 thread. The qualities of the two set-ups must agree to 1e-12 (relative).
``--quick``: 2 500 nodes for every case (a smoke run; the targets are then not judged).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from bench_threads import blas_env, print_target

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
#: The notched bar's area (mm²) and Triangle's triangles per (area / max_area) at its
#: default min_angle (``bench_memory.py``'s measured factor).
BAR_AREA_MM2, PER_AREA = 360.0 - 2 * 9.0, 1.6

CHILD = r"""
import json, sys, time
from deformclosure import reports
cmd, part, params = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
reports.run(cmd, part, {**params, "max_area": 2.0})                       # warm-up
t = time.perf_counter()
rep = reports.run(cmd, part, params)
took = time.perf_counter() - t
d = rep.data
q = d.get("quality")
if q is None:                                     # plan: the best candidate's quality
    q = max((a.get("quality") or 0.0 for a in d.get("axes", d.get("pairs", []))), default=0.0)
import deformclosure as dc                         # the mesh's size (after the timing)
nodes = dc.mesh_part(dc.Part.from_file(part), max_area=params["max_area"] * 1e-6).n_nodes
print("RESULT " + json.dumps({"seconds": took, "quality": q, "nodes": nodes}))
"""

CASES = [  # name, command, parameters, nodes, target (s)
    ("optimize --refine 1", "optimize", {"axis": "15,6,90", "pad_radius": 2.0, "refine": 1},
     20_000, 6.0),
    ("optimize --refine 1", "optimize", {"axis": "15,6,90", "pad_radius": 2.0, "refine": 1},
     80_000, 25.0),
    ("plan --verify 1", "plan", {"pad_radius": 2.0, "verify": 1}, 20_000, 25.0),
]
SETUPS = ("1 thread", "default")


def run(setup: str, cmd: str, params: dict) -> dict:
    """One case in a fresh interpreter; its RESULT line."""
    env = blas_env(setup == "1 thread")
    part = str(EXAMPLES / "notched_bar.json")
    out = subprocess.run([sys.executable, "-c", CHILD, cmd, part, json.dumps(params)],
                         env=env, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError((out.stderr or out.stdout).strip().splitlines()[-1])
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("RESULT ")][-1]
    return json.loads(line[7:])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--only", nargs="*", choices=("optimize", "plan"), default=None)
    ap.add_argument("--quick", action="store_true", help="2 500 nodes, targets not judged")
    args = ap.parse_args()
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"{cores} CPU cores; median of {args.repeat} alternated runs, in-process seconds")
    print(f"{'case':<22} {'nodes':>7} " + " ".join(f"{s:>9}" for s in SETUPS)
          + f" {'default/1':>10} {'target':>7}  met")
    all_met, done = True, set()
    for name, cmd, params, nodes, target in CASES:
        n = 2_500 if args.quick else nodes
        if (args.only and cmd not in args.only) or (name, n) in done:
            continue
        done.add((name, n))
        p = {**params, "max_area": BAR_AREA_MM2 * PER_AREA / (2.0 * n)}
        times = {s: [] for s in SETUPS}
        qual, seen = [], 0
        try:
            for _ in range(args.repeat):
                for s in SETUPS:
                    r = run(s, cmd, p)
                    times[s].append(r["seconds"])
                    qual.append(float(r["quality"]))
                    seen = r["nodes"] or seen
        except RuntimeError as err:
            print(f"{name:<22} {n:>7,} failed: {err}")
            all_met = False
            continue
        med = {s: statistics.median(v) for s, v in times.items()}
        same = max(qual) - min(qual) <= 1e-12 * max(abs(max(qual)), 1e-300)
        met = (med["1 thread"] <= target and med["default"] <= target and same)
        if not args.quick:
            all_met &= met
        verdict = "-" if args.quick else ("yes" if met else "NO")
        print(f"{name:<22} {seen:>7,} " + " ".join(f"{med[s]:>9.2f}" for s in SETUPS)
              + f" {med['default'] / med['1 thread']:>10.2f} {target:>7.0f}  {verdict}"
              + ("" if same else f"  (qualities differ: {min(qual)!r} .. {max(qual)!r})"),
              flush=True)
    print_target(args.quick, "every case within its seconds in both set-ups, same quality",
                 all_met)


if __name__ == "__main__":
    main()
