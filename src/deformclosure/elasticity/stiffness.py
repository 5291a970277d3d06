"""Plane stress / plane strain stiffness of linear (CST) triangles, vectorised.

For a triangle with nodes 1, 2, 3 (counter-clockwise, area A) the strain
``[exx, eyy, gamma_xy] = B u_e`` with ``u_e = [x1, y1, x2, y2, x3, y3]`` and

    B = 1/(2A) [[b1, 0, b2, 0, b3, 0], [0, c1, 0, c2, 0, c3], [c1, b1, c2, b2, c3, b3]],
    b_i = y_j - y_k,  c_i = x_k - x_j  (i, j, k cyclic),

and the element stiffness is ``K_e = t A Bᵀ D B`` (constant strain, exact integration).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import StiffnessError
from ..part import Material

__all__ = ["constitutive_matrix", "element_b_matrices", "element_stiffness", "stiffness_matrix",
           "assemble"]


def constitutive_matrix(material: Material) -> np.ndarray:
    """Elasticity matrix ``D`` (Pa) mapping ``[exx, eyy, gamma_xy]`` to stresses.

    Plane stress: ``E/(1-nu²) [[1, nu, 0], [nu, 1, 0], [0, 0, (1-nu)/2]]``;
    plane strain: ``E/((1+nu)(1-2nu)) [[1-nu, nu, 0], [nu, 1-nu, 0], [0, 0, (1-2nu)/2]]``.
    """
    E, nu = material.youngs_modulus, material.poisson_ratio
    if material.plane == "stress":
        c = E / (1.0 - nu**2)
        return c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, (1.0 - nu) / 2.0]])
    c = E / ((1.0 + nu) * (1.0 - 2.0 * nu))
    return c * np.array([[1.0 - nu, nu, 0.0], [nu, 1.0 - nu, 0.0], [0.0, 0.0, (1.0 - 2.0 * nu) / 2.0]])


def element_b_matrices(nodes: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strain-displacement matrices of all triangles.

    Returns
    -------
    B : ndarray, shape (m, 3, 6)
        In 1/m.
    area : ndarray, shape (m,)
        Signed areas (m²).
    """
    p = nodes[triangles]                       # (m, 3, 2)
    x, y = p[..., 0], p[..., 1]
    b = np.roll(y, -1, axis=1) - np.roll(y, -2, axis=1)   # y_j - y_k
    c = np.roll(x, -2, axis=1) - np.roll(x, -1, axis=1)   # x_k - x_j
    area = 0.5 * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
    m = len(triangles)
    B = np.zeros((m, 3, 6))
    B[:, 0, 0::2] = b
    B[:, 1, 1::2] = c
    B[:, 2, 0::2] = c
    B[:, 2, 1::2] = b
    B /= (2.0 * area)[:, None, None]
    return B, area


def element_stiffness(nodes: np.ndarray, triangles: np.ndarray, material: Material) -> np.ndarray:
    """Element stiffness matrices ``t A Bᵀ D B`` (N/m), shape ``(m, 6, 6)``."""
    B, area = element_b_matrices(nodes, triangles)
    D = constitutive_matrix(material)
    DB = np.einsum("ij,mjk->mik", D, B)
    return np.einsum("mji,mjk->mik", B, DB) * (material.thickness * np.abs(area))[:, None, None]


def assemble(triangles: np.ndarray, Ke: np.ndarray, n_nodes: int) -> sp.csr_matrix:
    """Assemble element matrices ``(m, 6, 6)`` into a ``(2n, 2n)`` CSR matrix (COO → CSR)."""
    dofs = np.empty((len(triangles), 6), dtype=np.int64)
    dofs[:, 0::2] = 2 * triangles
    dofs[:, 1::2] = 2 * triangles + 1
    rows = np.repeat(dofs, 6, axis=1).ravel()
    cols = np.tile(dofs, (1, 6)).ravel()
    K = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(2 * n_nodes, 2 * n_nodes))
    K.sum_duplicates()
    return K


def stiffness_matrix(mesh, material: Material | None = None) -> sp.csr_matrix:
    """Global stiffness ``K`` (N/m), ``(2n, 2n)`` CSR, DOF order ``[x0, y0, x1, y1, ...]``.

    Parameters
    ----------
    mesh : Mesh
    material : Material, optional
        Defaults to ``mesh.material``.

    Raises
    ------
    StiffnessError
        If no material is known.

    Notes
    -----
    For a connected mesh the null space of ``K`` is exactly the three planar rigid
    modes (tested). The energy of a displacement ``u`` is ``½ uᵀ K u`` (J).
    """
    material = material if material is not None else mesh.material
    if material is None:
        raise StiffnessError("no material: give the part's material (youngs_modulus, poisson_ratio, "
                             "thickness, elastic_limit_strain) with the mesh")
    Ke = element_stiffness(mesh.nodes, mesh.triangles, material)
    return assemble(mesh.triangles, Ke, mesh.n_nodes)
