"""Fields of a solved state, out to ParaView (``--export-fields FILE.vtu``).

One state is a displacement field ``u`` (m) and the contact forces on the nodes (N). Its
file holds, on the mesh *deformed* by ``u`` (so that ParaView shows the deformed part
at once):

point data
    ``displacement`` (m, 3 components, z = 0: ``Warp By Vector`` with scale −1 gives the
    rest shape), ``rest_position`` (m), ``contact_force`` (N, 3 components),
    ``contact_pressure`` (Pa): the normal force over the node's tributary boundary length
    times the thickness; 0 away from contacts.
cell data
    ``strain`` (3 components ``[exx, eyy, exy]``, tensor — not engineering — shear),
    ``strain_magnitude`` (largest absolute principal strain of the element),
    ``strain_magnitude_averaged`` (the same of the strain averaged over the critical
    distance, what the pad model compares with ``e_L``), and the material
    (``youngs_modulus`` …, see :func:`deformclosure.mesh.io.write_mesh`), so the file
    reads back as a mesh with its material.

Several states (``optimize``: σ* and σ_L) go to several files: the first to ``FILE``, the
next ones to ``FILE`` with ``_<label>`` before the suffix.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import DeformClosureError

__all__ = ["FieldState", "FIELD_FORMATS", "field_paths", "check_field_path", "state_data",
           "write_fields", "write_slice_fields"]

#: Suffixes ``--export-fields`` writes (meshio formats keeping point and cell data).
FIELD_FORMATS = (".vtu", ".vtk")


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
    """

    label: str
    displacement: np.ndarray
    forces: np.ndarray
    elastic: np.ndarray | None = None


def field_paths(path: str | Path, labels: list[str]) -> list[Path]:
    """The file of each state: ``path`` for the first, ``<stem>_<label><suffix>`` next."""
    path = Path(path)
    return [path] + [path.with_name(f"{path.stem}_{lab}{path.suffix}") for lab in labels[1:]]


def check_field_path(path: str | Path) -> None:
    """Refuse a suffix the fields cannot be written in, before any work."""
    if Path(path).suffix.lower() not in FIELD_FORMATS:
        raise DeformClosureError(f"--export-fields {path}: use a .vtu (ParaView) or .vtk file")


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


def _write_mesh(path: str | Path, points: np.ndarray, cells: list, **data) -> None:
    """``meshio.write_points_cells`` to ``path`` atomically; a failure is one line."""
    import meshio

    from .outputs import atomic_path

    try:
        with atomic_path(path, "fields") as tmp:
            meshio.write_points_cells(tmp, points, cells, **data)
    except OSError as err:
        raise DeformClosureError(f"--export-fields {path}: cannot write ({err.strerror})") from None


def state_data(mesh, state: FieldState, ell: float) -> tuple[dict, dict]:
    """Point and cell data of ``state`` on ``mesh`` (see the module docstring).

    Parameters
    ----------
    mesh : Mesh
        With a material (thickness for the pressure).
    state : FieldState
    ell : float
        Critical distance (m) of the averaged strain.

    Returns
    -------
    point_data, cell_data : dict
        meshio-style dictionaries (cell data as one-block lists).
    """
    from .elasticity.critical_distance import averaged_strains
    from .elasticity.strain import element_strains, principal_strains

    n = mesh.n_nodes
    u = _nodal(state.displacement, n, f"{state.label}.displacement")
    f = _nodal(state.forces, n, f"{state.label}.forces")
    ue = u if state.elastic is None else _nodal(state.elastic, n, f"{state.label}.elastic")
    eng = element_strains(mesh, ue.ravel())                # [exx, eyy, gamma_xy]
    avg = averaged_strains(mesh, eng, ell)
    mag = np.abs(principal_strains(eng)).max(axis=1)
    mag_avg = np.abs(principal_strains(avg)).max(axis=1)
    tensor = eng * np.array([1.0, 1.0, 0.5])
    t = mesh.material.thickness if mesh.material is not None else 1.0
    trib = _tributary_lengths(mesh)
    fn = np.linalg.norm(f, axis=1)
    pressure = np.divide(fn, trib * t, out=np.zeros(n), where=trib > 0)
    z = np.zeros((n, 1))
    point = {"displacement": np.hstack([u, z]), "rest_position": np.hstack([mesh.nodes, z]),
             "contact_force": np.hstack([f, z]), "contact_pressure": pressure}
    cell = {"strain": [tensor], "strain_magnitude": [mag],
            "strain_magnitude_averaged": [mag_avg]}
    if mesh.material is not None:
        from .mesh.io import material_cell_data

        cell.update(material_cell_data(mesh.material, len(mesh.triangles)))
    return point, cell


def write_fields(path: str | Path, mesh, states: list[FieldState], ell: float) -> list[Path]:
    """Write each state's fields on the deformed mesh (module docstring); atomically.

    Returns
    -------
    list of Path
        The files written, in the order of ``states``.
    """
    check_field_path(path)
    paths = field_paths(path, [s.label for s in states])
    for p, state in zip(paths, states):
        point, cell = state_data(mesh, state, ell)
        _write_mesh(p, point["rest_position"] + point["displacement"],
                    [("triangle", mesh.triangles)], point_data=point, cell_data=cell)
    return paths


def write_slice_fields(path: str | Path, result) -> Path:
    """A D-space slice (``slice``) as an image for ParaView: the grid of positions of the
    moving node (pixel centres, m) joined into quads, with point data ``energy`` (J),
    ``d_free`` and ``d_t`` (1 inside, 0 outside) and ``obstacle_<k>`` for each finger."""
    check_field_path(path)
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
