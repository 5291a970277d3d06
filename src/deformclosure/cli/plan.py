"""``deformclosure plan``: rank every jaw pair of a part by grasp quality."""

from __future__ import annotations

import click

from ..limits import limits_help
from .common import run_report, table_options

__all__ = ["command"]

EPILOG = """\b
Examples (pads, the default model, SPEC §6):
  deformclosure plan examples/notched_bar.json --pad-radius 2 --top 5 -o plan.json --plot plan/
\b
Paper model (every pair of perimeter nodes, point jaws, SPEC §4):
  deformclosure plan examples/c_shape.json --model paper --top 5 -o plan.json --plot plan/
  deformclosure plan examples/ring.json --model paper --expanding --eps 1e-5
  deformclosure plan examples/l_shape.json --model paper --eps 5e-7 --allow-pulling

\b
--pad-radius/--pad-width, --min-sep/--max-sep, --region and --jaw-width are in --units
(default: the part's); --eps is in joules: every pair's reported quality is within eps
of its optimum (default: the step of about 400 lattice values over the separation
range). Pairs flagged "pulls" (a jaw would have to pull) are ranked and marked but kept
out of the top list unless --allow-pulling.
"""


@click.command(epilog=EPILOG + limits_help("plan"))
@click.argument("part", type=click.Path(dir_okay=False))
@table_options("plan")
def command(part: str, **params) -> int:
    """Rank grasps of a part: grasp axes for pads (default) or jaw node pairs (paper)."""
    return run_report("plan", part, params)
