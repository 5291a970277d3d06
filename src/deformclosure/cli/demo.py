"""``deformclosure demo``: what a frictionless gripper can and cannot hold (no input files).

Two built-in rubber parts (E = 2 MPa, nu = 0.1, e_L = 0.8, thickness 1 mm, plane stress)
between rigid round pads (SPEC §6), each solved on three meshes (h halving) with error
estimates and a verdict:

1. a 30 × 12 mm bar with a V-notch in each long side, pads (ρ = 2 mm) seated in the
   notches: held, and the answer converges;
2. the paper's 12 × 20 mm block, pads (ρ = 1 mm) across its width: not held — a convex
   part between frictionless pads slides out sideways.

Then the paper's own model (point jaws at mesh nodes, SPEC §4) on the block, whose
"optimal" quality falls with every refinement: why the pads are the default model.
"""

from __future__ import annotations

import click

__all__ = ["command"]


@click.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="deformclosure-demo",
              show_default=True, help="Folder for the pictures and the JSON report.")
def command(out_dir: str) -> int:
    """Notched bar held by round pads, block not held; the paper's model for contrast."""
    from ..outputs import check_outputs
    from ..reports.demo import demo

    check_outputs([], [out_dir], [])
    rep = demo(out_dir, emit=click.echo)
    for path in rep.save():
        click.echo(f"wrote {path}")
    return 0
