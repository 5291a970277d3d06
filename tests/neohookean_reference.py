"""The vectorised numpy form of the compressible neo-Hookean law (SPEC §8) that the compiled
element loop of ``deformclosure.elasticity._neohookean_kernels`` replaced, kept as an
independent reference: ``tests/test_neohookean.py`` compares the two on random states, and
``benchmarks/bench_neohookean.py`` times them side by side. (Copied from
``deformclosure/elasticity/neohookean.py`` at a10d1c2; this header, the class docstring and
name and the constructor's material checks differ.)

The law and its derivatives are derived in that module's docstring; this file evaluates
them vectorised over the elements, with numpy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import scipy.sparse as sp

from deformclosure.errors import DeformClosureError

if TYPE_CHECKING:
    from deformclosure.mesh import Mesh

__all__ = ["NumpyNeoHookean"]

_EPS = np.finfo(float).eps


def _x_minus_log1p(x: np.ndarray) -> np.ndarray:
    """``x − ln(1 + x)`` without cancellation for small ``|x|`` (series below 0.1)."""
    out = x - np.log1p(x)
    small = np.abs(x) < 0.1
    if small.any():
        xs = x[small]
        acc = np.zeros_like(xs)
        for k in range(17, 1, -1):                    # Σ_{k≥2} (−1)^k x^k / k, |x|^18 < 1e-18
            acc = (-1.0) ** k / k + xs * acc
        out[small] = xs * xs * acc
    return out


def _expm1_minus(z: np.ndarray) -> np.ndarray:
    """``e^z − 1 − z`` without cancellation for small ``|z|`` (series below 0.1)."""
    out = np.expm1(z) - z
    small = np.abs(z) < 0.1
    if small.any():
        zs = z[small]
        acc = np.zeros_like(zs)
        fact = [1.0]
        for k in range(1, 14):
            fact.append(fact[-1] * k)
        for k in range(13, 1, -1):                    # Σ_{k≥2} z^k / k!
            acc = 1.0 / fact[k] + zs * acc
        out[small] = zs * zs * acc
    return out


class _Kinematics(NamedTuple):
    """Per-element kinematics of one displacement, shared by energy, force and tangent."""

    H: np.ndarray        # (m, 2, 2) displacement gradient ∂u_i/∂X_J
    F: np.ndarray        # (m, 2, 2) in-plane deformation gradient I + H
    x: np.ndarray        # (m,) J₂ − 1
    y: np.ndarray        # (m,) ln F₃₃ (0 in plane strain; nan where not ok)
    ok: np.ndarray       # (m,) bool: J > 0 and (plane stress) S₃₃ = 0 solvable


def _times_gradients(M: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``M g_p`` per element and node: ``out[e, p, i] = Σ_J M[e, i, J] g[e, p, J]``."""
    out = np.empty_like(g)
    for i in range(2):
        out[:, :, i] = M[:, i, 0, None] * g[:, :, 0] + M[:, i, 1, None] * g[:, :, 1]
    return out


class NumpyNeoHookean:
    """The vectorised numpy form of :class:`deformclosure.elasticity.NeoHookean` (same
    interface: ``energy``, ``gradient``, ``tangent``, ``energy_gradient_tangent``,
    ``element_energies`` and the kinematic accessors; inverted elements give ``inf`` energy
    and ``nan`` entries)."""

    def __init__(self, mesh: "Mesh") -> None:
        from deformclosure.elasticity import NeoHookean

        # the mesh data both forms share (Lamé constants, ∇N_p, t A_e, the CST pattern):
        # not the law, which this class evaluates on its own
        geo = NeoHookean(mesh)
        self.mesh, self.material = mesh, mesh.material
        self.mu, self.lam, self.plane = geo.mu, geo.lam, geo.plane
        self.thickness, self.n_dofs = geo.thickness, geo.n_dofs
        self._tri, self._g, self._vol, self._pattern = geo._tri, geo._g, geo._vol, geo._pattern

    # ------------------------------------------------------------------ kinematics
    def _kinematics(self, u: np.ndarray) -> _Kinematics:
        u = np.asarray(u, dtype=float)
        if u.shape != (self.n_dofs,):
            raise DeformClosureError(f"u: shape {u.shape}, expected ({self.n_dofs},) "
                                     "(DOFs [x0, y0, x1, y1, ...], m)")
        ue = u.reshape(-1, 2)[self._tri]                          # (m, 3, 2)
        g = self._g
        H = np.empty((len(ue), 2, 2))                             # H_iJ = Σ_p u_p,i ∂N_p/∂X_J
        for i in range(2):
            for J in range(2):
                H[:, i, J] = (ue[:, 0, i] * g[:, 0, J] + ue[:, 1, i] * g[:, 1, J]
                              + ue[:, 2, i] * g[:, 2, J])
        F = H.copy()
        F[:, 0, 0] += 1.0
        F[:, 1, 1] += 1.0
        x = H[:, 0, 0] + H[:, 1, 1] + (H[:, 0, 0] * H[:, 1, 1] - H[:, 0, 1] * H[:, 1, 0])
        with np.errstate(all="ignore"):
            ok = 1.0 + x > 0.0
            L2 = np.where(ok, np.log1p(np.where(ok, x, 0.0)), np.nan)
            if self.plane == "strain":
                y = np.where(ok, 0.0, np.nan)
            else:
                y, solved = self._thickness_stretch(L2)
                ok &= solved
        return _Kinematics(H, F, x, y, ok)

    def _thickness_stretch(self, L2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``y = ln F₃₃`` with ``h(y) = μ(e^{2y} − 1) + λ(y + ln J₂) = 0`` (S₃₃ = 0), by
        Newton vectorised over elements, and where a root exists.

        ``h`` is convex in ``y``; Newton started at a point with ``h ≥ 0`` and ``h' > 0``
        decreases monotonically to the (for ``λ < 0`` larger, stable) root, to machine
        precision. Start: the linearised root ``y₀ = −λ ln J₂ / (2μ + λ)`` (``h(y₀) ≥ 0``
        as ``e^{2y} − 1 ≥ 2y``), capped for ``λ > 0`` by ``½ ln(1 − λ ln J₂ / μ)``
        (``h = λ y ≥ 0`` there; keeps ``e^{2y}`` finite under extreme compression). For
        ``λ < 0`` a root exists iff ``h(y*) ≤ 0`` at the minimum ``y* = ½ ln r``,
        ``r = −λ/(2μ) ∈ (0, ⅓)``, i.e. ``ln J₂ ≥ (r − 1 − r ln r)/(2r)``; then
        ``y₀ − y* ≥ −½ − ln r / (2(1 − r)) > 0.32``, so ``h'(y₀) > 0`` and Newton finds
        the larger root.
        """
        mu, lam = self.mu, self.lam
        good = np.isfinite(L2)
        L = np.where(good, L2, 0.0)
        y = -lam * L / (2.0 * mu + lam)
        if lam > 0:
            y = np.minimum(y, 0.5 * np.log1p(np.maximum(-lam * L / mu, 0.0)))
        elif lam < 0:
            ys = 0.5 * np.log(-lam / (2.0 * mu))
            good &= mu * np.expm1(2.0 * ys) + lam * (ys + L) <= 0.0     # a root exists
        else:
            return np.where(good, 0.0, np.nan), good
        for _ in range(100):
            e = np.expm1(2.0 * y)
            dy = (mu * e + lam * (y + L)) / (2.0 * mu * (e + 1.0) + lam)
            y = y - dy
            if np.all(np.abs(dy[good]) <= 4.0 * _EPS * np.maximum(1.0, np.abs(y[good]))):
                break
        good &= np.isfinite(y)
        return np.where(good, y, np.nan), good

    # ------------------------------------------------------------------ pieces
    def _densities(self, k: _Kinematics) -> np.ndarray:
        """``W`` per element (Pa = J/m³), ``inf`` where not ok; cancellation-free form."""
        H, x, y = k.H, k.x, k.y
        with np.errstate(all="ignore"):
            xs = np.where(k.ok, x, 0.0)
            ys = np.where(k.ok, y, 0.0)
            dev = (H[:, 0, 0] - H[:, 1, 1]) ** 2 + (H[:, 0, 1] + H[:, 1, 0]) ** 2
            ell = np.log1p(xs) + ys
            W = 0.5 * self.mu * (dev + 2.0 * _x_minus_log1p(xs) + _expm1_minus(2.0 * ys)) \
                + 0.5 * self.lam * ell**2
        return np.where(k.ok, W, np.inf)

    def _stress_terms(self, k: _Kinematics) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``Q = F₂⁻ᵀ`` (m, 2, 2), ``γ = λℓ − μ`` and ``β`` (m,) of the module docstring."""
        F = k.F
        with np.errstate(all="ignore"):
            J2 = 1.0 + k.x
            Q = np.empty_like(F)
            Q[:, 0, 0] = F[:, 1, 1]
            Q[:, 0, 1] = -F[:, 1, 0]
            Q[:, 1, 0] = -F[:, 0, 1]
            Q[:, 1, 1] = F[:, 0, 0]
            Q /= J2[:, None, None]
            ell = np.log1p(k.x) + k.y
            gamma = self.lam * ell - self.mu
            if self.plane == "strain":
                beta = np.full(len(F), self.lam)
            else:
                s2 = np.exp(2.0 * k.y)
                beta = 2.0 * self.mu * s2 * self.lam / (2.0 * self.mu * s2 + self.lam)
        bad = ~k.ok
        Q[bad], gamma[bad], beta[bad] = np.nan, np.nan, np.nan
        return Q, gamma, beta

    def _gradient(self, k: _Kinematics, Q: np.ndarray, gamma: np.ndarray) -> np.ndarray:
        P = self.mu * (k.F - Q) + (gamma + self.mu)[:, None, None] * Q     # μF + γQ
        fe = self._vol[:, None, None] * _times_gradients(P, self._g)     # (m, 3, 2)
        ids = self._tri.ravel()
        n = self.n_dofs // 2
        f = np.empty(self.n_dofs)
        f[0::2] = np.bincount(ids, fe[..., 0].ravel(), minlength=n)
        f[1::2] = np.bincount(ids, fe[..., 1].ravel(), minlength=n)
        return f

    def _tangent(self, Q: np.ndarray, gamma: np.ndarray, beta: np.ndarray) -> sp.csr_matrix:
        a = _times_gradients(Q, self._g)                           # a_p = Q g_p, (m, 3, 2)
        v = self._vol[:, None, None, None, None]
        # Products a·a first, then the coefficients: entry (p,i,q,k) and its transpose are
        # then the same floating-point numbers, so K is exactly symmetric. The second
        # product a_q,i a_p,k is the first with p and q exchanged.
        aa = a[:, :, None, :, None] * a[:, None, :, None, :]       # a_p,i a_q,k
        Kb = v * (beta[:, None, None, None, None] * aa
                  - gamma[:, None, None, None, None] * aa.transpose(0, 2, 1, 3, 4))
        Kb += self._mu_blocks()
        return self._pattern.element_blocks(Kb, symmetric=True)

    def _mu_blocks(self) -> np.ndarray:
        """The constant part ``t A μ (g_p · g_q) δ_ik`` of the tangent's element blocks,
        (m, 3, 3, 2, 2) (N/m), computed once."""
        out = getattr(self, "_mu_blocks_cache", None)
        if out is None:
            g = self._g
            gg = (g[:, :, None, 0] * g[:, None, :, 0] + g[:, :, None, 1] * g[:, None, :, 1])
            out = (self.mu * self._vol)[:, None, None, None, None] \
                * gg[:, :, :, None, None] * np.eye(2)
            self._mu_blocks_cache = out
        return out

    # ------------------------------------------------------------------ public
    def element_energies(self, u: np.ndarray) -> np.ndarray:
        """Strain energy ``t A_e W(F_e)`` (J) per element, shape ``(m,)``; ``inf`` where
        the element is inverted."""
        return self._vol * self._densities(self._kinematics(u))

    def energy(self, u: np.ndarray) -> float:
        """Strain energy ``Ψ(u)`` (J); ``inf`` if any element is inverted (``J ≤ 0``).

        Parameters
        ----------
        u : ndarray, shape (2n,)
            Nodal displacements (m), DOFs ``[x0, y0, x1, y1, ...]``.
        """
        return float(self.element_energies(u).sum())

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """Internal force ``∂Ψ/∂u`` (N), shape ``(2n,)``."""
        k = self._kinematics(u)
        Q, gamma, _ = self._stress_terms(k)
        return self._gradient(k, Q, gamma)

    def tangent(self, u: np.ndarray) -> sp.csr_matrix:
        """Tangent stiffness ``∂²Ψ/∂u²`` (N/m), ``(2n, 2n)`` CSR, exactly symmetric, with
        the same sparsity structure for every ``u``."""
        Q, gamma, beta = self._stress_terms(self._kinematics(u))
        return self._tangent(Q, gamma, beta)

    def energy_gradient_tangent(self, u: np.ndarray) -> tuple[float, np.ndarray, sp.csr_matrix]:
        """``(energy(u), gradient(u), tangent(u))`` in one pass over the kinematics."""
        k = self._kinematics(u)
        Q, gamma, beta = self._stress_terms(k)
        E = float((self._vol * self._densities(k)).sum())
        return E, self._gradient(k, Q, gamma), self._tangent(Q, gamma, beta)

    def deformation_gradients(self, u: np.ndarray) -> np.ndarray:
        """In-plane deformation gradients ``F = I + ∇u`` per element, shape ``(m, 2, 2)``."""
        return self._kinematics(u).F

    def right_cauchy_green(self, u: np.ndarray) -> np.ndarray:
        """In-plane ``C = FᵀF`` per element, shape ``(m, 3)`` as ``[C11, C22, C12]``."""
        F = self._kinematics(u).F
        return np.stack([F[:, 0, 0] ** 2 + F[:, 1, 0] ** 2,
                         F[:, 0, 1] ** 2 + F[:, 1, 1] ** 2,
                         F[:, 0, 0] * F[:, 0, 1] + F[:, 1, 0] * F[:, 1, 1]], axis=1)

    def out_of_plane_stretch(self, u: np.ndarray) -> np.ndarray:
        """``F₃₃`` per element, shape ``(m,)``: 1 in plane strain, the ``S₃₃ = 0`` root in
        plane stress; ``nan`` where the element is inverted."""
        return np.exp(self._kinematics(u).y)
