"""Mesh files: the package's mesh JSON (SPEC §5) and every triangle mesh meshio reads.

Mesh JSON::

    {"format": "deformclosure-mesh/1", "units": "m",
     "nodes": [[x, y], ...], "triangles": [[i, j, k], ...],
     "boundary": {"outer": [i, ...], "holes": [[i, ...], ...]},
     "material": {"youngs_modulus": ..., "poisson_ratio": ..., "thickness": ...,
                  "elastic_limit_strain": ..., "plane": "stress"}}

Lengths are in metres when written; on reading, ``units`` may be any supported unit
(thickness is in the same unit). The boundary loops in the file are checked against
the loops recovered from the triangles.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MeshError, PartError
from ..part import Material
from ..units import length_scale
from .core import Mesh

__all__ = ["MESH_FORMAT", "MATERIAL_FORMATS", "mesh_to_dict", "mesh_from_dict", "read_mesh",
           "write_mesh", "is_mesh_file"]

MESH_FORMAT = "deformclosure-mesh/1"


def mesh_to_dict(mesh: Mesh) -> dict[str, Any]:
    """The SPEC §5 mesh JSON structure (SI) of ``mesh``."""
    d: dict[str, Any] = {
        "format": MESH_FORMAT,
        "name": mesh.name,
        "units": "m",
        "nodes": mesh.nodes.tolist(),
        "triangles": mesh.triangles.tolist(),
        "boundary": {"outer": mesh.outer_loop.tolist(),
                     "holes": [h.tolist() for h in mesh.hole_loops]},
    }
    if mesh.material is not None:
        d["material"] = mesh.material.to_dict()
    return d


def _same_loop(a: np.ndarray, b: np.ndarray) -> bool:
    if len(a) != len(b) or len(a) == 0:
        return False
    i = np.flatnonzero(b == a[0])
    return len(i) == 1 and np.array_equal(np.roll(b, -int(i[0])), a)


def mesh_from_dict(data: Any) -> Mesh:
    """Validated :class:`Mesh` from the mesh JSON structure.

    Raises
    ------
    MeshError
    """
    if not isinstance(data, dict):
        raise MeshError("mesh file: top level must be a JSON object {...}")
    allowed = {"format", "name", "units", "nodes", "triangles", "boundary", "material",
               "provenance"}   # provenance: written by the CLI, not read
    extra = set(data) - allowed
    if extra:
        raise MeshError(f"{sorted(extra)[0]}: unknown key in mesh file; remove it")
    if data.get("format") != MESH_FORMAT:
        raise MeshError(f"format: expected {MESH_FORMAT!r}, got {data.get('format')!r}")
    for key in ("units", "nodes", "triangles"):
        if key not in data:
            raise MeshError(f"{key}: required field is missing; add it")
    try:
        scale = length_scale(data["units"], "units")
    except Exception as err:
        raise MeshError(str(err)) from None
    def _numbers(rows, kinds) -> bool:
        return isinstance(rows, list) and all(
            isinstance(r, list) and all(isinstance(v, kinds) and not isinstance(v, bool) for v in r)
            for r in rows)

    if not _numbers(data["nodes"], (int, float)):
        raise MeshError("nodes: must be a list of [x, y] numbers (no strings or booleans)")
    if not _numbers(data["triangles"], int):
        raise MeshError("triangles: must be a list of [i, j, k] node ids, integers")
    try:
        nodes = np.asarray(data["nodes"], dtype=float) * scale
        tris_raw = np.asarray(data["triangles"])
    except (TypeError, ValueError, OverflowError):
        raise MeshError("nodes/triangles: must be lists of [x, y] numbers and [i, j, k] integers") from None
    if tris_raw.dtype.kind not in "iu":
        raise MeshError("triangles: node ids must be integers")
    material = None
    if data.get("material") is not None:
        m = data["material"]
        if not isinstance(m, dict):
            raise MeshError("material: must be an object")
        keys = {"youngs_modulus", "poisson_ratio", "thickness", "elastic_limit_strain", "plane",
                "critical_distance"}
        if set(m) - keys:
            raise MeshError(f"material.{sorted(set(m) - keys)[0]}: unknown key; remove it")
        missing = keys - {"plane", "critical_distance"} - set(m)
        if missing:
            raise MeshError(f"material.{sorted(missing)[0]}: required field is missing; add it")
        try:
            vals = [m[k] for k in ("youngs_modulus", "poisson_ratio", "thickness", "elastic_limit_strain")]
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
                raise MeshError("material: values must be numbers")
            cd = m.get("critical_distance")
            if cd is not None and (not isinstance(cd, (int, float)) or isinstance(cd, bool)):
                raise MeshError("material.critical_distance: must be a number (m)")
            material = Material(float(vals[0]), float(vals[1]), float(vals[2]) * scale,
                                float(vals[3]), m.get("plane", "stress"),
                                None if cd is None else float(cd) * scale)
        except PartError as err:
            raise MeshError(str(err)) from None
    mesh = Mesh.from_arrays(nodes, tris_raw, material=material, name=str(data.get("name", "part")))
    b = data.get("boundary")
    if b is not None:
        try:
            outer = np.asarray(b["outer"], dtype=np.int64)
            holes = [np.asarray(h, dtype=np.int64) for h in b.get("holes", [])]
            if outer.ndim != 1 or any(h.ndim != 1 for h in holes):
                raise ValueError
        except (KeyError, TypeError, ValueError, OverflowError, AttributeError):
            raise MeshError("boundary: expected {\"outer\": [ids], \"holes\": [[ids], ...]}") from None
        if not _same_loop(mesh.outer_loop, outer):
            raise MeshError("boundary.outer: does not match the outer boundary of the triangles "
                            "(counter-clockwise, listed once); fix it or omit 'boundary'")
        if len(holes) != len(mesh.hole_loops) or not all(
                any(_same_loop(h, g) for g in mesh.hole_loops) for h in holes):
            raise MeshError("boundary.holes: do not match the hole boundaries of the triangles "
                            "(clockwise, listed once); fix them or omit 'boundary'")
    return mesh


def is_mesh_file(path: str | Path) -> bool:
    """True if ``path`` is a mesh (mesh JSON or a meshio format), not a part file."""
    from ..drawing import is_drawing_file

    path = Path(path)
    if is_drawing_file(path):
        return False
    if path.suffix.lower() != ".json":
        return True
    from ..jsonfile import read_json

    try:
        data = read_json(path, MeshError, "mesh file")
    except MeshError:
        return False     # not a readable mesh JSON: the part reader will say what is wrong
    return isinstance(data, dict) and "format" in data and "outer" not in data


def read_mesh(path: str | Path, units: str = "m", material: Material | None = None) -> Mesh:
    """Read a mesh JSON file or any triangle mesh meshio reads.

    Parameters
    ----------
    path : path-like
    units : str
        Length unit of a meshio file's coordinates (mesh JSON states its own).
    material : Material, optional
        Material to attach (overrides the file's).

    Raises
    ------
    MeshError
    """
    path = Path(path)
    if path.suffix.lower() == ".json":
        from ..jsonfile import read_json

        mesh = mesh_from_dict(read_json(path, MeshError, "mesh file"))
    else:
        import contextlib
        import io

        from ..jsonfile import check_input_file

        check_input_file(path, MeshError, "mesh file")

        import meshio

        # meshio prints its diagnostics and calls sys.exit(1) when no reader accepts a
        # file: capture both so the user gets one line and our exit code.
        buf = io.StringIO()
        try:
            with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
                m = meshio.read(path)
        except (Exception, SystemExit) as err:  # meshio raises many types
            detail = " ".join((buf.getvalue() or str(err)).split())[:300]
            raise MeshError(f"{path}: meshio cannot read this file ({detail})") from None
        tris = [c.data for c in m.cells if c.type == "triangle"]
        if not tris:
            raise MeshError(f"{path}: contains no linear triangles ('triangle' cells)")
        if any(c.type not in ("triangle", "line", "vertex") for c in m.cells):
            kinds = sorted({c.type for c in m.cells} - {"triangle", "line", "vertex"})
            raise MeshError(f"{path}: unsupported cell types {kinds}; export linear triangles")
        pts = np.asarray(m.points, float)
        if pts.shape[1] == 3 and np.any(pts[:, 2] != 0):
            raise MeshError(f"{path}: node z coordinates are not all 0; a planar mesh is required")
        tri = np.concatenate(tris).astype(np.int64)
        if tri.size and (tri.min() < 0 or tri.max() >= len(pts)):
            bad = int(tri.min()) if tri.min() < 0 else int(tri.max())
            raise MeshError(f"{path}: a triangle names node {bad}, but the file has nodes 0.."
                            f"{len(pts) - 1} (OBJ faces count from 1); fix the faces")
        # meshio files often carry geometry points unused by any triangle: drop them.
        used = np.zeros(len(pts), bool)
        used[tri.ravel()] = True
        remap = np.cumsum(used) - 1
        try:
            scale = length_scale(units, "units")
        except Exception as err:
            raise MeshError(str(err)) from None
        mesh = Mesh.from_arrays(pts[used, :2] * scale, remap[tri], name=path.stem)
        stored = _material_from_cell_data(m, path)
        if stored is not None and material is None:
            if units != "m":
                raise MeshError(f"{path}: holds a material in SI units (written by deformclosure, "
                                "lengths in m); read it without --units")
            material = stored
    if material is not None:
        mesh = mesh.with_material(material)
    return mesh


#: meshio formats whose cell data survive a write and a read: the material goes there.
MATERIAL_FORMATS = (".vtu", ".vtk", ".dat", ".tec", ".avs")

#: Cell-data arrays holding the material (SI; one value per triangle, all equal), so that
#: ParaView shows them and :func:`read_mesh` restores the material.
_MATERIAL_FIELDS = ("youngs_modulus", "poisson_ratio", "thickness", "elastic_limit_strain",
                    "plane_strain", "critical_distance")


def _material_cell_data(material: Material, n: int) -> dict[str, list[np.ndarray]]:
    cd = material.critical_distance
    values = (material.youngs_modulus, material.poisson_ratio, material.thickness,
              material.elastic_limit_strain, float(material.plane == "strain"),
              np.nan if cd is None else cd)
    return {k: [np.full(n, v, dtype=float)] for k, v in zip(_MATERIAL_FIELDS, values)}


def _material_from_cell_data(m: Any, path: Path) -> Material | None:
    """The material a meshio mesh carries in its triangle cell data (written by us)."""
    if not all(k in m.cell_data for k in _MATERIAL_FIELDS):
        return None
    vals = []
    for k in _MATERIAL_FIELDS:
        arr = np.concatenate([np.asarray(a, float).ravel()
                              for c, a in zip(m.cells, m.cell_data[k]) if c.type == "triangle"])
        v = arr[0] if arr.size else np.nan
        same = np.all(arr == v) if not np.isnan(v) else np.all(np.isnan(arr))
        if not same:
            raise MeshError(f"{path}: cell data {k!r} differs between triangles; one material "
                            "per part is supported (give --material to override)")
        vals.append(float(v))
    E, nu, t, eL, strain, cd = vals
    try:
        return Material(E, nu, t, eL, "strain" if strain == 1.0 else "stress",
                        None if np.isnan(cd) else cd)
    except PartError as err:
        raise MeshError(f"{path}: stored material is invalid ({err}); give --material") from None


def write_mesh(mesh: Mesh, path: str | Path) -> bool:
    """Write ``mesh`` as mesh JSON (``.json``) or with meshio (any other suffix).

    The material goes into the file too: the ``"material"`` block of mesh JSON, or cell
    data (``youngs_modulus`` Pa, ``poisson_ratio``, ``thickness`` m,
    ``elastic_limit_strain``, ``plane_strain`` 0/1, ``critical_distance`` m or NaN) for the
    meshio formats of :data:`MATERIAL_FORMATS`.

    Returns
    -------
    bool
        Whether the file holds the material (``False`` for a mesh without one, or a format
        that cannot store it: give ``--material`` when reading such a file).
    """
    from ..outputs import atomic_path, write_text_atomic

    path = Path(path)
    if path.suffix.lower() == ".json":
        write_text_atomic(path, json.dumps(mesh_to_dict(mesh)), "mesh")
        return mesh.material is not None
    import meshio

    keep = mesh.material is not None and path.suffix.lower() in MATERIAL_FORMATS
    cell_data = _material_cell_data(mesh.material, len(mesh.triangles)) if keep else None
    try:
        with atomic_path(path) as tmp:
            meshio.write_points_cells(tmp, np.column_stack([mesh.nodes, np.zeros(mesh.n_nodes)]),
                                      [("triangle", mesh.triangles)], cell_data=cell_data)
    except (Exception, SystemExit) as err:  # unknown suffix, unwritable path, ...
        detail = " ".join(str(err).split())[:300]
        raise MeshError(f"{path}: cannot write mesh file ({detail}); use .json or a "
                        "suffix meshio knows (.vtk, .vtu, .msh, ...)") from None
    return keep
