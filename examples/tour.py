# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # A tour of deformclosure
#
# From a CAD drawing to a grasp you can trust: import a rubber gasket drawn in a DXF file,
# mesh it, find the best squeeze of two round pads in its notches, rank every grasp axis,
# and check a fixture of fixed fingers. Every number is SI (m, J, N).
#
# This file is a Jupyter notebook in jupytext's *percent* format: open it with Jupyter
# (with `jupytext` installed) or VS Code, or run it as a script. The test suite runs it.

# %%
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np


def _examples() -> Path:
    """The examples/ folder, wherever this runs from (the repository, examples/, a copy)."""
    here = [Path(__file__).resolve().parent] if "__file__" in globals() else []
    for d in here + [Path.cwd(), *Path.cwd().parents]:
        for e in (d, d / "examples"):
            if (e / "drawings" / "gasket.dxf").is_file():
                return e
    raise FileNotFoundError("run the tour inside the deformclosure repository (examples/ not found)")


EXAMPLES = _examples()

import deformclosure as dc
from deformclosure.part import part_from_drawing
from deformclosure.pads import GraspAxis, Pad, pad_grasp
from deformclosure.planning.pads import plan_pads
from deformclosure.plotting.mesh import plot_mesh
from deformclosure.plotting.pads import plot_pad_grasp, plot_pad_plan, plot_pad_quality

# %% [markdown]
# ## 1. The part, from a drawing
# `examples/drawings/gasket.dxf` is a 40 × 16 mm gasket with two bolt holes and a V-notch
# top and bottom, drawn in millimetres; its material (E = 2 MPa rubber) and mesh size
# sit beside it in `gasket.material.json`. Arcs are flattened on the exact curve.

# %%
part = part_from_drawing(EXAMPLES / "drawings" / "gasket.dxf", layer="OUTLINE")
print(f"{part.name}: area {part.area * 1e6:.1f} mm², {len(part.holes)} holes, "
      f"E = {part.material.youngs_modulus / 1e6:g} MPa")
mesh = dc.mesh_part(part)
print(mesh.summary())
fig, ax = plt.subplots(figsize=(7, 3))
plot_mesh(mesh, ax=ax, units="mm")
plt.show()

# %% [markdown]
# ## 2. Two round pads in the notches
# The closing axis is vertical through the notches (x = 20 mm). The pad model solves the
# frictionless contact exactly in the pad separation σ and finds σ* maximising
# Q = min(U_A, U_L): the release energy against the elastic margin.

#
# One mesh is not an answer: `rtol=0.05` refines the mesh (under the pads, at the notch
# roots, where the strain peaks) and the grid of axes until the error estimates of Q* and
# U_A are within 5 %, and only then decides "held" (a single coarse mesh says "undecided").

# %%
axis = GraspAxis.through([0.020, 0.0], [0.020, 0.016])
grasp = pad_grasp(part, axis, Pad(width=0.0, radius=0.0015), rtol=0.05)
best = grasp.finest
err = grasp.error_estimate()
print(f"verdict: {grasp.verdict}; σ0 = {best.sigma0 * 1e3:.3f} mm, "
      f"σ* = {best.sigma_star * 1e3:.3f} mm, Q* = {best.quality * 1e3:.4f} "
      f"± {err['quality'] * 1e3:.2g} mJ, grip force {best.force:.3g} N")
for level in grasp.convergence():
    print(f"  {level['nodes']:6d} nodes: σ* = {level['sigma_star'] * 1e3:.3f} mm, "
          f"Q* = {level['quality'] * 1e3:.4f} mJ")
assert grasp.verdict == "held" and grasp.converged
fig, axs = plt.subplots(1, 2, figsize=(11, 3.5))
plot_pad_grasp(best, best.solver.mesh, ax=axs[0], units="mm")
plot_pad_quality(best, ax=axs[1], units="mm")
plt.show()

# %% [markdown]
# ## 3. Every grasp axis, ranked
# `plan_pads` sweeps the grasp axes of the part on this mesh and solves the best ones
# exactly. Rows verified on one coarse mesh are "undecided" at best; the `plan` command
# (and `plan_pads(..., part=part)`) verifies them to `--rtol` as above.

# %%
plan = plan_pads(mesh, Pad(width=0.0, radius=0.0015), top=3)
for row in plan.rows[:3]:
    print(f"angle {np.degrees(row['angle']):6.1f}°, point {np.round(np.array(row['point']) * 1e3, 2)} mm,"
          f" Q = {row['quality']:.3g} J ({row['verdict']})")
fig, ax = plt.subplots(figsize=(7, 3.5))
plot_pad_plan(plan, mesh, ax=ax, units="mm", n=3)
plt.show()

# %% [markdown]
# ## 4. A fixture of fixed fingers
# Two pins in the bolt holes and a flat stop under the part: does the fixture hold it?
# The deform-closure test of SPEC §3 answers for the part at rest, with a certificate.

# %%
from deformclosure.dspace import DiscFinger, HalfPlaneFinger, deform_closure  # noqa: E402

fingers = [DiscFinger(center=[0.008, 0.008], radius=0.003),
           DiscFinger(center=[0.032, 0.008], radius=0.003),
           HalfPlaneFinger(point=[0.0, 0.0], normal=[0.0, 1.0])]
result = deform_closure(mesh, fingers)
print(f"deform closure: {result.deform_closure} (order {result.order})")

# %% [markdown]
# ## 5. A batch over a small catalogue
# `deformclosure batch` runs a command on many parts and keeps one row per job in an
# SQLite file, committed as each job finishes (a stopped run loses nothing finished and
# resumes where it stopped). Here a JSON job list over three example parts, run in this
# process (`scheduler="inline"`; the CLI uses worker processes or a Dask cluster).

# %%
import json  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402

from deformclosure.batch import format_results, load_jobs, read_results, run_batch  # noqa: E402

catalogue = Path(tempfile.mkdtemp(prefix="catalogue-"))
for name in ("notched_bar.json", "rectangle.json", "l_shape.json"):
    shutil.copy(EXAMPLES / name, catalogue / name)
readme_pads = ["--axis", "6,10,0", "--pad-radius", "1", "--pad-width", "4"]
jobs = [
    {"part": "notched_bar.json", "command": "optimize",
     "options": ["--at", "15,0", "15,12", "--pad-radius", "2"]},
    {"part": "rectangle.json", "command": "optimize", "options": readme_pads},
    {"part": "l_shape.json", "command": "plan",
     "options": ["--grid-angles", "8", "--grid-offsets", "10", "--verify", "1", "--top", "3"]},
]
(catalogue / "jobs.json").write_text(json.dumps(jobs))
summary = run_batch(load_jobs(catalogue / "jobs.json"), catalogue / "results.sqlite",
                    scheduler="inline", progress=False)
print(f"{summary.n_ok} of {summary.n_jobs} jobs ok")
print(format_results(read_results(catalogue / "results.sqlite")))
