"""The linear CST energy ``½ uᵀ K u`` behind the material-law interface of the finite-strain
contact solver (:mod:`deformclosure.contact.large_deformation`).

It lets the exact-geometry contact solver run on the small-strain material: with flat pads
(whose gap is linear in ``u``) it must reproduce the pads model of SPEC §6 exactly, which
tests the solver independently of the neo-Hookean law.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .stiffness import element_b_matrices, stiffness_matrix

__all__ = ["LinearEnergy"]


class LinearEnergy:
    """Energy ``½ uᵀ K u`` (J) of a mesh's CST stiffness ``K`` (N/m).

    Parameters
    ----------
    mesh : Mesh
    material : Material, optional
        Default ``mesh.material``.
    """

    def __init__(self, mesh, material=None) -> None:
        self.K = stiffness_matrix(mesh, material).tocsr()
        self.n_dofs = self.K.shape[0]
        self._tri = mesh.triangles
        self._B, _ = element_b_matrices(mesh.nodes, mesh.triangles)

    def small_strains(self, u: np.ndarray) -> np.ndarray:
        """Engineering element strains ``[exx, eyy, gamma_xy]`` of ``u`` (m), shape (m, 3):
        the strain this law's elastic limit is measured with (SPEC §6)."""
        ue = np.asarray(u, float).reshape(-1, 2)[self._tri].reshape(len(self._tri), 6)
        return np.einsum("mij,mj->mi", self._B, ue)

    def energy(self, u: np.ndarray) -> float:
        """Energy (J) of displacement ``u`` (m), shape (2n,)."""
        return 0.5 * float(u @ (self.K @ u))

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """Internal force ``K u`` (N)."""
        return self.K @ u

    def energy_gradient(self, u: np.ndarray) -> tuple[float, np.ndarray]:
        """Energy (J) and internal force (N) at ``u`` (m)."""
        f = self.K @ u
        return 0.5 * float(u @ f), f

    def tangent(self, u: np.ndarray) -> sp.csr_matrix:
        """Stiffness ``K`` (N/m)."""
        return self.K

    def energy_gradient_tangent(self, u: np.ndarray) -> tuple[float, np.ndarray, sp.csr_matrix]:
        """Energy (J), internal force (N) and tangent (N/m) at ``u`` (m)."""
        f = self.K @ u
        return 0.5 * float(u @ f), f, self.K
