"""``deformclosure plan``: rank every jaw pair of a part by grasp quality."""

from __future__ import annotations

import click
import numpy as np

from ..errors import GraspError
from ..units import length_scale
from .common import lazy_progress, pad_options, write_json
from .optimize import load_grasp_inputs

__all__ = ["command"]

EPILOG = """\b
Examples (pads, the default model, SPEC §6):
  deformclosure plan examples/notched_bar.json --pad-radius 2 --top 5 -o plan.json --plot plan/
\b
Paper model (every pair of perimeter nodes, point jaws, SPEC §4):
  deformclosure plan examples/c_shape.json --model paper --top 5 -o plan.json --plot plan/
  deformclosure plan examples/ring.json --model paper --expanding --eps 1e-5

\b
--pad-radius/--pad-width, --min-sep/--max-sep, --region and --jaw-width are in --units
(default: the part's); --eps is in joules (default: about 400 lattice values over the
separation range).
"""


@click.command(epilog=EPILOG)
@click.argument("part", type=click.Path(dir_okay=False))
@click.option("--model", type=click.Choice(["pads", "paper"]), default="pads", show_default=True,
              help="pads: grasp axes for rigid pads (SPEC §6); paper: node pairs (SPEC §4).")
@pad_options(angles=36, offsets=40)
@click.option("--top", type=int, default=10, show_default=True,
              help="Refine the best N pairs (paper) or axes (pads) with the exact method.")
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
def command(part, model, pad_radius, pad_width, grid_angles, grid_offsets, top, eps, expanding,
            jaw_width, min_sep, max_sep, region, units, output, plot, quiet) -> int:
    """Rank grasps of a part: grasp axes for pads (default) or jaw node pairs (paper)."""
    from ..outputs import check_outputs

    check_outputs([output], [plot], [part])
    if model == "pads":
        bad = [n for n, g in (("--eps", eps is not None), ("--expanding", expanding),
                              ("--jaw-width", jaw_width != 0.0), ("--min-sep", min_sep is not None),
                              ("--max-sep", max_sep is not None), ("--region", bool(region))) if g]
        if bad:
            raise GraspError(f"{bad[0]}: belongs to the paper model; add --model paper")
        return _pads(part, pad_radius, pad_width, grid_angles, grid_offsets, top, units, output,
                     plot, quiet)
    return _paper(part, top, eps, expanding, jaw_width, min_sep, max_sep, region, units, output,
                  plot, quiet)


def _pads(part, pad_radius, pad_width, grid_angles, grid_offsets, top, units, output, plot,
          quiet) -> int:
    from ..pads import PadContact
    from ..pads.noise import twin_mesh
    from ..pads.plan import plan_pads
    from .common import check_grid, load_part_or_mesh, pad_from_options

    if top < 0:
        raise GraspError(f"--top = {top}: must be >= 0")
    check_grid(grid_angles, grid_offsets)
    prt, mesh = load_part_or_mesh(part)
    unit = units if units is not None else ("m" if prt is None else prt.units)
    scale = length_scale(unit, "--units")
    pad = pad_from_options(pad_radius, pad_width, scale, mesh.diameter)
    progress, close = lazy_progress(quiet, "grasp axes", "axis")
    twin = PadContact(twin_mesh(prt)) if prt is not None else None
    try:
        res = plan_pads(mesh, pad, n_angles=grid_angles, n_offsets=grid_offsets, top=top,
                        twin=twin, progress=progress)
    finally:
        close()
    s = 1.0 / length_scale(unit)
    click.echo(f"{len(res.rows)} grasp axes (pads W = {pad.width * s:.4g}, rho = {pad.radius * s:.4g} {unit})")
    click.echo(f"{'rank':>4} {'angle':>7} {'contact A (' + unit + ')':>20} {'contact B':>18} "
               f"{'sigma*':>9} {'Q (J)':>11} {'verdict':>9} {'method':>8}")
    for i, r in enumerate(res.rows[:max(top, 5)]):
        ca, cb = (np.asarray(c) * s for c in r["contacts"])
        ss = "-" if r["sigma_star"] is None else f"{r['sigma_star'] * s:.4g}"
        click.echo(f"{i + 1:>4} {np.degrees(r['angle']):>6.1f}° {ca[0]:>9.4g},{ca[1]:<9.4g} "
                   f"{cb[0]:>8.4g},{cb[1]:<8.4g} {ss:>9} {r['quality']:>11.4g} {r['verdict']:>9} "
                   f"{r['method']:>8}")
    write_json(res.to_dict(), output)
    if plot:
        from pathlib import Path

        from ..plotting.mesh import save_figure
        from ..plotting.pads import plot_pad_plan

        out = Path(plot)
        out.mkdir(parents=True, exist_ok=True)
        ax = plot_pad_plan(res, mesh, units=unit if unit != "m" else "mm")
        save_figure(ax.figure, out / "top_axes.png")
        click.echo(f"wrote {out / 'top_axes.png'}")
    return 0


def _paper(part, top, eps, expanding, jaw_width, min_sep, max_sep, region, units, output, plot,
           quiet) -> int:
    """The paper's planner over node pairs (SPEC §4), unchanged."""
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
    progress, close = lazy_progress(quiet, "σ lattice", "σ")
    try:
        res = plan_grasps(mesh, eps=eps, mode="expanding" if expanding else "contracting",
                          jaw_width=jaw_width * scale, separation_range=rng, regions=boxes or None,
                          top=top, progress=progress)
    finally:
        close()
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
