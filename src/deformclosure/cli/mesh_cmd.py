"""``deformclosure mesh PART -o mesh.json [--plot mesh.png]``."""

from __future__ import annotations

import click

from ..errors import DeformClosureError
from ..limits import limits_help
from ..mesh import mesh_part, write_mesh
from ..mesh.io import is_mesh_file, mesh_to_dict
from .common import load_part_or_mesh, mesh_input_options, read_part, write_json

__all__ = ["command"]


@click.command(epilog="\b\nExample:\n  deformclosure mesh examples/plate_with_hole.json -o mesh.json --plot mesh.png\n"
                        + limits_help("mesh"))
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Mesh file to write: .json (SPEC mesh JSON, metres) or any meshio format.")
@click.option("--max-area", type=float, default=None,
              help="Override the part's mesh.max_area (in the part's units²).")
@click.option("--min-angle", type=float, default=None,
              help="Override the part's mesh.min_angle (degrees, <= 34).")
@click.option("--plot", type=click.Path(dir_okay=False), help="Write a picture of the mesh (PNG/SVG).")
@mesh_input_options()
def command(part: str, output: str | None, max_area: float | None, min_angle: float | None,
            plot: str | None, material: str | None, units: str | None) -> int:
    """Mesh a part file with quality linear triangles.

    Given a mesh file instead (mesh JSON or any meshio format), check it and convert it;
    --units states the unit of a meshio file's coordinates and --material gives it a
    material, written with it (mesh JSON, .vtu, .vtk keep it; other formats say so).
    """
    from ..outputs import check_outputs

    check_outputs([output, plot], [], [part])
    from pathlib import Path

    from ..units import length_scale

    if Path(part).exists() and is_mesh_file(part):
        if max_area is not None or min_angle is not None:
            raise DeformClosureError("--max-area/--min-angle: apply to part files only, "
                                     f"and {part} is a mesh file")
        _, mesh = load_part_or_mesh(part, units=units, material=material, need_material=False)
        shown = units or "mm"
    else:
        p = read_part(part, units, material)
        s = length_scale(p.units)
        mesh = mesh_part(p, max_area=None if max_area is None else max_area * s * s,
                         min_angle=min_angle)
        shown = p.units
    click.echo(mesh.summary())
    if output:
        if output == "-" or output.lower().endswith(".json"):
            write_json(mesh_to_dict(mesh), output)
        elif not write_mesh(mesh, output) and mesh.material is not None:
            click.echo(f"warning: {Path(output).suffix} files cannot hold the material; give "
                       "--material when reading the mesh back (.json, .vtu and .vtk keep it)",
                       err=True)
    if plot:
        from ..plotting.mesh import save_mesh_plot

        save_mesh_plot(mesh, plot, units=shown)
    return 0
