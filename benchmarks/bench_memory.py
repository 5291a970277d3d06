"""Memory estimates against measured peak memory: ``optimize``, ``plan`` and ``check`` (issue 25).

Run:  python benchmarks/bench_memory.py [--nodes 2500 5000 10000 20000] [--only CMD ...]
      [--phases] [--quick]

Each command runs in a fresh interpreter (``reports.run``, the library call of the CLI)
meshed to about the given number of nodes (``--max-area``):

* the notched bar (held by pads in its notches), ``optimize --axis 15,6,90 --pad-radius 2
  --refine 1`` (one mesh and its noise-floor twin), the same at the default accuracy
  (levels until ``--rtol 0.05``), and ``plan --pad-radius 2 --verify 1`` (the default
  36 × 40 grid; one candidate verified with optimize's code path);
* the README rectangle, ``check --fingers examples/fingers/rectangle.json --refine 1``.

The estimate is the largest total that the command's own size checks computed
(:func:`deformclosure.limits.check_plan_size`, recorded in the child); the peak is the
child's ``ru_maxrss`` (``os.wait4``), imports included. The table prints both, their
ratio and whether the estimate bounds the peak within +25 % (target: ``1 <= est/peak <=
1.25``, issue 25; ``est/peak < 1`` would accept what may not fit, larger would refuse what fits).
``--phases`` also prints, per command, the resident memory at each logged step.
``--quick``: 2 500 and 5 000 nodes only.

Measured (issue 25, after the refit, the elastic limit's groups, the condensing transient
and the saddle patches; 2 cores shared, one BLAS thread; ``--nodes 2500 20000``):

    command                  nodes  est (GB)  peak (GB)  est/peak
    optimize --refine 1      2,573     0.290      0.257      1.13
    optimize --refine 1     20,015     0.773      0.679      1.14
    optimize (rtol)          3,519     0.405      0.367      1.10
    optimize (rtol)         20,621     1.117      0.965      1.16
    plan --verify 1          3,656     0.589      0.477      1.23
    plan --verify 1         20,637     1.780      1.458      1.22
    check --refine 1         2,550     0.289      0.261      1.11
    check --refine 1        19,939     0.579      0.543      1.06

The estimate never fell below the peak; it is 6-23 % above it (the sweep gave 16-44 %
before the solver's build was counted as a transient, check stopped counting the path
limit's fields and the levels counted one solver each). Deeper ``--rtol`` levels (beyond
this sweep: the notched bar to ``--rtol 0.005``, levels 3-5 at 3 300-13 300 nodes) search
the saddle patches: 449-3 187 axes, once estimated as 600 (level 5: 1.13 GB estimated,
1.44 GB used); counted now (``size_limits.level_axes``), 2.06 GB estimated.

Before the refit the same sweep gave est/peak 1.60-1.86 (optimize --refine 1), 0.69-0.89
(plan: its verification's levels were checked as if the plan held nothing) and
0.88-2.04 (check). Extrapolated with the refitted costs to the notched bar at 85 000
nodes: optimize 2.5 GB for one level and 4.4 GB for two (the issue measured 4.8 GB used
by such a run; the second level is now refused and the run stops at the first, with its
reason), a plan 2.8 GB screening and 4.8 GB for its first verification (refused up front;
it used more than 5.5 GB), check 2.2 GB (accepted; 2.05 GB measured, formerly refused at
an estimated 4.8 GB).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
RECT_AREA_MM2 = 240.0
BAR_AREA_MM2 = 360.0 - 2 * 9.0
#: Triangles per (area / max_area) of Triangle at min_angle 30 on this part (measured).
PER_AREA = 1.6

CHILD = r"""
import json, logging, os, sys, threading, time
import deformclosure.pads.size_limits as psl
from deformclosure import reports

cmd, part, params, phases = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), sys.argv[4] == "1"
seen = []
orig = psl.check_plan_size


def recorded(*a, **k):
    est = orig(*a, **k)
    seen.append({"args": [int(a[0])], "n_nodes": k.get("n_nodes"), "solvers": k.get("solvers"),
                 "n_axes": k.get("n_axes"), **{x: float(v) for x, v in est.items()}})
    return est


psl.check_plan_size = recorded
page = os.sysconf("SC_PAGE_SIZE")
steps, peak = [], [0]


def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * page


def sample():
    while True:
        peak[0] = max(peak[0], rss())
        time.sleep(0.01)


class Steps(logging.Handler):
    def emit(self, record):
        steps.append((record.getMessage()[:90], rss() / 1e9, peak[0] / 1e9))
        peak[0] = 0


if phases:
    threading.Thread(target=sample, daemon=True).start()
    lg = logging.getLogger("deformclosure")
    lg.addHandler(Steps())
    lg.setLevel(logging.INFO)
t = time.perf_counter()
rep = reports.run(cmd, part, params)
out = {"seconds": time.perf_counter() - t, "estimates": seen, "steps": steps,
       "nodes": max([s["n_nodes"] for s in seen] or [0])}
print("RESULT " + json.dumps(out))
"""


def commands(folder: Path) -> dict[str, tuple[str, str, float, dict]]:
    """(command, part file, part area in mm², parameters) by name."""
    bar = folder / "notched_bar.json"
    bar.write_text((EXAMPLES / "notched_bar.json").read_text())
    rect = folder / "rectangle.json"
    rect.write_text((EXAMPLES / "rectangle.json").read_text())
    fingers = folder / "fingers.json"
    fingers.write_text((EXAMPLES / "fingers" / "rectangle.json").read_text())
    axis = {"axis": "15,6,90", "pad_radius": 2.0}
    return {
        "optimize --refine 1": ("optimize", str(bar), BAR_AREA_MM2, {**axis, "refine": 1}),
        "optimize (rtol)": ("optimize", str(bar), BAR_AREA_MM2, dict(axis)),
        "plan --verify 1": ("plan", str(bar), BAR_AREA_MM2, {"pad_radius": 2.0, "verify": 1}),
        "check --refine 1": ("check", str(rect), RECT_AREA_MM2,
                             {"fingers": str(fingers), "refine": 1}),
    }


def run_child(cmd: str, part: str, params: dict, phases: bool) -> tuple[float, dict]:
    """Run the child, reaping it with ``os.wait4`` for its own peak RSS."""
    proc = subprocess.Popen([sys.executable, "-c", CHILD, cmd, part, json.dumps(params),
                             "1" if phases else "0"], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    text = out.decode(errors="replace")
    if proc.returncode != 0:
        raise RuntimeError(text.strip().splitlines()[-1])
    line = [ln for ln in text.splitlines() if ln.startswith("RESULT ")][-1]
    return usage.ru_maxrss * 1024.0, json.loads(line[7:])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, nargs="+", default=[2500, 5000, 10000, 20000])
    ap.add_argument("--only", nargs="*", default=None, help="run only these commands "
                    "(optimize --refine 1, optimize (rtol), plan --verify 1, check --refine 1)")
    ap.add_argument("--phases", action="store_true", help="resident memory at each logged step")
    ap.add_argument("--quick", action="store_true", help="2 500 and 5 000 nodes only")
    args = ap.parse_args()
    if args.quick:
        args.nodes = [n for n in args.nodes if n <= 5000] or [2500]
    folder = Path(tempfile.mkdtemp(prefix="bench_memory_"))
    unknown = set(args.only or ()) - set(commands(folder))
    if unknown:
        ap.error(f"--only {sorted(unknown)}: not a command of this benchmark; choose from "
                 f"{sorted(commands(folder))}")
    print(f"{'command':<22} {'nodes':>7} {'est (GB)':>9} {'peak (GB)':>10} {'est/peak':>9} "
          f"{'time (s)':>9}  within +25 %", flush=True)
    all_met = True
    for name, (cmd, part, area, params) in commands(folder).items():
        if args.only and name not in args.only:
            continue
        for n in args.nodes:
            ma = area * PER_AREA / (2.0 * n)
            try:
                peak, res = run_child(cmd, part, {**params, "max_area": ma}, args.phases)
            except RuntimeError as err:
                print(f"{name:<22} {n:>7,} failed: {err}", flush=True)
                all_met = False
                continue
            est = max((e["total"] for e in res["estimates"]), default=float("nan"))
            r = est / peak
            ok = 1.0 <= r <= 1.25
            all_met &= ok
            print(f"{name:<22} {res['nodes']:>7,} {est / 1e9:>9.3f} {peak / 1e9:>10.3f} {r:>9.2f} "
                  f"{res['seconds']:>9.1f}  {'yes' if ok else 'NO'}", flush=True)
            if args.phases:
                big = max(res["estimates"], key=lambda e: e["total"])
                print("    estimate parts (GB): " + ", ".join(
                    f"{k} {v / 1e9:.3f}" for k, v in big.items()
                    if k not in ("args", "n_nodes", "solvers", "n_axes", "total") and v), flush=True)
                for msg, now, top in res["steps"]:
                    print(f"    {now:6.3f} GB (peak since last {top:6.3f})  {msg}", flush=True)
    print(f"target (every estimate within +25 % above the measured peak): "
          f"{'met' if all_met else 'NOT met'}")


if __name__ == "__main__":
    main()
