"""A-posteriori error indicator of a linear-triangle solution and the marking rule of
adaptive refinement (SPEC §6 "Accuracy by default").

**Indicator** (Zienkiewicz–Zhu, recovered strain): the CST strain ``ε_h`` is constant on
each element; the recovered strain ``ε*`` is continuous and linear, its nodal values the
area-weighted mean of the strains of the elements around the node. The element indicator
is the energy norm of the difference,

    η_e² = t ∫_e (ε* − ε_h)ᵀ C (ε* − ε_h) dA,

integrated exactly (``∫_e φ_i φ_j = A/12 (1 + δ_ij)`` for the linear shape functions), so
``Σ η_e²`` estimates the squared energy-norm error and has the units of energy (J).
(O. C. Zienkiewicz and J. Z. Zhu, Int. J. Numer. Meth. Eng. 24, 1987.)

**Marking** (Dörfler's bulk criterion): the fewest elements whose indicators carry the
fraction ``θ`` of the total; they are refined (``h`` halved), the rest kept.
"""

from __future__ import annotations

import numpy as np

from .stiffness import constitutive_matrix
from .strain import element_strains

__all__ = ["recovered_strain_indicator", "bulk_marking"]


def recovered_strain_indicator(mesh, u: np.ndarray, material=None) -> np.ndarray:
    """Element indicators ``η_e²`` (J) of the displacement ``u`` (m, shape (2n,) or
    (n, 2)) on ``mesh`` (module docstring).

    Examples
    --------
    A uniform strain is recovered exactly, so the indicator vanishes:

    >>> from deformclosure import Mesh, Material
    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2], [0, 2, 3]],
    ...                         material=Material(1e6, 0.3, 0.01, 0.5))
    >>> float(recovered_strain_indicator(mesh, 0.01 * mesh.nodes).max()) < 1e-20
    True
    """
    material = mesh.material if material is None else material
    eps = element_strains(mesh, u)                            # (m, 3)
    A = np.asarray(mesh.areas, float)
    T = mesh.triangles
    n = mesh.n_nodes
    num = np.zeros((n, 3))
    den = np.zeros(n)
    for k in range(3):
        np.add.at(num, T[:, k], A[:, None] * eps)
        np.add.at(den, T[:, k], A)
    nodal = num / den[:, None]
    d = nodal[T] - eps[:, None, :]                            # (m, 3 nodes, 3 components)
    C = constitutive_matrix(material)
    Cd = np.einsum("ij,mkj->mki", C, d)
    # ∫ d·Cd over a linear triangle = A/12 (Σ_k d_k·Cd_k + (Σ_k d_k)·(Σ_k Cd_k))
    own = np.einsum("mki,mki->m", d, Cd)
    cross = np.einsum("mi,mi->m", d.sum(axis=1), Cd.sum(axis=1))
    return material.thickness * A / 12.0 * (own + cross)


def bulk_marking(eta2: np.ndarray, theta: float = 0.5) -> np.ndarray:
    """Dörfler marking: the fewest elements (bool mask) whose ``eta2`` sum to at least
    ``theta`` of the total (none when the total is 0)."""
    eta2 = np.asarray(eta2, float)
    total = float(eta2.sum())
    marked = np.zeros(len(eta2), bool)
    if not total > 0:
        return marked
    order = np.argsort(eta2)[::-1]
    k = int(np.searchsorted(np.cumsum(eta2[order]), theta * total)) + 1
    marked[order[:k]] = True
    return marked
