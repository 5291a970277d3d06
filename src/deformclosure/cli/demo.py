"""``deformclosure demo``: the whole two-jaw pipeline on the built-in rubber part.

No input files: builds the 12 × 20 mm rubber part (E = 2 MPa, nu = 0.1, e_L = 0.8,
thickness 1 mm, plane stress), meshes it, assembles K, puts point jaws at the
mid-points of the long sides (12 mm apart at rest), finds σ* with the three methods
side by side, reports the quality at the paper's example separation of 10 mm, and
writes the mesh and the three grasp plots.
"""

from __future__ import annotations

import time
from pathlib import Path

import click
import numpy as np

from ..elasticity import stiffness_matrix
from ..mesh import mesh_part
from ..part import demo_part
from .common import write_json

__all__ = ["command"]


def _warm_up() -> float:
    """Compile the numba kernels on a tiny part so that the timings compare the methods,
    not the one-off compilation of a fresh install (seconds spent)."""
    from ..grasp.analysis import grasp_model, optimize_separation
    from ..part import Part

    t0 = time.perf_counter()
    part = Part.from_dict({"name": "warm-up", "units": "mm", "outer": [[0, 0], [4, 0], [4, 6], [0, 6]],
                           "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
                                        "elastic_limit_strain": 0.8},
                           "mesh": {"max_area": 4.0, "points": [[0, 3], [4, 3]]}})
    mesh = mesh_part(part)
    model = grasp_model(mesh)
    jaws = (mesh.find_node([0.0, 0.003]), mesh.find_node([0.004, 0.003]))
    for method in ("exact", "paper", "approx"):
        optimize_separation(mesh, jaws, method=method, model=model)
    return time.perf_counter() - t0


@click.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="deformclosure-demo",
              show_default=True, help="Folder for the pictures and the JSON report.")
@click.option("--eps", type=float, default=1e-6, show_default=True,
              help="ε (J) of the approximate method.")
def command(out_dir: str, eps: float) -> int:
    """Run the whole pipeline on the built-in 12 × 20 mm rubber part (no input files)."""
    from ..grasp.analysis import grasp_model, optimize_separation
    from ..grasp.separation import quality_at
    from ..plotting.grasp import save_grasp_plots
    from ..plotting.mesh import save_mesh_plot

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    part = demo_part()
    mat = part.material
    click.echo(f"part: {part.name}, 12 x 20 mm rubber, E = {mat.youngs_modulus / 1e6:g} MPa, "
               f"nu = {mat.poisson_ratio:g}, thickness = {mat.thickness * 1e3:g} mm, "
               f"e_L = {mat.elastic_limit_strain:g}, plane {mat.plane}")
    t0 = time.perf_counter()
    mesh = mesh_part(part)
    K = stiffness_matrix(mesh)
    click.echo(f"mesh: {mesh.summary()} ({time.perf_counter() - t0:.3f} s with K)")
    save_mesh_plot(mesh, out / "mesh.png", units=part.units)
    n0 = mesh.find_node([0.0, 0.010])
    n1 = mesh.find_node([0.012, 0.010])
    t0 = time.perf_counter()
    model = grasp_model(mesh, K)
    t_model = time.perf_counter() - t0
    click.echo(f"contact graph: {model.graph.n_vertices} vertices, {model.graph.n_edges} edges; "
               f"all pair stiffnesses and graph in {t_model:.3f} s")
    t_warm = _warm_up()
    rows = []
    results = {}
    for method in ("exact", "paper", "approx"):
        t0 = time.perf_counter()
        res = optimize_separation(mesh, (n0, n1), method=method, eps=eps if method == "approx" else None,
                                  K=K, model=model)
        dt = time.perf_counter() - t0
        results[method] = res
        ss = res.sigma_star
        rows.append((method, "-" if ss is None else f"{ss * 1e3:.6f}", f"{res.quality * 1e3:.6f}",
                     f"{res.separation.n_evaluations}", f"{dt:.3f}"))
    lim = results["exact"].limit
    click.echo(f"jaws: nodes {n0} (0, 10) mm and {n1} (12, 10) mm; sigma0 = {lim.sigma0 * 1e3:g} mm, "
               f"k01 = {lim.k01:.6g} N/m, e_max = {lim.e_max:.6g} 1/m, sigma_L = {lim.sigma_L * 1e3:.6f} mm")
    click.echo(f"(compiled kernels warmed up on a tiny part in {t_warm:.2f} s, not counted below)")
    click.echo(f"{'method':<8} {'sigma* (mm)':>12} {'Q* (mJ)':>12} {'U_A evals':>10} {'time (s)':>9}")
    for r in rows:
        click.echo(f"{r[0]:<8} {r[1]:>12} {r[2]:>12} {r[3]:>10} {r[4]:>9}")
    ex = results["exact"]
    q10, ua10, ul10 = quality_at(np.array([0.010]), model.stiffness.sigma0, model.stiffness.k,
                                 model.graph, model.graph.vertex_index(n0, n1), lim.sigma_L, "contracting")
    click.echo(f"at the paper's example separation sigma = 10 mm: Q = {float(q10[0]) * 1e3:.6f} mJ "
               f"(U_A = {float(ua10[0]) * 1e3:.6f} mJ, U_L = {float(ul10[0]) * 1e3:.6f} mJ)")
    report = ex.to_dict()
    report["comparison"] = {m: {"sigma_star": r.sigma_star, "quality": r.quality,
                                "n_evaluations": r.separation.n_evaluations}
                            for m, r in results.items()}
    write_json(report, out / "report.json")
    for pth in [out / "mesh.png", *save_grasp_plots(ex, out, units="mm"), out / "report.json"]:
        click.echo(f"wrote {pth}")
    return 0
