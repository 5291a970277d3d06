"""``check``: does a set of fixed fingers hold the part? The release energy U_A over the
part's placements (SPEC §7), the equilibrium and the rigid test at rest (SPEC §3)."""

from __future__ import annotations

import numpy as np

from ..errors import DeformClosureError
from .base import Report, provenance, write_report
from .inputs import read_inputs, source_of

__all__ = ["run", "contact_points", "merge_release"]


def contact_points(part, fingers) -> np.ndarray:
    """Point-finger and polygon-corner positions on the part's boundary (m), ``(k, 2)``,
    within the touching tolerance (SPEC §3); they become mesh nodes so point contacts sit
    on nodes."""
    import shapely

    from ..geometry import touch_tolerance

    pts = [np.asarray(f.vertices, float).reshape(-1, 2) for f in fingers]
    pts = np.concatenate(pts) if pts else np.zeros((0, 2))
    if not len(pts):
        return pts
    d = shapely.distance(shapely.points(pts), part.polygon.boundary)
    return pts[d <= touch_tolerance(part.diameter)]


def check_finger_sizes(fingers, diameter: float) -> None:
    """Refuse a disc finger whose radius is outside
    :data:`~deformclosure.limits.MIN_DISC_RADIUS_FRACTION`..``MAX_BODY_FRACTION`` times
    the part's ``diameter`` (m): the release lattice's step follows the smallest disc
    (issue 23; a 1e-300 mm disc never finished)."""
    from ..limits import MIN_DISC_RADIUS_FRACTION, check_body_size

    for i, f in enumerate(fingers):
        rc = f.round_centre()
        if rc is not None:
            check_body_size(f"fingers[{i}].radius", rc[1], diameter, MIN_DISC_RADIUS_FRACTION,
                            hint="; a smaller finger is a point finger "
                                 '({"type": "point", "at": [x, y]})')


def _check_params(p: dict) -> None:
    from ..fields import check_field_path

    if p["export_fields"] is not None:
        check_field_path(p["export_fields"])
    if not (8 <= p["grid_steps"] <= 1000):
        raise DeformClosureError(f"--grid-steps = {p['grid_steps']}: give a whole number from 8 to 1000")
    if not (0 <= p["saddle_levels"] <= 4):
        raise DeformClosureError(f"--saddle-levels = {p['saddle_levels']}: give a whole number "
                                 "from 0 to 4")
    from ..pads.friction_grasp import check_friction

    if check_friction(p.get("friction")) > 0:
        # SPEC §9 on the §7 placement landscape (slip of each finger contact per placement
        # move, the fingers' frictional holding loads) is not built yet
        raise DeformClosureError("--friction: not yet supported for check (its placement "
                                 "landscape, SPEC §7, is frictionless); use --friction 0, or "
                                 "optimize/plan with pads for friction (SPEC §9)")


def run(part, params: dict, progress=None, notify=None) -> Report:
    """Check the fingers of ``params["fingers"]`` (a finger file or Source) on ``part``."""
    from ..dspace.closure import deform_closure
    from ..dspace.escape import release_energy_fingers
    from ..dspace.fingers import load_fingers
    from ..limits import PLACEMENT_KERNEL_BYTES, holding
    from ..pads.size_limits import WITH_TWIN, check_pads_size

    from ..pads.refine import check_accuracy, check_refine

    from ..plotting.animate import check_animate

    p = params
    _check_params(p)
    check_animate(p)
    check_accuracy(p.get("rtol"), p.get("max_seconds"))
    check_refine(p.get("refine"))
    fsrc = source_of(p["fingers"], "finger file")
    fingers = load_fingers(fsrc)
    inp = read_inputs(part, p["units"], p["material"], max_area=p["max_area"],
                      points=lambda prt: contact_points(prt, fingers))
    inp.sources.insert(1, fsrc)
    check_finger_sizes(fingers, inp.mesh.diameter)
    elasticity = p.get("elasticity") or getattr(inp.mesh.material, "model", "linear")
    if elasticity == "neo-hookean":
        for i, f in enumerate(fingers):          # refused before any work (one line)
            f.obstacle(f"fingers[{i}]")
    # at most two factorised meshes at once: the release landscape's and its twin's (the
    # rigid test's is released before them; measured, benchmarks/bench_memory.py)
    with holding(PLACEMENT_KERNEL_BYTES):
        check_pads_size(inp.mesh, solvers=1 if inp.part is None else WITH_TWIN,
                        path_limit=False, what="check")

    def solve(mesh, part=inp.part):
        # ``part``: the geometry of the twin realisation (noise floor), meshed as finely
        # as ``mesh`` — a coarse twin would measure the coarse mesh's noise
        res = deform_closure(mesh, fingers)
        rel = release_energy_fingers(mesh, fingers, part=part, start=res.equilibrium,
                                     rigid_closed=res.deform_closure,
                                     n_translation=p["grid_steps"], levels=p["saddle_levels"],
                                     count=None if progress is None else lambda n: progress(n, None))
        return res, rel

    from .optimize import accuracy_request

    # SPEC §6 "Accuracy by default": --rtol 0.05 unless --refine N is given; a mesh file
    # cannot be re-meshed, so it is solved once (with a warning)
    rtol, refine, acc_warnings = accuracy_request(p, inp.part is None)
    if rtol is None and (refine or 1) <= 1:
        levels = [(inp.mesh, *solve(inp.mesh))]
    else:
        levels = _refined(inp, fingers, solve, rtol, refine, p.get("max_seconds"), notify)
    mesh, res, rel = levels[-1][:3]
    inp.mesh = mesh
    finite = []
    if elasticity == "neo-hookean":
        finite = _finite_strain(levels, fingers, p, notify)
        rel = finite[-1]
    data = {**merge_release(res.to_dict(), res, rel), "provenance": provenance(inp.sources)}
    data.setdefault("elasticity", "linear")
    lines, warnings = _lines(mesh, fingers, res, rel)
    if len(levels) > 1 or rtol is not None:
        more_lines, more = _refinement_lines(data, levels, rtol)
        lines += more_lines
        warnings += more
    if finite:
        lines += _finite_strain_lines(data, levels, finite)
    return Report("check", data, lines, inp.warnings + acc_warnings + warnings, p,
                  (res, rel, fingers, inp),
                  _writer)


def _refined(inp, fingers, solve, rtol: float | None, refine: int | None,
             max_seconds: float | None, notify) -> list:
    """``(mesh, closure, release[, why stopped])`` on meshes with ``h`` halved per level:
    ``refine`` levels, or — with ``rtol`` — until the estimates of U_A and of the quality
    (:func:`_check_error`) are within ``rtol`` of them, the start shows no barrier on two
    levels in a row, or the budget (``max_seconds``, the memory limits) ends it (SPEC §6
    "Accuracy by default"). Point fingers that press the part stop it after two levels:
    their energies follow the mesh (a point force in 2-D has no finite stiffness), so no
    level converges."""
    import time
    from dataclasses import replace

    from ..mesh import mesh_part
    from ..mesh.generate import default_max_area
    from ..pads.refine import DEFAULT_MAX_SECONDS, MAX_LEVELS
    from ..limits import PLACEMENT_KERNEL_BYTES, holding
    from ..pads.size_limits import WITH_TWIN, check_pads_size

    budget = DEFAULT_MAX_SECONDS if max_seconds is None else float(max_seconds)
    n_levels = MAX_LEVELS if refine is None else int(refine)
    base = default_max_area(inp.part)
    pts = contact_points(inp.part, fingers)
    t_start, levels, seconds = time.perf_counter(), [], []
    for k in range(n_levels):
        t0 = time.perf_counter()
        level_part = replace(inp.part, mesh_options=replace(inp.part.mesh_options,
                                                            max_area=base / 4.0**k))
        if k == 0:
            mesh = inp.mesh
        else:
            if notify is not None:
                notify(f"level {k + 1} ..." if rtol is not None else f"mesh {k + 1} of {n_levels} ...")
            try:
                mesh = mesh_part(inp.part, max_area=base / 4.0**k, points=pts)
                with holding(PLACEMENT_KERNEL_BYTES):
                    check_pads_size(mesh, solvers=WITH_TWIN, path_limit=False, what="check")
            except DeformClosureError as err:
                levels[-1] += (f"memory or size limit at level {k + 1}: {err}",)
                return levels
        levels.append((mesh, *solve(mesh, level_part)))
        seconds.append(time.perf_counter() - t0)
        if rtol is None:
            continue
        if len(levels) > 1 and _met(levels, rtol):
            return levels
        if len(levels) > 1 and _pressing_points(levels[-1][2]):
            levels[-1] += ("point fingers press the part: its energies follow the mesh, so "
                           "refining does not converge (model the fingertips as discs)",)
            return levels
        growth = seconds[-1] / seconds[-2] if len(seconds) > 1 and seconds[-2] > 0 else 4.0
        predicted = seconds[-1] * min(max(growth, 1.5), 16.0)
        if k + 1 < n_levels and time.perf_counter() - t_start + predicted > budget:
            levels[-1] += (f"time budget: level {k + 2} would take about {predicted:.0f} s, "
                           f"beyond --max-seconds {budget:g}",)
            return levels
    if rtol is not None:
        levels[-1] += (f"{n_levels} levels solved",)
    return levels


def _finite_strain(levels, fingers, p: dict, notify) -> list:
    """The finite-strain release (SPEC §8, :mod:`deformclosure.dspace.finite_strain_release`)
    on the finest level and the one before it (their difference is the mesh part of its
    error estimate)."""
    from ..dspace.finite_strain_release import finite_strain_release

    from ..pads.refine import DEFAULT_MAX_SECONDS

    budget = DEFAULT_MAX_SECONDS if p.get("max_seconds") is None else float(p["max_seconds"])
    last = levels[-2:]
    return [finite_strain_release(lv[0], fingers, lv[2], levels=p["saddle_levels"],
                                  max_seconds=budget / len(last), say=notify)
            for lv in last]


def _finite_strain_lines(data: dict, levels, finite: list) -> list[str]:
    """Add ``finite_strain_levels`` and ``finite_strain_error`` to ``data``; the lines."""
    import math

    from ..pads.refine import level_error

    num = lambda v: None if not math.isfinite(v) else float(v)  # noqa: E731
    first = len(levels) - len(finite)
    data["finite_strain_levels"] = [
        {"level": first + k, "nodes": lv[0].n_nodes, "U_A": num(fs.U_A),
         "U_A_infinite": math.isinf(fs.U_A), "U_A_lower": num(fs.U_A_lower),
         "quality": num(fs.quality), "deform_closure": fs.deform_closure}
        for k, (lv, fs) in enumerate(zip(levels[first:], finite))]
    est = level_error([fs.U_A for fs in finite]) if len(finite) > 1 else None
    data["finite_strain_error"] = {"U_A": None if est is None else num(est + finite[-1].U_A_error)}
    fs = finite[-1]
    err = data["linear_model_error"]
    pct = lambda v: "-" if v is None else f"{v:+.1%}"  # noqa: E731
    found = (f"U_A = {_joules(fs.U_A)} (the whole lattice searched)" if fs.exact else
             f"U_A <= {_joules(fs.U_A)} (found path), >= {_joules(fs.U_A_lower)} (certified)")
    lines = [f"finite strain ({fs.elasticity}): {found}; linear U_A = {_joules(fs.linear.U_A)}; "
             f"{fs.n_evaluations} placements solved in {fs.seconds:.1f} s",
             f"linear model error at this grasp: U {pct(err['U'])}, F {pct(err['F'])}, "
             f"quality {pct(err['quality'])}"]
    if len(finite) > 1:
        e = data["finite_strain_error"]["U_A"]
        lines.append("finite-strain U_A on the last two levels: "
                     + ", ".join(_joules(f.U_A) for f in finite)
                     + f"; error estimate ± {'-' if e is None else f'{e:.3g} J'}")
    return lines


def _pressing_points(rel) -> bool:
    """Whether point fingers press the part in this release result (its warning)."""
    return any(w.startswith("point fingers") for w in rel.warnings)


def _met(levels, rtol: float) -> bool:
    """The stopping rule of ``check --rtol``: U_A and the quality within ``rtol`` by their
    estimates, or no barrier at the start on the last two levels (SPEC §6)."""
    import math

    e_ua, e_q = _check_error(levels)
    last = levels[-1][2]
    if last.U_A == 0 and levels[-2][2].U_A == 0:
        return True
    return (e_ua <= rtol * abs(last.U_A) and
            (e_q <= rtol * abs(last.quality) or not math.isfinite(last.quality)))


def _check_error(levels) -> tuple[float, float]:
    """Error estimates (J) of U_A and of the quality on the last level: the change between
    levels (mesh) plus the lattice's own estimate of U_A (placements)."""
    import math

    from ..pads.refine import level_error

    UA = [lv[2].U_A for lv in levels]
    Q = [lv[2].quality for lv in levels]
    lattice = float(levels[-1][2].U_A_error)
    e_ua, e_q = level_error(UA), level_error(Q)
    if e_ua is None:
        return math.nan, math.nan
    return e_ua + lattice, e_q + lattice


def _refinement_lines(data: dict, levels, rtol: float | None) -> tuple[list[str], list[str]]:
    """Add ``convergence``, ``error_estimate``, ``converged``, ``rtol`` and ``refinement``
    to ``data``; the lines and warnings they print."""
    import math

    e_ua, e_q = _check_error(levels) if len(levels) > 1 else (math.nan, math.nan)
    fine = levels[-1][2]
    from ..pads.refine import DEFAULT_RTOL

    converged = len(levels) > 1 and _met(levels, DEFAULT_RTOL if rtol is None else rtol)
    num = lambda v: None if not math.isfinite(v) else float(v)  # noqa: E731
    data["convergence"] = [{"level": k, "nodes": lv[0].n_nodes, "U_A": num(lv[2].U_A),
                            "U_A_infinite": math.isinf(lv[2].U_A), "U_A_error": num(lv[2].U_A_error),
                            "quality": num(lv[2].quality), "deform_closure": lv[2].deform_closure}
                           for k, lv in enumerate(levels)]
    data["error_estimate"] = {"U_A": num(e_ua), "quality": num(e_q)}
    data["converged"] = bool(converged)
    data["rtol"] = rtol
    data["refinement"] = "uniform"
    lines = [f"{'level':>5} {'nodes':>7} {'U_A (J)':>12} {'± lattice (J)':>14} {'quality (J)':>12}"]
    for row in data["convergence"]:
        ua = "infinite" if row["U_A_infinite"] else f"{row['U_A']:.5g}"
        le = "-" if row["U_A_error"] is None else f"{row['U_A_error']:.3g}"
        q = "infinite" if row["quality"] is None else f"{row['quality']:.5g}"
        lines.append(f"{row['level']:>5} {row['nodes']:>7} {ua:>12} {le:>14} {q:>12}")
    target = "" if rtol is None else f", target rtol {rtol:g}"
    lines.append(f"error estimate (mesh levels plus lattice{target}): U_A ± {e_ua:.3g} J, "
                 f"quality ± {e_q:.3g} J; converged: {'yes' if converged else 'no'}")
    warnings = []
    if rtol is not None and not converged:
        why = levels[-1][3] if len(levels[-1]) > 3 else "no estimate"
        fix = ("" if _pressing_points(fine) else ": raise --max-seconds or --rtol")
        warnings.append(f"not converged to --rtol {rtol:g} ({why}){fix}")
    return lines, warnings


def merge_release(report: dict, closure, release) -> dict:
    """The check report (SPEC §5, §7): the rigid test's keys as before, ``deform_closure``
    from the release energy, the rigid verdict as ``rigid_closure``, and the release keys."""
    out = dict(report)
    out["rigid_closure"] = bool(closure.deform_closure)
    out.update(release.to_dict())
    out["units"] = {**report.get("units", {}), "angle": "rad"}
    return out


def _lines(mesh, fingers, res, rel) -> tuple[list[str], list[str]]:
    """Summary lines and warnings for people."""
    eq = res.equilibrium
    lines = [f"{mesh.name}: {mesh.n_nodes} nodes, {len(fingers)} fingers",
             f"verdict: {_verdict(rel)}",
             f"release energy U_A = {_joules(rel.U_A)} ± {rel.U_A_error:.3g} J (noise floor "
             f"{rel.noise_relative:.1%}), escape {_target(rel)}; "
             f"{rel.n_evaluations} placements solved in {rel.seconds:.1f} s",
             f"quality min(U_A, U_L) = {_joules(rel.quality)}, U_L = {_joules(rel.U_L)} "
             f"(elastic limit over the critical distance {rel.critical_distance:.3g} m)"]
    warnings = list(rel.warnings)
    if rel.by_theorem1 and rel.U_A <= rel.U_A_error:
        warnings.append(f"U_A = {_joules(rel.U_A)} is within its error estimate "
                        f"{rel.U_A_error:.3g} J: the part is held (rigid form closure at rest, "
                        "Thm 1), but this mesh does not resolve how much work its release "
                        "takes; refine the mesh for the value")
    rigid = "closed" if res.deform_closure else "not closed (escaping twist below)"
    lines.append(f"rigid test at rest (Thm 1): {rigid}, decided at order {res.order}")
    lines.append(f"energy at equilibrium: {res.energy:.6g} J (linear), {eq.iterations} "
                 "linearisations" + ("" if eq.converged else " (NOT converged)"))
    lines += [f"  finger {c.finger}: {'active' if c.active else 'inactive'}, {c.feature}, "
              f"force ({c.force[0]:.4g}, {c.force[1]:.4g}) N" for c in res.contacts]
    mat = getattr(mesh, "material", None)
    if mat is not None and eq.max_strain > mat.elastic_limit_strain:
        warnings.append(f"the largest strain at equilibrium, {eq.max_strain:.3g}, exceeds the "
                        f"elastic limit e_L = {mat.elastic_limit_strain:g}: the fingers squeeze "
                        "the part beyond its elastic range (and beyond the small-displacement "
                        "model)")
    if res.twist is not None:
        t = res.twist
        t = np.asarray(t, float) + 0.0                # no "-0" in print
        lines.append(f"escaping twist: v = ({t[0]:.4g}, {t[1]:.4g}) m/s, omega = {t[2]:.4g} "
                     "rad/s (about the area centroid)")
    return lines, warnings


def _writer(rep: Report, report: bool) -> list[str]:
    write_report(rep, report)
    res, rel, fingers, inp = rep.result
    p, written = rep.params, []
    if p["export_fields"]:
        from ..fields import FieldState, write_fields
        from ..elasticity.critical_distance import critical_distance_of

        eq = res.equilibrium
        state = FieldState("equilibrium", np.asarray(eq.q) - inp.mesh.nodes, eq.nodal_forces,
                           elastic=eq.displacement)
        written += write_fields(p["export_fields"], inp.mesh, [state],
                                critical_distance_of(inp.mesh))
    if p["plot"]:
        from ..plotting.escape import plot_check_and_escape
        from ..plotting.mesh import figure_path, save_figure

        units = inp.part.units if inp.part is not None else "m"
        path = figure_path(p["plot"], "check", single=True)
        save_figure(plot_check_and_escape(inp.mesh, res, rel, fingers, units=units), path)
        written.append(path)
        from ..plotting.animate import check_animate

        gif = check_animate(p)
        if gif is not None:
            from ..plotting.animate import check_escape_animation
            from ..plotting.escape import escape_note

            done = check_escape_animation(inp.mesh, rel, fingers, gif, units=units)
            if done is None:
                rep.warnings.append(f"--animate: {escape_note(rel)}; no GIF written")
            else:
                written.append(done)
        conv = rep.data.get("convergence") or []
        if len(conv) > 1:           # a refined run: U_A and the quality against the nodes
            from ..plotting.pads import plot_convergence

            path = figure_path(p["plot"], "convergence")
            save_figure(plot_convergence(conv, units=units), path)
            written.append(path)
    return [str(w) for w in written]


def _joules(v: float) -> str:
    return "infinite" if not np.isfinite(v) else f"{v:.6g} J"


def _target(rel) -> str:
    if rel.U_A_infinite:
        return "impossible within the fingers' reach" + (" (a cage)" if rel.caged else "")
    if not rel.complete:
        return "search stopped (U_A is a lower bound)"
    return {"released": "to a released placement", "equilibrium": "to another equilibrium"}.get(
        rel.target, "none")


def _verdict(rel) -> str:
    if getattr(rel, "verdict", None) == "undecided" and rel.U_A == 0.0:
        return (f"UNDECIDED at finite strain (a climb of {rel.barrier:.4g} J lies within the "
                f"noise floor {rel.noise_relative:.0%}: this mesh does not resolve it; refine)")
    if getattr(rel, "verdict", None) == "undecided":
        return (f"UNDECIDED at finite strain (U_A between {rel.U_A_lower:.4g} J and "
                f"{_joules(rel.U_A)}, error {rel.U_A_error:.3g} J: the search's budget ran "
                "out; raise --max-seconds)")
    if rel.deform_closure and rel.by_theorem1:
        return ("HELD (deform closure at rest: the rigid part is in form closure, so every exit "
                "deforms it and U_A > 0, Thm 1)")
    if rel.deform_closure and getattr(rel, "elasticity", "linear") != "linear":
        return ("HELD (deform closure at finite strain: the certified lower bound of U_A "
                "exceeds its error)")
    if rel.deform_closure:
        return "HELD (deform closure: U_A exceeds its error)"
    if rel.caged:
        return "CAGED (not held in place, but leaving takes U_A)"
    if rel.U_A > 0:
        return "NOT HELD (U_A is within its error: no barrier is resolved)"
    return "NOT HELD (the part escapes without work)"
