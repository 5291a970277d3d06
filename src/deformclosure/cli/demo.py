"""``deformclosure demo``: what a frictionless gripper can and cannot hold (no input files).

Two built-in rubber parts (E = 2 MPa, nu = 0.1, e_L = 0.8, thickness 1 mm, plane stress)
between rigid round pads (SPEC §6), each solved on three meshes (h halving) with error
estimates and a verdict:

1. a 30 × 12 mm bar with a V-notch in each long side, pads (ρ = 2 mm) seated in the
   notches: held, and the answer converges;
2. the paper's 12 × 20 mm block, pads (ρ = 1 mm) across its width: not held — a convex
   part between frictionless pads slides out sideways.

Then the paper's own model (point jaws at mesh nodes, SPEC §4) on the block, whose
"optimal" quality falls with every refinement: why the pads are the default model.
"""

from __future__ import annotations

import time
from pathlib import Path

import click
import numpy as np

from ..mesh import mesh_part
from ..part import demo_part, notched_part
from .common import write_json

__all__ = ["command"]


def _table(res, unit_area: float = 1e-6) -> list[str]:
    lines = [f"  {'max_area (mm^2)':>15} {'nodes':>7} {'sigma* (mm)':>12} {'Q* (mJ)':>10} {'U_A (mJ)':>10}"]
    for r, a in zip(res.levels, res.max_areas):
        ss = "-" if r.sigma_star is None else f"{r.sigma_star * 1e3:.4f}"
        ua = "inf" if np.isinf(r.U_A) else f"{r.U_A * 1e3:.4f}"
        lines.append(f"  {a / unit_area:>15.4g} {r.n_nodes:>7} {ss:>12} {r.quality * 1e3:>10.4f} {ua:>10}")
    return lines


def _summary(res) -> str:
    fine, err = res.finest, res.error_estimate()
    if fine.sigma_star is None:
        return (f"  verdict: {res.verdict.upper()} — no release barrier above the noise floor "
                f"({fine.noise_relative:.2%} of U) at any separation")
    es = "" if err["sigma_star"] is None else f" ± {err['sigma_star'] * 1e3:.3g}"
    return (f"  verdict: {res.verdict.upper()} — sigma* = {fine.sigma_star * 1e3:.4f}{es} mm, "
            f"Q* = {fine.quality * 1e3:.4f} ± {err['quality'] * 1e3:.2g} mJ (Richardson)")


@click.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="deformclosure-demo",
              show_default=True, help="Folder for the pictures and the JSON report.")
def command(out_dir: str) -> int:
    """Notched bar held by round pads, block not held; the paper's model for contrast."""
    from ..grasp.analysis import optimize_separation
    from ..pads import GraspAxis, Pad, pad_grasp
    from ..plotting.mesh import save_figure
    from ..plotting.pads import plot_pad_grasp, plot_pad_quality

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    report = {}
    cases = [
        ("notched_bar", notched_part(0.4), GraspAxis.through([0.015, 0.0], [0.015, 0.012]),
         Pad(0.0, 0.002), "30 x 12 mm bar, 3 mm V-notches; round pads rho = 2 mm in the notches"),
        ("block", demo_part(1.0), GraspAxis.through([0.0, 0.010], [0.012, 0.010]),
         Pad(0.0, 0.001), "12 x 20 mm block (the paper's example); round pads rho = 1 mm across it"),
    ]
    results = {}
    for i, (key, part, axis, pad, text) in enumerate(cases, 1):
        mat = part.material
        click.echo(f"{i}) {text}")
        click.echo(f"   rubber E = {mat.youngs_modulus / 1e6:g} MPa, nu = {mat.poisson_ratio:g}, "
                   f"e_L = {mat.elastic_limit_strain:g}, thickness {mat.thickness * 1e3:g} mm; "
                   "frictionless rigid pads (SPEC §6)")
        click.echo(f"   mesh: {mesh_part(part).summary()}; then h halved twice")
        t0 = time.perf_counter()
        res = pad_grasp(part, axis, pad, refine=3)
        results[key] = res
        for line in _table(res):
            click.echo(line)
        click.echo(_summary(res) + f"   [{time.perf_counter() - t0:.1f} s]")
        report[key] = res.to_dict()
    # The paper's model on the block: point jaws at the mid-points of the long sides.
    click.echo("3) the paper's model on the same block (point jaws at mesh nodes, --model paper):")
    click.echo(f"  {'max_area (mm^2)':>15} {'nodes':>7} {'sigma* (mm)':>12} {'Q* (mJ)':>10}")
    paper_rows = []
    for area in (1.0, 0.25, 0.0625):
        mesh = mesh_part(demo_part(area))
        jaws = (mesh.find_node([0.0, 0.010]), mesh.find_node([0.012, 0.010]))
        r = optimize_separation(mesh, jaws, method="exact")
        ss = "-" if r.sigma_star is None else f"{r.sigma_star * 1e3:.4f}"
        click.echo(f"  {area:>15.4g} {mesh.n_nodes:>7} {ss:>12} {r.quality * 1e3:>10.5f}")
        paper_rows.append({"max_area": area * 1e-6, "nodes": mesh.n_nodes,
                           "sigma_star": r.sigma_star, "quality": r.quality})
    click.echo("  a point force in 2-D has no finite stiffness: these numbers follow the mesh, not "
               "the part (docs/pads.md)")
    report["paper_block"] = {"model": "paper", "convergence": paper_rows,
                             "units": {"length": "m", "energy": "J"}}
    write_json(report, out / "report.json")
    from ..plotting.mesh import save_mesh_plot

    save_mesh_plot(mesh_part(cases[0][1]), out / "mesh.png", units="mm")
    fig_paths = [out / "mesh.png"]
    for key in ("notched_bar", "block"):
        fine = results[key].finest
        mesh = mesh_part(cases[0][1] if key == "notched_bar" else cases[1][1])
        save_figure(plot_pad_grasp(fine, mesh, units="mm"), out / f"{key}.png")
        save_figure(plot_pad_quality(fine, units="mm"), out / f"{key}_quality.png")
        fig_paths += [out / f"{key}.png", out / f"{key}_quality.png"]
    for pth in [*fig_paths, out / "report.json"]:
        click.echo(f"wrote {pth}")
    return 0
