"""The demonstration (``deformclosure demo``): two rubber parts between round pads, each
solved on three meshes, then the paper's model on the block for contrast (see
:mod:`deformclosure.cli.demo`)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

import numpy as np

from .base import Report, provenance

__all__ = ["demo"]


def _table(res, unit_area: float = 1e-6) -> list[str]:
    lines = [f"  {'max_area (mm^2)':>15} {'nodes':>7} {'sigma* (mm)':>12} {'Q* (mJ)':>10} {'U_A (mJ)':>10}"]
    for r, a in zip(res.levels, res.max_areas):
        ss = "-" if r.sigma_star is None else f"{r.sigma_star * 1e3:.4f}"
        ua = "inf" if np.isinf(r.U_A) else f"{r.U_A * 1e3:.4f}"
        lines.append(f"  {a / unit_area:>15.4g} {r.n_nodes:>7} {ss:>12} {r.quality * 1e3:>10.4f} {ua:>10}")
    return lines


def _summary(res) -> str:
    fine, err = res.finest, res.error_estimate()
    if fine.sigma_star is None:
        return (f"  verdict: {res.verdict.upper()} — no release barrier above the noise floor "
                f"({fine.noise_relative:.2%} of U) at any separation")
    es = "" if err["sigma_star"] is None else f" ± {err['sigma_star'] * 1e3:.3g}"
    return (f"  verdict: {res.verdict.upper()} — sigma* = {fine.sigma_star * 1e3:.4f}{es} mm, "
            f"Q* = {fine.quality * 1e3:.4f} ± {err['quality'] * 1e3:.2g} mJ (Richardson)")


def _cases():
    from ..pads import GraspAxis, Pad
    from ..part import demo_part, notched_part

    return [
        ("notched_bar", notched_part(0.4), GraspAxis.through([0.015, 0.0], [0.015, 0.012]),
         Pad(0.0, 0.002), "30 x 12 mm bar, 3 mm V-notches; round pads rho = 2 mm in the notches"),
        ("block", demo_part(1.0), GraspAxis.through([0.0, 0.010], [0.012, 0.010]),
         Pad(0.0, 0.001), "12 x 20 mm block (the paper's example); round pads rho = 1 mm across it"),
    ]


def _pad_cases(cases, emit: Callable[[str], None]) -> dict:
    """The two pad grasps, each on three meshes, with their tables and verdicts."""
    from ..mesh import mesh_part
    from ..pads import pad_grasp

    results = {}
    for i, (key, part, axis, pad, text) in enumerate(cases, 1):
        mat = part.material
        emit(f"{i}) {text}")
        emit(f"   rubber E = {mat.youngs_modulus / 1e6:g} MPa, nu = {mat.poisson_ratio:g}, "
             f"e_L = {mat.elastic_limit_strain:g}, thickness {mat.thickness * 1e3:g} mm; "
             "frictionless rigid pads (SPEC §6)")
        emit(f"   mesh: {mesh_part(part).summary()}; then h halved twice")
        t0 = time.perf_counter()
        res = pad_grasp(part, axis, pad, refine=3)
        results[key] = res
        for line in _table(res):
            emit(line)
        emit(_summary(res) + f"   [{time.perf_counter() - t0:.1f} s]")
    return results


def _paper_block(emit: Callable[[str], None]) -> dict:
    """The paper's model on the block: point jaws at the mid-points of the long sides, on
    three meshes (its numbers follow the mesh)."""
    from ..grasp.analysis import optimize_separation
    from ..mesh import mesh_part
    from ..part import demo_part

    emit("3) the paper's model on the same block (point jaws at mesh nodes, --model paper):")
    emit(f"  {'max_area (mm^2)':>15} {'nodes':>7} {'sigma* (mm)':>12} {'Q* (mJ)':>10}")
    rows = []
    for area in (1.0, 0.25, 0.0625):
        mesh = mesh_part(demo_part(area))
        jaws = (mesh.find_node([0.0, 0.010]), mesh.find_node([0.012, 0.010]))
        r = optimize_separation(mesh, jaws, method="exact")
        ss = "-" if r.sigma_star is None else f"{r.sigma_star * 1e3:.4f}"
        emit(f"  {area:>15.4g} {mesh.n_nodes:>7} {ss:>12} {r.quality * 1e3:>10.5f}")
        rows.append({"max_area": area * 1e-6, "nodes": mesh.n_nodes,
                     "sigma_star": r.sigma_star, "quality": r.quality})
    emit("  a point force in 2-D has no finite stiffness: these numbers follow the mesh, not "
         "the part (docs/pads.md)")
    return {"model": "paper", "convergence": rows, "units": {"length": "m", "energy": "J"}}


def demo(out_dir: str | Path = "deformclosure-demo", emit: Callable[[str], None] = print) -> Report:
    """Run the demonstration; ``emit`` receives each summary line as it is ready.

    :meth:`Report.save` writes ``report.json`` and the pictures into ``out_dir``.
    """
    cases = _cases()
    results = _pad_cases(cases, emit)
    data = {key: res.to_dict() for key, res in results.items()}
    data["paper_block"] = _paper_block(emit)
    data["provenance"] = provenance([])
    return Report("demo", data, [], [], {"out_dir": str(out_dir)}, (cases, results), _writer)


def _writer(rep: Report, report: bool) -> list[str]:
    from ..mesh import mesh_part
    from ..outputs import write_json
    from ..plotting.mesh import save_figure, save_mesh_plot
    from ..plotting.pads import plot_pad_grasp, plot_pad_quality

    cases, results = rep.result
    out = Path(rep.params["out_dir"])
    out.mkdir(parents=True, exist_ok=True)
    if report:
        write_json(out / "report.json", rep.data)
    save_mesh_plot(mesh_part(cases[0][1]), out / "mesh.png", units="mm")
    paths = [out / "mesh.png"]
    for (key, part, *_rest) in cases:
        fine = results[key].finest
        save_figure(plot_pad_grasp(fine, units="mm"), out / f"{key}.png")
        save_figure(plot_pad_quality(fine, units="mm"), out / f"{key}_quality.png")
        paths += [out / f"{key}.png", out / f"{key}_quality.png"]
    return [str(p) for p in paths + ([out / "report.json"] if report else [])]
