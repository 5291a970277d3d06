"""``deformclosure plan``: rank every jaw pair of a part by grasp quality."""

from __future__ import annotations

import click
import numpy as np

from ..errors import GraspError
from ..limits import check_model_size, limits_help
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
@click.option("--model", type=click.Choice(["pads", "paper"]), default="pads", show_default=True,
              help="pads: grasp axes for rigid pads (SPEC §6); paper: node pairs (SPEC §4).")
@pad_options(angles=36, offsets=40)
@click.option("--top", type=int, default=10, show_default=True,
              help="Refine the best N pairs (paper) or axes (pads) with the exact method.")
@click.option("--eps", type=float, default=None,
              help="paper: every pair's quality within eps of its optimum, in joules.")
@click.option("--allow-pulling", is_flag=True,
              help="paper: let pairs whose jaws would have to pull into the top list.")
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
def command(part, model, pad_radius, pad_width, grid_angles, grid_offsets, top, eps,
            allow_pulling, expanding, jaw_width, min_sep, max_sep, region, units, output, plot,
            quiet) -> int:
    """Rank grasps of a part: grasp axes for pads (default) or jaw node pairs (paper)."""
    from ..outputs import check_outputs

    check_outputs([output], [plot], [part])
    if model == "pads":
        bad = [n for n, g in (("--eps", eps is not None), ("--expanding", expanding),
                              ("--jaw-width", jaw_width != 0.0), ("--min-sep", min_sep is not None),
                              ("--max-sep", max_sep is not None), ("--region", bool(region)),
                              ("--allow-pulling", allow_pulling)) if g]
        if bad:
            raise GraspError(f"{bad[0]}: belongs to the paper model; add --model paper")
        return _pads(part, pad_radius, pad_width, grid_angles, grid_offsets, top, units, output,
                     plot, quiet)
    return _paper(part, top, eps, expanding, jaw_width, min_sep, max_sep, region, units, output,
                  plot, quiet, allow_pulling)


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
    check_model_size(mesh, "pads", solvers=1 if prt is None else 2,  # before the work
                     n_axes=grid_angles * grid_offsets)
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
        save_figure(plot_pad_plan(res, mesh, units=unit if unit != "m" else "mm"),
                    out / "top_axes.png")
        click.echo(f"wrote {out / 'top_axes.png'}")
    return 0


def _paper(part, top, eps, expanding, jaw_width, min_sep, max_sep, region, units, output, plot,
           quiet, allow_pulling=False) -> int:
    """The paper's planner over node pairs (SPEC §4), every pair within ε."""
    from ..planning.plan import plan_grasps

    if eps is not None and not (np.isfinite(eps) and eps > 0):
        raise GraspError(f"--eps = {eps!r}: must be a finite energy > 0 in joules")
    if top < 0:
        raise GraspError(f"--top = {top}: must be >= 0")
    if not (np.isfinite(jaw_width) and jaw_width >= 0):
        raise GraspError(f"--jaw-width = {jaw_width!r}: must be a finite length >= 0 (0 = point jaws)")
    mesh, unit, scale, _ = load_grasp_inputs(part, None, units)
    check_model_size(mesh, "paper", mode="expanding" if expanding else "contracting", plan=True,
                     restricted=bool(region) or min_sep is not None or max_sep is not None)
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
    progress, close = lazy_progress(quiet, "σ lattice, then pairs", "step")
    try:
        res = plan_grasps(mesh, eps=eps, mode="expanding" if expanding else "contracting",
                          jaw_width=jaw_width * scale, separation_range=rng, regions=boxes or None,
                          top=top, progress=progress, allow_pulling=allow_pulling)
    finally:
        close()
    _print_paper_table(res, top, unit)
    write_json(res.to_dict(), output)
    if plot:
        from ..plotting.grasp import save_plan_plots

        for pth in save_plan_plots(res, plot, units=unit if unit != "m" else "mm"):
            click.echo(f"wrote {pth}")
    return 0


def _print_paper_table(res, top: int, unit: str) -> None:
    """The ranking as a table: jaw nodes and positions, how each row was settled, the
    pairs whose jaws would pull, and which rows are the exact ``top`` list."""
    s = 1.0 / length_scale(unit)
    c = res.settled_counts()
    click.echo(f"{len(res.pairs)} jaw pairs, every quality within ε = {res.epsilon:.3g} J of its "
               f"optimum ({c['zero']} never held, {c['bounds']} by bounds, {c['exact']} exact; "
               f"{res.n_sigma} shared σ values)")
    in_top = {tuple(int(v) for v in r.jaws): n + 1 for n, r in enumerate(res.refined)}
    keys = [tuple(int(v) for v in p) for p in res.pairs]
    shown = set(range(min(max(top, 5), len(res.pairs))))
    shown |= {i for i, key in enumerate(keys) if key in in_top}     # top rows further down
    pos = f"jaw a ({unit})"
    sig = f"sigma* ({unit})"
    click.echo(f"{'rank':>4} {'a':>6} {'b':>6} {pos:>18} {'jaw b':>18} {sig:>12} {'Q (J)':>11} "
               f"{'settled':>7} {'top':>4}  pulls")
    prev = -1
    for i in sorted(shown):
        if i != prev + 1:
            click.echo(f"{'...':>4}")
        prev = i
        a, b = keys[i]
        (ax, ay), (bx, by) = res.jaw_xy[i] * s
        ss = "-" if np.isnan(res.sigma_star[i]) else f"{res.sigma_star[i] * s:.5g}"
        t = in_top.get((a, b))
        click.echo(f"{i + 1:>4} {a:>6} {b:>6} {ax:>8.4g},{ay:<9.4g} {bx:>8.4g},{by:<9.4g} {ss:>12} "
                   f"{res.quality[i]:>11.5g} {res.settled[i]:>7} {'#' + str(t) if t else '':>4}  "
                   f"{'PULLS' if res.pulls[i] else ''}")
    if any(res.pulls[i] for i in shown):
        click.echo("PULLS: the jaw line leaves the part at a jaw (the jaw would have to pull)"
                   + ("." if res.allow_pulling else "; kept out of the top list (--allow-pulling "
                                                      "to keep them)."))
