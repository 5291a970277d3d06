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

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DeformClosureError, MeshError, PartError
from ..jsonfile import InputFile, Source, check_input_file, read_json
from ..limits import MAX_TRIANGLES
from ..part import Material
from ..units import length_scale
from .core import Mesh

__all__ = ["MESH_FORMAT", "MATERIAL_FORMATS", "mesh_to_dict", "mesh_from_dict", "read_mesh",
           "write_mesh", "is_mesh_file", "material_cell_data"]

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


#: Keys of a mesh JSON file (``provenance`` is written by the CLI, not read).
_MESH_KEYS = {"format", "name", "units", "nodes", "triangles", "boundary", "material",
              "provenance"}
#: Keys of its ``material`` block; all but ``plane``, ``critical_distance`` and ``model``
#: required.
_MATERIAL_KEYS = ("youngs_modulus", "poisson_ratio", "thickness", "elastic_limit_strain", "plane",
                  "critical_distance", "model")


def _check_mesh_keys(data: Any) -> None:
    """A JSON object of known keys, the right format, and units, nodes and triangles."""
    if not isinstance(data, dict):
        raise MeshError("mesh file: top level must be a JSON object {...}")
    extra = set(data) - _MESH_KEYS
    if extra:
        raise MeshError(f"{sorted(extra)[0]}: unknown key in mesh file; remove it")
    if data.get("format") != MESH_FORMAT:
        raise MeshError(f"format: expected {MESH_FORMAT!r}, got {data.get('format')!r}")
    for key in ("units", "nodes", "triangles"):
        if key not in data:
            raise MeshError(f"{key}: required field is missing; add it")


def _is_number(v: Any, kinds: tuple = (int, float)) -> bool:
    return isinstance(v, kinds) and not isinstance(v, bool)


def _rows_of(rows: Any, kinds: tuple) -> bool:
    """Whether ``rows`` is a list of lists of numbers of ``kinds`` (no booleans)."""
    return isinstance(rows, list) and all(
        isinstance(r, list) and all(_is_number(v, kinds) for v in r) for r in rows)


def _mesh_arrays(data: dict, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (m) and raw triangle ids of a mesh JSON structure."""
    if not _rows_of(data["nodes"], (int, float)):
        raise MeshError("nodes: must be a list of [x, y] numbers (no strings or booleans)")
    if not _rows_of(data["triangles"], (int,)):
        raise MeshError("triangles: must be a list of [i, j, k] node ids, integers")
    try:
        nodes = np.asarray(data["nodes"], dtype=float) * scale
        tris = np.asarray(data["triangles"])
    except (TypeError, ValueError, OverflowError):
        raise MeshError("nodes/triangles: must be lists of [x, y] numbers and [i, j, k] integers") from None
    if tris.dtype.kind not in "iu":
        raise MeshError("triangles: node ids must be integers")
    return nodes, tris


def _material_block(m: Any, scale: float) -> Material:
    """The ``material`` block of a mesh JSON (lengths in the file's units)."""
    if not isinstance(m, dict):
        raise MeshError("material: must be an object")
    unknown = set(m) - set(_MATERIAL_KEYS)
    if unknown:
        raise MeshError(f"material.{sorted(unknown)[0]}: unknown key; remove it")
    missing = set(_MATERIAL_KEYS[:4]) - set(m)
    if missing:
        raise MeshError(f"material.{sorted(missing)[0]}: required field is missing; add it")
    vals = [m[k] for k in _MATERIAL_KEYS[:4]]
    if not all(_is_number(v) for v in vals):
        raise MeshError("material: values must be numbers")
    cd = m.get("critical_distance")
    if cd is not None and not _is_number(cd):
        raise MeshError("material.critical_distance: must be a number (m)")
    try:
        return Material(float(vals[0]), float(vals[1]), float(vals[2]) * scale, float(vals[3]),
                        m.get("plane", "stress"), None if cd is None else float(cd) * scale,
                        m.get("model", "linear"))
    except PartError as err:
        raise MeshError(str(err)) from None


def _loop_ids(ids: Any) -> np.ndarray | None:
    """``ids`` as a 1-D int64 array, ``None`` if it is not a list of node ids."""
    try:
        arr = np.asarray(ids, dtype=np.int64)
    except (TypeError, ValueError, OverflowError):
        return None
    return arr if arr.ndim == 1 else None


def _check_boundary_block(mesh: Mesh, b: Any) -> None:
    """The file's ``boundary`` loops must be the loops recovered from the triangles."""
    outer = _loop_ids(b.get("outer")) if isinstance(b, dict) and "outer" in b else None
    holes_in = b.get("holes", []) if isinstance(b, dict) else None
    holes = [_loop_ids(h) for h in holes_in] if isinstance(holes_in, list) else None
    if outer is None or holes is None or any(h is None for h in holes):
        raise MeshError("boundary: expected {\"outer\": [ids], \"holes\": [[ids], ...]}")
    if not _same_loop(mesh.outer_loop, outer):
        raise MeshError("boundary.outer: does not match the outer boundary of the triangles "
                        "(counter-clockwise, listed once); fix it or omit 'boundary'")
    if len(holes) != len(mesh.hole_loops) or not all(
            any(_same_loop(h, g) for g in mesh.hole_loops) for h in holes):
        raise MeshError("boundary.holes: do not match the hole boundaries of the triangles "
                        "(clockwise, listed once); fix them or omit 'boundary'")


def check_mesh_file_size(n_triangles: int, field: str) -> None:
    """Refuse a mesh file of more than :data:`~deformclosure.limits.MAX_TRIANGLES`
    triangles before it is validated (validating a million triangles took 14 s, and no
    analysis may factorise such a mesh)."""
    if n_triangles > MAX_TRIANGLES:
        raise MeshError(f"{field}: {n_triangles:,} triangles, more than the limit "
                        f"{MAX_TRIANGLES:,} (the sparse factorisation of K every analysis "
                        "starts with); coarsen the mesh")


def mesh_from_dict(data: Any) -> Mesh:
    """Validated :class:`Mesh` from the mesh JSON structure (SPEC §5).

    Parameters
    ----------
    data : dict
        ``format`` (``"deformclosure-mesh/1"``), ``units`` of the coordinates and of the
        material's lengths, ``nodes``, ``triangles``, optional ``boundary`` (checked
        against the loops recovered from the triangles), ``material`` and ``name``.

    Raises
    ------
    MeshError
        Naming the offending key.

    Examples
    --------
    >>> mesh = mesh_from_dict({"format": "deformclosure-mesh/1", "units": "mm",
    ...     "nodes": [[0, 0], [1, 0], [1, 1], [0, 1]], "triangles": [[0, 1, 2], [0, 2, 3]]})
    >>> mesh.nodes[2].tolist(), mesh.outer_loop.tolist()
    ([0.001, 0.001], [0, 1, 2, 3])
    """
    _check_mesh_keys(data)
    tris_in = data["triangles"]
    check_mesh_file_size(len(tris_in) if isinstance(tris_in, list) else 0, "triangles")
    scale = length_scale(data["units"], "units", MeshError)
    nodes, tris = _mesh_arrays(data, scale)
    material = None
    if data.get("material") is not None:
        material = _material_block(data["material"], scale)
    mesh = Mesh.from_arrays(nodes, tris, material=material, name=str(data.get("name", "part")))
    if data.get("boundary") is not None:
        _check_boundary_block(mesh, data["boundary"])
    return mesh


def _suffix(path: InputFile) -> str:
    """The lower-case suffix that selects a file's format (a Source's from its name)."""
    return path.suffix if isinstance(path, Source) else Path(path).suffix.lower()


def is_mesh_file(path: InputFile) -> bool:
    """True if ``path`` (a path or a :class:`~deformclosure.jsonfile.Source`) is a mesh
    (mesh JSON or a meshio format), not a part file."""
    from ..drawing import is_drawing_file

    if is_drawing_file(path):
        return False
    if _suffix(path) != ".json":
        return True
    try:
        data = read_json(path, MeshError, "mesh file")
    except MeshError:
        return False     # not a readable mesh JSON: the part reader will say what is wrong
    return isinstance(data, dict) and "format" in data and "outer" not in data


def read_mesh(path: InputFile, units: str = "m", material: Material | None = None) -> Mesh:
    """Read a mesh JSON file or any triangle mesh meshio reads.

    Parameters
    ----------
    path : path-like or Source
        The file, or a :class:`~deformclosure.jsonfile.Source` holding its bytes (its
        name selects the format and names the file in errors).
    units : str
        Length unit of a meshio file's coordinates (mesh JSON states its own).
    material : Material, optional
        Material to attach (overrides the file's).

    Raises
    ------
    MeshError

    Examples
    --------
    A mesh written as mesh JSON reads back the same, from its path or from its bytes:

    >>> import pathlib, tempfile
    >>> from deformclosure import Source, demo_part, mesh_part
    >>> mesh = mesh_part(demo_part(max_area_mm2=20.0))
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = pathlib.Path(d) / "block.json"
    ...     stored = write_mesh(mesh, path)
    ...     back, again = read_mesh(path), read_mesh(Source("block.json", path.read_bytes()))
    >>> stored, bool((back.nodes == mesh.nodes).all()), again.material == mesh.material
    (True, True, True)
    """
    if _suffix(path) == ".json":
        mesh = mesh_from_dict(read_json(path, MeshError, "mesh file"))
    else:
        mesh, stored = _read_meshio_file(path, units)
        if stored is not None and material is None:
            if units != "m":
                raise MeshError(f"{path}: holds a material in SI units (written by deformclosure, "
                                "lengths in m); read it without --units")
            material = stored
    if material is not None:
        mesh = mesh.with_material(material)
    return mesh


def _meshio_read(path: InputFile) -> Any:
    """``meshio.read`` of a path, or of a Source through a temporary file of the same
    suffix; errors name the file as given, never the temporary copy."""
    import contextlib
    import io
    import tempfile

    import meshio

    name = str(path)
    with contextlib.ExitStack() as stack:
        if isinstance(path, Source):
            tmpdir = stack.enter_context(tempfile.TemporaryDirectory(prefix="deformclosure-"))
            with tempfile.NamedTemporaryFile(suffix=path.suffix, dir=tmpdir, delete=False) as f:
                f.write(path.data)
            real = f.name
        else:
            check_input_file(path, MeshError, "mesh file")
            real = str(path)
        # meshio prints its diagnostics and calls sys.exit(1) when no reader accepts a
        # file: capture both so the user gets one line and our exit code.
        buf = io.StringIO()
        try:
            with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
                return meshio.read(real)
        except (Exception, SystemExit) as err:  # meshio raises many types
            detail = " ".join((buf.getvalue() or str(err)).split()).replace(real, name)[:300]
            raise MeshError(f"{name}: meshio cannot read this file ({detail})") from None


def _read_meshio_file(path: InputFile, units: str) -> tuple[Mesh, Material | None]:
    """A meshio file's linear triangles as a :class:`Mesh` (coordinates in ``units``),
    and the material it stores in its cell data, if any."""
    m = _meshio_read(path)
    tris = [c.data for c in m.cells if c.type == "triangle"]
    if not tris:
        raise MeshError(f"{path}: contains no linear triangles ('triangle' cells)")
    if any(c.type not in ("triangle", "line", "vertex") for c in m.cells):
        kinds = sorted({c.type for c in m.cells} - {"triangle", "line", "vertex"})
        raise MeshError(f"{path}: unsupported cell types {kinds}; export linear triangles")
    pts = np.asarray(m.points, float)
    if pts.shape[1] == 3 and np.any(pts[:, 2] != 0):
        raise MeshError(f"{path}: node z coordinates are not all 0; a planar mesh is required")
    check_mesh_file_size(sum(len(t) for t in tris), f"{path}: triangles")
    tri = np.concatenate(tris).astype(np.int64)
    if tri.size and (tri.min() < 0 or tri.max() >= len(pts)):
        bad = int(tri.min()) if tri.min() < 0 else int(tri.max())
        raise MeshError(f"{path}: a triangle names node {bad}, but the file has nodes 0.."
                        f"{len(pts) - 1} (OBJ faces count from 1); fix the faces")
    # meshio files often carry geometry points unused by any triangle: drop them.
    used = np.zeros(len(pts), bool)
    used[tri.ravel()] = True
    remap = np.cumsum(used) - 1
    scale = length_scale(units, "units", MeshError)
    mesh = Mesh.from_arrays(pts[used, :2] * scale, remap[tri], name=Path(str(path)).stem)
    return mesh, _material_from_cell_data(m, path)


#: meshio formats whose cell data survive a write and a read: the material goes there.
MATERIAL_FORMATS = (".vtu", ".vtk", ".dat", ".tec", ".avs")

#: Cell-data arrays holding the material (SI; one value per triangle, all equal), so that
#: ParaView shows them and :func:`read_mesh` restores the material.
_MATERIAL_FIELDS = ("youngs_modulus", "poisson_ratio", "thickness", "elastic_limit_strain",
                    "plane_strain", "critical_distance")


def material_cell_data(material: Material, n: int) -> dict[str, list[np.ndarray]]:
    """The material as constant cell fields of ``n`` triangles (meshio ``cell_data``: one
    list of one array per field of :data:`_MATERIAL_FIELDS`, SI), as every mesh file we
    write carries it. A material without its own critical distance (the default, 2 % of
    the diameter) has no ``critical_distance`` array: no NaN in a file ParaView shows."""
    cd = material.critical_distance
    values = (material.youngs_modulus, material.poisson_ratio, material.thickness,
              material.elastic_limit_strain, float(material.plane == "strain"), cd)
    return {k: [np.full(n, v, dtype=float)] for k, v in zip(_MATERIAL_FIELDS, values)
            if v is not None}


def _material_from_cell_data(m: Any, path: InputFile) -> Material | None:
    """The material a meshio mesh carries in its triangle cell data (written by us); no
    ``critical_distance`` array (or NaN, as older files wrote it) is the default one."""
    if not all(k in m.cell_data for k in _MATERIAL_FIELDS[:-1]):
        return None
    vals = []
    for k in _MATERIAL_FIELDS:
        if k not in m.cell_data:
            vals.append(np.nan)
            continue
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
    ``elastic_limit_strain``, ``plane_strain`` 0/1, ``critical_distance`` m when the material
    sets one) for the meshio formats of :data:`MATERIAL_FORMATS`.

    Returns
    -------
    bool
        Whether the file holds the material (``False`` for a mesh without one, or a format
        that cannot store it: give ``--material`` when reading such a file).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from deformclosure import demo_part, mesh_part
    >>> mesh = mesh_part(demo_part(max_area_mm2=20.0))
    >>> with tempfile.TemporaryDirectory() as d:
    ...     kept = write_mesh(mesh, pathlib.Path(d) / "block.vtu"), write_mesh(mesh, pathlib.Path(d) / "block.msh")
    >>> kept        # .vtu stores the material as cell data, .msh cannot
    (True, False)
    """
    from ..outputs import atomic_path, write_json

    path = Path(path)
    if path.suffix.lower() == ".json":
        write_json(path, mesh_to_dict(mesh), "mesh", indent=None)
        return mesh.material is not None
    import meshio

    keep = mesh.material is not None and path.suffix.lower() in MATERIAL_FORMATS
    cell_data = material_cell_data(mesh.material, len(mesh.triangles)) if keep else None
    try:
        with atomic_path(path, "mesh file") as tmp:
            meshio.write_points_cells(tmp, np.column_stack([mesh.nodes, np.zeros(mesh.n_nodes)]),
                                      [("triangle", mesh.triangles)], cell_data=cell_data)
    except DeformClosureError:              # the target itself (outputs.atomic_path)
        raise
    except OSError as err:
        raise MeshError(f"{path}: cannot write mesh file ({err.strerror or err})") from None
    except (Exception, SystemExit) as err:  # unknown suffix, ...
        detail = " ".join(str(err).split())[:300]
        raise MeshError(f"{path}: cannot write mesh file ({detail}); use .json or a "
                        "suffix meshio knows (.vtk, .vtu, .msh, ...)") from None
    return keep
