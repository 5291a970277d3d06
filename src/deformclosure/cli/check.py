"""``deformclosure check``: is a contact set holding the part? (SPEC §3, §5)."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from ..errors import DeformClosureError
from .common import load_part_or_mesh, mesh_input_options, write_json

__all__ = ["command", "contact_points"]

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


@click.command(epilog=EPILOG)
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("--fingers", "finger_file", required=True, type=click.Path(dir_okay=False),
              help="Finger file (JSON, see below).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Write the JSON report here ('-' for stdout).")
@click.option("--plot", type=click.Path(dir_okay=False), default=None,
              help="Draw the part, fingers, contact forces and escaping motion (PNG/SVG).")
@mesh_input_options()
def command(part: str, finger_file: str, output: str | None, plot: str | None,
            material: str | None, units: str | None) -> int:
    """Deform closure of a contact set: equilibrium, contact forces, verdict, certificate.

    PART is a part file (JSON) or a mesh file.
    """
    from ..outputs import check_outputs

    check_outputs([output, plot], [], [part, finger_file])
    from ..dspace.closure import deform_closure
    from ..dspace.fingers import load_fingers
    from ..mesh.io import is_mesh_file
    from ..part import Part

    fingers = load_fingers(finger_file)
    p = Path(part)
    if not p.exists():
        raise DeformClosureError(f"{part}: file not found; give a part file (.json) or a mesh file")
    pts = None
    if not is_mesh_file(p):
        pts = contact_points(Part.from_file(p), fingers)
    part_obj, mesh = load_part_or_mesh(p, points=pts, units=units, material=material)
    res = deform_closure(mesh, fingers)
    report = res.to_dict()
    eq = res.equilibrium
    verdict = "HELD (deform closure)" if res.deform_closure else "NOT HELD (the part escapes)"
    click.echo(f"{mesh.name}: {mesh.n_nodes} nodes, {len(fingers)} fingers")
    click.echo(f"verdict: {verdict}, decided at order {res.order}")
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
    if plot:
        from ..plotting.dspace import plot_check
        from ..plotting.mesh import new_figure, save_figure

        units = part_obj.units if part_obj is not None else "m"
        fig, ax = new_figure()
        plot_check(mesh, res, fingers, ax=ax, units=units)
        save_figure(fig, plot)
    return 0
