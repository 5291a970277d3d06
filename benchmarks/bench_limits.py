"""Every documented maximum of :mod:`deformclosure.limits` runs within 4 GB.

Run:  python benchmarks/bench_limits.py [--only NAME ...] [--keep DIR]

Each case runs one ``deformclosure`` command in a fresh interpreter on an input built at
(or just under) one documented maximum, and prints its peak resident memory (the child's
``ru_maxrss`` from ``os.wait4``) and wall time as a table; a last column says whether it
stayed within :data:`~deformclosure.limits.MEMORY_BUDGET`. The inputs:

* ``mesh``: a 12 × 20 mm block with the max_area estimated at 97 % of MAX_TRIANGLES;
  a thin strip whose narrow feature needs 97 % of MAX_THIN_ELEMENTS boundary elements;
  MAX_MESH_POINTS inserted points (a tenth on the ring of a 6000-vertex circle).
* ``plan`` / ``optimize --model paper``: a circle with MAX_BOUNDARY_NODES_PAPER vertices
  (the jaw nodes), meshed with the default max_area (plan with ``--top 0``: the exact
  refinement's time depends on the pairs, not on the limits; optimize with
  ``--method approx``).
* ``plan`` (screening, ``--verify 0``) / ``optimize`` (pads) and ``check``: a circle with
  MAX_BOUNDARY_NODES_PADS vertices; ``optimize`` on a block meshed so that the
  critical-distance averaging has 97 % of MAX_AVERAGING_NONZEROS element pairs, and on
  the largest block (small critical distance) the memory estimate accepts — the
  factorisation's share.
* ``slice``: MAX_SLICE_RESOLUTION pixels per axis, four fingers, ``-o`` JSON.

The machine's other load slows the times down; the memory is what the limits promise.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from deformclosure import limits
from deformclosure.pads.size_limits import WITH_TWIN, search_axes

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
       "elastic_limit_strain": 0.8, "plane": "stress"}


def write(folder: Path, name: str, data: dict) -> str:
    path = folder / name
    path.write_text(json.dumps({"units": "mm", "material": MAT, **data}))
    return str(path)


def circle(k: int, r: float = 10.0) -> list:
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    return np.column_stack([r * np.cos(t), r * np.sin(t)]).round(12).tolist()


def largest_pads_block(solvers: float, ell_mm: float, n_axes: int = search_axes(48, 50)) -> int:
    """Most triangles of a 12 x 20 mm block (critical distance ``ell_mm``) the pads
    estimate of ``optimize`` (default grid) accepts."""
    lo, hi = 1000, limits.MAX_TRIANGLES
    while lo < hi:
        m = (lo + hi + 1) // 2
        est = limits.estimate_model_bytes("pads", n_nodes=m // 2, n_triangles=m,
                                          n_boundary=int(2.5 * math.sqrt(m)), area=240e-6,
                                          ell=ell_mm * 1e-3, solvers=solvers, n_axes=n_axes)
        ok = est["total"] <= limits.MEMORY_BUDGET and \
            limits._averaging_nonzeros(m, 240e-6, ell_mm * 1e-3) <= limits.MAX_AVERAGING_NONZEROS
        lo, hi = (m, hi) if ok else (lo, m - 1)
    return lo


def cases(folder: Path) -> list[tuple[str, str, list[str]]]:
    """(name, what is at its maximum, command line) of every case."""
    out = []
    block = [[0, 0], [12, 0], [12, 20], [0, 20]]
    per_area = float(np.interp(30.0, limits._ANGLES, limits._PER_AREA))
    ma = 240.0 * per_area / (0.97 * limits.MAX_TRIANGLES)
    f = write(folder, "block_max.json", {"outer": block, "mesh": {"max_area": ma}})
    out.append(("mesh-triangles", f"~{0.97 * limits.MAX_TRIANGLES:,.0f} triangles (est.)",
                ["mesh", f, "-o", str(folder / "block_max_mesh.json")]))

    L = 10.0
    w = 2 * L / (0.97 * limits.MAX_THIN_ELEMENTS)
    f = write(folder, "strip.json", {"outer": [[0, 0], [L, 0], [L, w], [0, w]]})
    out.append(("mesh-thin", f"{L:g} x {w:.3g} mm strip, {0.97 * limits.MAX_THIN_ELEMENTS:,.0f} "
                "thin elements", ["mesh", f]))

    rng = np.random.default_rng(0)
    ring = np.array(circle(6_000))
    npts = limits.MAX_MESH_POINTS
    n_on = npts // 10
    e = rng.choice(len(ring), n_on, replace=False)        # mid-points of distinct edges
    on = 0.5 * (ring[e] + np.roll(ring, -1, 0)[e])
    r = 9.5 * np.sqrt(rng.uniform(0, 1, npts - n_on))
    t = rng.uniform(0, 2 * np.pi, npts - n_on)
    inner = np.column_stack([r * np.cos(t), r * np.sin(t)])
    f = write(folder, "points.json", {"outer": ring.tolist(), "mesh": {
        "points": np.concatenate([on, inner]).round(12).tolist()}})
    out.append(("mesh-points", f"{npts:,} mesh.points, {n_on:,} on a 6,000-vertex ring",
                ["mesh", f, "-o", str(folder / "points_mesh.json")]))

    P = limits.MAX_BOUNDARY_NODES_PAPER
    f = write(folder, "circle_paper.json", {"outer": circle(P)})
    out.append(("plan-paper", f"{P:,} jaw nodes (circle)",
                ["plan", f, "--model", "paper", "--top", "0", "--quiet"]))
    out.append(("optimize-paper", f"{P:,} jaw nodes (circle), approx",
                ["optimize", f, "--model", "paper", "--jaws", "0", str(P // 2), "--method",
                 "approx"]))

    p_plan = limits.MAX_BOUNDARY_NODES_PADS
    f = write(folder, "circle_pads.json", {"outer": circle(p_plan)})
    # screening only: verifying beside the plan's solvers and curves needs about 5 GB at
    # this boundary (refused up front by the estimate); the verification is optimize's
    # code path, whose own case follows
    out.append(("plan-pads", f"{p_plan:,} boundary nodes (circle), twin, --verify 0",
                ["plan", f, "--top", "1", "--verify", "0", "--quiet"]))
    out.append(("optimize-pads", f"{p_plan:,} boundary nodes (circle), twin",
                ["optimize", f, "--at", "-10,0", "10,0", "--quiet"]))
    p_check = limits.MAX_BOUNDARY_NODES_PADS
    f = write(folder, "circle_check.json", {"outer": circle(p_check)})
    fingers = folder / "fingers_check.json"
    fingers.write_text(json.dumps({"units": "mm", "fingers": [
        {"type": "point", "at": [-10, 0]}, {"type": "point", "at": [10, 0]},
        {"type": "point", "at": [0, 10]}]}))
    out.append(("check", f"{p_check:,} boundary nodes (circle), twin",
                ["check", f, "--fingers", str(fingers)]))

    # averaging: nnz ≈ m + m² π ℓ² / A; a critical distance of 4 mm puts 97 % of the
    # maximum (4e8 pairs since the averages are pruned, issue 25) on ~43 000 triangles, a
    # mesh small enough for the rest (solver, twin) to fit and to run in minutes
    ell = 4.0
    m = math.sqrt(0.97 * limits.MAX_AVERAGING_NONZEROS * 240.0 / (math.pi * ell ** 2))
    f = write(folder, "block_avg.json", {"outer": block, "mesh": {"max_area": 240.0 * 1.59 / m}})
    data = json.loads(Path(f).read_text())
    data["material"] = {**MAT, "critical_distance": ell}
    Path(f).write_text(json.dumps(data))
    out.append(("optimize-pads-avg", f"~{0.97 * limits.MAX_AVERAGING_NONZEROS:.2g} averaging pairs "
                f"(l = {ell:g} mm), twin", ["optimize", f, "--axis", "6,10,0", "--quiet"]))

    # the factorisation: the largest block the pads estimate accepts (small critical
    # distance), less 15 %: the mesher's count and the nodes per triangle (n ≈ m/2 + p/2)
    # are estimates too, and a mesh just above the line is refused
    m = int(0.85 * largest_pads_block(WITH_TWIN, 0.05))
    f = write(folder, "block_fact.json", {"outer": block, "mesh": {"max_area": 240.0 * 1.59 / m}})
    data = json.loads(Path(f).read_text())
    data["material"] = {**MAT, "critical_distance": 0.05}
    Path(f).write_text(json.dumps(data))
    out.append(("optimize-pads-fact", f"~{m:,} triangles (largest block accepted), twin",
                ["optimize", f, "--axis", "6,10,0", "--quiet"]))

    R = limits.MAX_SLICE_RESOLUTION
    fingers = folder / "fingers_slice.json"
    fingers.write_text(json.dumps({"units": "mm", "fingers": [
        {"type": "point", "at": [0.5, 10]}, {"type": "disc", "center": [-1, 10], "radius": 0.5},
        {"type": "halfplane", "point": [0, 0], "normal": [0, 1]},
        {"type": "polygon", "vertices": [[-2, 11], [-1, 11], [-1, 12]]}]}))
    out.append(("slice", f"{R:,} x {R:,} pixels, 4 fingers, JSON",
                ["slice", str(Path(__file__).resolve().parents[1] / "examples" / "rectangle.json"),
                 "--at", "0,10", "--fingers", str(fingers), "--resolution", str(R),
                 "--extent", "-2,2,8,12", "-o", str(folder / "slice.json")]))
    return out


def run(argv: list[str]) -> tuple[int, float, float, str]:
    """Run ``deformclosure argv`` in a child; exit code, peak RSS (bytes), seconds, last line."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "deformclosure", *argv],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    took = time.perf_counter() - t0
    lines = [ln for ln in out.decode(errors="replace").splitlines() if ln.strip()]
    return proc.returncode, usage.ru_maxrss * 1024.0, took, (lines[-1] if lines else "")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None, help="run only these cases")
    ap.add_argument("--keep", default=None, help="write the inputs and outputs here")
    args = ap.parse_args()
    folder = Path(args.keep or tempfile.mkdtemp(prefix="bench_limits_"))
    folder.mkdir(parents=True, exist_ok=True)
    budget = limits.MEMORY_BUDGET
    print(f"memory budget {budget / 1e9:.0f} GB; inputs in {folder}", flush=True)
    print(f"{'case':<18} {'at the maximum':<46} {'rc':>3} {'peak RSS':>9} {'time':>8}  ok", flush=True)
    for name, what, argv in cases(folder):
        if args.only and name not in args.only:
            continue
        rc, rss, took, last = run(argv)
        ok = "yes" if rc == 0 and rss <= budget else "NO"
        print(f"{name:<18} {what:<46} {rc:>3} {rss / 1e9:>7.2f}GB {took:>7.0f}s  {ok}", flush=True)
        if rc != 0:
            print(f"    {last[:150]}", flush=True)


if __name__ == "__main__":
    main()
