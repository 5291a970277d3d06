"""BLAS threads: the same ``optimize`` with OpenBLAS' default threads and with one (issue 25).

Run:  python benchmarks/bench_threads.py [--repeat 3] [--quick]

The package caps BLAS at :data:`deformclosure.limits.BLAS_THREADS` (1) threads inside its
loops over small problems and its dense condensation steps (``limits.blas_threads``). On
the notched bar (the example's mesh, ~2 800 nodes) and on the same bar at ~5 600 nodes
it runs the pads ``optimize`` (``--axis 15,6,90 --pad-radius 2 --refine 1``: one mesh,
its landscape, σ*, the noise floor from a second mesh realisation) in a fresh
interpreter per run, in three set-ups, alternated run by run so the machine's other load
falls on all of them alike:

* ``uncapped``: the default threads and ``limits.BLAS_THREADS = None`` (as before the cap);
* ``capped``: the default threads, the package as shipped;
* ``1 thread``: ``OPENBLAS_NUM_THREADS=1`` for the whole process.

Times are in-process seconds of ``reports.run`` (imports and the compiled kernels'
loading excluded: a warm-up on a coarse mesh comes first), the median of ``--repeat``
runs. The ratio table divides each by ``1 thread``. Target: ``capped`` within 15 % of
``1 thread`` on both parts (the cap removes the oversubscription), and the same quality
to 1e-12 relative in every set-up of one part.

Measured (2 cores shared with other jobs, median of 3; issue 25):

    part                                         uncapped     capped   1 thread  uncapped/1  capped/1
    notched bar (example mesh, ~2.8k nodes)          1.72       1.43       1.62        1.06      0.88
    notched bar, ~5.6k nodes                        10.81       3.62       3.87        2.79      0.94

(uncapped, the default threads fought in the condensation's ``dpotri``: 4.8 of 11.5 s
under a profiler.)
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

CHILD = r"""
import json, sys, time
from deformclosure import limits, reports
if sys.argv[1] == "uncapped":
    limits.BLAS_THREADS = None
params = {"axis": "15,6,90", "pad_radius": 2.0, "refine": 1}
reports.run("optimize", sys.argv[2], {**params, "max_area": 1.0})        # warm-up
if sys.argv[3] != "default":
    params["max_area"] = float(sys.argv[3])
t = time.perf_counter()
rep = reports.run("optimize", sys.argv[2], params)
took = time.perf_counter() - t
print(json.dumps({"seconds": took, "quality": rep.data["quality"]}))
"""

SETUPS = ("uncapped", "capped", "1 thread")


def blas_env(one_thread: bool) -> dict:
    """This process's environment without BLAS thread settings, or with OpenBLAS held to
    one thread (``one_thread``): the set-ups the thread benchmarks compare."""
    env = dict(os.environ)
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env.pop(k, None)
    if one_thread:
        env["OPENBLAS_NUM_THREADS"] = "1"
    return env


def print_target(quick: bool, what: str, met: bool) -> None:
    """The benchmarks' last line: whether ``what`` (the target) is met, or not judged on a
    ``--quick`` run."""
    if quick:
        print("target: not judged (--quick)")
    else:
        print(f"target ({what}): {'met' if met else 'NOT met'}")


def run(setup: str, part: str, max_area: str) -> dict:
    env = blas_env(setup == "1 thread")
    out = subprocess.run([sys.executable, "-c", CHILD, setup.split()[0], part, max_area],
                         env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="the example's mesh only, 1 run each")
    args = ap.parse_args()
    part = str(EXAMPLES / "notched_bar.json")
    cases = [("notched bar (example mesh, ~2.8k nodes)", "default"),
             ("notched bar, ~5.6k nodes", "0.05")]
    if args.quick:
        cases, args.repeat = cases[:1], 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"{cores} CPU cores; median of {args.repeat} alternated runs, in-process seconds")
    print(f"{'part':<42} " + " ".join(f"{s:>10}" for s in SETUPS)
          + "  uncapped/1  capped/1  target")
    all_met = True
    for name, area in cases:
        times = {s: [] for s in SETUPS}
        quality = {s: [] for s in SETUPS}
        for _ in range(args.repeat):
            for s in SETUPS:
                r = run(s, part, area)
                times[s].append(r["seconds"])
                quality[s].append(r["quality"])
        med = {s: statistics.median(v) for s, v in times.items()}
        q = [v for vs in quality.values() for v in vs]
        same = max(q) - min(q) <= 1e-12 * max(abs(max(q)), abs(min(q)), 1e-300)
        met = med["capped"] <= 1.15 * med["1 thread"] and same
        all_met &= met
        print(f"{name:<42} " + " ".join(f"{med[s]:>10.2f}" for s in SETUPS)
              + f"  {med['uncapped'] / med['1 thread']:>10.2f}"
              f"  {med['capped'] / med['1 thread']:>8.2f}  {'met' if met else 'NOT met'}"
              + ("" if same else f"  (qualities differ: {min(q)!r} .. {max(q)!r})"))
    print(f"target (capped within 15 % of 1 thread, same Q*): {'met' if all_met else 'NOT met'}")


if __name__ == "__main__":
    main()
