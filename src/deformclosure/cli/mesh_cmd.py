"""``deformclosure mesh PART -o mesh.json [--plot mesh.png]``."""

from __future__ import annotations

import click

from ..limits import limits_help
from .common import run_report, table_options

__all__ = ["command"]

EPILOG = """\b
Example:
  deformclosure mesh examples/plate_with_hole.json -o mesh.json --plot mesh.png
"""


@click.command(epilog=EPILOG + limits_help("mesh"))
@click.argument("part", type=click.Path(dir_okay=False))
@table_options("mesh")
def command(part: str, **params) -> int:
    """Mesh a part file with quality linear triangles.

    Given a mesh file instead (mesh JSON or any meshio format), check it and convert it;
    --units states the unit of a meshio file's coordinates and --material gives it a
    material, written with it (mesh JSON, .vtu, .vtk keep it; other formats say so).
    """
    return run_report("mesh", part, params)
