"""``deformclosure optimize``: optimal separation of a two-jaw grasp (SPEC §4)."""

from __future__ import annotations

import json

import click
import numpy as np

from ..errors import DeformClosureError, GraspError
from ..limits import check_model_size, limits_help
from ..mesh import mesh_part
from ..mesh.io import is_mesh_file
from ..part import PartError
from ..units import length_scale
from ..outputs import check_outputs, write_text_atomic
from .common import json_safe, mesh_input_options, pad_options, parse_xy, write_json

__all__ = ["command", "load_grasp_inputs"]

EPILOG = """\b
Examples (pads, the default model, SPEC §6):
  deformclosure optimize examples/notched_bar.json --at 15,0 15,12 --pad-radius 2 -o report.json --plot out/
  deformclosure optimize examples/rectangle.json --axis 6,10,0 --pad-radius 1 --pad-width 4 --refine 3
\b
Paper model (point jaws at mesh nodes, SPEC §4, for reproduction):
  deformclosure optimize examples/rectangle.json --model paper --at 0,10 12,10 -o report.json
  deformclosure optimize mesh.json --model paper --jaws 3 17 --method approx --eps 1e-6
  deformclosure optimize examples/ring.json --model paper --at 1.5,0 -1.5,0 --expanding

\b
Lengths given here (--at, --axis, --pad-radius, --pad-width, --jaw-width) are in --units
(default: the part file's units, metres for mesh files); --eps is in joules. The JSON
report is SI throughout and says which model made it.
"""


def load_grasp_inputs(path: str, at: tuple[str, ...] | None, units: str | None,
                      material: str | None = None):
    """Read a part (meshing it with the ``--at`` points inserted) or a mesh file.

    Returns
    -------
    mesh, units (str), scale (m per unit), at_points (ndarray (k, 2) in m or None)
    """
    from pathlib import Path

    from .common import load_part_or_mesh, read_part

    p = Path(path)
    if not p.exists():
        raise DeformClosureError(f"{path}: file not found; give a part file (.json) or a mesh file")
    part = None if is_mesh_file(p) else read_part(p, units, material)
    unit = units if units is not None else ("m" if part is None else part.units)
    scale = length_scale(unit, "--units")
    pts = None
    if at:
        pts = np.array([parse_xy(s, "--at") for s in at]) * scale
    if part is None:
        return load_part_or_mesh(p, units=units, material=material)[1], unit, scale, pts
    far = 100 * part.diameter + float(np.abs(part.outer).max())
    if pts is not None and np.abs(pts).max() > far:
        raise GraspError(f"--at: a jaw position is far outside the part ({', '.join(at)} "
                         f"{unit}); check the values and --units")
    try:
        mesh = mesh_part(part, points=pts)
    except PartError as err:   # name the option, not the mesher's internal point list
        if "points[" not in str(err):
            raise
        raise GraspError(f"--at: a jaw position lies outside the part "
                         f"({', '.join(at)} {unit}); move it onto the part's boundary") from None
    return mesh, unit, scale, pts


@click.command(epilog=EPILOG + limits_help("optimize"))
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("--model", type=click.Choice(["pads", "paper"]), default=None,
              help="pads (default): rigid pads on a grasp axis, converged (SPEC §6); "
                   "paper: point jaws at mesh nodes (SPEC §4). --jaws implies paper.")
@click.option("--jaws", nargs=2, type=int, default=None, metavar="A B",
              help="Jaw node ids (paper model).")
@click.option("--at", nargs=2, type=str, default=None, metavar="X,Y X,Y",
              help="pads: the closing axis through these points; paper: jaw positions "
                   "(inserted as mesh nodes for part files).")
@click.option("--axis", type=str, default=None, metavar="X,Y,DEG",
              help="pads: the closing axis through (X, Y) at DEG degrees.")
@pad_options(angles=48, offsets=50)
@click.option("--refine", type=int, default=1, show_default=True,
              help="pads: solve on N meshes (h halving); report error estimates and a verdict.")
@click.option("--method", type=click.Choice(["exact", "approx", "paper"]), default="exact",
              show_default=True, help="paper model: exact: ours; paper: every crossing; approx: ε-grid.")
@click.option("--eps", type=float, default=None,
              help="paper model, --method approx: ε in joules (default 1e-3 · ½ k01 (σ0 − σ_L)², "
                   "or larger if needed for at most 20 000 grid steps).")
@click.option("--expanding", is_flag=True,
              help="Jaws push outward from inside a hole (pads: the hole holding the --at "
                   "mid-point or the --axis point).")
@click.option("--jaw-width", type=float, default=0.0, show_default=True,
              help="paper model: jaw contact width (0 = point jaws).")
@mesh_input_options()
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="JSON report (SI units).")
@click.option("--plot", type=click.Path(file_okay=False), help="Folder for the plots.")
@click.option("--export-graph", type=click.Path(dir_okay=False),
              help="paper model: write the contact graph (JSON).")
@click.option("--export-fields", type=click.Path(dir_okay=False), default=None,
              help="Write the fields at σ* to FILE.vtu (and at σ_L to FILE_sigma_L.vtu) for "
                   "ParaView: deformed mesh, displacement, strain, contact pressure.")
@click.option("--quiet", is_flag=True, help="No progress output.")
def command(part, model, jaws, at, axis, pad_radius, pad_width, refine, grid_angles, grid_offsets,
            method, eps, expanding, jaw_width, material, units, output, plot, export_graph,
            export_fields, quiet) -> int:
    """Optimal separation σ* maximising Q = min(U_A, U_L) for one grasp."""
    from ..fields import check_field_path, field_paths

    if export_fields is not None:
        check_field_path(export_fields)
    check_outputs([output, export_graph,
                   *(field_paths(export_fields, ["sigma_star", "sigma_L"]) if export_fields else [])],
                  [plot], [part])
    if model is None:
        model = "paper" if jaws is not None else "pads"
    if model == "paper":
        return _paper(part, jaws, at, method, eps, expanding, jaw_width, units, material, output,
                      plot, export_graph, export_fields)
    bad = [name for name, given in (("--jaws", jaws is not None),
                                    ("--jaw-width", jaw_width != 0.0), ("--eps", eps is not None),
                                    ("--export-graph", export_graph is not None),
                                    ("--method", method != "exact")) if given]
    if bad:
        raise GraspError(f"{bad[0]}: belongs to the paper model; add --model paper, or give the "
                         "pads an axis with --at X,Y X,Y or --axis X,Y,DEG")
    return _pads(part, at, axis, pad_radius, pad_width, refine, grid_angles, grid_offsets, units,
                 material, output, plot, quiet, expanding, export_fields)


def parse_axis(at, axis, scale: float):
    """The grasp axis from ``--at X,Y X,Y`` or ``--axis X,Y,DEG`` (lengths × ``scale`` → m)."""
    from ..pads import GraspAxis

    if (at is None) == (axis is None):
        raise GraspError("axis: give exactly one of --at X,Y X,Y (two points on the closing axis) "
                         "or --axis X,Y,DEG (a point and the closing direction in degrees)")
    if at is not None:
        p, q = (np.array(parse_xy(v, "--at")) * scale for v in at)
        return GraspAxis.through(p, q)
    try:
        x, y, deg = (float(v) for v in axis.split(","))
    except ValueError:
        raise GraspError(f"--axis: expected X,Y,DEG (three numbers), got {axis!r}") from None
    if not all(np.isfinite([x, y, deg])):
        raise GraspError(f"--axis: values must be finite, got {axis!r}")
    return GraspAxis.at(np.array([x, y]) * scale, np.radians(deg))


def _pads(part, at, axis, pad_radius, pad_width, refine, grid_angles, grid_offsets, units,
          material, output, plot, quiet, expanding=False, export_fields=None) -> int:
    from ..pads import pad_grasp
    from .common import check_grid, load_part_or_mesh, pad_from_options

    check_grid(grid_angles, grid_offsets)
    prt, mesh = load_part_or_mesh(part, units=units, material=material)
    check_model_size(mesh, "pads", solvers=1 if prt is None else 2, refine=refine,
                     n_axes=grid_angles * grid_offsets)
    unit = units if units is not None else ("m" if prt is None else prt.units)
    scale = length_scale(unit, "--units")
    ax = parse_axis(at, axis, scale)
    pad = pad_from_options(pad_radius, pad_width, scale, mesh.diameter)

    def progress(k: int, n: int) -> None:
        if not quiet and n > 1:
            click.echo(f"mesh {k + 1} of {n} ...", err=True)

    start = None
    if expanding:
        if at is not None:
            start = 0.5 * sum(np.array(parse_xy(v, "--at")) for v in at) * scale
        else:
            start = np.array([float(v) for v in axis.split(",")[:2]]) * scale
    res = pad_grasp(prt, ax, pad, mesh=mesh, refine=refine, progress=progress,
                    expanding_from=start, n_angles=grid_angles, n_offsets=grid_offsets)
    report = res.to_dict()
    fine = res.finest
    s = 1.0 / length_scale(unit)
    click.echo(f"model: pads, W = {pad.width * s:.4g} {unit}, rho = {pad.radius * s:.4g} {unit}; "
               f"axis through ({fine.axis.point[0] * s:.4g}, {fine.axis.point[1] * s:.4g}) {unit} "
               f"at {np.degrees(fine.axis.angle):.4g} deg")
    click.echo(f"sigma0 = {fine.sigma0 * s:.6g} {unit}  sigma_L = {fine.sigma_L * s:.6g} {unit}  "
               f"(critical distance {fine.limit.critical_distance * s:.3g} {unit})")
    if fine.sigma_star is None:
        click.echo("Q = 0 on the whole range: no barrier above the noise floor "
                   f"({fine.noise_relative:.2%} of U)")
    else:
        ua = "infinite" if np.isinf(fine.U_A) else f"{fine.U_A:.6g} J"
        click.echo(f"sigma* = {fine.sigma_star * s:.6g} {unit}  Q* = {fine.quality:.6g} J  "
                   f"U_A = {ua}  U_L = {fine.U_L:.6g} J  (noise floor {fine.noise:.3g} J)")
    if "convergence" in report:
        click.echo(f"{'max_area (' + unit + '^2)':>18} {'nodes':>7} {'sigma* (' + unit + ')':>14} {'Q* (J)':>12}")
        for row in report["convergence"]:
            ss = "-" if row["sigma_star"] is None else f"{row['sigma_star'] * s:.6g}"
            click.echo(f"{row['max_area'] * s * s:>18.4g} {row['nodes']:>7} {ss:>14} {row['quality']:>12.5g}")
        e = report["error_estimate"]
        es = "-" if e["sigma_star"] is None else f"{e['sigma_star'] * s:.3g} {unit}"
        click.echo(f"error estimate (Richardson): Q* ± {e['quality']:.3g} J, sigma* ± {es}")
    for w in fine.warnings:
        click.echo(f"warning: {w}", err=True)
    click.echo(f"verdict: {report['verdict'].upper()}")
    write_json(report, output)
    if export_fields:
        from ..fields import write_fields

        sigmas = ([("sigma_star", fine.sigma_star)] if fine.sigma_star is not None else []) \
            + [("sigma_L", fine.sigma_L)]
        states = [fine.state_at(sig, label) for label, sig in sigmas]
        for pth in write_fields(export_fields, fine.solver.mesh, states,
                                fine.limit.critical_distance):
            click.echo(f"wrote {pth}")
    if plot:
        from ..plotting.pads import save_pad_plots

        for pth in save_pad_plots(fine, mesh, plot,
                                  units=unit if unit != "m" else "mm"):
            click.echo(f"wrote {pth}")
    return 0


def _paper(part, jaws, at, method, eps, expanding, jaw_width, units, material, output, plot,
           export_graph, export_fields=None) -> int:
    """The paper's two-jaw model (SPEC §4), unchanged."""
    from ..grasp.analysis import grasp_model, optimize_separation
    if (jaws is None) == (at is None):
        raise GraspError("jaws: give exactly one of --jaws A B (node ids) or --at X,Y X,Y (positions)")
    if eps is not None and not (np.isfinite(eps) and eps > 0):
        raise GraspError(f"--eps = {eps!r}: must be a finite energy > 0 in joules")
    if not (np.isfinite(jaw_width) and jaw_width >= 0):
        raise GraspError(f"--jaw-width = {jaw_width!r}: must be a finite length >= 0 (0 = point jaws)")
    mesh, unit, scale, pts = load_grasp_inputs(part, at, units, material)
    check_model_size(mesh, "paper", mode="expanding" if expanding else "contracting")
    if jaw_width * scale > mesh.diameter:
        raise GraspError(f"--jaw-width = {jaw_width:g} {unit}: wider than the part "
                         f"({mesh.diameter / scale:.4g} {unit}); check the value and --units")
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
        write_text_atomic(export_graph, json.dumps(json_safe(g), allow_nan=False), "graph")
    if export_fields:
        from ..fields import write_fields
        from ..pads.limit import critical_distance_of

        sigmas = ([("sigma_star", ss)] if ss is not None else []) + \
            [("sigma_L", res.limit.sigma_L)]
        states = [paper_state(res, (n0, n1), sig, label) for label, sig in sigmas]
        for pth in write_fields(export_fields, mesh, states, critical_distance_of(mesh)):
            click.echo(f"wrote {pth}")
    if plot:
        from ..plotting.grasp import save_grasp_plots

        for pth in save_grasp_plots(res, plot, units=unit if unit != "m" else "mm"):
            click.echo(f"wrote {pth}")
    return 0


def paper_state(res, jaws: tuple[int, int], sigma: float, label: str):
    """The paper model's state at separation ``sigma`` (m): the linear displacement field
    of the jaw pair for the squeeze ``|σ0 − σ|`` and the jaw forces ``k01 δ`` along the jaw
    line (SPEC §4), as a :class:`deformclosure.fields.FieldState`."""
    from ..fields import FieldState

    lim = res.limit
    mesh = res.model.mesh
    delta = abs(lim.sigma0 - sigma)
    sign = -1.0 if res.model.mode == "expanding" else 1.0
    u = sign * lim.displacement_per_length * delta
    a, b = jaws
    d = mesh.nodes[b] - mesh.nodes[a]
    d = d / np.linalg.norm(d)
    forces = np.zeros((mesh.n_nodes, 2))
    forces[a] = sign * lim.k01 * delta * d          # jaw a pushes towards b (contracting)
    forces[b] = -forces[a]
    return FieldState(label, u, forces)
