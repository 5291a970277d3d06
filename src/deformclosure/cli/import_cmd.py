"""``deformclosure import DRAWING -o part.json``: a part file from a DXF or SVG drawing."""

from __future__ import annotations

import click

from .common import run_report, table_options

__all__ = ["command"]

EPILOG = """\b
Examples:
  deformclosure import examples/drawings/gasket.dxf -o gasket.json
  deformclosure import examples/drawings/gasket.dxf -o gasket.json --layer OUTLINE --units mm --tolerance 0.01
  deformclosure import examples/drawings/gasket.dxf -o gasket.json --material '{"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1, "elastic_limit_strain": 0.8}'

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
@table_options("import")
def command(drawing: str, **params) -> int:
    """Make a part file from a CAD drawing (DXF or SVG)."""
    return run_report("import", drawing, params)
