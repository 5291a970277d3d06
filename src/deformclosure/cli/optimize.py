"""``deformclosure optimize``: optimal separation of a two-jaw grasp (SPEC §4)."""

from __future__ import annotations

import json

import click
import numpy as np

from ..errors import DeformClosureError, GraspError
from ..mesh import mesh_part, read_mesh
from ..mesh.io import is_mesh_file
from ..part import Part
from ..units import length_scale
from .common import json_safe, parse_xy, write_json

__all__ = ["command", "load_grasp_inputs"]

EPILOG = """\b
Examples:
  deformclosure optimize examples/rectangle.json --at 0,10 12,10 -o report.json --plot out/
  deformclosure optimize mesh.json --jaws 3 17 --method approx --eps 1e-6
  deformclosure optimize examples/ring.json --at 1.5,0 -1.5,0 --expanding

\b
--at coordinates and --jaw-width are in --units (default: the part file's units,
metres for mesh files); --eps is in joules. The JSON report is SI throughout.
"""


def load_grasp_inputs(path: str, at: tuple[str, ...] | None, units: str | None):
    """Read a part (meshing it with the ``--at`` points inserted) or a mesh file.

    Returns
    -------
    mesh, units (str), scale (m per unit), at_points (ndarray (k, 2) in m or None)
    """
    from pathlib import Path

    p = Path(path)
    if not p.exists():
        raise DeformClosureError(f"{path}: file not found; give a part file (.json) or a mesh file")
    mesh_file = is_mesh_file(p)
    part = None if mesh_file else Part.from_file(p)
    unit = units or ("m" if part is None else part.units)
    scale = length_scale(unit, "--units")
    pts = None
    if at:
        pts = np.array([parse_xy(s, "--at") for s in at]) * scale
    if part is None:
        mesh = read_mesh(p)
    else:
        mesh = mesh_part(part, points=pts)
    return mesh, unit, scale, pts


@click.command(epilog=EPILOG)
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("--jaws", nargs=2, type=int, default=None, metavar="A B", help="Jaw node ids.")
@click.option("--at", nargs=2, type=str, default=None, metavar="X,Y X,Y",
              help="Jaw positions (inserted as mesh nodes for part files).")
@click.option("--method", type=click.Choice(["exact", "approx", "paper"]), default="exact",
              show_default=True, help="exact: ours; paper: every crossing (reference); approx: ε-grid.")
@click.option("--eps", type=float, default=None,
              help="ε of --method approx, in joules (default 1e-3 · ½ k01 (σ0 − σ_L)², the pair squeezed "
                   "to σ_L, or larger if needed for at most 20 000 grid steps).")
@click.option("--expanding", is_flag=True, help="Jaws push outward (e.g. from inside a hole).")
@click.option("--jaw-width", type=float, default=0.0, show_default=True,
              help="Jaw contact width in --units (0 = point jaws).")
@click.option("--units", type=str, default=None, help="Unit of --at and --jaw-width (m, cm, mm, in).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="JSON report (SI units).")
@click.option("--plot", type=click.Path(file_okay=False), help="Folder for quality/deformed/landscape plots.")
@click.option("--export-graph", type=click.Path(dir_okay=False), help="Write the contact graph (JSON).")
def command(part, jaws, at, method, eps, expanding, jaw_width, units, output, plot, export_graph) -> int:
    """Optimal jaw separation σ* maximising Q = min(U_A, U_L) for one jaw pair."""
    from ..grasp.analysis import grasp_model, optimize_separation

    if (jaws is None) == (at is None):
        raise GraspError("jaws: give exactly one of --jaws A B (node ids) or --at X,Y X,Y (positions)")
    if eps is not None and not (np.isfinite(eps) and eps > 0):
        raise GraspError(f"--eps = {eps!r}: must be a finite energy > 0 in joules")
    if not (np.isfinite(jaw_width) and jaw_width >= 0):
        raise GraspError(f"--jaw-width = {jaw_width!r}: must be a finite length >= 0 (0 = point jaws)")
    mesh, unit, scale, pts = load_grasp_inputs(part, at, units)
    if pts is not None:
        n0, n1 = (mesh.find_node(p, tol=1e-6 * mesh.diameter) for p in pts)
    else:
        n0, n1 = jaws
    mode = "expanding" if expanding else "contracting"
    with click.progressbar(length=3, label="analysing", file=None, show_eta=False) as bar:
        model = grasp_model(mesh, mode=mode, jaw_width=jaw_width * scale)
        bar.update(2)
        res = optimize_separation(mesh, (n0, n1), method=method, eps=eps, mode=mode,
                                  jaw_width=jaw_width * scale, model=model)
        bar.update(1)
    report = res.to_dict()
    s = 1.0 / length_scale(unit)
    ss = res.sigma_star
    click.echo(f"jaws: nodes {n0}, {n1}  sigma0 = {res.limit.sigma0 * s:.6g} {unit}  "
               f"k01 = {res.limit.k01:.6g} N/m  e_max = {res.limit.e_max:.6g} 1/m")
    click.echo(f"sigma_L = {res.limit.sigma_L * s:.6g} {unit}")
    if ss is None:
        click.echo("this jaw pair cannot hold the part: Q = 0 on the whole range")
    else:
        ua = "infinite (no other equilibrium reachable)" if report["U_A_infinite"] else f"{report['U_A']:.6g} J"
        click.echo(f"sigma* = {ss * s:.6g} {unit}  Q* = {res.quality:.6g} J  U_A = {ua}  "
                   f"U_L = {report['U_L']:.6g} J  ({method}, {res.separation.n_evaluations} U_A evaluations)")
    if report.get("pulls"):
        click.echo("note: the jaw line leaves the part at a jaw (a jaw would have to pull); "
                   "the linear model still applies the force along the jaw line")
    write_json(report, output)
    if export_graph:
        g = model.graph.to_dict(model.stiffness.sigma0, model.stiffness.k, pulls=model.pulls)
        try:
            with open(export_graph, "w") as fh:
                json.dump(json_safe(g), fh, allow_nan=False)
        except OSError as err:
            raise DeformClosureError(f"{export_graph}: cannot write graph ({err.strerror})") from None
    if plot:
        from ..plotting.grasp import save_grasp_plots

        for pth in save_grasp_plots(res, plot, units=unit if unit != "m" else "mm"):
            click.echo(f"wrote {pth}")
    return 0
