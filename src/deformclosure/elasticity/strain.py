"""Element strains, principal strains and the strain magnitude compared with ``e_L``.

Strains are engineering strains ``[exx, eyy, gamma_xy]`` (``gamma_xy = 2 exy``), constant
per CST element. The *strain magnitude* of an element is its largest absolute in-plane
principal strain, ``max(|e1|, |e2|)`` (SPEC §1); the out-of-plane strain of plane stress
is not included.
"""

from __future__ import annotations

import numpy as np

from ..errors import MeshError
from .stiffness import element_b_matrices

__all__ = ["element_strains", "principal_strains", "strain_magnitude", "element_stresses"]


def _as_nodal(u: np.ndarray, n: int) -> np.ndarray:
    u = np.asarray(u, float)
    if u.shape == (2 * n,):
        return u.reshape(n, 2)
    if u.shape == (n, 2):
        return u
    raise MeshError(f"u: displacement of shape {u.shape} does not fit a mesh of {n} nodes; "
                    f"give shape ({2 * n},) (x0, y0, x1, ...) or ({n}, 2)")


def element_strains(mesh, u: np.ndarray) -> np.ndarray:
    """Engineering strains of every element, shape ``(m, 3)``: ``[exx, eyy, gamma_xy]``.

    Parameters
    ----------
    mesh : Mesh
    u : ndarray, shape (2n,) or (n, 2)
        Nodal displacements (m).

    Raises
    ------
    MeshError
        If ``u`` does not fit the mesh.

    Examples
    --------
    A unit square stretched by 1 % along x:

    >>> from deformclosure import Mesh
    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2], [0, 2, 3]])
    >>> element_strains(mesh, 0.01 * mesh.nodes * [1, 0]).round(12)
    array([[0.01, 0.  , 0.  ],
           [0.01, 0.  , 0.  ]])
    """
    un = _as_nodal(u, mesh.n_nodes)
    B, _ = element_b_matrices(mesh.nodes, mesh.triangles)
    ue = un[mesh.triangles].reshape(len(mesh.triangles), 6)
    return np.einsum("mij,mj->mi", B, ue)


def principal_strains(strains: np.ndarray) -> np.ndarray:
    """In-plane principal strains ``(e1, e2)``, ``e1 >= e2``, shape ``(m, 2)``.

    Examples
    --------
    Pure shear ``gamma_xy = 0.02`` has principal strains ``±0.01``:

    >>> principal_strains(np.array([[0.0, 0.0, 0.02]]))
    array([[ 0.01, -0.01]])
    """
    exx, eyy, g = strains[:, 0], strains[:, 1], strains[:, 2]
    c = 0.5 * (exx + eyy)
    r = np.hypot(0.5 * (exx - eyy), 0.5 * g)
    return np.column_stack([c + r, c - r])


def strain_magnitude(mesh, u: np.ndarray) -> np.ndarray:
    """Largest absolute in-plane principal strain of every element, shape ``(m,)``
    (SPEC §1: the strain compared with ``e_L``).

    Examples
    --------
    >>> from deformclosure import Mesh
    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2], [0, 2, 3]])
    >>> strain_magnitude(mesh, -0.02 * mesh.nodes * [0, 1]).round(12)     # 2 % squeeze
    array([0.02, 0.02])
    """
    e = principal_strains(element_strains(mesh, u))
    return np.abs(e).max(axis=1)


def element_stresses(mesh, u: np.ndarray, material=None) -> np.ndarray:
    """Stresses ``[sxx, syy, sxy]`` (Pa) of every element, shape ``(m, 3)``."""
    from .stiffness import constitutive_matrix

    material = material if material is not None else mesh.material
    return element_strains(mesh, u) @ constitutive_matrix(material).T
