"""``deformclosure import DRAWING -o part.json``: a part file from a DXF or SVG drawing."""

from __future__ import annotations

import click

__all__ = ["command"]

EPILOG = """\b
Examples:
  deformclosure import gasket.dxf -o gasket.json --material rubber.json
  deformclosure import bracket.dxf -o bracket.json --layer OUTLINE --units mm --tolerance 0.01
  deformclosure import logo.svg -o logo.json --material '{"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1, "elastic_limit_strain": 0.8}'

\b
DXF: closed LWPOLYLINE/POLYLINE, chains of LINE/ARC/open polylines/splines, CIRCLE,
ELLIPSE and SPLINE entities, block references exploded; units from $INSUNITS. SVG: paths
and basic shapes; units from the root's width/height (plain user units are CSS pixels,
96 per inch). Curves are flattened to chords within --tolerance. The largest closed loop
is the outer ring; the loops inside it are holes. The material comes from --material or
from <name>.material.json beside the drawing (with an optional "mesh" block). The same
drawings are accepted directly wherever a part file is.
"""


@click.command(epilog=EPILOG)
@click.argument("drawing", type=click.Path(dir_okay=False))
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="Part file to write (JSON, SI: metres); '-' for stdout.")
@click.option("--units", type=str, default=None,
              help="Unit of the drawing's coordinates, overriding its header (m, cm, mm, in).")
@click.option("--layer", type=str, default=None,
              help="DXF: read only this layer; SVG: only the element (group) with this id.")
@click.option("--tolerance", type=float, default=None,
              help="Largest chord-to-curve distance, in the drawing's units "
                   "(default 0.1 % of its bounding-box diagonal).")
@click.option("--material", type=str, default=None, metavar="FILE|JSON",
              help="Material: a JSON file or inline JSON (youngs_modulus Pa, poisson_ratio, "
                   "thickness, elastic_limit_strain [, plane, critical_distance, units]).")
@click.option("--plot", type=click.Path(dir_okay=False), default=None,
              help="Draw the imported outline (PNG/SVG).")
def command(drawing: str, output: str, units: str | None, layer: str | None,
            tolerance: float | None, material: str | None, plot: str | None) -> int:
    """Make a part file from a CAD drawing (DXF or SVG)."""
    from ..drawing import is_drawing_file, part_from_drawing
    from ..errors import PartError
    from ..outputs import check_outputs
    from ..units import length_scale
    from .common import warn_part, write_json

    check_outputs([output, plot], [], [drawing])
    if not is_drawing_file(drawing):
        raise PartError(f"{drawing}: not a drawing; give a .dxf or .svg file")
    part = part_from_drawing(drawing, material=material, units=units, layer=layer,
                             tolerance=tolerance)
    warn_part(part)
    s = length_scale(part.units)
    click.echo(f"{part.name}: outer ring of {len(part.outer)} vertices, {len(part.holes)} hole(s), "
               f"area {part.area / s**2:.6g} {part.units}^2")
    data = part.to_dict()
    write_json(data, output)
    if plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..outputs import atomic_path

        fig, ax = plt.subplots(figsize=(6, 5))
        for ring in (part.outer, *part.holes):
            xy = ring / s
            ax.fill(xy[:, 0], xy[:, 1], alpha=0.25 if ring is part.outer else 1.0,
                    fc="tab:blue" if ring is part.outer else "white", ec="k", lw=0.8)
        ax.set_aspect("equal")
        ax.set_xlabel(f"x ({part.units})")
        ax.set_ylabel(f"y ({part.units})")
        ax.set_title(part.name)
        with atomic_path(plot) as tmp:
            fig.savefig(tmp, dpi=150, bbox_inches="tight")
        plt.close(fig)
    return 0
