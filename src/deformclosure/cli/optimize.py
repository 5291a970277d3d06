"""``deformclosure optimize``: optimal separation of a two-jaw grasp (SPEC §4)."""

from __future__ import annotations

import click

from ..limits import limits_help
from .common import run_report, table_options

__all__ = ["command"]

EPILOG = """\b
Examples (pads, the default model, SPEC §6):
  deformclosure optimize examples/notched_bar.json --at 15,0 15,12 --pad-radius 2 -o report.json --plot out/
  deformclosure optimize examples/rectangle.json --axis 6,10,0 --pad-radius 1 --pad-width 4 --rtol 0.02
  deformclosure optimize examples/notched_bar.json --at 15,0 15,12 --pad-radius 2 --export-fields squeeze.pvd
\b
Paper model (point jaws at mesh nodes, SPEC §4, for reproduction):
  deformclosure optimize examples/rectangle.json --model paper --at 0,10 12,10 -o report.json
  deformclosure optimize examples/rectangle.json --model paper --jaws 6 127 --method approx --eps 1e-6
  deformclosure optimize examples/ring.json --model paper --at 1.5,0 -1.5,0 --expanding

\b
Lengths given here (--at, --axis, --pad-radius, --pad-width, --jaw-width) are in --units
(default: the part file's units, metres for mesh files); --eps is in joules. The JSON
report is SI throughout and says which model made it.
"""


@click.command(epilog=EPILOG + limits_help("optimize"))
@click.argument("part", type=click.Path(dir_okay=False))
@table_options("optimize")
def command(part: str, **params) -> int:
    """Optimal separation σ* maximising Q = min(U_A, U_L) for one grasp."""
    return run_report("optimize", part, params)
