"""``slice``: a slice of D-space, one node moving and all others fixed (paper Fig. 3,
SPEC §2): D_free membership, D_T and the energy over the node's positions."""

from __future__ import annotations

import numpy as np

from ..errors import DeformClosureError
from .base import Report, provenance
from .inputs import parse_numbers, parse_xy, read_inputs, source_of

__all__ = ["run"]


def _node(mesh, node, at, scale: float) -> int:
    """The moving node from ``--node`` or ``--at`` (in units of ``scale`` m)."""
    if (node is None) == (at is None):
        raise DeformClosureError("give exactly one of --node N or --at X,Y")
    if at is not None:
        node = mesh.find_node(np.array(parse_xy(at, "--at")) * scale)
    if not 0 <= node < mesh.n_nodes:
        raise DeformClosureError(f"--node {node}: the mesh has nodes 0..{mesh.n_nodes - 1}")
    return int(node)


def _extent(mesh, extent, scale: float):
    """``--extent`` in m, checked to be finite and near the part (``None``: default)."""
    if extent is None:
        return None
    ext = [v * scale for v in parse_numbers(extent, 4, "--extent", "XMIN,XMAX,YMIN,YMAX")]
    reach = 100 * mesh.diameter + float(np.abs(mesh.nodes).max())
    if max(abs(v) for v in ext) > reach:
        raise DeformClosureError(f"--extent {extent}: must be finite and within 100 part "
                                 "diameters of the part; check the values and --units")
    return ext


def run(part, params: dict, progress=None, notify=None) -> Report:
    """The slice of ``params["fingers"]`` for one node of ``part``. The report is the
    slice's JSON (SI) for a ``.json`` output; an ``.npz`` output holds its arrays."""
    from ..dspace.fingers import load_fingers
    from ..dspace.slices import dfree_slice
    from ..fields import check_field_path
    from ..limits import check_slice_size

    p = params
    if p["export_fields"] is not None:
        check_field_path(p["export_fields"], series=False)
    fsrc = source_of(p["fingers"], "finger file")
    fingers = load_fingers(fsrc)
    out = p["output"]
    check_slice_size(p["resolution"], len(fingers),      # before the part is even meshed
                     json_output=bool(out) and str(out).lower().endswith(".json"))
    inp = read_inputs(part, p["units"], p["material"], max_area=p["max_area"])
    inp.sources.insert(1, fsrc)
    node = _node(inp.mesh, p["node"], p["at"], inp.scale)
    ext = _extent(inp.mesh, p["extent"], inp.scale)
    res = dfree_slice(inp.mesh, None, node, fingers, extent=ext, resolution=p["resolution"],
                      energy=p["energy"])
    data = {**res.to_dict(), "provenance": provenance(inp.sources)}
    line = (f"node {node}: {p['resolution']}x{p['resolution']} slice, D_free "
            f"{100 * res.free.mean():.1f}% of pixels, D_T {100 * res.in_dt.mean():.1f}%, "
            f"{p['energy']} energy {res.energy.min():.4g}..{res.energy.max():.4g} J")
    return Report("slice", data, [line], inp.warnings, p, (res, fingers, inp), _writer)


def _writer(rep: Report, report: bool) -> list[str]:
    res, fingers, inp = rep.result
    p, written = rep.params, []
    if report and p["output"] and p["output"] != "-":
        try:
            if str(p["output"]).lower().endswith(".json"):
                from ..outputs import write_json

                write_json(p["output"], rep.data, "slice", indent=None)
            else:
                res.save(p["output"])
        except OSError as err:
            raise DeformClosureError(f"{p['output']}: cannot write ({err.strerror})") from None
    if p["export_fields"]:
        from ..fields import write_slice_fields

        written.append(str(write_slice_fields(p["export_fields"], res)))
    if p["plot"]:
        from ..plotting.dspace import plot_slice
        from ..plotting.mesh import new_figure, figure_path, save_figure

        fig, ax = new_figure()
        plot_slice(res, mesh=inp.mesh, fingers=fingers, ax=ax, units=inp.unit)
        path = figure_path(p["plot"], "slice", single=True)
        save_figure(fig, path)
        written.append(str(path))
    return written
