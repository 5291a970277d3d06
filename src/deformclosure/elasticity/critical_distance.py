"""Strain averaged over a critical distance: a mesh-converged elastic-limit measure (SPEC §6).

At a re-entrant corner (a notch root, the inside corner of an L) the strain of the linear
solution is singular, so the largest *element* strain grows without bound as the mesh is
refined (like ``h^(λ-1)``, ``λ ≈ 0.544`` for a 270° corner). Following the theory of
critical distances for notched parts, the elastic limit is instead checked on the strain
averaged over a disc of radius ``ℓ`` (the material's critical distance):

- for every element ``i``, the disc is the set of elements whose centroids lie within
  ``ℓ`` of the centroid of ``i`` (``i`` itself always belongs to it);
- the engineering strain *tensor* ``[exx, eyy, gamma_xy]`` is averaged over the disc with
  the element areas as weights (components averaged, not magnitudes);
- its *strain magnitude* is the largest absolute in-plane principal value of that average
  (SPEC §1), and the grasp's ``e`` is its maximum over the elements.

The averaging is a sparse row-stochastic matrix ``W`` (:func:`averaging_operator`), built
once per mesh and ``ℓ`` and applied to any number of strain fields. Its number of non-zeros
is about ``m`` times the number of elements per disc; a disc that covers the whole part
makes it dense (``m²`` entries), so keep ``ℓ`` a small fraction of the part's size on fine
meshes.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..errors import GraspError, MeshError
from .strain import principal_strains

__all__ = [
    "default_critical_distance",
    "critical_distance_of",
    "averaging_operator",
    "averaged_strains",
    "averaged_strain_magnitude",
]

#: Default critical distance as a fraction of the part's diameter (SPEC §6).
DEFAULT_CRITICAL_FRACTION = 0.02


def critical_distance_of(mesh) -> float:
    """The critical distance ``ℓ`` (m) of a mesh's material: its ``critical_distance``,
    else :func:`default_critical_distance` of the mesh's diameter (SPEC §6). The one
    home of the default, for every model."""
    mat = getattr(mesh, "material", None)
    cd = getattr(mat, "critical_distance", None) if mat is not None else None
    return default_critical_distance(mesh.diameter) if cd is None else float(cd)


def _check_ell(ell: float) -> float:
    try:
        value = float(ell)
    except (TypeError, ValueError):
        raise GraspError(f"critical_distance = {ell!r}: must be a finite length >= 0 (m)") from None
    if not (math.isfinite(value) and value >= 0.0):
        raise GraspError(f"critical_distance = {ell!r}: must be a finite length >= 0 (m); "
                         "use 0 for the element strains themselves")
    return value


def default_critical_distance(diameter: float) -> float:
    """Default critical distance: 2 % of the part's diameter (SPEC §6).

    Parameters
    ----------
    diameter : float
        Largest distance between two points of the part (m), finite and > 0.

    Returns
    -------
    float
        ``0.02 * diameter`` (m).

    Raises
    ------
    GraspError
        If ``diameter`` is not a finite length > 0.
    """
    d = float(diameter)
    if not (math.isfinite(d) and d > 0.0):
        raise GraspError(f"diameter = {diameter!r}: must be a finite length > 0 (m) to set the "
                         "default critical_distance")
    return DEFAULT_CRITICAL_FRACTION * d


def averaging_operator(mesh, ell: float) -> sp.csr_matrix:
    """Area-weighted averaging over discs of radius ``ell`` around element centroids.

    Row ``i`` holds, for every element ``j`` whose centroid lies within ``ell`` of the
    centroid of element ``i`` (distance ``<= ell``; ``j = i`` always included),
    the weight ``A_j / sum_k A_k`` (sum over the same disc), so every row sums to 1 and
    ``W @ f`` is the area-weighted mean of an element field ``f`` over each disc.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh (nodes in m).
    ell : float
        Critical distance ``ℓ`` (m), finite and >= 0. ``ell = 0`` gives the identity.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (m, m)
        Row-stochastic averaging matrix (dimensionless), ``m`` = number of triangles.

    Raises
    ------
    GraspError
        If ``ell`` is negative or not finite (the message names ``critical_distance``).
    """
    from scipy.spatial import cKDTree  # lazy: scipy.spatial is slow to import

    ell = _check_ell(ell)
    tri = np.asarray(mesh.triangles)
    nodes = np.asarray(mesh.nodes, float)
    m = len(tri)
    centroids = nodes[tri].mean(axis=1)
    d1 = nodes[tri[:, 1]] - nodes[tri[:, 0]]
    d2 = nodes[tri[:, 2]] - nodes[tri[:, 0]]
    areas = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])       # m²
    diag = np.arange(m)
    if ell > 0.0:
        pairs = cKDTree(centroids).query_pairs(ell, output_type="ndarray")  # i < j, d <= ell
        rows = np.concatenate([diag, pairs[:, 0], pairs[:, 1]])
        cols = np.concatenate([diag, pairs[:, 1], pairs[:, 0]])
    else:
        rows = cols = diag
    # Every (row, col) pair occurs once: normalise the weights per row before assembly.
    weights = areas[cols]
    weights /= np.bincount(rows, weights=weights, minlength=m)[rows]
    return sp.csr_matrix((weights, (rows, cols)), shape=(m, m))


def _operator(mesh, ell: float | None, operator) -> sp.csr_matrix:
    m = len(mesh.triangles)
    if operator is None:
        if ell is None:
            raise GraspError("critical_distance = None: give a finite length >= 0 (m) or an "
                             "averaging operator")
        return averaging_operator(mesh, ell)
    if operator.shape != (m, m):
        raise MeshError(f"operator: shape {operator.shape} does not fit this mesh of {m} "
                        "triangles; build it with averaging_operator(mesh, ell)")
    return operator


def averaged_strains(mesh, strains: np.ndarray, ell: float | None,
                     operator: sp.spmatrix | None = None) -> np.ndarray:
    """Strain tensor averaged (area-weighted) over the critical-distance disc of each element.

    Parameters
    ----------
    mesh : Mesh
    strains : ndarray, shape (m, 3) or (k, m, 3)
        Engineering element strains ``[exx, eyy, gamma_xy]`` (dimensionless), one field or
        a stack of ``k`` fields.
    ell : float or None
        Critical distance (m), finite and >= 0; ignored (may be ``None``) when
        ``operator`` is given.
    operator : sparse matrix, shape (m, m), optional
        A precomputed :func:`averaging_operator` of this mesh, to reuse for many fields.

    Returns
    -------
    ndarray, same shape as ``strains``
        Averaged ``[exx, eyy, gamma_xy]`` per element (dimensionless).

    Raises
    ------
    GraspError
        If ``ell`` is invalid (and no operator is given).
    MeshError
        If ``strains`` or ``operator`` do not match the mesh.
    """
    m = len(mesh.triangles)
    e = np.asarray(strains, float)
    if e.ndim not in (2, 3) or e.shape[-2:] != (m, 3):
        raise MeshError(f"strains: shape {e.shape} does not fit this mesh of {m} triangles; "
                        f"give ({m}, 3) or (k, {m}, 3) [exx, eyy, gamma_xy] per element")
    W = _operator(mesh, ell, operator)
    if e.ndim == 2:
        return np.asarray(W @ e)
    k = e.shape[0]
    flat = np.ascontiguousarray(e.transpose(1, 0, 2)).reshape(m, 3 * k)
    return np.asarray(W @ flat).reshape(m, k, 3).transpose(1, 0, 2)


def averaged_strain_magnitude(mesh, strains: np.ndarray, ell: float | None,
                              operator: sp.spmatrix | None = None) -> np.ndarray:
    """Largest absolute in-plane principal value of the disc-averaged strain tensor.

    This is the critical-distance strain magnitude of SPEC §6; its maximum over the
    elements is compared with the elastic-limit strain ``e_L``. With ``ell = 0`` it is the
    element strain magnitude of SPEC §1.

    Parameters
    ----------
    mesh : Mesh
    strains : ndarray, shape (m, 3) or (k, m, 3)
        Engineering element strains ``[exx, eyy, gamma_xy]`` (dimensionless).
    ell : float or None
        Critical distance (m), finite and >= 0; ignored when ``operator`` is given.
    operator : sparse matrix, shape (m, m), optional
        A precomputed :func:`averaging_operator` of this mesh.

    Returns
    -------
    ndarray, shape (m,) or (k, m)
        Averaged strain magnitude per element (dimensionless).
    """
    avg = averaged_strains(mesh, strains, ell, operator)
    mag = np.abs(principal_strains(avg.reshape(-1, 3))).max(axis=1)
    return mag.reshape(avg.shape[:-1])
