"""``deformclosure slice``: a slice of D-space, one node moving (paper Fig. 3, SPEC §2)."""

from __future__ import annotations

import click
import numpy as np

from ..errors import DeformClosureError
from ..limits import MAX_SLICE_RESOLUTION, limits_help
from .common import load_part_or_mesh, mesh_input_options, parse_xy

__all__ = ["command"]

EPILOG = """\b
Examples:
  deformclosure slice examples/rectangle.json --node 3 --fingers fingers.json --plot slice.png
  deformclosure slice mesh.json --at 0,10 --fingers f.json --extent -2,2,8,12 -o slice.npz

\b
Node ids are those of `deformclosure mesh PART` (the part is meshed the same way).
--at and --extent are in --units (default: the part file's units, metres for mesh
files). -o writes .npz arrays or, for a .json name, a JSON report; both SI.
""" + limits_help("slice")


@click.command(epilog=EPILOG)
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("--node", type=int, default=None, help="Id of the moving node.")
@click.option("--at", type=str, default=None, metavar="X,Y", help="Move the node at X,Y instead of --node.")
@click.option("--fingers", "finger_file", required=True, type=click.Path(dir_okay=False),
              help="Finger file (JSON; see `deformclosure check --help`).")
@click.option("--extent", type=str, default=None, metavar="XMIN,XMAX,YMIN,YMAX",
              help="Region swept by the node (default: twice its longest edge around it).")
@click.option("--resolution", type=int, default=200, show_default=True,
              help=f"Pixels per axis (2..{MAX_SLICE_RESOLUTION:,}).")
@click.option("--energy", type=click.Choice(["linear", "corotational"]), default="linear", show_default=True)
@click.option("--units", type=click.Choice(["m", "cm", "mm", "in"]), default=None,
              help="Units of --at and --extent, and of a meshio file's coordinates.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None, help="Write .npz or .json.")
@click.option("--plot", type=click.Path(dir_okay=False), default=None, help="Draw the slice (PNG/SVG).")
@click.option("--export-fields", type=click.Path(dir_okay=False), default=None,
              help="Write the slice as an image for ParaView (.vtu): energy, D_free, D_T and "
                   "each D-obstacle over the positions of the moving node.")
@mesh_input_options(units=False)
def command(part: str, node: int | None, at: str | None, finger_file: str, extent: str | None,
            resolution: int, energy: str, units: str | None, output: str | None, plot: str | None,
            export_fields: str | None, material: str | None) -> int:
    """D_free membership and energy while one node moves and all others stay.

    PART is a part file (JSON) or a mesh file.
    """
    from ..outputs import check_outputs

    from ..fields import check_field_path

    if export_fields is not None:
        check_field_path(export_fields)
    check_outputs([output, plot, export_fields], [], [part, finger_file])
    from ..dspace.fingers import load_fingers
    from ..dspace.slices import dfree_slice
    from ..units import length_scale

    fingers = load_fingers(finger_file)
    from ..limits import check_slice_size

    check_slice_size(resolution, len(fingers),         # before the part is even meshed
                     json_output=bool(output) and str(output).lower().endswith(".json"))
    part_obj, mesh = load_part_or_mesh(part, units=units, material=material)
    unit = units if units is not None else (part_obj.units if part_obj is not None else "m")
    s = length_scale(unit, "--units")
    if (node is None) == (at is None):
        raise DeformClosureError("give exactly one of --node N or --at X,Y")
    if at is not None:
        node = mesh.find_node(np.array(parse_xy(at, "--at")) * s)
    if not 0 <= node < mesh.n_nodes:
        raise DeformClosureError(f"--node {node}: the mesh has nodes 0..{mesh.n_nodes - 1}")
    ext = None
    if extent is not None:
        try:
            ext = [float(v) * s for v in extent.split(",")]
        except ValueError:
            raise DeformClosureError(f"--extent: expected XMIN,XMAX,YMIN,YMAX, got {extent!r}") from None
        if len(ext) != 4:
            raise DeformClosureError(f"--extent: expected 4 numbers XMIN,XMAX,YMIN,YMAX, got {extent!r}")
        reach = 100 * mesh.diameter + float(np.abs(mesh.nodes).max())
        if not all(np.isfinite(ext)) or max(abs(v) for v in ext) > reach:
            raise DeformClosureError(f"--extent {extent}: must be finite and within 100 part "
                                     "diameters of the part; check the values and --units")
    res = dfree_slice(mesh, None, node, fingers, extent=ext, resolution=resolution, energy=energy)
    click.echo(f"node {node}: {resolution}x{resolution} slice, D_free {100 * res.free.mean():.1f}% of pixels, "
               f"D_T {100 * res.in_dt.mean():.1f}%, {energy} energy {res.energy.min():.4g}..{res.energy.max():.4g} J")
    if output:
        try:
            res.save(output)
        except OSError as err:
            raise DeformClosureError(f"{output}: cannot write ({err.strerror})") from None
    if export_fields:
        from ..fields import write_slice_fields

        click.echo(f"wrote {write_slice_fields(export_fields, res)}")
    if plot:
        from ..plotting.dspace import plot_slice
        from ..plotting.mesh import new_figure, save_figure

        fig, ax = new_figure()
        plot_slice(res, mesh=mesh, fingers=fingers, ax=ax, units=unit)
        save_figure(fig, plot)
    return 0
