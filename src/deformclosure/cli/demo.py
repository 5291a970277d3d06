"""``deformclosure demo``: the built-in rubber part, no input files needed."""

from __future__ import annotations

from pathlib import Path

import click

from ..elasticity import stiffness_matrix
from ..mesh import mesh_part
from ..part import demo_part

__all__ = ["command"]


@click.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="deformclosure-demo",
              show_default=True, help="Folder for the pictures and reports.")
def command(out_dir: str) -> int:
    """Run the pipeline on the built-in 12 × 20 mm rubber part and write pictures."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    part = demo_part()
    mat = part.material
    click.echo(f"part: {part.name}, 12 x 20 mm rubber, E = {mat.youngs_modulus / 1e6:g} MPa, "
               f"nu = {mat.poisson_ratio:g}, thickness = {mat.thickness * 1e3:g} mm, "
               f"e_L = {mat.elastic_limit_strain:g}, plane {mat.plane}")
    mesh = mesh_part(part)
    K = stiffness_matrix(mesh)
    click.echo(f"mesh: {mesh.summary()}")
    click.echo(f"stiffness: {K.shape[0]} x {K.shape[1]} sparse, {K.nnz} non-zeros")
    from ..plotting.mesh import save_mesh_plot

    save_mesh_plot(mesh, out / "mesh.png", units=part.units)
    click.echo(f"wrote {out / 'mesh.png'}")
    return 0
