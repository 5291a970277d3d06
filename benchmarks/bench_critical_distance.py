"""Critical-distance strain maxima: the full averaging operator vs the pruned rows (issue 25).

Run:  python benchmarks/bench_critical_distance.py [--quick]

On the notched rubber bar (30 × 12 mm, V-notches, default ℓ = 2 % of the diameter) meshed
at ~5 000, ~20 000 and ~50 000 nodes (``--quick``: ~5 000 only) it prints, side by side in
one run, seconds and peak memory of

* **limit**: one pads grasp's elastic limit from its element strains at the contact path's
  breakpoints (pads seated in the notches, closed to σ = 0) — before: the full operator
  ``averaging_operator``, every element averaged at every breakpoint, the 60-step
  bisection over every element (``first_limit_crossing``); now: ``path_elastic_limit`` on
  a fresh ``DiscAverage`` (its KD-tree and grid included);
* **stack**: the maximum averaged strain of each of 50 fields along that path (linear
  between breakpoints) — before: ``W @ E`` for the stack and a max; now
  ``DiscAverage.maxima``;

and the numbers' largest relative difference. The displacements and element strains at
the breakpoints, which both share, are computed once beforehand and not counted.

Peak memory is the rise of the process's resident high-water mark during the step
(``/proc/self/clear_refs`` resets it; elsewhere tracemalloc's peak, which misses the
KD-tree's C++ buffers). Ratios are before / now. Run with ``OPENBLAS_NUM_THREADS=1`` for
steadier times on a shared machine.

Targets: the same numbers within 1e-12 (relative), and less peak memory and time than the
full operator at every size.
"""

from __future__ import annotations

import argparse
import ctypes
import gc
import time
import tracemalloc
from pathlib import Path

import numpy as np

import deformclosure as dc
from deformclosure.elasticity.critical_distance import (DiscAverage, averaged_strain_magnitude,
                                                        averaged_strains, averaging_operator,
                                                        critical_distance_of)
from deformclosure.landscape.limit import first_limit_crossing, path_elastic_limit, strain_measure
from deformclosure.pads import GraspAxis, Pad, PadContact

AXIS = GraspAxis.through([0.015, 0.0], [0.015, 0.012])
PAD = Pad(0.0, 0.002)
#: max_area (m²) of the notched bar for about 5 000, 20 000 and 50 000 nodes
SIZES = {"~5k": 0.05e-6, "~20k": 0.0135e-6, "~50k": 0.0055e-6}
N_STACK = 50
REL = 1e-12
_PROC = Path("/proc/self")


def _rss_kb(field: str) -> int:
    for line in (_PROC / "status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise KeyError(field)


def _trim() -> None:
    """Give freed heap memory back to the system (glibc), so that a step's peak shows as
    a rise of the resident set rather than reusing what an earlier step left."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def measured(fn, *args):
    """``(seconds, peak bytes above the start, result)`` of ``fn(*args)``."""
    gc.collect()
    _trim()
    try:
        (_PROC / "clear_refs").write_text("5")           # high-water mark := current RSS
        start = _rss_kb("VmRSS")
        t0 = time.perf_counter()
        out = fn(*args)
        dt = time.perf_counter() - t0
        return dt, 1024.0 * max(_rss_kb("VmHWM") - start, 0), out
    except OSError:
        tracemalloc.start()
        t0 = time.perf_counter()
        out = fn(*args)
        dt = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        return dt, float(peak), out


def old_limit(mesh, ell, E, e_L):
    W = averaging_operator(mesh, ell)
    Ebar = averaged_strains(mesh, E, None, operator=W)
    hit = first_limit_crossing(Ebar, e_L)
    at = hit.interpolate(Ebar) if hit.reached else Ebar[-1]
    return (strain_measure(Ebar).max(axis=1), hit, int(np.argmax(strain_measure(at))), W.nnz)


def new_limit(mesh, ell, E, e_L):
    disc = DiscAverage(mesh, ell)
    lim = path_elastic_limit(disc, E, e_L)
    return lim.e_breakpoints, lim.crossing, lim.critical_element, disc.pairs_built


def old_stack(mesh, ell, S):
    W = averaging_operator(mesh, ell)
    return averaged_strain_magnitude(mesh, S, None, operator=W).max(axis=1), W.nnz


def new_stack(mesh, ell, S):
    disc = DiscAverage(mesh, ell)
    return disc.maxima(S)[0], disc.pairs_built


def rel_diff(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = np.maximum(np.abs(a), np.abs(b))
    return float(np.max(np.divide(np.abs(a - b), scale, out=np.zeros_like(a), where=scale > 0)))


def one_size(label: str, area: float) -> list[tuple]:
    part = dc.notched_part()
    mesh = dc.mesh_part(part, max_area=area)
    pc = PadContact(mesh)
    curve = pc.curve(AXIS, PAD, 0.0)
    path = curve.path
    F = np.column_stack([pc.load_vector(curve, lam) for lam in path.lam])
    E = pc.element_strains(pc.displacement(F))                        # (k, m, 3)
    e_L = mesh.material.elastic_limit_strain
    ell = critical_distance_of(mesh)
    # 50 fields along the path: linear between breakpoints in the squeeze δ
    d = np.linspace(path.delta[0], path.delta[-1], N_STACK)
    j = np.clip(np.searchsorted(path.delta, d, side="right") - 1, 0, len(path.delta) - 2)
    span = path.delta[j + 1] - path.delta[j]
    s = np.divide(d - path.delta[j], span, out=np.zeros_like(d), where=span > 0)[:, None, None]
    S = (1 - s) * E[j] + s * E[j + 1]
    head = f"{label} ({mesh.n_nodes:,} nodes, {mesh.n_triangles:,} triangles, ℓ = {ell * 1e3:.3g} mm)"
    rows = []
    tn, mn, new = measured(new_limit, mesh, ell, E, e_L)
    to, mo, old = measured(old_limit, mesh, ell, E, e_L)
    diff = max(rel_diff(new[0], old[0]),
               rel_diff(new[1].fraction, old[1].fraction) if new[1].piece == old[1].piece else 1.0)
    same_elem = new[2] == old[2]
    rows.append((head, f"limit ({len(E)} breakpoints)", to, tn, mo, mn, diff, old[3], new[3],
                 same_elem))
    tn, mn, new = measured(new_stack, mesh, ell, S)
    to, mo, old = measured(old_stack, mesh, ell, S)
    rows.append((head, f"stack of {N_STACK} fields", to, tn, mo, mn, rel_diff(new[0], old[0]),
                 old[1], new[1], True))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the ~5 000-node mesh only (< 60 s)")
    args = ap.parse_args()
    sizes = {"~5k": SIZES["~5k"]} if args.quick else SIZES
    # warm-up: imports, numba kernels of the contact path
    one_size("warm-up", 2e-6)
    rows = []
    for label, area in sizes.items():
        rows += one_size(label, area)
        r = rows[-2:]
        print(f"{r[0][0]}: done", flush=True)
    MB = 1e6
    print(f"\n{'mesh':<56} {'case':<24} {'s before':>9} {'s now':>8} {'x':>6} "
          f"{'MB before':>10} {'MB now':>8} {'x':>7} {'pairs W':>11} {'pairs now':>10} "
          f"{'rel diff':>9}")
    ok = True
    for head, case, to, tn, mo, mn, diff, nnz, pairs, same in rows:
        ok &= diff <= REL and mn < mo and tn < to
        print(f"{head:<56} {case:<24} {to:9.3f} {tn:8.3f} {to / tn:6.1f} {mo / MB:10.1f} "
              f"{mn / MB:8.1f} {mo / max(mn, 1.0):7.1f} {nnz:11,} {pairs:10,} {diff:9.1e}"
              + ("" if same else "  (critical element differs: a tie)"))
    print(f"\ntarget: numbers within {REL:g} relative, and less time and peak memory than the "
          f"full operator at every size: {'met' if ok else 'NOT met'}")


if __name__ == "__main__":
    main()
