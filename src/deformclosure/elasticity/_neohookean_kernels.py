"""Compiled element loops of the compressible neo-Hookean law (SPEC §8).

The formulas are those of :mod:`deformclosure.elasticity.neohookean` (its docstring derives
them); this module evaluates them element by element in one pass — the displacement
gradient, the out-of-plane stretch of plane stress, the energy density, the first
Piola–Kirchhoff stress and the tangent's element blocks — and adds the tangent straight
into the values of the mesh's CST sparsity pattern (CSR) through a precomputed position
map. ``benchmarks/bench_neohookean.py`` measures it against the vectorised numpy form it
replaced (kept in ``tests/neohookean_reference.py`` as the independent reference).

Numerics (besides the module docstring's cancellation-free energy): the stress is formed
as ``P = μ (F − Q) + λ ℓ Q`` with ``F − Q = H − (Q − I)`` and
``Q − I = −[[H₀₀ + det H, H₁₀], [H₀₁, H₁₁ + det H]] / J₂``, so small strains keep their
relative precision in the internal force as well as in the energy.

``cache=True`` keeps the compiled code between runs; ``NUMBA_DISABLE_JIT=1`` runs the same
functions as Python.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["element_kinematics", "neo_hookean_pass", "csr_positions"]

_EPS = 2.220446049250313e-16
#: Coefficients ``(−1)^k / k`` of ``x − ln(1 + x) = Σ_{k≥2} (−1)^k x^k / k`` (|x| < 0.1:
#: 17 terms, |x|^18 < 1e-18).
_LOG_SERIES = np.array([0.0, 0.0] + [(-1.0) ** k / k for k in range(2, 18)])
#: Coefficients ``1 / k!`` of ``e^z − 1 − z = Σ_{k≥2} z^k / k!`` (|z| < 0.1: 13 terms).
_EXP_SERIES = np.array([1.0 / math.factorial(k) for k in range(14)])


@njit(cache=True)
def _tail_series(z: float, coef: np.ndarray) -> float:
    """``Σ_{k≥2} coef[k] z^k`` by Horner's rule (the terms of ``coef`` from index 2)."""
    acc = 0.0
    for k in range(len(coef) - 1, 1, -1):
        acc = coef[k] + z * acc
    return z * z * acc


@njit(cache=True)
def x_minus_log1p(x: float) -> float:
    """``x − ln(1 + x)`` without cancellation for small ``|x|`` (series below 0.1)."""
    return _tail_series(x, _LOG_SERIES) if abs(x) < 0.1 else x - math.log1p(x)


@njit(cache=True)
def expm1_minus(z: float) -> float:
    """``e^z − 1 − z`` without cancellation for small ``|z|`` (series below 0.1)."""
    return _tail_series(z, _EXP_SERIES) if abs(z) < 0.1 else math.expm1(z) - z


@njit(cache=True)
def log_thickness_stretch(L2: float, mu: float, lam: float) -> float:
    """``y = ln F₃₃`` of plane stress: the root of ``h(y) = μ(e^{2y} − 1) + λ(y + ln J₂)``
    (``S₃₃ = 0``) by Newton, ``nan`` where none exists; ``L2 = ln J₂``.

    ``h`` is convex in ``y``; Newton started where ``h ≥ 0`` and ``h' > 0`` decreases
    monotonically to the (for ``λ < 0`` larger, stable) root. Start: the linearised root
    ``y₀ = −λ L₂ / (2μ + λ)`` (``h(y₀) ≥ 0`` as ``e^{2y} − 1 ≥ 2y``), capped for ``λ > 0``
    by ``½ ln(1 − λ L₂ / μ)`` (``h = λ y ≥ 0`` there; keeps ``e^{2y}`` finite under
    extreme compression). For ``λ < 0`` a root exists iff ``h(y*) ≤ 0`` at the minimum
    ``y* = ½ ln r``, ``r = −λ/(2μ) ∈ (0, ⅓)``, i.e. ``ln J₂ ≥ (r − 1 − r ln r)/(2r)``; then
    ``y₀ − y* ≥ −½ − ln r / (2(1 − r)) > 0.32``, so ``h'(y₀) > 0`` and Newton finds the
    larger root.
    """
    if not math.isfinite(L2):
        return math.nan
    if lam == 0.0:
        return 0.0
    y = -lam * L2 / (2.0 * mu + lam)
    if lam > 0.0:
        # h is then increasing and convex: Newton converges from any start (its first
        # step lands right of the root), so the start may be the second-order root
        # y₀ − 2μ y₀² / (2μ + λ) (one iteration fewer at strains of 1e-3 to 0.1)
        y -= 2.0 * mu * y * y / (2.0 * mu + lam)
        y = min(y, 0.5 * math.log1p(max(-lam * L2 / mu, 0.0)))
    else:
        ys = 0.5 * math.log(-lam / (2.0 * mu))
        if not mu * math.expm1(2.0 * ys) + lam * (ys + L2) <= 0.0:
            return math.nan
    for _ in range(100):
        e = math.expm1(2.0 * y)
        d1 = 2.0 * mu * (e + 1.0) + lam                    # h'(y)
        dy = (mu * e + lam * (y + L2)) / d1
        y = y - dy
        # converged when this step, or the next one Newton's quadratic convergence
        # predicts, (h''/2h') dy², is at round-off (saves the confirming iteration)
        tol = 4.0 * _EPS * max(1.0, abs(y))
        if abs(dy) <= tol or (abs(dy) < 1e-4
                              and 2.0 * mu * (e + 1.0) / abs(d1) * dy * dy <= tol):
            break
    return y if math.isfinite(y) else math.nan


@njit(cache=True)
def _displacement_gradient(u, tri, g, e):
    """``H = ∇u`` (``H_iJ = Σ_p u_p,i ∂N_p/∂X_J``) of element ``e``."""
    a, b, c = tri[e, 0], tri[e, 1], tri[e, 2]
    H00 = u[2 * a] * g[e, 0, 0] + u[2 * b] * g[e, 1, 0] + u[2 * c] * g[e, 2, 0]
    H01 = u[2 * a] * g[e, 0, 1] + u[2 * b] * g[e, 1, 1] + u[2 * c] * g[e, 2, 1]
    H10 = u[2 * a + 1] * g[e, 0, 0] + u[2 * b + 1] * g[e, 1, 0] + u[2 * c + 1] * g[e, 2, 0]
    H11 = u[2 * a + 1] * g[e, 0, 1] + u[2 * b + 1] * g[e, 1, 1] + u[2 * c + 1] * g[e, 2, 1]
    return H00, H01, H10, H11


@njit(cache=True)
def _log_stretch(x: float, mu: float, lam: float, plane_stress: bool) -> float:
    """``y = ln F₃₃`` at ``J₂ = 1 + x``: 0 in plane strain; ``nan`` where ``J₂ ≤ 0`` or (plane
    stress) ``S₃₃ = 0`` has no root."""
    if not 1.0 + x > 0.0:
        return math.nan
    if not plane_stress:
        return 0.0
    return log_thickness_stretch(math.log1p(x), mu, lam)


@njit(cache=True)
def element_kinematics(u, tri, g, mu, lam, plane_stress):
    """Per element: ``H`` (m, 2, 2), ``x = J₂ − 1`` (m,) and ``y = ln F₃₃`` (m,; ``nan``
    where the element is inverted or plane stress has no thickness root)."""
    m = tri.shape[0]
    H = np.empty((m, 2, 2))
    xs = np.empty(m)
    ys = np.empty(m)
    for e in range(m):
        H00, H01, H10, H11 = _displacement_gradient(u, tri, g, e)
        H[e, 0, 0], H[e, 0, 1], H[e, 1, 0], H[e, 1, 1] = H00, H01, H10, H11
        x = H00 + H11 + (H00 * H11 - H01 * H10)
        xs[e] = x
        ys[e] = _log_stretch(x, mu, lam, plane_stress)
    return H, xs, ys


@njit(cache=True)
def neo_hookean_pass(u, tri, g, vol, mu, lam, plane_stress, gradient, energies, pos, data):
    """Energy (J) of ``u`` (m), and on request the internal force and the tangent.

    Parameters
    ----------
    u : (2n,) float
    tri : (m, 3) int
    g : (m, 3, 2) float
        Shape-function gradients ``∇N_p`` (1/m).
    vol : (m,) float
        ``t A_e`` (m³).
    mu, lam : float
        3-D Lamé constants (Pa).
    plane_stress : bool
    gradient : (2n,) or (0,) float
        Filled with ``∂Ψ/∂u`` (N) when of length 2n.
    energies : (m,) or (0,) float
        Filled with the element energies (J) when of length m.
    pos : (m, 6, 6) or (0, 6, 6) int
        Position in ``data`` of each element matrix entry (rows and columns local DOFs
        ``2p + i``); the tangent is formed when ``m`` rows are given.
    data : (nnz,) float
        The CSR values of the tangent (N/m), overwritten.

    Returns
    -------
    float
        ``Ψ(u)``; ``inf`` if an element is inverted (its entries of the gradient and
        tangent are then ``nan``).
    """
    m = tri.shape[0]
    want_f = gradient.shape[0] > 0
    want_w = energies.shape[0] > 0
    want_k = pos.shape[0] > 0
    if want_f:
        gradient[:] = 0.0
    if want_k:
        data[:] = 0.0
    total = 0.0
    a = np.empty((3, 2))
    P = np.empty((2, 2))
    Q = np.empty((2, 2))
    for e in range(m):
        H00, H01, H10, H11 = _displacement_gradient(u, tri, g, e)
        det = H00 * H11 - H01 * H10
        x = H00 + H11 + det
        y = _log_stretch(x, mu, lam, plane_stress)
        v = vol[e]
        if not math.isfinite(y):
            total = math.inf
            if want_w:
                energies[e] = math.inf
            if want_f:
                for p in range(3):
                    gradient[2 * tri[e, p]] = math.nan
                    gradient[2 * tri[e, p] + 1] = math.nan
            if want_k:
                for r in range(6):
                    for c in range(6):
                        data[pos[e, r, c]] = math.nan
            continue
        ell = math.log1p(x) + y
        dev = (H00 - H11) ** 2 + (H01 + H10) ** 2
        W = 0.5 * mu * (dev + 2.0 * x_minus_log1p(x) + expm1_minus(2.0 * y)) \
            + 0.5 * lam * ell * ell
        total += v * W
        if want_w:
            energies[e] = v * W
        if not (want_f or want_k):
            continue
        J2 = 1.0 + x
        Q[0, 0] = (1.0 + H11) / J2
        Q[0, 1] = -H10 / J2
        Q[1, 0] = -H01 / J2
        Q[1, 1] = (1.0 + H00) / J2
        if want_f:
            # P = μ(F − Q) + λℓ Q, F − Q = H − (Q − I) without cancellation
            le = lam * ell
            P[0, 0] = mu * (H00 + (H00 + det) / J2) + le * Q[0, 0]
            P[0, 1] = mu * (H01 + H10 / J2) + le * Q[0, 1]
            P[1, 0] = mu * (H10 + H01 / J2) + le * Q[1, 0]
            P[1, 1] = mu * (H11 + (H11 + det) / J2) + le * Q[1, 1]
            for p in range(3):
                n = tri[e, p]
                for i in range(2):
                    gradient[2 * n + i] += v * (P[i, 0] * g[e, p, 0] + P[i, 1] * g[e, p, 1])
        if want_k:
            gamma = lam * ell - mu
            if plane_stress:
                s2 = math.exp(2.0 * y)
                beta = 2.0 * mu * s2 * lam / (2.0 * mu * s2 + lam)
            else:
                beta = lam
            for p in range(3):
                for i in range(2):
                    a[p, i] = Q[i, 0] * g[e, p, 0] + Q[i, 1] * g[e, p, 1]
            vm = mu * v
            # K_pq,ik = tA [μ δ_ik g_p·g_q + β a_p,i a_q,k − γ a_q,i a_p,k]; each entry is
            # formed once and written to both (r, c) and (c, r): exactly symmetric
            for r in range(6):
                p, i = r // 2, r % 2
                for c in range(r, 6):
                    q, k = c // 2, c % 2
                    val = v * (beta * (a[p, i] * a[q, k]) - gamma * (a[q, i] * a[p, k]))
                    if i == k:
                        val += vm * (g[e, p, 0] * g[e, q, 0] + g[e, p, 1] * g[e, q, 1])
                    data[pos[e, r, c]] += val
                    if c != r:
                        data[pos[e, c, r]] += val
    return total


def csr_positions(triangles: np.ndarray, indptr: np.ndarray, indices: np.ndarray
                  ) -> np.ndarray:
    """Position in a CSR matrix's values of every element-matrix entry: ``(m, 6, 6)`` with
    rows and columns the local DOFs ``2p + i`` of the element's nodes ``p``.

    The matrix's column indices must be sorted within each row and hold every entry of
    every element (the CST pattern does).
    """
    t = np.asarray(triangles, np.int64)
    n2 = len(indptr) - 1
    dofs = np.stack([2 * t, 2 * t + 1], axis=-1).reshape(len(t), 6)        # (m, 6)
    rows = np.repeat(np.arange(n2, dtype=np.int64), np.diff(indptr))
    keys = rows * n2 + indices.astype(np.int64)                              # sorted
    want = dofs[:, :, None] * n2 + dofs[:, None, :]
    at = np.searchsorted(keys, want)
    if np.any(at >= len(keys)) or np.any(keys[np.minimum(at, len(keys) - 1)] != want):
        raise ValueError("the CSR pattern misses an element entry")
    return at.astype(np.int32 if len(keys) < 2**31 else np.int64)
