"""``deformclosure slice``: a slice of D-space, one node moving (paper Fig. 3, SPEC §2)."""

from __future__ import annotations

import click

from ..limits import limits_help
from .common import run_report, table_options

__all__ = ["command"]

EPILOG = """\b
Examples:
  deformclosure slice examples/rectangle.json --node 3 --fingers examples/fingers/rectangle.json --plot slice.png
  deformclosure slice examples/rectangle.json --at 0,10 --fingers examples/fingers/rectangle.json --extent -2,2,8,12 -o slice.npz

\b
Node ids are those of `deformclosure mesh PART` (the part is meshed the same way).
--at and --extent are in --units (default: the part file's units, metres for mesh
files). -o writes .npz arrays or, for a .json name, a JSON report; both SI.
"""


@click.command(epilog=EPILOG + limits_help("slice"))
@click.argument("part", type=click.Path(dir_okay=False))
@table_options("slice")
def command(part: str, **params) -> int:
    """D_free membership and energy while one node moves and all others stay.

    PART is a part file (JSON), a drawing or a mesh file.
    """
    return run_report("slice", part, params)
