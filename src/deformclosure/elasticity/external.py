"""User-supplied stiffness matrices (Matrix Market, Harwell-Boeing) with their mesh.

Commercial FEM codes export the global stiffness of the mesh they solved; we accept it
instead of assembling our own, after checking that it fits the mesh: shape ``(2n, 2n)``,
symmetric, the three rigid modes in its null space and no other zero-energy mode.
The DOF order must be ``[x0, y0, x1, y1, ...]`` in the node order of the mesh and the
units N/m.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..errors import StiffnessError
from .solve import FreeBodySolver, rigid_modes

__all__ = ["read_stiffness", "check_stiffness"]


def check_stiffness(K: sp.spmatrix, nodes: np.ndarray, rtol: float = 1e-8) -> sp.csr_matrix:
    """Validate ``K`` against the mesh nodes and return it as CSR.

    Raises
    ------
    StiffnessError
        Wrong shape, non-finite, not symmetric, rigid modes not in the null space, or a
        further zero-energy mode.
    """
    n2 = 2 * len(nodes)
    K = sp.csr_matrix(K, dtype=float)
    if K.shape != (n2, n2):
        raise StiffnessError(f"stiffness has shape {K.shape}, expected ({n2}, {n2}) for a mesh "
                             f"of {len(nodes)} nodes (DOF order x0, y0, x1, y1, ...)")
    if not np.all(np.isfinite(K.data)):
        raise StiffnessError("stiffness has non-finite entries")
    scale = abs(K).max()
    if scale == 0:
        raise StiffnessError("stiffness is all zero")
    asym = abs(K - K.T).max()
    if asym > rtol * scale:
        raise StiffnessError(f"stiffness is not symmetric (max |K - Kᵀ| = {asym:.3g}, "
                             f"{asym / scale:.2g} of max |K|); export the full symmetric matrix")
    R = rigid_modes(nodes)
    # Rotation column scales with coordinates; compare with K's action on unit vectors.
    L = float(np.ptp(nodes, axis=0).max())
    resid = np.abs(K @ (R / np.array([1.0, 1.0, L]))).max()
    if resid > 1e-6 * scale:
        raise StiffnessError("stiffness does not have the 3 rigid modes in its null space "
                             f"(max |K r| = {resid:.3g}); is it the free (unsupported) matrix of "
                             "this mesh, DOFs ordered x0, y0, x1, y1, ...?")
    FreeBodySolver(K, nodes)  # raises on extra zero modes
    return K


def read_stiffness(path: str | Path, mesh) -> sp.csr_matrix:
    """Read a stiffness matrix (``.mtx`` Matrix Market, ``.rb/.rua/.rsa/.hb`` Harwell-Boeing).

    A symmetric file storing one triangle is expanded by the reader.

    Parameters
    ----------
    path : path-like
        The matrix file (N/m, DOF order ``x0, y0, x1, y1, …`` of ``mesh``).
    mesh : Mesh
        The mesh it belongs to (checked by :func:`check_stiffness`).

    Returns
    -------
    scipy.sparse.csr_matrix

    Raises
    ------
    StiffnessError

    Examples
    --------
    A stiffness exported by another code reads back as the one we assemble:

    >>> import pathlib, tempfile, scipy.io
    >>> from deformclosure import Material, Mesh, stiffness_matrix
    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2], [0, 2, 3]],
    ...                         Material(1e6, 0.3, 1e-3, 0.1))
    >>> with tempfile.TemporaryDirectory() as d:
    ...     scipy.io.mmwrite(pathlib.Path(d) / "K.mtx", stiffness_matrix(mesh))
    ...     K = read_stiffness(pathlib.Path(d) / "K.mtx", mesh)
    >>> K.shape, bool(abs(K - stiffness_matrix(mesh)).max() <= 1e-9 * abs(K).max())
    ((8, 8), True)
    """
    import scipy.io  # imported here: it costs a CLI start-up 0.1 s for a rare path

    path = Path(path)
    suffix = path.suffix.lower()
    try:
        if suffix in (".mtx", ".mm"):
            K = scipy.io.mmread(str(path))
        elif suffix in (".rb", ".rua", ".rsa", ".hb", ".hwb"):
            K = _hb_read_any(path)
        else:
            raise StiffnessError(f"{path}: unknown stiffness format {suffix!r}; use .mtx (Matrix "
                                 "Market) or .rb/.rsa/.rua (Harwell-Boeing)")
    except StiffnessError:
        raise
    except Exception as err:  # scipy readers raise many types
        raise StiffnessError(f"{path}: cannot read stiffness matrix ({err})") from None
    return check_stiffness(sp.csr_matrix(K), mesh.nodes)


def _hb_read_any(path: Path) -> sp.csr_matrix:
    """Read an assembled real Harwell-Boeing file, unsymmetric (RUA) or symmetric (RSA).

    scipy's reader accepts RUA only; FEM codes usually write the stiffness as RSA (one
    triangle stored). An RSA file is read as RUA and its stored triangle mirrored.
    """
    import io

    import scipy.io

    lines = path.read_text().splitlines(keepends=True)
    if len(lines) < 3:
        raise StiffnessError(f"{path}: not a Harwell-Boeing file (header too short)")
    symmetric = lines[2][:3].upper() == "RSA"
    if symmetric:
        lines[2] = "RUA" + lines[2][3:]
    K = sp.csr_matrix(scipy.io.hb_read(io.StringIO("".join(lines))))
    if symmetric:
        if sp.triu(K, 1).nnz and sp.tril(K, -1).nnz:
            raise StiffnessError(f"{path}: symmetric (RSA) file stores entries on both sides "
                                 "of the diagonal; store one triangle or write it as RUA")
        K = (K + K.T - sp.diags(K.diagonal())).tocsr()
    return K
