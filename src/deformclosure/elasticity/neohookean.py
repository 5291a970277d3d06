"""Compressible neo-Hookean energy of a linear-triangle mesh, total Lagrangian (SPEC §8).

Per unit reference volume

    W(F) = μ/2 (I₁ − 3 − 2 ln J) + λ/2 (ln J)²,   I₁ = tr(FᵀF),  J = det F,

with the 3-D Lamé constants ``μ = E/(2(1+ν))``, ``λ = Eν/((1+ν)(1−2ν))`` of the part's
``E``, ``ν``. ``F`` is 3×3 with the in-plane block ``F₂ = I + ∇u`` (constant on a linear
triangle) and ``F₃₃ = s``: plane strain ``s = 1``; plane stress ``s`` such that
``S₃₃ = ∂W/∂F₃₃ / s = 0``, i.e. ``μ(s² − 1) + λ ln(J₂ s) = 0`` with ``J₂ = det F₂`` — so
``s`` depends on ``F₂`` through ``J₂`` only. The energy is ``Ψ(u) = Σ_e t A_e W(F_e)``.

Derivatives (``Q = F₂⁻ᵀ``, ``ℓ = ln J = ln J₂ + ln s``, ``γ = λℓ − μ``): the in-plane first
Piola–Kirchhoff stress is ``P = μF₂ + γQ`` for both planes (in plane stress ``∂W/∂s = 0``
at the solved ``s``, so the dependence of ``s`` on ``F₂`` drops out of the gradient), and

    ∂P_iJ/∂F_kL = μ δ_ik δ_JL + β Q_iJ Q_kL − γ Q_iL Q_kJ,

with ``β = λ`` in plane strain and, in plane stress, the statically condensed
``β = λ − W_Fs W_sF / W_ss = λ − λ²/(2μs² + λ) = 2μs²λ/(2μs² + λ)`` (``W_Fs = λQ/s``,
``W_ss = 2μ + λ/s²`` at ``S₃₃ = 0``). At ``F = I`` this is the linear plane-stress or
plane-strain elasticity tensor of §1 exactly (``β(1) = 2μλ/(2μ + λ)`` is the plane-stress
λ*). With the shape-function gradients ``g_p = ∇N_p`` and ``a_p = Q g_p`` the element
force and the 2×2 node blocks of the element tangent are

    f_p = tA P g_p,   K_pq,ik = tA [μ δ_ik g_p·g_q + β a_p,i a_q,k − γ a_q,i a_p,k].

The energy is evaluated in a form without cancellation near ``F = I``:
``I₁ − 3 − 2ℓ = (H₁₁ − H₂₂)² + (H₁₂ + H₂₁)² + 2(x − ln(1 + x)) + (e^{2y} − 1 − 2y)``
with ``H = ∇u``, ``x = J₂ − 1 = tr H + det H`` and ``y = ln s``, so small strains keep
their relative precision.

The element loop — kinematics, the plane-stress thickness root, energy, stress and the
tangent's element blocks added straight into the CST pattern's CSR values — is compiled
(:mod:`._neohookean_kernels`; 3.5–9× the vectorised numpy form it replaced per full
pass, ``benchmarks/bench_neohookean.py``, which
``tests/neohookean_reference.py`` keeps as the reference the tests compare with).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from ..errors import DeformClosureError, StiffnessError
from ..part import Material
from ._neohookean_kernels import csr_positions, element_kinematics, neo_hookean_pass
from .stiffness import _gradients, _Pattern

if TYPE_CHECKING:
    from ..mesh import Mesh

__all__ = ["NeoHookean", "lame_constants", "material_law"]


def material_law(mesh, elasticity: str):
    """The material law ``elasticity`` (``"neo-hookean"``, or ``"linear"``: the
    small-strain energy) of ``mesh``'s material, behind the interface of the finite-strain
    contact solver (:mod:`deformclosure.contact.large_deformation`)."""
    if elasticity == "linear":
        from .linear_energy import LinearEnergy
        return LinearEnergy(mesh)
    return NeoHookean(mesh)


def lame_constants(material: Material) -> tuple[float, float]:
    """3-D Lamé constants ``(μ, λ)`` (Pa) of the material's ``E``, ``ν`` (SPEC §8).

    Examples
    --------
    >>> lame_constants(Material(2.6e6, 0.3, 1e-3, 0.8))        # doctest: +ELLIPSIS
    (1000000.0, 1500000.0...)
    """
    E, nu = material.youngs_modulus, material.poisson_ratio
    return E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


class NeoHookean:
    """Total-Lagrangian compressible neo-Hookean energy of a triangle mesh (SPEC §8).

    Parameters
    ----------
    mesh : Mesh
        Linear triangles (counter-clockwise), nodes in m.
    material : Material, optional
        Defaults to ``mesh.material``. Uses ``youngs_modulus``, ``poisson_ratio``,
        ``thickness`` and ``plane``; its ``model`` field is not read (this class *is* the
        ``"neo-hookean"`` law).

    Attributes
    ----------
    n_dofs : int
        ``2 * mesh.n_nodes``, DOF order ``[x0, y0, x1, y1, ...]``.
    mu, lam : float
        The 3-D Lamé constants μ, λ (Pa).
    plane : {"stress", "strain"}
    thickness : float
        ``t`` (m).

    Raises
    ------
    StiffnessError
        If no material is known.

    Notes
    -----
    Where an element is inverted (``J ≤ 0``, or in plane stress the condition ``S₃₃ = 0``
    has no root — possible only for ``ν < 0`` under strong compression) the energy is
    ``inf`` and that element's entries of the gradient and tangent are ``nan``; nothing is
    raised, so a line search can step back. The tangent has the same CSR structure for
    every ``u`` (the mesh's cached CST pattern), so a symbolic factorisation can be
    reused. The model is of the law only: no gauge, no contact (those are ``contact/``'s).

    Examples
    --------
    A unit square of two triangles, stretched 10 % along x: positive energy, no force on a
    rigid translation, and the small-strain tangent equals the CST stiffness.

    >>> from deformclosure import Mesh, stiffness_matrix
    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2], [0, 2, 3]],
    ...                         Material(1e6, 0.3, 1e-3, 0.1))
    >>> law = NeoHookean(mesh)
    >>> u = np.zeros(law.n_dofs); u[0::2] = 0.1 * mesh.nodes[:, 0]
    >>> bool(law.energy(u) > 0), bool(abs(law.gradient(u) @ np.tile([1.0, 0.0], 4)) < 1e-9)
    (True, True)
    >>> K0 = stiffness_matrix(mesh)
    >>> bool(abs(law.tangent(np.zeros(8)) - K0).max() < 1e-9 * abs(K0).max())
    True
    """

    def __init__(self, mesh: "Mesh", material: Material | None = None) -> None:
        material = material if material is not None else mesh.material
        if material is None:
            raise StiffnessError("no material: give the part's material (youngs_modulus, "
                                 "poisson_ratio, thickness, elastic_limit_strain) with the mesh")
        if not isinstance(material, Material):
            raise StiffnessError(f"material = {material!r}: give a deformclosure Material")
        self.mesh, self.material = mesh, material
        self.mu, self.lam = lame_constants(material)
        self.plane = material.plane
        self.thickness = material.thickness
        self.n_dofs = 2 * mesh.n_nodes
        self._tri = np.asarray(mesh.triangles, dtype=np.int64)
        b, c, a2 = _gradients(mesh.nodes, mesh.triangles)
        self._g = np.stack([b, c], axis=-1) / a2[:, None, None]   # (m, 3, 2): ∇N_p (1/m)
        self._vol = 0.5 * material.thickness * np.abs(a2)        # t A_e (m³)
        self._pattern = _Pattern.of_mesh(mesh)
        self._no_positions = np.zeros((0, 6, 6), np.int32)

    # ------------------------------------------------------------------ kernels
    def _check(self, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=float)
        if u.shape != (self.n_dofs,):
            raise DeformClosureError(f"u: shape {u.shape}, expected ({self.n_dofs},) "
                                     "(DOFs [x0, y0, x1, y1, ...], m)")
        return np.ascontiguousarray(u)

    def _pass(self, u: np.ndarray, gradient: bool = False, energies: bool = False,
              tangent: bool = False) -> tuple[float, np.ndarray | None, np.ndarray | None,
                                               sp.csr_matrix | None]:
        """One compiled pass over the elements (:func:`._neohookean_kernels.neo_hookean_pass`):
        ``(Ψ, ∂Ψ/∂u or None, element energies or None, tangent or None)``."""
        u = self._check(u)
        f = np.empty(self.n_dofs if gradient else 0)
        w = np.empty(len(self._tri) if energies else 0)
        if tangent:
            pos = self._positions()
            data = np.empty(len(self._pattern.indices))
        else:
            pos, data = self._no_positions, np.empty(0)
        E = neo_hookean_pass(u, self._tri, self._g, self._vol, self.mu, self.lam,
                             self.plane == "stress", f, w, pos, data)
        K = None
        if tangent:
            K = sp.csr_matrix((data, self._pattern.indices, self._pattern.indptr),
                              shape=(self.n_dofs, self.n_dofs))
            K.has_sorted_indices = True
        return float(E), (f if gradient else None), (w if energies else None), K

    def _positions(self) -> np.ndarray:
        """Where each element-matrix entry goes in the CST pattern's CSR values (computed
        once per mesh and kept in its cache)."""
        cache = self.mesh._cache
        pos = cache.get("cst_positions")
        if pos is None:
            pos = cache["cst_positions"] = csr_positions(self._tri, self._pattern.indptr,
                                                         self._pattern.indices)
        return pos

    def _kinematics(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(H, x = J₂ − 1, y = ln F₃₃)`` per element (``y`` nan where inverted)."""
        return element_kinematics(self._check(u), self._tri, self._g, self.mu, self.lam,
                                  self.plane == "stress")

    # ------------------------------------------------------------------ public
    def element_energies(self, u: np.ndarray) -> np.ndarray:
        """Strain energy ``t A_e W(F_e)`` (J) per element, shape ``(m,)``; ``inf`` where
        the element is inverted."""
        return self._pass(u, energies=True)[2]

    def energy(self, u: np.ndarray) -> float:
        """Strain energy ``Ψ(u)`` (J); ``inf`` if any element is inverted (``J ≤ 0``).

        Parameters
        ----------
        u : ndarray, shape (2n,)
            Nodal displacements (m), DOFs ``[x0, y0, x1, y1, ...]``.
        """
        return self._pass(u)[0]

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """Internal force ``∂Ψ/∂u`` (N), shape ``(2n,)``."""
        return self._pass(u, gradient=True)[1]

    def energy_gradient(self, u: np.ndarray) -> tuple[float, np.ndarray]:
        """``(energy(u), gradient(u))`` in one pass."""
        E, f, _, _ = self._pass(u, gradient=True)
        return E, f

    def tangent(self, u: np.ndarray) -> sp.csr_matrix:
        """Tangent stiffness ``∂²Ψ/∂u²`` (N/m), ``(2n, 2n)`` CSR, exactly symmetric, with
        the same sparsity structure for every ``u``."""
        return self._pass(u, tangent=True)[3]

    def energy_gradient_tangent(self, u: np.ndarray) -> tuple[float, np.ndarray, sp.csr_matrix]:
        """``(energy(u), gradient(u), tangent(u))`` in one pass."""
        E, f, _, K = self._pass(u, gradient=True, tangent=True)
        return E, f, K

    def deformation_gradients(self, u: np.ndarray) -> np.ndarray:
        """In-plane deformation gradients ``F = I + ∇u`` per element, shape ``(m, 2, 2)``."""
        F = self._kinematics(u)[0]
        F[:, 0, 0] += 1.0
        F[:, 1, 1] += 1.0
        return F

    def right_cauchy_green(self, u: np.ndarray) -> np.ndarray:
        """In-plane ``C = FᵀF`` per element, shape ``(m, 3)`` as ``[C11, C22, C12]``."""
        F = self.deformation_gradients(u)
        return np.stack([F[:, 0, 0] ** 2 + F[:, 1, 0] ** 2,
                         F[:, 0, 1] ** 2 + F[:, 1, 1] ** 2,
                         F[:, 0, 0] * F[:, 0, 1] + F[:, 1, 0] * F[:, 1, 1]], axis=1)

    def out_of_plane_stretch(self, u: np.ndarray) -> np.ndarray:
        """``F₃₃`` per element, shape ``(m,)``: 1 in plane strain, the ``S₃₃ = 0`` root in
        plane stress; ``nan`` where the element is inverted."""
        return np.exp(self._kinematics(u)[2])
