"""``deformclosure check``: is a contact set holding the part? (SPEC §3, §5)."""

from __future__ import annotations

import click

from ..limits import limits_help
from .common import run_report, table_options

__all__ = ["command"]

EPILOG = """\b
Examples:
  deformclosure check examples/rectangle.json --fingers examples/fingers/rectangle.json
  deformclosure check examples/l_shape.json --fingers examples/fingers/l_shape.json -o check.json --plot check.png

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

\b
The verdict is the paper's definition: U_A, the least work that releases the part,
from the energy landscape over the part's placement (x, y, phi) among the fixed
fingers; deform_closure = U_A > its error at a strict minimum. The rigid-motion test at
rest (Thm 1) is reported as rigid_closure with its order and certificate. The escape
path (placements in m and rad, energies in J) is in the report and, with --plot, drawn
beside the check picture with its energy profile.

\b
--elasticity neo-hookean (or material.model in the part file) searches the same
placements at finite strain (SPEC §8; disc and half-plane fingers): U_A of the whole
lattice when the search ends within --max-seconds, else a bracket U_A_lower..U_A on
which the verdict is decided; linear_model_error compares the two models.
"""


@click.command(epilog=EPILOG + limits_help("check"))
@click.argument("part", type=click.Path(dir_okay=False))
@table_options("check")
def command(part: str, **params) -> int:
    """Deform closure of a contact set: release energy U_A and escape path, equilibrium,
    contact forces, rigid-closure order and certificate.

    PART is a part file (JSON), a drawing or a mesh file."""
    return run_report("check", part, params)
