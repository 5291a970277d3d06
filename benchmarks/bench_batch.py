"""Batch throughput: the same jobs on a local pool of 1 and 2 worker processes.

Run:  python benchmarks/bench_batch.py [--jobs 8] [--workers 1 2] [--repeat 3] [--quick]

``--quick``: two ``optimize`` jobs on the rectangle, one run per pool size (< 1 min).

The jobs are ``plan`` runs on the example parts (then ``optimize`` on the rectangle with
other jaw positions, if more jobs are asked for than there are examples). Each row is
a fresh results file, so every job runs; the wall time (best of ``--repeat`` runs)
includes starting the worker processes, not the fork server they come from (started
once, before timing). "job time" is the sum of the jobs' own run times. A last line
re-runs the batch on a finished file: the cost of resuming (every job skipped).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

from deformclosure.batch import load_jobs, read_results, run_batch
from deformclosure.batch.worker import mp_context

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def job_list(folder: Path, n: int, plans: bool = True) -> Path:
    """A JSON job list of ``n`` distinct jobs on copies of the example parts.

    The parts are copied into ``folder`` beside the list and named relative to it: a job
    list may only name files inside its own folder (``load_jobs``' safety rule), as a
    user's list on their own parts would.
    """
    parts = sorted(EXAMPLES.glob("*.json"))
    for p in parts:
        shutil.copyfile(p, folder / p.name)
    entries = [{"part": p.name, "command": "plan", "options": ["--top", "3", "--quiet"]}
               for p in parts[:n if plans else 0]]
    extra = n - len(entries)
    for i in range(extra):
        y = 2 + 16 * (i + 0.5) / extra
        entries.append({"part": "rectangle.json", "command": "optimize",
                        "options": ["--at", f"0,{y:.3f}", f"12,{y:.3f}"]})
    path = folder / "jobs.json"
    path.write_text(json.dumps(entries))
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=8)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="2 optimize jobs, 1 run each")
    args = ap.parse_args()
    if args.quick:
        args.jobs, args.repeat = 2, 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        jobs = load_jobs(job_list(tmp, args.jobs, plans=not args.quick))
        print(f"{len(jobs)} jobs ({sum(j.command == 'plan' for j in jobs)} plan, "
              f"{sum(j.command == 'optimize' for j in jobs)} optimize), {cores} CPU cores")
        print(f"{'workers':>7} {'wall (s)':>9} {'job time (s)':>13} {'jobs/s':>7} {'speed-up':>9}")
        mp_context()  # start the fork server (it imports the package once) before timing
        base = None
        for w in args.workers:
            best = (float("inf"), 0.0)
            for r in range(args.repeat):
                db = tmp / f"w{w}-{r}.sqlite"
                t = time.perf_counter()
                s = run_batch(jobs, db, workers=w, progress=False)
                wall = time.perf_counter() - t
                assert s.n_failed == 0, s.failures
                best = min(best, (wall, sum(row["seconds"] for row in read_results(db))))
            wall, busy = best
            base = base or wall
            print(f"{w:>7} {wall:>9.2f} {busy:>13.2f} {len(jobs) / wall:>7.2f} {base / wall:>8.2f}x")
        t = time.perf_counter()
        s = run_batch(jobs, db, workers=args.workers[-1], progress=False)
        wall = time.perf_counter() - t
        print(f"resume of a finished file: {s.n_skipped} jobs skipped in {wall:.3f} s")


if __name__ == "__main__":
    main()
