"""``check`` with the release energy over placements (SPEC §7, issue 14).

Run:  python benchmarks/bench_check.py [--quick]

On the tapered, notched rubber bar (30 × 12 mm, V-notches 1.5 mm deep, ends 6 mm wide)
meshed to ~5 000 nodes, with four fingers — two round pads (discs, ρ = 2 mm) pressed into
the notches at σ = 7.09 mm and two discs (ρ = 2 mm) 1 mm beyond the bar's ends — it prints,
warm (compiled kernels loaded first):

* the contact-energy kernel alone: placements per second on a 20 × 20 × 12 block of the
  lattice around the equilibrium (each contact problem warm-started from the previous
  one), split into placements where fingers press and where nothing does, and the time
  per *solved* placement (placements a finger makes inadmissible cost next to nothing, so
  the block's time alone hides a change in how many are solved);
* ``deformclosure check PART --fingers F -o report.json`` end to end (meshing, the rigid
  test of SPEC §3 with its contact equilibrium, both factorisations, the release landscape
  with its twin-mesh noise floor and saddle refinement, the report), and its parts.

Target (issue 14): check with four fingers on a 5k-node part ≤ 30 s.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import deformclosure as dc
from deformclosure.dspace import PlacementEnergy, deform_closure, release_energy_fingers
from deformclosure.dspace.escape import equilibrium_placement

RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0, "elastic_limit_strain": 0.8,
          "plane": "stress"}
OUTER = [[0, 3], [12, 0], [15, 1.5], [18, 0], [30, 3], [30, 9], [18, 12], [15, 10.5], [12, 12], [0, 9]]
SIGMA, RHO = 7.09, 2.0        # mm


def part_dict(max_area: float) -> dict:
    return {"name": "tapered-notched-bar", "units": "mm", "outer": OUTER, "material": RUBBER,
            "mesh": {"max_area": max_area, "min_angle": 30}}


def fingers_dict(mesh) -> dict:
    """Two pads in the notches at σ (each pressed half the squeeze past first touch) and
    two discs 1 mm beyond the ends, in mm."""
    from deformclosure.pads.geometry import GraspAxis, Pad, first_touch

    axis = GraspAxis.through([0.015, 0.0], [0.015, 0.012])
    t = first_touch(mesh.nodes[mesh.outer_loop], axis, Pad(0.0, RHO * 1e-3))
    a = axis.direction
    za = (t.contact_a + 0.5 * (t.sigma0 - SIGMA * 1e-3) * a) * 1e3
    cA, cB = za - RHO * a, za + (SIGMA + RHO) * a
    return {"units": "mm", "fingers": [
        {"type": "disc", "center": cA.tolist(), "radius": RHO},
        {"type": "disc", "center": cB.tolist(), "radius": RHO},
        {"type": "disc", "center": [-1.0 - RHO, 6.0], "radius": RHO},
        {"type": "disc", "center": [31.0 + RHO, 6.0], "radius": RHO}]}


def timed(fn, *a, **k):
    t0 = time.perf_counter()
    out = fn(*a, **k)
    return time.perf_counter() - t0, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="~1 200 nodes instead of ~5 000")
    args = ap.parse_args()
    area = 0.2 if args.quick else 0.045
    # warm-up: load the compiled kernels (first use compiles them, ~1-2 min, then cached)
    small = dc.Part.from_dict(part_dict(2.0))
    sm = dc.mesh_part(small)
    release_energy_fingers(sm, dc.dspace.fingers_from_dict(fingers_dict(sm)), part=small, levels=1)

    part = dc.Part.from_dict(part_dict(area))
    mesh = dc.mesh_part(part)
    fingers = dc.dspace.fingers_from_dict(fingers_dict(mesh))
    print(f"part: {mesh.n_nodes} nodes, {len(mesh.perimeter_nodes)} on the boundary; 4 disc fingers")

    # ---- the kernel alone
    t_pe, pe = timed(PlacementEnergy, mesh, fingers)
    g0 = equilibrium_placement(pe, np.zeros(3), 6.4e-4, 0.042)
    h, hp = 0.25e-3, 0.01
    I, J, K = np.meshgrid(np.arange(-10, 10), np.arange(-10, 10), np.arange(-6, 6), indexing="ij")
    G = g0 + np.c_[I.ravel() * h, J.ravel() * h, K.ravel() * hp]
    t_k, (E, st) = timed(pe.energies, G)
    press = st == 1
    t_c, _ = timed(pe.energies, G[press])
    t_f, _ = timed(pe.energies, np.c_[G[:, 0], G[:, 1] + 0.05, G[:, 2]])   # far away: free
    print()
    print(f"{'contact-energy kernel':<44} {'placements':>10} {'time (s)':>9} {'per second':>11}")
    print(f"{'  lattice block around the equilibrium':<44} {len(G):>10} {t_k:>9.3f} {len(G) / t_k:>11.0f}")
    print(f"{'  of which fingers press (' + str(int(press.sum())) + ')':<44} {int(press.sum()):>10} "
          f"{t_c:>9.3f} {press.sum() / t_c:>11.0f}")
    print(f"{'  nothing presses (far away)':<44} {len(G):>10} {t_f:>9.3f} {len(G) / t_f:>11.0f}")
    solved = st == 1
    print(f"  lattice: {int(solved.sum())} solved, {int((st == 2).sum())} inadmissible; "
          f"{t_k / max(int(solved.sum()), 1) * 1e6:.1f} µs per solved placement")

    # ---- check end to end (CLI) and its parts
    from deformclosure.cli.main import main as cli

    with tempfile.TemporaryDirectory() as tmp:
        pf, ff, out = Path(tmp) / "part.json", Path(tmp) / "fingers.json", Path(tmp) / "r.json"
        pf.write_text(json.dumps(part_dict(area)))
        ff.write_text(json.dumps(fingers_dict(mesh)))
        t_cli, rc = timed(cli, ["check", str(pf), "--fingers", str(ff), "-o", str(out), "--quiet"])
        rep = json.loads(out.read_text())
    t_rig, res = timed(deform_closure, mesh, fingers)
    t_rel, rel = timed(release_energy_fingers, mesh, fingers, part=part, start=res.equilibrium,
                       rigid_closed=res.deform_closure)
    print()
    print(f"{'check (four fingers)':<44} {'time (s)':>9}")
    print(f"{'  deformclosure check ... -o report.json':<44} {t_cli:>9.2f}   (target 30 s)")
    print(f"{'  of which: rigid test (equilibrium, §3)':<44} {t_rig:>9.2f}")
    print(f"{'  of which: release energy (landscape, §7)':<44} {t_rel:>9.2f}   "
          f"({rel.n_evaluations} placements solved, kernel setup {t_pe:.1f} s)")
    ua = "inf" if rep["U_A_infinite"] else f"{rep['U_A'] * 1e3:.4f} ± {rep['U_A_error'] * 1e3:.3f} mJ"
    print(f"  report: deform_closure = {rep['deform_closure']}, U_A = {ua}, escape "
          f"{rep['escape_path']['target']}, {len(rep['escape_path']['placements'])} placements; "
          f"rigid_closure = {rep['rigid_closure']} (order {rep['order']}); exit code {rc}")


if __name__ == "__main__":
    main()
