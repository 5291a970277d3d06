"""``mesh``: mesh a part (or drawing) with quality triangles, or check and convert a mesh."""

from __future__ import annotations

from pathlib import Path

from ..errors import DeformClosureError
from .base import Report, provenance

__all__ = ["run"]


def run(part, params: dict, progress=None, notify=None) -> Report:
    """Mesh ``part`` (``max_area`` in the part's units², ``min_angle`` in degrees), or read a
    mesh file (``units`` of its coordinates, ``material`` to attach). The report is the
    SPEC §5 mesh JSON (metres) with provenance; the mesh is :attr:`Report.result`."""
    from ..mesh import mesh_part
    from ..mesh.io import is_mesh_file, mesh_to_dict
    from ..units import length_scale
    from .inputs import read_inputs, source_of

    src = source_of(part, "part file")
    max_area, min_angle = params["max_area"], params["min_angle"]
    if is_mesh_file(src):
        if max_area is not None or min_angle is not None:
            raise DeformClosureError("--max-area/--min-angle: apply to part files only, "
                                     f"and {src.name} is a mesh file")
        inp = read_inputs(src, params["units"], params["material"], need_material=False)
        shown = params["units"] or "mm"
    else:
        inp = read_inputs(src, params["units"], params["material"], mesh=False)
        s = length_scale(inp.part.units)
        inp.mesh = mesh_part(inp.part, max_area=None if max_area is None else max_area * s * s,
                             min_angle=min_angle)
        shown = inp.part.units
    data = {**mesh_to_dict(inp.mesh), "provenance": provenance(inp.sources)}
    return Report("mesh", data, [inp.mesh.summary()], inp.warnings, params, inp.mesh,
                  _writer(shown))


def _writer(units: str):
    def write(rep: Report, report: bool) -> list[str]:
        from ..mesh import write_mesh
        from ..outputs import write_json

        out, written = rep.params.get("output"), []  # mesh formats: not JSON
        if report and out is not None and out != "-":
            if out.lower().endswith(".json"):
                write_json(out, rep.data)
            elif not write_mesh(rep.result, out) and rep.result.material is not None:
                rep.warnings.append(f"{Path(out).suffix} files cannot hold the material; give "
                                    "--material when reading the mesh back (.json, .vtu and "
                                    ".vtk keep it)")
        if rep.params.get("plot"):
            from ..plotting.mesh import figure_path, save_mesh_plot

            path = figure_path(rep.params["plot"], "mesh", single=True)
            save_mesh_plot(rep.result, path, units=units)
            written.append(str(path))
        return written

    return write
