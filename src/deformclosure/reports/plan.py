"""``plan``: rank the grasps of a part, grasp axes for pads (SPEC §6, the default) or
every pair of perimeter nodes for the paper's point jaws (SPEC §4)."""

from __future__ import annotations

import numpy as np

from ..errors import GraspError
from .base import Report, provenance, write_report
from .inputs import (check_eps, check_grid, check_jaw_width, only_for, pad_from_options,
                     parse_numbers, read_inputs)

__all__ = ["run"]


def run(part, params: dict, progress=None, notify=None) -> Report:
    """Plan the grasps of ``part``; ``top`` best refined exactly; lengths in ``units``."""
    from ..plotting.pads import check_scale

    p = params
    p["scale"] = check_scale(p.get("scale", 1.0))
    if p["top"] < 0:
        raise GraspError(f"--top = {p['top']}: must be >= 0")
    if p["verify"] < 0:
        raise GraspError(f"--verify = {p['verify']}: must be >= 0 (0: screen only)")
    from ..pads.friction_grasp import check_friction, check_friction_model
    from ..pads.refine import check_accuracy

    check_accuracy(p["rtol"], p["max_seconds"])
    p["friction"] = check_friction(p.get("friction"))
    check_friction_model(p["friction"], p.get("elasticity"))
    if p["model"] == "pads":
        only_for("paper", [("--eps", p["eps"] is not None), ("--expanding", p["expanding"]),
                           ("--jaw-width", p["jaw_width"] != 0.0),
                           ("--min-sep", p["min_sep"] is not None),
                           ("--max-sep", p["max_sep"] is not None),
                           ("--region", bool(p["region"])),
                           ("--allow-pulling", p["allow_pulling"])], "add --model paper")
        return _pads(part, p, progress)
    only_for("pads", [("--verify", p["verify"] != 5), ("--rtol", p["rtol"] is not None),
                      ("--max-seconds", p["max_seconds"] is not None),
                      ("--friction", p["friction"] > 0)], "drop --model paper")
    return _paper(part, p, progress)


# ----------------------------------------------------------------------------- pads


def _pads(part, p: dict, progress) -> Report:
    from ..pads import PadContact
    from ..mesh.generate import twin_mesh
    from ..planning.pads import plan_pads
    from ..limits import holding, kept_bytes
    from ..pads.size_limits import WITH_TWIN, check_pads_size, search_axes

    check_grid(p["grid_angles"], p["grid_offsets"])
    inp = read_inputs(part, p["units"], p["material"], max_area=p["max_area"])
    # before the work: the plan's solvers and the curves of every axis of its grid
    est = check_pads_size(inp.mesh, solvers=1 if inp.part is None else WITH_TWIN,
                          n_axes=p["grid_angles"] * p["grid_offsets"])
    if p["verify"] and inp.part is not None:
        # the plan keeps its solvers and curves while it verifies: the verification's
        # first level (optimize's code path on a mesh like the plan's) must fit beside them
        try:
            with holding(kept_bytes(est)):
                check_pads_size(inp.mesh, solvers=WITH_TWIN,   # its grid: twice the angles
                                n_axes=search_axes(2 * p["grid_angles"], p["grid_offsets"]),
                                what="plan --verify (beside the plan's solvers and curves)")
        except GraspError as err:
            raise GraspError(f"{err}; or screen only (--verify 0)") from None
    pad = pad_from_options(p["pad_radius"], p["pad_width"], inp.scale, inp.mesh.diameter)
    from ..pads.friction_grasp import check_friction_model

    elasticity = p.get("elasticity") or getattr(inp.mesh.material, "model", "linear")
    check_friction_model(p["friction"], elasticity)
    twin = PadContact(twin_mesh(inp.part)) if inp.part is not None else None
    # the verification's later levels count what the plan keeps (limits.holding)
    with holding(kept_bytes(est)):
        res = plan_pads(inp.mesh, pad, n_angles=p["grid_angles"], n_offsets=p["grid_offsets"],
                        top=p["verify"], twin=twin, progress=progress, part=inp.part,
                        rtol=p["rtol"], max_seconds=p["max_seconds"], friction=p["friction"],
                        elasticity=elasticity)
    data = {**res.to_dict(), "provenance": provenance(inp.sources)}
    return Report("plan", data, _pads_lines(res, pad, p["top"], inp), inp.warnings, p,
                  (res, inp), _pads_writer)


def _clean(v: float, scale: float) -> float:
    """A printed coordinate without floating-point dust (``-9.2e-16`` → 0), relative to the
    part's size ``scale``."""
    return 0.0 if abs(v) < 1e-9 * scale else v


def _pads_lines(res, pad, top: int, inp) -> list[str]:
    s, unit = 1.0 / inp.scale, inp.unit
    size = inp.mesh.diameter * s
    nv = sum(r["verified"] for r in res.rows)
    lines = [f"{len(res.rows)} grasp axes (pads W = {pad.width * s:.4g}, rho = "
             f"{pad.radius * s:.4g} {unit}); {nv} verified, the others screened "
             f"(a screened row is a candidate, never 'held')"
             + (f"; friction mu = {res.friction:g}: verified rows rank by Q with the release "
                "work U_A^mu, the screening is frictionless" if res.friction > 0 else ""),
             f"{'rank':>4} {'--axis X,Y,DEG (' + unit + ')':>26} {'sigma*':>9} {'Q (J)':>11} "
             f"{'± (J)':>9} {'verdict':>10}"]
    for i, r in enumerate(res.rows[:max(top, 5)]):
        x, y = (_clean(v * s, size) for v in r["axis"]["point"])
        ax = f"{x:.4g},{y:.4g},{_clean(np.degrees(r['axis']['angle']), 360.0):.4g}"
        ss = "-" if r["sigma_star"] is None else f"{r['sigma_star'] * s:.4g}"
        err = (r.get("error_estimate") or {}).get("quality")
        es = "-" if err is None else f"{err:.3g}"
        lines.append(f"{i + 1:>4} {ax:>26} {ss:>9} {r['quality']:>11.4g} {es:>9} "
                     f"{r['verdict']:>10}")
    held = res.held
    if held:
        r = held[0]
        x, y = (_clean(v * s, size) for v in r["axis"]["point"])
        lines.append(f"best verified grasp: optimize --axis {x:.6g},{y:.6g},"
                     f"{_clean(np.degrees(r['axis']['angle']), 360.0):.6g} "
                     f"(Q* = {r['quality']:.4g} J)")
    else:
        lines.append("no verified axis holds the part (top is empty): "
                     + ("every verified candidate is 'not held' or 'undecided'" if nv
                        else "no candidate showed a barrier to verify"))
    return lines


def _pads_writer(rep: Report, report: bool) -> list[str]:
    write_report(rep, report)
    res, inp = rep.result
    if not rep.params["plot"]:
        return []
    from ..plotting.pads import save_pad_plan_plots

    return [str(w) for w in save_pad_plan_plots(res, inp.mesh, rep.params["plot"],
                                                units=inp.unit if inp.unit != "m" else "mm",
                                                scale=rep.params.get("scale", 1.0))]


# ----------------------------------------------------------------------------- paper


def _restrictions(p: dict, scale: float):
    """``--min-sep``/``--max-sep`` as a range (m) and ``--region`` boxes (m)."""
    rng = None
    if p["min_sep"] is not None or p["max_sep"] is not None:
        rng = ((p["min_sep"] or 0.0) * scale,
               (p["max_sep"] if p["max_sep"] is not None else np.inf) * scale)
    boxes = [tuple(v * scale for v in parse_numbers(r, 4, f"--region {r!r}", "X0,Y0,X1,Y1"))
             for r in p["region"]]
    return rng, boxes


def _paper(part, p: dict, progress) -> Report:
    """The paper's planner over node pairs (SPEC §4), every pair within ε."""
    from ..grasp.size_limits import check_paper_size
    from ..planning.plan import plan_grasps

    check_eps(p["eps"])
    check_jaw_width(p["jaw_width"])
    inp = read_inputs(part, p["units"], p["material"], max_area=p["max_area"])
    mode = "expanding" if p["expanding"] else "contracting"
    restricted = bool(p["region"]) or p["min_sep"] is not None or p["max_sep"] is not None
    check_paper_size(inp.mesh, mode=mode, plan=True, restricted=restricted)
    rng, boxes = _restrictions(p, inp.scale)
    res = plan_grasps(inp.mesh, eps=p["eps"], mode=mode, jaw_width=p["jaw_width"] * inp.scale,
                      separation_range=rng, regions=boxes or None, top=p["top"],
                      progress=progress, allow_pulling=p["allow_pulling"])
    data = {**res.to_dict(), "provenance": provenance(inp.sources)}
    return Report("plan", data, paper_table(res, p["top"], inp.unit), inp.warnings, p,
                  (res, inp), _paper_writer)


def _paper_writer(rep: Report, report: bool) -> list[str]:
    write_report(rep, report)
    res, inp = rep.result
    if not rep.params["plot"]:
        return []
    from ..plotting.grasp import save_plan_plots

    return [str(w) for w in save_plan_plots(res, rep.params["plot"],
                                            units=inp.unit if inp.unit != "m" else "mm")]


def paper_table(res, top: int, unit: str) -> list[str]:
    """The ranking as a table: jaw nodes and positions, how each row was settled, the
    pairs whose jaws would pull, and which rows are the exact ``top`` list."""
    from ..units import length_scale

    s = 1.0 / length_scale(unit)
    c = res.settled_counts()
    lines = [f"{len(res.pairs)} jaw pairs, every quality within ε = {res.epsilon:.3g} J of its "
             f"optimum ({c['zero']} never held, {c['bounds']} by bounds, {c['exact']} exact; "
             f"{res.n_sigma} shared σ values)"]
    in_top = {tuple(int(v) for v in r.jaws): n + 1 for n, r in enumerate(res.refined)}
    keys = [tuple(int(v) for v in p) for p in res.pairs]
    shown = set(range(min(max(top, 5), len(res.pairs))))
    shown |= {i for i, key in enumerate(keys) if key in in_top}     # top rows further down
    lines.append(f"{'rank':>4} {'a':>6} {'b':>6} {f'jaw a ({unit})':>18} {'jaw b':>18} "
                 f"{f'sigma* ({unit})':>12} {'Q (J)':>11} {'settled':>7} {'top':>4}  pulls")
    prev = -1
    for i in sorted(shown):
        if i != prev + 1:
            lines.append(f"{'...':>4}")
        prev = i
        a, b = keys[i]
        (ax, ay), (bx, by) = res.jaw_xy[i] * s
        ss = "-" if np.isnan(res.sigma_star[i]) else f"{res.sigma_star[i] * s:.5g}"
        t = in_top.get((a, b))
        lines.append(f"{i + 1:>4} {a:>6} {b:>6} {ax:>8.4g},{ay:<9.4g} {bx:>8.4g},{by:<9.4g} "
                     f"{ss:>12} {res.quality[i]:>11.5g} {res.settled[i]:>7} "
                     f"{'#' + str(t) if t else '':>4}  {'PULLS' if res.pulls[i] else ''}")
    if any(res.pulls[i] for i in shown):
        lines.append("PULLS: the jaw line leaves the part at a jaw (the jaw would have to pull)"
                     + ("." if res.allow_pulling else "; kept out of the top list "
                                                      "(--allow-pulling to keep them)."))
    return lines
