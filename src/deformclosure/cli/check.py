"""``deformclosure check``: is a contact set holding the part? (SPEC §3, §5)."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from ..errors import DeformClosureError
from ..limits import check_model_size, limits_help
from .common import load_part_or_mesh, mesh_input_options, write_json

__all__ = ["command", "contact_points", "merge_release"]

EPILOG = """\b
Examples:
  deformclosure check examples/rectangle.json --fingers fingers.json
  deformclosure check part.json --fingers fingers.json -o report.json --plot check.png

\b
The finger file (JSON) lists fingers in its own "units":
  {"units": "mm", "fingers": [{"type": "point", "at": [x, y]},
     {"type": "disc", "center": [x, y], "radius": r},
     {"type": "polygon", "vertices": [[x, y], ...]},
     {"type": "halfplane", "point": [x, y], "normal": [nx, ny]}]}
A half-plane occupies the side its normal points away from. Place fingers against the
part at rest: touching, or overlapping it to pre-squeeze it. Point fingers on the
boundary of a part file are inserted as mesh nodes. The report is SI (m, N, J); the
certificate twist [vx, vy, omega] is the velocity of the part's area centroid (m/s) and
its angular velocity (rad/s).

\b
The verdict is the paper's definition: U_A, the least work that releases the part,
from the energy landscape over the part's placement (x, y, phi) among the fixed
fingers; deform_closure = U_A > its error at a strict minimum. The rigid-motion test at
rest (Thm 1) is reported as rigid_closure with its order and certificate. The escape
path (placements in m and rad, energies in J) is in the report and, with --plot, drawn
beside the check picture with its energy profile.
"""


def contact_points(part, fingers) -> np.ndarray:
    """Point-finger and polygon-corner positions on the part's boundary (m), ``(k, 2)``.

    They are inserted as mesh nodes so point contacts sit on nodes.
    """
    import shapely

    pts = []
    for f in fingers:
        pts.extend(np.asarray(f.vertices, float).reshape(-1, 2))
    if not pts:
        return np.zeros((0, 2))
    pts = np.asarray(pts)
    tol = 1e-9 * part.diameter
    d = shapely.distance(shapely.points(pts), part.polygon.boundary)
    return pts[d <= tol]


@click.command(epilog=EPILOG + limits_help("check"))
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("--fingers", "finger_file", required=True, type=click.Path(dir_okay=False),
              help="Finger file (JSON, see below).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Write the JSON report here ('-' for stdout).")
@click.option("--plot", type=click.Path(dir_okay=False), default=None,
              help="Draw the part, fingers, contact forces and escaping motion (PNG/SVG).")
@click.option("--grid-steps", type=int, default=48, show_default=True,
              help="Release landscape: translation steps per part diameter (at most half "
                   "the smallest disc radius per step).")
@click.option("--saddle-levels", type=int, default=2, show_default=True,
              help="Release landscape: halvings of the lattice near the saddle (error estimate).")
@click.option("--export-fields", type=click.Path(dir_okay=False), default=None,
              help="Write the fields at the equilibrium to FILE.vtu for ParaView: deformed "
                   "mesh, displacement, strain, contact pressure.")
@mesh_input_options()
def command(part: str, finger_file: str, output: str | None, plot: str | None,
            grid_steps: int, saddle_levels: int, export_fields: str | None,
            material: str | None, units: str | None) -> int:
    """Deform closure of a contact set: release energy U_A and escape path, equilibrium,
    contact forces, rigid-closure order and certificate.

    PART is a part file (JSON) or a mesh file.
    """
    from ..fields import check_field_path
    from ..outputs import check_outputs

    if export_fields is not None:
        check_field_path(export_fields)
    check_outputs([output, plot, export_fields], [], [part, finger_file])
    if not (8 <= grid_steps <= 1000):
        raise DeformClosureError(f"--grid-steps = {grid_steps}: give a whole number from 8 to 1000")
    if not (0 <= saddle_levels <= 4):
        raise DeformClosureError(f"--saddle-levels = {saddle_levels}: give a whole number from 0 to 4")
    from ..dspace.closure import deform_closure
    from ..dspace.fingers import load_fingers
    from ..mesh.io import is_mesh_file

    fingers = load_fingers(finger_file)
    p = Path(part)
    if not p.exists():
        raise DeformClosureError(f"{part}: file not found; give a part file (.json) or a mesh file")
    if is_mesh_file(p):
        part_obj, mesh = load_part_or_mesh(p, units=units, material=material)
    else:
        from ..mesh import mesh_part
        from .common import read_part

        part_obj = read_part(p, units, material)
        mesh = mesh_part(part_obj, points=contact_points(part_obj, fingers))
    check_model_size(mesh, "pads", solvers=2 if part_obj is None else 3, what="check")
    res = deform_closure(mesh, fingers)
    from ..dspace.escape import release_energy_fingers
    from .common import lazy_progress

    tick, close = lazy_progress(False, "release landscape", "placements")
    try:
        rel = release_energy_fingers(mesh, fingers, part=part_obj, start=res.equilibrium,
                                     rigid_closed=res.deform_closure, n_translation=grid_steps,
                                     levels=saddle_levels, count=lambda n: tick(n, None))
    finally:
        close()
    report = merge_release(res.to_dict(), res, rel)
    eq = res.equilibrium
    click.echo(f"{mesh.name}: {mesh.n_nodes} nodes, {len(fingers)} fingers")
    click.echo(f"verdict: {_verdict(rel)}")
    click.echo(f"release energy U_A = {_joules(rel.U_A)} ± {rel.U_A_error:.3g} J (noise floor "
               f"{rel.noise_relative:.1%}), escape {_target(rel)}; "
               f"{rel.n_evaluations} placements solved in {rel.seconds:.1f} s")
    click.echo(f"quality min(U_A, U_L) = {_joules(rel.quality)}, U_L = {_joules(rel.U_L)} "
               f"(elastic limit over the critical distance {rel.critical_distance:.3g} m)")
    for w in rel.warnings:
        click.echo(f"warning: {w}", err=True)
    rigid = "closed" if res.deform_closure else "not closed (escaping twist below)"
    click.echo(f"rigid test at rest (Thm 1): {rigid}, decided at order {res.order}")
    click.echo(f"energy at equilibrium: {res.energy:.6g} J (linear), {eq.iterations} linearisations"
               + ("" if eq.converged else " (NOT converged)"))
    for c in res.contacts:
        click.echo(f"  finger {c.finger}: {'active' if c.active else 'inactive'}, {c.feature}, "
                   f"force ({c.force[0]:.4g}, {c.force[1]:.4g}) N")
    mat = getattr(mesh, "material", None)
    if mat is not None and eq.max_strain > mat.elastic_limit_strain:
        click.echo(f"warning: the largest strain at equilibrium, {eq.max_strain:.3g}, exceeds the elastic "
                   f"limit e_L = {mat.elastic_limit_strain:g}: the fingers squeeze the part beyond its "
                   "elastic range (and beyond the small-displacement model)", err=True)
    if res.twist is not None:
        t = res.twist
        click.echo(f"escaping twist: v = ({t[0]:.4g}, {t[1]:.4g}) m/s, omega = {t[2]:.4g} rad/s "
                   "(about the area centroid)")
    write_json(report, output)
    if export_fields:
        from ..fields import FieldState, write_fields
        from ..pads.limit import critical_distance_of

        eq = res.equilibrium
        state = FieldState("equilibrium", np.asarray(eq.q) - mesh.nodes, eq.nodal_forces,
                           elastic=eq.displacement)
        for pth in write_fields(export_fields, mesh, [state], critical_distance_of(mesh)):
            click.echo(f"wrote {pth}")
    if plot:
        from ..plotting.escape import plot_check_and_escape
        from ..plotting.mesh import save_figure

        units = part_obj.units if part_obj is not None else "m"
        fig = plot_check_and_escape(mesh, res, rel, fingers, units=units)
        save_figure(fig, plot)
    return 0


def merge_release(report: dict, closure, release) -> dict:
    """The check report (SPEC §5, §7): the rigid test's keys as before, ``deform_closure``
    from the release energy, the rigid verdict as ``rigid_closure``, and the release keys."""
    out = dict(report)
    out["rigid_closure"] = bool(closure.deform_closure)
    rel = release.to_dict()
    out.update(rel)
    out["units"] = {**report.get("units", {}), "angle": "rad"}
    return out


def _joules(v: float) -> str:
    return "infinite" if not np.isfinite(v) else f"{v:.6g} J"


def _target(rel) -> str:
    if rel.U_A_infinite:
        return "impossible within the fingers' reach (a cage)"
    if not rel.complete:
        return "search stopped (U_A is a lower bound)"
    return {"released": "to a released placement", "equilibrium": "to another equilibrium"}.get(
        rel.target, "none")


def _verdict(rel) -> str:
    if rel.deform_closure:
        return "HELD (deform closure: U_A exceeds its error)"
    if rel.caged:
        return "CAGED (not held in place, but leaving takes U_A)"
    return "NOT HELD (the part escapes without work)" 
