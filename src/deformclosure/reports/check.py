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


def _check_params(p: dict) -> None:
    from ..fields import check_field_path

    if p["export_fields"] is not None:
        check_field_path(p["export_fields"])
    if not (8 <= p["grid_steps"] <= 1000):
        raise DeformClosureError(f"--grid-steps = {p['grid_steps']}: give a whole number from 8 to 1000")
    if not (0 <= p["saddle_levels"] <= 4):
        raise DeformClosureError(f"--saddle-levels = {p['saddle_levels']}: give a whole number "
                                 "from 0 to 4")


def run(part, params: dict, progress=None, notify=None) -> Report:
    """Check the fingers of ``params["fingers"]`` (a finger file or Source) on ``part``."""
    from ..dspace.closure import deform_closure
    from ..dspace.escape import release_energy_fingers
    from ..dspace.fingers import load_fingers
    from ..pads.size_limits import check_pads_size

    p = params
    _check_params(p)
    fsrc = source_of(p["fingers"], "finger file")
    fingers = load_fingers(fsrc)
    inp = read_inputs(part, p["units"], p["material"], max_area=p["max_area"],
                      points=lambda prt: contact_points(prt, fingers))
    inp.sources.insert(1, fsrc)
    check_pads_size(inp.mesh, solvers=2 if inp.part is None else 3, what="check")
    res = deform_closure(inp.mesh, fingers)
    rel = release_energy_fingers(inp.mesh, fingers, part=inp.part, start=res.equilibrium,
                                 rigid_closed=res.deform_closure, n_translation=p["grid_steps"],
                                 levels=p["saddle_levels"],
                                 count=None if progress is None else lambda n: progress(n, None))
    data = {**merge_release(res.to_dict(), res, rel), "provenance": provenance(inp.sources)}
    lines, warnings = _lines(inp.mesh, fingers, res, rel)
    return Report("check", data, lines, inp.warnings + warnings, p, (res, rel, fingers, inp),
                  _writer)


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
        from ..plotting.mesh import save_figure

        units = inp.part.units if inp.part is not None else "m"
        save_figure(plot_check_and_escape(inp.mesh, res, rel, fingers, units=units), p["plot"])
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
    if rel.deform_closure and rel.by_theorem1:
        return ("HELD (deform closure at rest: the rigid part is in form closure, so every exit "
                "deforms it and U_A > 0, Thm 1)")
    if rel.deform_closure:
        return "HELD (deform closure: U_A exceeds its error)"
    if rel.caged:
        return "CAGED (not held in place, but leaving takes U_A)"
    if rel.U_A > 0:
        return "NOT HELD (U_A is within its error: no barrier is resolved)"
    return "NOT HELD (the part escapes without work)"
