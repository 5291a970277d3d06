"""Fields of a solved state, out to ParaView (``--export-fields FILE.vtu|FILE.pvd``).

One state is a displacement field ``u`` (m) and the contact forces on the nodes (N). Its
file holds the mesh at *rest* (reference coordinates) with:

point data
    ``displacement`` (m, 3 components, z = 0: ParaView's ``Warp By Vector`` with scale 1
    shows the deformed part, at true scale), ``rest_position`` (m, the points
    themselves), ``contact_force`` (N, 3 components), ``contact_pressure`` (Pa): the
    normal force over the node's tributary boundary length times the thickness; 0 away
    from contacts.
cell data
    ``strain`` (9 components ``XX XY XZ YX YY YZ ZX ZY ZZ``, named in the file, so that
    ParaView treats it as a tensor: the small-strain tensor of the element, tensor — not
    engineering — shear, with the out-of-plane ``ZZ`` of the material's plane stress
    ``−ν/(1−ν) (XX + YY)`` or plane strain ``0``), ``stress`` (Pa, 9 components the
    same: the linear law's stress of that strain, ``σ = λ tr(ε) I + 2μ ε``; plane
    stress ``ZZ = 0``, plane strain ``ν (XX + YY)``; for a neo-Hookean part it is the
    linear law's stress of the linearised strain, a reference, not the Cauchy stress),
    ``strain_magnitude`` (largest absolute in-plane principal strain of the element),
    ``strain_magnitude_averaged`` (the same of the strain averaged over the critical
    distance, what the pad model compares with ``e_L``), and the material
    (``youngs_modulus`` …, see :func:`deformclosure.mesh.io.write_mesh`), so the file
    reads back as a mesh with its material.
field data
    ``critical_distance`` (m, the averaging radius used, never NaN), and for a state of a
    squeeze ``sigma`` (m, the jaws' separation), ``squeeze`` (m, ``|σ0 − σ|``) and
    ``TimeValue`` (= ``squeeze``).

**Pads.** A pad grasp's state also writes the two pads where they are at that squeeze, as
a separate file ``<stem>_pads<suffix>`` (ParaView opens both; one polygon cell per pad,
cell data ``pad`` 0 = A, 1 = B, and a zero ``displacement`` so that one ``Warp By Vector``
over both leaves the pads in place). A separate file, not a multi-block one, so each
opens in any VTK reader and ``meshio.read`` reads the part's file unchanged.

**Several states** (``optimize``: σ* and σ_L) go to several files: the first to ``FILE``,
the next ones to ``FILE`` with ``_<label>`` before the suffix. **A series**
(``--export-fields FILE.pvd``): ``optimize`` writes the squeeze from first touch to σ_L
(:data:`SERIES_FRAMES` evenly spaced separations, and σ*), one ``.vtu`` per frame (and its
pads) in the folder ``<stem>_series/`` beside ``FILE.pvd``, a ParaView collection whose
time is the squeeze ``δ`` (m), so the Play button squeezes the part; ``check`` writes its
one equilibrium as a one-frame collection.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import DeformClosureError

__all__ = ["FieldState", "FIELD_FORMATS", "SERIES_FRAMES", "TENSOR_COMPONENTS", "field_paths",
           "pads_path", "check_field_path", "series_sigmas", "state_data", "write_fields",
           "write_slice_fields"]

#: Suffixes ``--export-fields`` writes: meshio formats keeping point and cell data, and
#: the ParaView collection of a series.
FIELD_FORMATS = (".vtu", ".vtk", ".pvd")

#: Evenly spaced separations of a ``.pvd`` series, first touch and σ_L included (σ* is
#: added to them).
SERIES_FRAMES = 21

#: Component names of the 3 × 3 tensors, row by row (ParaView's order of 9 components).
TENSOR_COMPONENTS = ("XX", "XY", "XZ", "YX", "YY", "YZ", "ZX", "ZY", "ZZ")


@dataclass(frozen=True)
class FieldState:
    """A solved state of the part.

    Attributes
    ----------
    label : str
        Its name in file names and messages (``"sigma_star"``).
    displacement : ndarray, shape (2n,) or (n, 2)
        Node displacements (m).
    forces : ndarray, shape (n, 2)
        Contact forces on the nodes (N); zeros where nothing touches.
    elastic : ndarray, optional
        The displacement whose linear strains are the state's (m); default
        ``displacement``. A part that also turns (``check``) places its nodes by the
        exact rotation but strains by the elastic part only.
    sigma : float, optional
        The jaws' separation of the state (m).
    squeeze : float, optional
        Its squeeze ``|σ0 − σ|`` beyond first touch (m): the time of a series.
    pads : tuple of ndarray, optional
        Outlines (m, shape (k, 2) each, same k) of pads A and B at the state; empty for
        jaws without a shape.
    """

    label: str
    displacement: np.ndarray
    forces: np.ndarray
    elastic: np.ndarray | None = None
    sigma: float | None = None
    squeeze: float | None = None
    pads: tuple = ()


def field_paths(path: str | Path, labels: list[str]) -> list[Path]:
    """The file of each state: ``path`` for the first, ``<stem>_<label><suffix>`` next;
    a ``.pvd`` series is the one file ``path`` (its frames go to ``<stem>_series/``)."""
    path = Path(path)
    if path.suffix.lower() == ".pvd":
        return [path]
    return [path] + [path.with_name(f"{path.stem}_{lab}{path.suffix}") for lab in labels[1:]]


def pads_path(path: str | Path) -> Path:
    """The pads' file beside a state's file ``path``: ``<stem>_pads<suffix>``."""
    path = Path(path)
    return path.with_name(f"{path.stem}_pads{path.suffix}")


def check_field_path(path: str | Path, series: bool = True) -> None:
    """Refuse a suffix the fields cannot be written in, before any work (``series``:
    whether a ``.pvd`` collection is possible)."""
    formats = FIELD_FORMATS if series else tuple(f for f in FIELD_FORMATS if f != ".pvd")
    if Path(path).suffix.lower() not in formats:
        choices = "a .vtu (ParaView), .vtk" + (" or .pvd (a series over σ)" if series else "")
        raise DeformClosureError(f"--export-fields {path}: use {choices} file")


def series_sigmas(sigma0: float, sigma_L: float, sigma_star: float | None = None,
                  n: int = SERIES_FRAMES) -> list[tuple[str, float]]:
    """Labelled separations (m) of a series: ``n`` evenly spaced from first touch
    ``sigma0`` to the elastic limit ``sigma_L`` and ``sigma_star`` among them, in the
    order of the squeeze (a σ* within 10⁻⁹ of a frame replaces that frame).

    Examples
    --------
    >>> [(lab, round(s, 3)) for lab, s in series_sigmas(1.0, 0.5, 0.8, n=3)]
    [('frame_000', 1.0), ('sigma_star', 0.8), ('frame_001', 0.75), ('frame_002', 0.5)]
    """
    sig = [(f"frame_{k:03d}", float(s)) for k, s in enumerate(np.linspace(sigma0, sigma_L, n))]
    if sigma_star is not None:
        tol = 1e-9 * max(abs(sigma0 - sigma_L), abs(sigma0))
        sig = [(lab, s) for lab, s in sig if abs(s - sigma_star) > tol]
        sig.append(("sigma_star", float(sigma_star)))
    return sorted(sig, key=lambda ls: abs(ls[1] - sigma0))


def _tributary_lengths(mesh) -> np.ndarray:
    """Half the length of the boundary edges at each node (m); 0 inside."""
    e = mesh.boundary_edges
    L = np.linalg.norm(mesh.nodes[e[:, 1]] - mesh.nodes[e[:, 0]], axis=1)
    out = np.zeros(mesh.n_nodes)
    np.add.at(out, e[:, 0], 0.5 * L)
    np.add.at(out, e[:, 1], 0.5 * L)
    return out


def _nodal(values, n: int, field: str) -> np.ndarray:
    """``values`` as an ``(n, 2)`` float array: one vector per node."""
    try:
        arr = np.asarray(values, float)
    except (TypeError, ValueError):
        raise DeformClosureError(f"{field}: not an array of numbers") from None
    if arr.size != 2 * n:
        raise DeformClosureError(f"{field}: {arr.size} values for a mesh of {n} nodes; give "
                                 f"shape ({2 * n},) or ({n}, 2)")
    return arr.reshape(n, 2)


def _vtu_extras(path: Path, components: dict[str, tuple[str, ...]],
                field: dict[str, float]) -> None:
    """Add what meshio does not write to a ``.vtu`` file: the component names of arrays
    (``ComponentName0`` …, so ParaView labels them) and the field data (one Float64 value
    each, in a ``FieldData`` block of the grid)."""
    tree = ET.parse(path)
    root = tree.getroot()
    for da in root.iter("DataArray"):
        names = components.get(da.get("Name", ""))
        if names and da.get("NumberOfComponents") == str(len(names)):
            for i, c in enumerate(names):
                da.set(f"ComponentName{i}", c)
    grid = root.find("UnstructuredGrid")
    if field and grid is not None:
        block = ET.Element("FieldData")
        for k, v in field.items():
            e = ET.SubElement(block, "DataArray", type="Float64", Name=k,
                              NumberOfTuples="1", format="ascii")
            e.text = repr(float(v))
        grid.insert(0, block)
    tree.write(path, xml_declaration=True, encoding="utf-8")


def _write_mesh(path: str | Path, points: np.ndarray, cells: list,
                components: dict[str, tuple[str, ...]] | None = None,
                field: dict[str, float] | None = None, **data) -> None:
    """``meshio.write_points_cells`` to ``path`` atomically (and, ``.vtu``, the component
    names and the field data, :func:`_vtu_extras`); a failure is one line."""
    import meshio

    from .outputs import atomic_path

    try:
        with atomic_path(path, "fields") as tmp:
            meshio.write_points_cells(tmp, points, cells, field_data=dict(field or {})
                                      if Path(path).suffix.lower() != ".vtu" else None,
                                      **data)
            if Path(path).suffix.lower() == ".vtu" and (components or field):
                _vtu_extras(Path(tmp), components or {}, field or {})
    except OSError as err:
        raise DeformClosureError(f"--export-fields {path}: cannot write ({err.strerror})") from None


def _tensor9(t2: np.ndarray, zz: np.ndarray) -> np.ndarray:
    """Symmetric in-plane tensors ``[xx, yy, xy]`` (m, 3) and their ``zz`` as 3 × 3
    tensors flattened row by row, shape (m, 9)."""
    out = np.zeros((len(t2), 9))
    out[:, 0], out[:, 4], out[:, 8] = t2[:, 0], t2[:, 1], zz
    out[:, 1] = out[:, 3] = t2[:, 2]
    return out


def state_data(mesh, state: FieldState, ell: float) -> tuple[dict, dict]:
    """Point and cell data of ``state`` on ``mesh`` (see the module docstring).

    Parameters
    ----------
    mesh : Mesh
        With a material (thickness for the pressure, the law for the stress).
    state : FieldState
    ell : float
        Critical distance (m) of the averaged strain.

    Returns
    -------
    point_data, cell_data : dict
        meshio-style dictionaries (cell data as one-block lists).
    """
    from .elasticity.critical_distance import averaged_strains
    from .elasticity.strain import element_strains, element_stresses, principal_strains

    n = mesh.n_nodes
    u = _nodal(state.displacement, n, f"{state.label}.displacement")
    f = _nodal(state.forces, n, f"{state.label}.forces")
    ue = u if state.elastic is None else _nodal(state.elastic, n, f"{state.label}.elastic")
    eng = element_strains(mesh, ue.ravel())                # [exx, eyy, gamma_xy]
    avg = averaged_strains(mesh, eng, ell)
    mag = np.abs(principal_strains(eng)).max(axis=1)
    mag_avg = np.abs(principal_strains(avg)).max(axis=1)
    tensor = eng * np.array([1.0, 1.0, 0.5])
    mat = mesh.material
    t = mat.thickness if mat is not None else 1.0
    trib = _tributary_lengths(mesh)
    fn = np.linalg.norm(f, axis=1)
    pressure = np.divide(fn, trib * t, out=np.zeros(n), where=trib > 0)
    z = np.zeros((n, 1))
    point = {"displacement": np.hstack([u, z]), "rest_position": np.hstack([mesh.nodes, z]),
             "contact_force": np.hstack([f, z]), "contact_pressure": pressure}
    cell: dict[str, list[np.ndarray]] = {}
    if mat is not None:
        nu = mat.poisson_ratio
        sig = element_stresses(mesh, ue.ravel(), mat)      # [sxx, syy, sxy] (Pa)
        if mat.plane == "stress":
            e_zz, s_zz = -nu / (1.0 - nu) * (tensor[:, 0] + tensor[:, 1]), np.zeros(len(sig))
        else:
            e_zz, s_zz = np.zeros(len(sig)), nu * (sig[:, 0] + sig[:, 1])
        cell["strain"] = [_tensor9(tensor, e_zz)]
        cell["stress"] = [_tensor9(sig, s_zz)]
    else:
        cell["strain"] = [_tensor9(tensor, np.zeros(len(tensor)))]
    cell.update({"strain_magnitude": [mag], "strain_magnitude_averaged": [mag_avg]})
    if mat is not None:
        from .mesh.io import material_cell_data

        cell.update(material_cell_data(mat, len(mesh.triangles)))
    return point, cell


def _field_data(state: FieldState, ell: float) -> dict[str, float]:
    """The state's field data (module docstring): finite numbers only."""
    out = {"critical_distance": float(ell)}
    if state.sigma is not None:
        out["sigma"] = float(state.sigma)
    if state.squeeze is not None:
        out["squeeze"] = out["TimeValue"] = float(state.squeeze)
    return {k: v for k, v in out.items() if np.isfinite(v)}


_COMPONENTS = {"strain": TENSOR_COMPONENTS, "stress": TENSOR_COMPONENTS,
               "displacement": ("X", "Y", "Z"), "rest_position": ("X", "Y", "Z"),
               "contact_force": ("X", "Y", "Z")}


def _write_state(path: Path, mesh, state: FieldState, ell: float) -> list[Path]:
    """The state's part file at ``path`` and, with pads, its pads file beside it."""
    point, cell = state_data(mesh, state, ell)
    field = _field_data(state, ell)
    _write_mesh(path, point["rest_position"], [("triangle", mesh.triangles)],
                components=_COMPONENTS, field=field, point_data=point, cell_data=cell)
    out = [path]
    if state.pads:
        P = np.vstack([np.asarray(p, float) for p in state.pads])
        k = len(state.pads[0])
        polys = np.arange(len(P)).reshape(len(state.pads), k)
        pts = np.column_stack([P, np.zeros(len(P))])
        _write_mesh(pads_path(path), pts, [("polygon", polys)], components=_COMPONENTS,
                    field=field, point_data={"displacement": np.zeros_like(pts)},
                    cell_data={"pad": [np.arange(len(state.pads), dtype=np.int32)]})
        out.append(pads_path(path))
    return out


def _write_series(path: Path, mesh, states: list[FieldState], ell: float) -> list[Path]:
    """``states`` as the frames of the ParaView collection ``path`` (.pvd), their files in
    ``<stem>_series/``; time = squeeze (m), or the frame number without one."""
    from .outputs import atomic_path

    folder = path.with_name(f"{path.stem}_series")
    try:
        folder.mkdir(exist_ok=True)
    except OSError as err:
        raise DeformClosureError(f"--export-fields {path}: cannot make the folder {folder} "
                                 f"({err.strerror})") from None
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for k, state in enumerate(states):
        time = state.squeeze if state.squeeze is not None else float(k)
        files = _write_state(folder / f"part_{k:03d}.vtu", mesh, state, ell)
        for part, f in enumerate(files):
            ET.SubElement(coll, "DataSet", timestep=repr(float(time)), group="",
                          part=str(part), file=f"{folder.name}/{f.name}", name=state.label)
    ET.indent(root)
    try:
        with atomic_path(path, "fields") as tmp:
            ET.ElementTree(root).write(tmp, xml_declaration=True, encoding="utf-8")
    except OSError as err:
        raise DeformClosureError(f"--export-fields {path}: cannot write ({err.strerror})") from None
    return [path, folder]


def write_fields(path: str | Path, mesh, states: list[FieldState], ell: float) -> list[Path]:
    """Write each state's fields on the rest mesh (module docstring); atomically.

    A ``.vtu``/``.vtk`` path: one file per state (:func:`field_paths`), and its pads'
    file. A ``.pvd`` path: the states are the frames of one series.

    Returns
    -------
    list of Path
        The files written, in the order of ``states`` (a series: the ``.pvd`` and the
        folder of its frames).
    """
    check_field_path(path)
    path = Path(path)
    if path.suffix.lower() == ".pvd":
        return _write_series(path, mesh, states, ell)
    out: list[Path] = []
    for p, state in zip(field_paths(path, [s.label for s in states]), states):
        out += _write_state(p, mesh, state, ell)
    return out


def write_slice_fields(path: str | Path, result) -> Path:
    """A D-space slice (``slice``) as an image for ParaView: the grid of positions of the
    moving node (pixel centres, m) joined into quads, with point data ``energy`` (J),
    ``d_free`` and ``d_t`` (1 inside, 0 outside) and ``obstacle_<k>`` for each finger."""
    check_field_path(path, series=False)
    xs, ys = np.asarray(result.xs, float), np.asarray(result.ys, float)
    nx, ny = len(xs), len(ys)
    X, Y = np.meshgrid(xs, ys)                        # row iy = ys[iy], as the images
    pts = np.column_stack([X.ravel(), Y.ravel(), np.zeros(nx * ny)])
    idx = np.arange(nx * ny).reshape(ny, nx)
    quads = np.column_stack([idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(),
                             idx[1:, 1:].ravel(), idx[1:, :-1].ravel()])
    data = {"energy": np.asarray(result.energy, float).ravel(),
            "d_free": np.asarray(result.free, float).ravel(),
            "d_t": np.asarray(result.in_dt, float).ravel()}
    for k, ob in enumerate(np.asarray(result.obstacles)):
        data[f"obstacle_{k}"] = ob.astype(float).ravel()
    _write_mesh(path, pts, [("quad", quads)], point_data=data)
    return Path(path)
