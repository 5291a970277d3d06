"""``deformclosure plan``: rank every jaw pair of a part by grasp quality."""

from __future__ import annotations

import click
import numpy as np
from tqdm import tqdm

from ..errors import GraspError
from ..units import length_scale
from .common import parse_xy, write_json
from .optimize import load_grasp_inputs

__all__ = ["command"]

EPILOG = """\b
Examples:
  deformclosure plan examples/c_shape.json --top 5 -o plan.json --plot plan/
  deformclosure plan examples/ring.json --expanding --eps 1e-5

\b
--eps is in joules (default: about 400 lattice values over the separation range);
--min-sep/--max-sep, --region and --jaw-width are in --units (default: the part's).
"""


@click.command(epilog=EPILOG)
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("--top", type=int, default=10, show_default=True,
              help="Refine the best N pairs with the exact method.")
@click.option("--eps", type=float, default=None, help="ε of the shared σ lattice, in joules.")
@click.option("--expanding", is_flag=True, help="Jaws push outward (e.g. from inside a hole).")
@click.option("--jaw-width", type=float, default=0.0, show_default=True,
              help="Jaw contact width in --units (0 = point jaws).")
@click.option("--min-sep", type=float, default=None, help="Smallest rest distance of a pair, in --units.")
@click.option("--max-sep", type=float, default=None, help="Largest rest distance of a pair, in --units.")
@click.option("--region", multiple=True, metavar="X0,Y0,X1,Y1",
              help="Allowed box for both jaws (repeatable; union), in --units.")
@click.option("--units", type=str, default=None, help="Unit of lengths given here (m, cm, mm, in).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="JSON report (SI units).")
@click.option("--plot", type=click.Path(file_okay=False), help="Folder for the quality map and top grasps.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def command(part, top, eps, expanding, jaw_width, min_sep, max_sep, region, units, output, plot,
            quiet) -> int:
    """Rank all jaw pairs of a part by ε-optimal quality; refine the top ones exactly."""
    from ..planning.plan import plan_grasps

    if eps is not None and not (np.isfinite(eps) and eps > 0):
        raise GraspError(f"--eps = {eps!r}: must be a finite energy > 0 in joules")
    if top < 0:
        raise GraspError(f"--top = {top}: must be >= 0")
    if not (np.isfinite(jaw_width) and jaw_width >= 0):
        raise GraspError(f"--jaw-width = {jaw_width!r}: must be a finite length >= 0 (0 = point jaws)")
    mesh, unit, scale, _ = load_grasp_inputs(part, None, units)
    rng = None
    if min_sep is not None or max_sep is not None:
        rng = ((min_sep or 0.0) * scale, (max_sep if max_sep is not None else np.inf) * scale)
    boxes = []
    for r in region:
        try:
            x0, y0, x1, y1 = (float(v) * scale for v in r.split(","))
        except ValueError:
            raise GraspError(f"--region {r!r}: expected X0,Y0,X1,Y1 (four numbers)") from None
        boxes.append((x0, y0, x1, y1))
    bar = None  # created at the first lattice value, so input errors print no bar

    def progress(done: int, total: int) -> None:
        nonlocal bar
        if quiet:
            return
        if bar is None:
            bar = tqdm(total=total, desc="σ lattice", unit="σ", leave=False)
        bar.update(done - bar.n)

    try:
        res = plan_grasps(mesh, eps=eps, mode="expanding" if expanding else "contracting",
                          jaw_width=jaw_width * scale, separation_range=rng, regions=boxes or None,
                          top=top, progress=progress)
    finally:
        if bar is not None:
            bar.close()
    s = 1.0 / length_scale(unit)
    click.echo(f"{len(res.pairs)} jaw pairs, ε = {res.epsilon:.3g} J on {res.n_sigma} σ values")
    click.echo(f"{'rank':>4} {'a':>6} {'b':>6} {'sigma* (' + unit + ')':>14} {'Q (J)':>12} {'method':>8}")
    for i in range(min(max(top, 5), len(res.pairs))):
        a, b = (int(v) for v in res.pairs[i])
        ss = None if np.isnan(res.sigma_star[i]) else res.sigma_star[i]
        q, meth = res.quality[i], "exact" if res.exact[i] else "approx"
        sss = "-" if ss is None else f"{ss * s:.5g}"
        click.echo(f"{i + 1:>4} {a:>6} {b:>6} {sss:>14} {q:>12.5g} {meth:>8}")
    write_json(res.to_dict(), output)
    if plot:
        from ..plotting.grasp import save_plan_plots

        for pth in save_plan_plots(res, plot, units=unit if unit != "m" else "mm"):
            click.echo(f"wrote {pth}")
    return 0
