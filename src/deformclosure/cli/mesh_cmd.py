"""``deformclosure mesh PART -o mesh.json [--plot mesh.png]``."""

from __future__ import annotations

import click

from ..mesh import mesh_part, write_mesh
from ..mesh.io import mesh_to_dict
from ..part import Part
from .common import write_json

__all__ = ["command"]


@click.command(epilog="\b\nExample:\n  deformclosure mesh examples/plate_with_hole.json -o mesh.json --plot mesh.png")
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Mesh file to write: .json (SPEC mesh JSON, metres) or any meshio format.")
@click.option("--max-area", type=float, default=None,
              help="Override the part's mesh.max_area (in the part's units²).")
@click.option("--min-angle", type=float, default=None,
              help="Override the part's mesh.min_angle (degrees, <= 34).")
@click.option("--plot", type=click.Path(dir_okay=False), help="Write a picture of the mesh (PNG/SVG).")
def command(part: str, output: str | None, max_area: float | None, min_angle: float | None,
            plot: str | None) -> int:
    """Mesh a part file with quality linear triangles."""
    p = Part.from_file(part)
    from ..units import length_scale

    s = length_scale(p.units)
    mesh = mesh_part(p, max_area=None if max_area is None else max_area * s * s,
                     min_angle=min_angle)
    click.echo(mesh.summary())
    if output:
        if output.endswith(".json"):
            write_json(mesh_to_dict(mesh), output)
        else:
            write_mesh(mesh, output)
    if plot:
        from ..plotting.mesh import save_mesh_plot

        save_mesh_plot(mesh, plot, units=p.units)
    return 0
