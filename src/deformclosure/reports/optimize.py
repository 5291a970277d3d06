"""``optimize``: the optimal separation σ* of one two-jaw grasp, with pads (SPEC §6, the
default) or with the paper's point jaws at mesh nodes (SPEC §4, for reproduction)."""

from __future__ import annotations

import numpy as np

from ..errors import GraspError
from .base import Report, provenance, write_report
from .inputs import (check_eps, check_grid, check_jaw_width, only_for, pad_from_options,
                     parse_numbers, parse_xy, read_inputs)

__all__ = ["run", "parse_axis", "paper_state"]


def run(part, params: dict, progress=None, notify=None) -> Report:
    """Optimise one grasp. ``model`` defaults to ``pads`` (``paper`` when ``jaws`` is
    given); lengths in ``units`` (default the part's); ``eps`` in J."""
    from ..fields import check_field_path

    from ..plotting.animate import check_animate
    from ..plotting.pads import check_scale

    p = params
    if p["export_fields"] is not None:
        check_field_path(p["export_fields"])
    p["scale"] = check_scale(p.get("scale", 1.0))
    model = p["model"] or ("paper" if p["jaws"] is not None else "pads")
    if p.get("animate"):
        if model == "paper":
            raise GraspError("--animate: animates the pads model's escape path; drop it for "
                             "--model paper / --jaws (its pictures are in --plot)")
        check_animate(p)
    _check_friction_request(p, model)
    if p.get("elasticity") == "neo-hookean" and model == "paper":
        raise GraspError("--elasticity neo-hookean: only with the pads model (SPEC §8); drop "
                         "--model paper / --jaws")
    if model == "paper":
        return _paper(part, p)
    only_for("paper", [("--jaws", p["jaws"] is not None), ("--jaw-width", p["jaw_width"] != 0.0),
                       ("--eps", p["eps"] is not None),
                       ("--export-graph", p["export_graph"] is not None),
                       ("--method", p["method"] != "exact")],
             "add --model paper, or give the pads an axis with --at X,Y X,Y or --axis X,Y,DEG")
    return _pads(part, p, notify)


def parse_axis(at, axis, scale: float):
    """The grasp axis from ``--at X,Y X,Y`` or ``--axis X,Y,DEG`` (lengths × ``scale`` → m)."""
    from ..pads import GraspAxis

    if (at is None) == (axis is None):
        raise GraspError("axis: give exactly one of --at X,Y X,Y (two points on the closing axis) "
                         "or --axis X,Y,DEG (a point and the closing direction in degrees)")
    if at is not None:
        p, q = (np.array(parse_xy(v, "--at")) * scale for v in at)
        return GraspAxis.through(p, q)
    x, y, deg = parse_numbers(axis, 3, "--axis", "X,Y,DEG")
    return GraspAxis.at(np.array([x, y]) * scale, np.radians(deg))


def _axis_start(at, axis, scale: float):
    """Where expanding pads start: the --at mid-point or the --axis point (m)."""
    if at is not None:
        return 0.5 * sum(np.array(parse_xy(v, "--at")) for v in at) * scale
    return np.array(parse_numbers(axis, 3, "--axis", "X,Y,DEG")[:2]) * scale


# ----------------------------------------------------------------------------- pads


def _pads(part, p: dict, notify) -> Report:
    from ..pads import pad_grasp
    from ..pads.size_limits import WITH_TWIN, check_pads_size, level_axes

    check_grid(p["grid_angles"], p["grid_offsets"])
    inp = read_inputs(part, p["units"], p["material"], max_area=p["max_area"])
    rtol, refine, warnings = accuracy_request(p, inp.part is None)
    # --refine N: the finest level's curves, its saddle patches one per earlier level
    last = (refine or 1) - 1
    check_pads_size(inp.mesh, solvers=1 if inp.part is None else WITH_TWIN, refine=refine or 1,
                    n_axes=level_axes(p["grid_angles"], p["grid_offsets"], last, last))
    scale = inp.scale
    ax = parse_axis(p["at"], p["axis"], scale)
    pad = pad_from_options(p["pad_radius"], p["pad_width"], scale, inp.mesh.diameter)

    def progress(k: int, n: int) -> None:
        if notify is not None and n > 1:
            notify(f"level {k + 1} ..." if rtol is not None else f"mesh {k + 1} of {n} ...")

    start = _axis_start(p["at"], p["axis"], scale) if p["expanding"] else None
    res = pad_grasp(inp.part, ax, pad, mesh=inp.mesh, refine=refine, rtol=rtol,
                    max_seconds=p["max_seconds"], adaptive=not p.get("uniform", False),
                    progress=progress, expanding_from=start, n_angles=p["grid_angles"],
                    n_offsets=p["grid_offsets"])
    elasticity = p.get("elasticity") or getattr(inp.mesh.material, "model", "linear")
    if p["friction"] > 0:
        from ..pads.friction_grasp import check_friction_model

        check_friction_model(p["friction"], elasticity)
    if elasticity == "neo-hookean":
        from ..pads.finite_strain_grasp import finite_strain_levels

        if notify is not None:
            notify("finite strain (neo-Hookean) ...")
        res = finite_strain_levels(res, "neo-hookean", rtol, max_seconds=p["max_seconds"])
    fdata, friction_lines = None, []
    if p["friction"] > 0:
        res, fdata, friction_lines = _with_friction(res, p["friction"], notify,
                                                    p["max_seconds"])
    data = {**(res.to_dict() if fdata is None else fdata), "provenance": provenance(inp.sources)}
    lines = _pads_lines(res, data, pad, inp.unit, scale)
    lines[-1:-1] = friction_lines
    rep = Report("optimize", data, lines,
                 inp.warnings + warnings + list(res.finest.warnings) + refinement_warnings(res),
                 p, res, _pads_writer(inp))
    return rep


# ----------------------------------------------------------------------------- friction


def _check_friction_request(p: dict, model: str) -> None:
    """``--friction μ``: a finite μ ≥ 0; with μ > 0 only the linear pads model (SPEC §9)."""
    from ..pads.friction_grasp import check_friction, check_friction_model

    mu = p["friction"] = check_friction(p.get("friction"))
    if mu == 0.0:
        return
    if model == "paper":
        raise GraspError("--friction: the paper model (SPEC §4) is frictionless; drop "
                         "--model paper / --jaws, or use --friction 0")
    check_friction_model(mu, p.get("elasticity"))


def _with_friction(res, mu: float, notify, max_seconds: float | None = None):
    """The refined grasp read with friction μ (:mod:`deformclosure.pads.friction_grasp`)
    and its summary lines (hold at σ*, the release work's dissipation)."""
    from ..pads.friction_grasp import frictional_refined

    if notify is not None:
        notify(f"friction mu = {mu:g}: release work with dissipation ...")
    fr = frictional_refined(res, mu, max_seconds=max_seconds)
    data = fr.to_dict()
    return fr.refined, data, friction_lines(data)


#: Standard gravity (m/s²), for the hold force as a mass held against gravity.
G0 = 9.80665


def friction_lines(data: dict) -> list[str]:
    """The printed friction summary: the hold at σ* (the cross-axis force as the mass it
    carries against gravity; where the small-displacement hold is unbounded — round pads
    wedge the part, a block jams under torque — the friction-exhausted ``slide`` load is
    printed and marked so) and the release work's dissipation."""
    lines = []
    hold = data.get("hold")
    if hold is not None and hold.get("force") is not None:
        def num(x: float) -> str:
            return f"{x + 0.0:+.4g}"          # no "-0"

        def show(key: str, unit: str) -> str:
            """``f− .. f+`` per direction: the value, or for a geometric entry the
            friction-exhausted ``slide`` load, marked."""
            kinds, parts, notes = hold["limited_by"][key], [], set()
            for j, k in enumerate(kinds):
                v, sl = hold[key][j], hold["slide"][key][j]
                if k == "geometry":
                    parts.append(("-inf" if j == 0 else "+inf") if sl is None else num(sl))
                    notes.add("until friction is exhausted; beyond: wedged, no gross slip"
                              if sl is not None else "no gross slip: jammed or seated")
                elif v is None:
                    parts.append("?")
                    notes.add(f"{k}: not computed")
                else:
                    parts.append(num(v))
                    if k == "unbalanced":
                        notes.add("not held at zero load: unbalanced")
            return f"{parts[0]} .. {parts[1]} {unit}" + "".join(f" ({n})" for n in sorted(notes))

        f = [v if k != "geometry" else sl for v, sl, k in
             zip(hold["force"], hold["slide"]["force"], hold["limited_by"]["force"])]
        carries = ("" if None in f else
                   f", i.e. {min(abs(f[0]), abs(f[1])) / G0 * 1e3 + 0.0:.4g} g against gravity")
        lines.append(f"hold at sigma* (mu = {data['friction']:g}): across the axis "
                     f"{show('force', 'N')}{carries}; torque {show('torque', 'N*m')}")
        if any(k == "budget" for v in hold["limited_by"].values() for k in v):
            lines.append("hold at sigma*: TRUNCATED, the time budget (--max-seconds) was "
                         "spent first")
    elif hold is not None:
        lines.append(f"hold at sigma*: not computed ({hold['reason']})")
    stage = data.get("friction_stage") or {}
    if stage.get("stopped"):
        lines.append(f"friction stage STOPPED EARLY after {stage['seconds']:.0f} s (budget "
                     f"{stage['max_seconds']:g} s, --max-seconds): "
                     f"{stage['stopped'].removeprefix('friction: ')}; sigma* "
                     "and Q* are the best of the separations evaluated"
                     + (", U_A only a lower bound" if data.get("U_A_lower_bound") else ""))
    dis = data.get("dissipation")
    fl = data["frictionless"]
    lines.append(f"release work with friction: U_A = "
                 f"{'infinite' if data['U_A_infinite'] else format(data['U_A'], '.6g') + ' J'}"
                 + ("" if dis is None else f", {dis:.4g} J dissipated along the escape path "
                    f"({len(data['escape_path'])} axes)")
                 + f"; frictionless: Q* = {fl['quality']:.4g} J, {fl['verdict']}")
    return lines


def accuracy_request(p: dict, mesh_file: bool) -> tuple[float | None, int | None, list[str]]:
    """``(rtol, refine, warnings)`` of a pads command: ``--rtol`` (default 0.05) or
    ``--refine N``; a mesh file cannot be refined, so it is solved once, with a warning."""
    from ..pads.refine import DEFAULT_RTOL

    rtol, refine = p.get("rtol"), p.get("refine")
    if rtol is not None and refine is not None:
        raise GraspError("--refine and --rtol: give one (--refine N solves N uniform levels; "
                         "--rtol R refines until the error estimate is within R)")
    if p.get("uniform") and refine is not None:
        raise GraspError("--uniform: only with --rtol (--refine N is uniform already)")
    if mesh_file:
        if rtol is not None:
            raise GraspError("--rtol: needs a part file (a mesh file cannot be re-meshed); "
                             "give the part, or drop --rtol to solve the mesh once")
        return None, refine, ["a mesh file cannot be refined: one mesh, no error estimate "
                              "(give a part file for an answer to --rtol)"] if refine is None else []
    if refine is None and rtol is None:
        rtol = DEFAULT_RTOL
    return rtol, refine, []


def refinement_warnings(res) -> list[str]:
    """Warnings of a refinement that stopped before its accuracy, or that has none."""
    import math

    out = []
    if res.rtol is not None and not res.converged:
        why = f" ({res.stopped})" if res.stopped else ""
        out.append(f"not converged to --rtol {res.rtol:g}{why}: the verdict stands only if "
                   "its error bounds decide it; raise --max-seconds or --rtol")
    fine, e = res.finest, res.error_estimate()["U_A"]
    if e is not None and math.isfinite(fine.U_A) and fine.U_A > 0 \
            and fine.U_A - e <= fine.noise < fine.U_A + e and res.verdict == "undecided":
        out.append(f"the verdict hangs on the noise floor: U_A = {fine.U_A:.3g} ± {e:.3g} J "
                   f"straddles the floor {fine.noise:.3g} J (energy differences the mesh does "
                   "not resolve); refine further (a smaller --rtol) to decide it")
    return out


def _pads_lines(res, data: dict, pad, unit: str, scale: float) -> list[str]:
    """The summary printed for people, lengths in the part's units."""
    fine, s = res.finest, 1.0 / scale
    lines = [f"model: pads, W = {pad.width * s:.4g} {unit}, rho = {pad.radius * s:.4g} {unit}; "
             f"axis through ({_clean(fine.axis.point[0] * s)}, {_clean(fine.axis.point[1] * s)}) "
             f"{unit} at {_clean(np.degrees(fine.axis.angle))} deg",
             f"sigma0 = {fine.sigma0 * s:.6g} {unit}  sigma_L = {fine.sigma_L * s:.6g} {unit}  "
             f"(critical distance {fine.limit.critical_distance * s:.3g} {unit})"]
    if fine.sigma_star is None:
        lines.append("Q = 0 on the whole range: no barrier above the noise floor "
                     f"({fine.noise_relative:.2%} of U)")
    else:
        ua = "infinite" if np.isinf(fine.U_A) else f"{fine.U_A:.6g} J"
        lines.append(f"sigma* = {fine.sigma_star * s:.6g} {unit}  Q* = {fine.quality:.6g} J  "
                     f"U_A = {ua}  U_L = {fine.U_L:.6g} J  (noise floor {fine.noise:.3g} J)")
        stiff = "-" if fine.stiffness is None else f"{fine.stiffness:.4g}"
        lines.append(f"grip force at sigma* = {fine.force:.4g} N  (stiffness {stiff} N/m)")
    if data.get("elasticity") == "neo-hookean":
        lin, err = data["linear"], data["linear_model_error"]
        ls = "-" if lin["sigma_star"] is None else f"{lin['sigma_star'] * s:.6g} {unit}"
        lines.append(f"neo-Hookean (finite strain, exact pad contact); the linear model at the "
                     f"same grasp: sigma* = {ls}, Q* = {lin['quality']:.6g} J; linear model "
                     f"error: U {_pct(err['U'])}, F {_pct(err['F'])}, Q* {_pct(err['quality'])}, "
                     f"sigma* {_pct(err['sigma_star'])}")
    if len(data["convergence"]) > 1:
        lines.append(f"{'level':>5} {'nodes':>7} {'grid x':>6} {'sigma* (' + unit + ')':>14} "
                     f"{'Q* (J)':>12} {'U_A (J)':>12}")
        for row in data["convergence"]:
            ss = "-" if row["sigma_star"] is None else f"{row['sigma_star'] * s:.6g}"
            ua = "infinite" if row["U_A_infinite"] else f"{row['U_A']:.5g}"
            lines.append(f"{row['level']:>5} {row['nodes']:>7} {row['grid']['refinement']:>6} "
                         f"{ss:>14} {row['quality']:>12.5g} {ua:>12}")
        e = data["error_estimate"]
        es = "-" if e["sigma_star"] is None else f"{e['sigma_star'] * s:.3g} {unit}"
        how = data["refinement"]
        target = f", target rtol {res.rtol:g}" if res.rtol is not None else ""
        lines.append(f"error estimate ({how} refinement, mesh and landscape{target}): "
                     f"Q* ± {e['quality']:.3g} J, U_A ± {_fmt(e['U_A'])} J, sigma* ± {es}; "
                     f"converged: {'yes' if data['converged'] else 'no'}")
    lines.append(f"verdict: {data['verdict'].upper()}")
    return lines


def _pct(x) -> str:
    return "-" if x is None else f"{x:+.1%}"


def _fmt(x) -> str:
    return "-" if x is None else f"{x:.3g}"


def _clean(x: float) -> str:
    """A coordinate for people: 4 significant digits, no floating-point dust (-0, 1e-16)."""
    v = float(x)
    if abs(v) < 1e-9:
        v = 0.0
    return f"{v:.4g}"


def _pads_writer(inp):
    from ..plotting.animate import check_animate

    def write(rep: Report, report: bool) -> list[str]:
        write_report(rep, report)
        fine, p, written = rep.result.finest, rep.params, []
        if p["export_fields"]:
            states = [fine.state_at(sig, label) for label, sig in
                      _field_sigmas(p["export_fields"], fine.sigma0, fine.sigma_L,
                                    fine.sigma_star)]
            from ..fields import write_fields

            written += write_fields(p["export_fields"], fine.solver.mesh, states,
                                    fine.limit.critical_distance)
        if p["plot"]:
            from ..plotting.pads import save_pad_plots

            # finite strain: its own state and curves; the escape strip is the linear twin's
            written += save_pad_plots(fine, inp.mesh, p["plot"],
                                      units=inp.unit if inp.unit != "m" else "mm",
                                      scale=p.get("scale", 1.0),
                                      convergence=rep.data.get("convergence"))
        gif = check_animate(p)
        if gif is not None:
            from ..plotting.animate import pad_escape_animation

            done = pad_escape_animation(fine, gif, units=inp.unit if inp.unit != "m" else "mm",
                                        scale=p.get("scale", 1.0))
            if done is None:
                rep.warnings.append("--animate: no escape path to animate (Q* = 0, or U_A "
                                    "infinite); no GIF written")
            else:
                written.append(done)
        return [str(w) for w in written]

    return write


# ----------------------------------------------------------------------------- paper


def _paper_inputs(part, p: dict):
    """The mesh with the --at points inserted as nodes, the jaw nodes, and the inputs."""
    at = p["at"]
    inp = read_inputs(part, p["units"], p["material"], mesh=False,   # a mesh file: its mesh
                      max_area=p["max_area"])
    pts = None if not at else np.array([parse_xy(v, "--at") for v in at]) * inp.scale
    if inp.part is not None:
        _check_near(inp, pts, at)
        inp.mesh = _mesh_with_jaws(inp, pts, at)
    if pts is not None:
        jaws = tuple(inp.mesh.find_node(q, tol=1e-6 * inp.mesh.diameter) for q in pts)
    else:
        jaws = tuple(p["jaws"])
    return inp, jaws


def _check_near(inp, pts, at) -> None:
    if pts is None:
        return
    far = 100 * inp.part.diameter + float(np.abs(inp.part.outer).max())
    if np.abs(pts).max() > far:
        raise GraspError(f"--at: a jaw position is far outside the part ({', '.join(at)} "
                         f"{inp.unit}); check the values and --units")


def _mesh_with_jaws(inp, pts, at):
    from ..mesh import mesh_part
    from ..part import PartError

    try:
        return mesh_part(inp.part, points=pts)
    except PartError as err:   # name the option, not the mesher's internal point list
        if "points[" not in str(err):
            raise
        raise GraspError(f"--at: a jaw position lies outside the part "
                         f"({', '.join(at)} {inp.unit}); move it onto the part's boundary") from None


def _paper(part, p: dict) -> Report:
    """The paper's two-jaw model (SPEC §4), unchanged."""
    from ..grasp.analysis import grasp_model, optimize_separation
    from ..grasp.size_limits import check_paper_size

    if (p["jaws"] is None) == (p["at"] is None):
        raise GraspError("jaws: give exactly one of --jaws A B (node ids) or --at X,Y X,Y (positions)")
    for flag, key in (("--rtol", "rtol"), ("--refine", "refine"), ("--max-seconds", "max_seconds")):
        if p.get(key) is not None:
            raise GraspError(f"{flag}: the paper model (SPEC §4) is exact on its mesh and is "
                             "not refined; drop it, or use the pads model (SPEC §6)")
    check_eps(p["eps"])
    check_jaw_width(p["jaw_width"])
    inp, jaws = _paper_inputs(part, p)
    mesh, mode = inp.mesh, "expanding" if p["expanding"] else "contracting"
    check_paper_size(mesh, mode=mode)
    width = p["jaw_width"] * inp.scale
    if width > mesh.diameter:
        raise GraspError(f"--jaw-width = {p['jaw_width']:g} {inp.unit}: wider than the part "
                         f"({mesh.diameter / inp.scale:.4g} {inp.unit}); check the value and --units")
    model = grasp_model(mesh, mode=mode, jaw_width=width)
    res = optimize_separation(mesh, jaws, method=p["method"], eps=p["eps"], mode=mode,
                              jaw_width=width, model=model)
    data = {**res.to_dict(), "provenance": provenance(inp.sources)}
    return Report("optimize", data, _paper_lines(res, data, jaws, p["method"], inp),
                  inp.warnings, p, res, _paper_writer(inp, jaws, model))


def _paper_lines(res, data: dict, jaws, method: str, inp) -> list[str]:
    s, unit, lim = 1.0 / inp.scale, inp.unit, res.limit
    lines = [f"jaws: nodes {jaws[0]}, {jaws[1]}  sigma0 = {lim.sigma0 * s:.6g} {unit}  "
             f"k01 = {lim.k01:.6g} N/m  e_max = {lim.e_max:.6g} 1/m",
             f"sigma_L = {lim.sigma_L * s:.6g} {unit}"]
    if res.sigma_star is None:
        lines.append("this jaw pair cannot hold the part: Q = 0 on the whole range")
    else:
        ua = ("infinite (no other equilibrium reachable)" if data["U_A_infinite"]
              else f"{data['U_A']:.6g} J")
        lines.append(f"sigma* = {res.sigma_star * s:.6g} {unit}  Q* = {res.quality:.6g} J  "
                     f"U_A = {ua}  U_L = {data['U_L']:.6g} J  ({method}, "
                     f"{res.separation.n_evaluations} U_A evaluations)")
    if data.get("pulls"):
        lines.append("note: the jaw line leaves the part at a jaw (a jaw would have to pull); "
                     "the linear model still applies the force along the jaw line")
    return lines


def _paper_writer(inp, jaws, model):
    def write(rep: Report, report: bool) -> list[str]:
        from ..outputs import write_json

        write_report(rep, report)
        res, p, written = rep.result, rep.params, []
        if p["export_graph"]:
            write_json(p["export_graph"], model.graph.to_dict(
                model.stiffness.sigma0, model.stiffness.k, pulls=model.pulls), "graph", indent=None)
        if p["export_fields"]:
            from ..fields import write_fields
            from ..elasticity.critical_distance import critical_distance_of

            states = [paper_state(res, jaws, sig, label) for label, sig in
                      _field_sigmas(p["export_fields"], res.limit.sigma0, res.limit.sigma_L,
                                    res.sigma_star)]
            written += write_fields(p["export_fields"], inp.mesh, states,
                                    critical_distance_of(inp.mesh))
        if p["plot"]:
            from ..plotting.grasp import save_grasp_plots

            written += save_grasp_plots(res, p["plot"], units=inp.unit if inp.unit != "m" else "mm")
        return [str(w) for w in written]

    return write


def _field_sigmas(path, sigma0: float, sigma_L: float, sigma_star: float | None
                  ) -> list[tuple[str, float]]:
    """The labelled separations (m) ``--export-fields`` writes: σ* and σ_L, or for a
    ``.pvd`` the series from first touch to σ_L (:func:`deformclosure.fields.series_sigmas`)."""
    from pathlib import Path

    from ..fields import series_sigmas

    if Path(path).suffix.lower() == ".pvd":
        return series_sigmas(sigma0, sigma_L, sigma_star)
    return ([("sigma_star", sigma_star)] if sigma_star is not None else []) \
        + [("sigma_L", sigma_L)]


def paper_state(res, jaws: tuple[int, int], sigma: float, label: str):
    """The paper model's state at separation ``sigma`` (m): the linear displacement field
    of the jaw pair for the squeeze ``|σ0 − σ|`` and the jaw forces ``k01 δ`` along the jaw
    line (SPEC §4), as a :class:`deformclosure.fields.FieldState`."""
    from ..fields import FieldState

    lim = res.limit
    mesh = res.model.mesh
    delta = abs(lim.sigma0 - sigma)
    sign = -1.0 if res.model.mode == "expanding" else 1.0
    u = sign * lim.displacement_per_length * delta
    a, b = jaws
    d = mesh.nodes[b] - mesh.nodes[a]
    d = d / np.linalg.norm(d)
    forces = np.zeros((mesh.n_nodes, 2))
    forces[a] = sign * lim.k01 * delta * d          # jaw a pushes towards b (contracting)
    forces[b] = -forces[a]
    return FieldState(label, u, forces, sigma=float(sigma), squeeze=float(delta))
