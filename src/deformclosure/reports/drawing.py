"""``import``: a part file from a CAD drawing (DXF or SVG)."""

from __future__ import annotations

from ..errors import PartError
from .base import Report, provenance, write_report
from .inputs import material_of, source_of

__all__ = ["run"]


def run(part, params: dict, progress=None, notify=None) -> Report:
    """The part of the drawing ``part`` (``units``, ``layer``, ``tolerance`` in the
    drawing's units, ``material``); the report is the part file (SI: metres)."""
    from ..drawing import is_drawing_file
    from ..jsonfile import Source
    from ..part import part_from_drawing
    from ..units import length_scale

    p = params
    src = source_of(part, "drawing")
    if not is_drawing_file(src):
        raise PartError(f"{src.name}: not a drawing; give a .dxf or .svg file")
    mat = material_of(p["material"])
    prt = part_from_drawing(src, material=mat, units=p["units"], layer=p["layer"],
                            tolerance=p["tolerance"])
    s = length_scale(prt.units)
    line = (f"{prt.name}: outer ring of {len(prt.outer)} vertices, {len(prt.holes)} hole(s), "
            f"area {prt.area / s**2:.6g} {prt.units}^2")
    sources = [src, src.sidecar] + ([mat] if isinstance(mat, Source) else [])
    data = {**prt.to_dict(), "provenance": provenance(sources)}
    return Report("import", data, [line], list(prt.sanity_warnings()), p, prt, _writer)


def _writer(rep: Report, report: bool) -> list[str]:
    write_report(rep, report)
    if not rep.params["plot"]:
        return []
    from ..plotting.mesh import figure_path, save_figure
    from ..plotting.part import plot_outline

    path = figure_path(rep.params["plot"], "outline", single=True)
    save_figure(plot_outline(rep.result), path)
    return [str(path)]
