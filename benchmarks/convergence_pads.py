"""Pads model under mesh AND landscape refinement, with the error estimates (SPEC §6).

Run:  python benchmarks/convergence_pads.py

The notched bar (30 × 12 mm, V-notches) and round pads ρ = 2 mm on the notch axis: three
meshes (h halved, landscape grid 48 × 50), then three landscape grids (doubled, on the
0.1 mm² mesh). For each sequence it prints σ*, Q*, the two-level estimate from the first
two levels and the change to the third (an estimate that brackets the finer value is
>= that change), and the three-level Richardson estimate.
"""
import time

import deformclosure as dc
from deformclosure.pads import GraspAxis, Pad, pad_grasp
from deformclosure.pads.refine import richardson
part = dc.notched_part(0.4)
ax = GraspAxis.through([0.015, 0.0], [0.015, 0.012]); pad = Pad(0.0, 0.002)
t=time.time()
r = pad_grasp(part, ax, pad, refine=3)
print("mesh levels (grid 48x50):")
for a, lv in zip(r.max_areas, r.levels):
    print(f"  {a*1e6:6.3g} mm2 {lv.n_nodes:6d} nodes  sigma* {lv.sigma_star*1e3:.4f} mm  Q* {lv.quality*1e3:.4f} mJ  U_A {lv.U_A*1e3:.4f}")
e2 = r.__class__(r.levels[:2], r.max_areas[:2]).error_estimate()
print("  2-level estimate:", {k: v for k, v in e2.items()}, " |Q3-Q2| =", abs(r.levels[2].quality-r.levels[1].quality))
print("  3-level estimate:", r.error_estimate(), r.verdict, round(time.time()-t,1), "s")
mesh = dc.mesh_part(part, max_area=0.1e-6)
print("landscape levels (mesh 0.1 mm2):")
Q=[]; S=[]
for na, no in [(24, 25), (48, 50), (96, 100)]:
    res = pad_grasp(part, ax, pad, mesh=mesh, max_area=0.1e-6, n_angles=na, n_offsets=no)
    f = res.finest; Q.append(f.quality); S.append(f.sigma_star)
    print(f"  grid {na}x{no}: sigma* {f.sigma_star*1e3:.4f} mm  Q* {f.quality*1e3:.4f} mJ  axes {f.n_axes}")
ext, err, p = richardson(Q[:2]); print("  2-level grid estimate err", err, " |Q3-Q2|", abs(Q[2]-Q[1]))
print("  3-level:", richardson(Q))
