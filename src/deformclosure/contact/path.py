"""Parametric frictionless contact: the exact solution path of a linear complementarity
problem as the squeeze grows (SPEC §6).

With contact multipliers ``λ`` (N) and the Delassus matrix ``W = Gᵀ Y G`` (m/N) the
linearised gaps are ``g = g0 − δ b + W λ + e t`` (m): ``δ`` is the squeeze, ``b`` marks
the contacts of the moving pad, ``t`` the free translation of the part along the axis and
``e = ±1`` its effect on each pad's gaps. The contact problem is::

    g ≥ 0,  λ ≥ 0,  λᵀ g = 0,  eᵀ λ = 0   (the pads' axial forces balance)

and its solution is piecewise linear in ``δ``: on each piece the set of active contacts
is fixed. We follow it exactly (a homotopy / parametric active-set method): at each
breakpoint the direction ``(dλ/dδ, dt/dδ)`` solves the *derivative* problem — the same
complementarity on the contacts that are active or just touching — posed as the convex QP
``min ½ xᵀ W x − bᵀ x`` s.t. ``eᵀx = 0`` and ``x ≥ 0`` on the just-touching contacts
(a primal active-set method, compiled); the piece ends where a multiplier reaches 0 or a gap
closes. The energy ``½ λᵀ W λ`` is then exactly quadratic on every piece.

References
----------
K. G. Murty, *Linear Complementarity, Linear and Nonlinear Programming* (1988), ch. 5
(parametric LCP).
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass, field

import numpy as np
from numba import njit

__all__ = ["ContactPath", "trace_contact_path"]


@dataclass(frozen=True)
class ContactPath:
    """Exact piecewise-linear solution path ``λ(δ)``.

    Attributes
    ----------
    delta : ndarray, shape (k,)
        Breakpoints of the squeeze (m), increasing; ``delta[0]`` is the first touch.
    lam : ndarray, shape (k, m)
        Multipliers (N) at the breakpoints; linear in between.
    t : ndarray, shape (k,)
        Axial translation of the part (m) at the breakpoints.
    energy_coef : ndarray, shape (k − 1, 3)
        On piece ``i``, ``U = c0 + c1 (δ − delta[i]) + c2 (δ − delta[i])²`` (J).
    """

    delta: np.ndarray
    lam: np.ndarray
    t: np.ndarray
    energy_coef: np.ndarray
    _lists: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # Plain lists for the scalar fast path (the landscape evaluates ~10⁵ energies).
        object.__setattr__(self, "_lists", (self.delta.tolist(), self.energy_coef.tolist()))

    def energy_at(self, delta: float) -> float:
        """Energy (J) at one squeeze ``delta`` (m); same as :meth:`energy`, faster."""
        D, C = self._lists
        if len(D) < 2 or delta <= D[0]:
            return 0.0
        i = min(bisect_right(D, delta) - 1, len(D) - 2)
        h = delta - D[i]
        c0, c1, c2 = C[i]
        return c0 + h * (c1 + h * c2)

    def piece(self, delta: np.ndarray) -> np.ndarray:
        """Index of the piece holding each squeeze value (clipped to the traced range)."""
        i = np.searchsorted(self.delta, delta, side="right") - 1
        return np.clip(i, 0, max(len(self.delta) - 2, 0))

    def energy(self, delta: np.ndarray) -> np.ndarray:
        """Energy (J) at squeezes ``delta`` (m); 0 before first touch."""
        delta = np.asarray(delta, float)
        if len(self.delta) < 2:
            return np.zeros_like(delta)
        i = self.piece(delta)
        h = delta - self.delta[i]
        c = self.energy_coef[i]
        U = c[..., 0] + h * (c[..., 1] + h * c[..., 2])
        return np.where(delta <= self.delta[0], 0.0, U)

    def multipliers(self, delta: float) -> np.ndarray:
        """Multipliers (N) at squeeze ``delta`` (m), linear between breakpoints."""
        if delta <= self.delta[0] or len(self.delta) < 2:
            return np.zeros(self.lam.shape[1])
        i = int(self.piece(np.array(delta)))
        w = (delta - self.delta[i]) / (self.delta[i + 1] - self.delta[i])
        return (1 - w) * self.lam[i] + w * self.lam[i + 1]


@njit(cache=True, nogil=True)
def _derivative_qp(Wj, bj, ej, zmask):  # pragma: no cover - compiled
    """``min ½xᵀWx − bᵀx`` s.t. ``eᵀx = 0`` and ``x_i ≥ 0`` where ``zmask``: a primal
    active-set method (Nocedal & Wright, Alg. 16.3) on this small dense problem.

    Returns ``(x, μ)``; ``μ`` is the multiplier of the equality (the axial drift rate).
    """
    n = bj.shape[0]
    x = np.zeros(n)
    fixed = zmask.copy()
    mu = 0.0
    bscale = 1.0
    for i in range(n):
        bscale = max(bscale, abs(bj[i]))
    tol = 1e-12
    for _ in range(20 * n + 50):
        F = np.flatnonzero(~fixed)
        nf = F.shape[0]
        if nf == 0:
            # Nothing free: release the bound whose multiplier at μ = 0 is most negative.
            arg = _most_negative(-bj, 0.0)
            if arg < 0:
                return x, mu
            fixed[arg] = False
            continue
        sol = _equality_qp(Wj, bj, ej, F)
        if _take_if_stationary(x, sol, F, tol):
            # At the minimum on the working set: keep it, or free the worst active bound.
            mu = sol[nf]
            arg = _most_negative(_bound_multipliers(Wj, bj, ej, x, mu, fixed), -1e-10 * bscale)
            if arg < 0:
                return x, mu
            fixed[arg] = False
            continue
        _step_to_bound(x, sol, F, zmask, fixed)
    return x, 0.0       # no convergence: no drift


@njit(cache=True, nogil=True)
def _most_negative(values, below):  # pragma: no cover - compiled
    """Index of the first smallest of ``values`` strictly below ``below``, or −1."""
    worst, arg = below, -1
    for i in range(values.shape[0]):
        if values[i] < worst:
            worst, arg = values[i], i
    return arg


@njit(cache=True, nogil=True)
def _equality_qp(Wj, bj, ej, F):  # pragma: no cover - compiled
    """Solution ``[x_F, μ]`` of ``min ½xᵀWx − bᵀx`` on the free set ``F`` with ``eᵀx = 0``
    (the other entries held at 0): its KKT system."""
    nf = F.shape[0]
    K = np.zeros((nf + 1, nf + 1))
    rhs = np.zeros(nf + 1)
    for a in range(nf):
        for c in range(nf):
            K[a, c] = Wj[F[a], F[c]]
        K[a, nf] = ej[F[a]]
        K[nf, a] = ej[F[a]]
        rhs[a] = bj[F[a]]
    return np.linalg.solve(K, rhs)


@njit(cache=True, nogil=True)
def _bound_multipliers(Wj, bj, ej, x, mu, fixed):  # pragma: no cover - compiled
    """Multipliers ``ν = W x + μ e − b`` of the active bounds (``inf`` elsewhere): all must
    be ≥ 0 at the optimum (ν is a rate of gap change per unit squeeze, dimensionless like b)."""
    n = bj.shape[0]
    out = np.full(n, np.inf)
    for i in range(n):
        if fixed[i]:
            nu = -bj[i] + mu * ej[i]
            for c in range(n):
                nu += Wj[i, c] * x[c]
            out[i] = nu
    return out


@njit(cache=True, nogil=True)
def _take_if_stationary(x, sol, F, tol):  # pragma: no cover - compiled
    """Whether the working set's solution ``sol`` (the free entries, then μ) is the current
    ``x`` on the free rows ``F`` to ``1e3 tol`` (relative): the active-set iteration is at
    the minimum on its working set; then ``x_F`` takes it (in place)."""
    nf = F.shape[0]
    pmax, xmax = 0.0, 0.0
    for a in range(nf):
        pmax = max(pmax, abs(sol[a] - x[F[a]]))
        xmax = max(xmax, abs(sol[a]))
    if not pmax <= tol * (1.0 + xmax) * 1e3:      # (a NaN is not stationary)
        return False
    for a in range(nf):
        x[F[a]] = sol[a]
    return True


@njit(cache=True, nogil=True)
def _step_to_bound(x, sol, F, zmask, fixed):  # pragma: no cover - compiled
    """Move the free entries ``x_F`` towards ``sol`` until a bounded one reaches 0 (it is
    then fixed), in place."""
    nf = F.shape[0]
    alpha, block = 1.0, -1
    for a in range(nf):
        i = F[a]
        p = sol[a] - x[i]
        if zmask[i] and p < 0:
            r = -x[i] / p
            if r < alpha:
                alpha, block = r, i
    for a in range(nf):
        x[F[a]] += alpha * (sol[a] - x[F[a]])
    if block >= 0:
        x[block] = 0.0
        fixed[block] = True


# ------------------------------------------------------------------ the factored QP
# The derivative QP of consecutive breakpoints differs by a row or two: its free set's
# Cholesky factor is kept across the active-set iterations and the pieces of a path, and
# rows are added (a bordered solve) or removed (a rank-one update of the trailing block)
# in O(n²) instead of a new O(n³) factorisation per iteration. The factor holds the rows
# `order[:size]` (global row ids) of the symmetrised, regularised Delassus matrix `Ws`.


@njit(cache=True, nogil=True)
def _factor_append(L, order, size, Ws, i):  # pragma: no cover - compiled
    """Border the factor with row ``i``; returns the new size (unchanged when the bordered
    matrix is not numerically positive definite: the caller refactors densely)."""
    n = size
    d = Ws[i, i]
    for a in range(n):
        v = Ws[order[a], i]
        for c in range(a):
            v -= L[a, c] * L[n, c]
        v /= L[a, a]
        L[n, a] = v
        d -= v * v
    if not d > 1e-14 * Ws[i, i]:
        return -1
    L[n, n] = np.sqrt(d)
    for c in range(n + 1, L.shape[0]):
        L[n, c] = 0.0
    order[n] = i
    return n + 1


@njit(cache=True, nogil=True)
def _factor_remove(L, order, size, k):  # pragma: no cover - compiled
    """Remove the factor's ``k``-th row: drop it and update the trailing block by the
    removed column (a rank-one Cholesky update); returns the new size."""
    n = size
    # the trailing block gains l lᵀ, l = L[k+1:, k]
    w = np.empty(n - k - 1)
    for a in range(k + 1, n):
        w[a - k - 1] = L[a, k]
    # shift rows/columns k+1.. up/left by one
    for a in range(k + 1, n):
        for c in range(k):
            L[a - 1, c] = L[a, c]
        for c in range(k + 1, a + 1):
            L[a - 1, c - 1] = L[a, c]
        order[a - 1] = order[a]
    m = n - k - 1
    for j in range(m):
        jj = k + j
        r = np.sqrt(L[jj, jj] * L[jj, jj] + w[j] * w[j])
        cs = r / L[jj, jj]
        sn = w[j] / L[jj, jj]
        L[jj, jj] = r
        for a in range(j + 1, m):
            aa = k + a
            L[aa, jj] = (L[aa, jj] + sn * w[a]) / cs
            w[a] = cs * w[a] - sn * L[aa, jj]
    return n - 1


@njit(cache=True, nogil=True)
def _factor_solve(L, size, r):  # pragma: no cover - compiled
    """``(L Lᵀ)⁻¹ r`` on the factor's first ``size`` rows."""
    n = size
    y = np.empty(n)
    for a in range(n):
        v = r[a]
        for c in range(a):
            v -= L[a, c] * y[c]
        y[a] = v / L[a, a]
    for a in range(n - 1, -1, -1):
        v = y[a]
        for c in range(a + 1, n):
            v -= L[c, a] * y[c]
        y[a] = v / L[a, a]
    return y


@njit(cache=True, nogil=True)
def _factor_to(L, order, size, Ws, free, where):  # pragma: no cover - compiled
    """Make the factor hold exactly the rows with ``free`` set (global row ids); ``where``
    maps a row to its place in the factor (−1 outside), kept up to date. Returns the size,
    or −1 if a bordered row was not positive definite (the factor is then invalid)."""
    k = size - 1
    while k >= 0:
        if not free[order[k]]:
            where[order[k]] = -1
            size = _factor_remove(L, order, size, k)
        k -= 1
    for a in range(size):
        where[order[a]] = a
    for i in range(free.shape[0]):
        if free[i] and where[i] < 0:
            size = _factor_append(L, order, size, Ws, i)
            if size < 0:
                return -1
            where[i] = size - 1
    return size


@njit(cache=True, nogil=True)
def _factored_equality_qp(L, order, size, Ws, b, e):  # pragma: no cover - compiled
    """``[x, μ]`` in the factor's row order: ``W x + μ e = b``, ``eᵀ x = 0`` on the rows
    ``order[:size]`` (the KKT system of :func:`_equality_qp`) by two solves with the
    factor."""
    n = size
    bf = np.empty(n)
    ef = np.empty(n)
    for a in range(n):
        bf[a] = b[order[a]]
        ef[a] = e[order[a]]
    wb = _factor_solve(L, n, bf)
    we = _factor_solve(L, n, ef)
    num, den = 0.0, 0.0
    for a in range(n):
        num += ef[a] * wb[a]
        den += ef[a] * we[a]
    mu = num / den if den != 0.0 else 0.0
    out = np.empty(n + 1)
    for a in range(n):
        out[a] = wb[a] - mu * we[a]
    out[n] = mu
    return out


@njit(cache=True, nogil=True)
def _factored_qp(Ws, b, e, J, zmask, fac):  # pragma: no cover - compiled
    """:func:`_derivative_qp` on the rows ``J`` of ``Ws`` (global ids; ``zmask`` over
    ``J``) with the kept factor ``fac = (L, order, where, size)``; the same active-set
    iterations. Returns ``(x over J, μ, size)``; ``size < 0``: the factor broke down."""
    L, order, where, sz = fac[0], fac[1], fac[2], fac[3][0]
    nj = J.shape[0]
    m = Ws.shape[0]
    x = np.zeros(nj)
    fixed = zmask.copy()
    mu = 0.0
    bscale = 1.0
    for a in range(nj):
        bscale = max(bscale, abs(b[J[a]]))
    tol = 1e-12
    free = np.zeros(m, np.bool_)
    for _ in range(20 * nj + 50):
        F = np.flatnonzero(~fixed)
        nf = F.shape[0]
        if nf == 0:
            arg = -1
            worst = 0.0
            for a in range(nj):
                if b[J[a]] > 0.0 and -b[J[a]] < worst:
                    worst, arg = -b[J[a]], a
            if arg < 0:
                fac[3][0] = sz
                return x, mu, sz
            fixed[arg] = False
            continue
        free[:] = False
        for a in range(nf):
            free[J[F[a]]] = True
        sz = _factor_to(L, order, sz, Ws, free, where)
        if sz < 0:
            fac[3][0] = 0
            where[:] = -1
            return x, mu, -1
        raw = _factored_equality_qp(L, order, sz, Ws, b, e)
        sol = np.empty(nf + 1)
        for a in range(nf):
            sol[a] = raw[where[J[F[a]]]]
        sol[nf] = raw[sz]
        if _take_if_stationary(x, sol, F, tol):
            mu = sol[nf]
            # multipliers of the active bounds, ν = W x + μ e − b (Wj = Ws[J, J])
            worst, arg = -1e-10 * bscale, -1
            for a in range(nj):
                if fixed[a]:
                    nu = -b[J[a]] + mu * e[J[a]]
                    for c in range(nj):
                        nu += Ws[J[a], J[c]] * x[c]
                    if nu < worst:
                        worst, arg = nu, a
            if arg < 0:
                fac[3][0] = sz
                return x, mu, sz
            fixed[arg] = False
            continue
        _step_to_bound(x, sol, F, zmask, fixed)
    fac[3][0] = sz
    return x, 0.0, sz       # no convergence: no drift


@njit(cache=True, nogil=True)
def _trace(W, g0, b, e, delta_max, gap_tol, max_pieces):  # pragma: no cover - compiled
    m = g0.shape[0]
    t = np.inf
    for i in range(m):
        if e[i] > 0:
            t = min(t, g0[i] / e[i])
    t = -t
    delta = np.inf
    for i in range(m):
        if e[i] < 0:
            delta = min(delta, (g0[i] + e[i] * t) / b[i])
    lam = np.zeros(m)
    cap = 64
    D = np.empty(cap)
    L = np.empty((cap, m))
    T = np.empty(cap)
    D[0], T[0] = delta, t
    L[0] = lam
    k = 1
    reg = 0.0
    for i in range(m):
        reg += W[i, i]
    reg *= 1e-13 / max(m, 1)
    # the symmetrised, regularised Delassus matrix of every derivative QP, and its kept
    # factor (module comment above)
    Ws = 0.5 * (W + W.T)
    for i in range(m):
        Ws[i, i] += reg
    fac = (np.zeros((m, m)), np.zeros(m, np.int64), np.full(m, -1, np.int64),
           np.zeros(1, np.int64))
    for _ in range(max_pieces):
        # done at delta_max, to rounding: the last step's end can fall a few ulps short,
        # and a degenerate contact set there can then only take zero-length steps
        # (max_pieces of them, each a full QP: hours on a large mesh)
        if delta >= delta_max or delta_max - delta <= 1e-11 * abs(delta_max):
            break
        lam_scale = 1e-300
        for i in range(m):
            lam_scale = max(lam_scale, abs(lam[i]))
        strong = lam > 1e-12 * lam_scale
        nz = np.flatnonzero(lam)
        g = g0 - delta * b + e * t
        for i in range(m):
            v = 0.0
            for c in nz:
                v += W[i, c] * lam[c]
            g[i] += v
        touching = (~strong) & (g <= gap_tol)
        J = np.flatnonzero(strong | touching)
        nj = J.shape[0]
        x, dt, ok = _factored_qp(Ws, b, e, J, touching[J], fac)
        if ok < 0:
            # the kept factor lost positive definiteness: the dense QP on this piece
            Wj = np.empty((nj, nj))
            for a in range(nj):
                for c in range(nj):
                    Wj[a, c] = Ws[J[a], J[c]]
            x, dt = _derivative_qp(Wj, b[J], e[J], touching[J])
        dlam = np.zeros(m)
        for a in range(nj):
            dlam[J[a]] = x[a]
        dg = e * dt - b
        for i in range(m):
            v = 0.0
            for a in range(nj):
                v += W[i, J[a]] * x[a]
            dg[i] += v
        xs = 1e-300
        for a in range(nj):
            xs = max(xs, abs(x[a]))
        stays = np.zeros(m, np.bool_)
        for a in range(nj):
            if strong[J[a]] or x[a] > 1e-12 * xs:
                stays[J[a]] = True
        h = delta_max - delta
        for i in range(m):
            if dlam[i] < 0:
                h = min(h, lam[i] / -dlam[i])
            elif dlam[i] == 0 and dg[i] < 0 and not stays[i]:
                h = min(h, max(g[i], 0.0) / -dg[i])
        h = max(h, 0.0)
        for i in range(m):
            lam[i] = max(lam[i] + h * dlam[i], 0.0)
            if dlam[i] < 0 and abs(lam[i]) <= 1e-12 * lam_scale:
                lam[i] = 0.0
        t += h * dt
        delta += h
        if h > 0 or delta >= delta_max:
            if k == cap:
                cap *= 2
                D2, L2, T2 = np.empty(cap), np.empty((cap, m)), np.empty(cap)
                D2[:k], L2[:k], T2[:k] = D[:k], L[:k], T[:k]
                D, L, T = D2, L2, T2
            D[k], T[k] = delta, t
            L[k] = lam
            k += 1
    return D[:k], L[:k], T[:k]


def trace_contact_path(W: np.ndarray, g0: np.ndarray, b: np.ndarray, e: np.ndarray,
                       delta_max: float, *, gap_tol: float, max_pieces: int = 10000
                       ) -> ContactPath:
    """Follow the frictionless contact solution from first touch to ``delta_max``.

    Parameters
    ----------
    W : ndarray, shape (m, m)
        Delassus matrix (m/N), symmetric positive definite.
    g0 : ndarray, shape (m,)
        Rest gaps (m) with pad A at its first-touch position and no squeeze.
    b : ndarray, shape (m,)
        Rate at which each gap shrinks with ``δ`` (> 0 for the contacts of pad B, 0 for
        pad A).
    e : ndarray, shape (m,)
        Rate at which each gap grows with the part's axial translation (> 0 for pad A's
        contacts, < 0 for pad B's).
    delta_max : float
        Largest squeeze to trace (m).
    gap_tol : float
        Gaps below this (m) count as closed.

    Returns
    -------
    ContactPath
    """
    m = len(g0)
    A, B = e > 0, e < 0
    if not A.any() or not B.any():
        empty = np.array([np.inf])
        return ContactPath(empty, np.zeros((1, m)), np.zeros(1), np.zeros((0, 3)))
    # First touch on the nodes (translate until pad A touches, squeeze until B does), then
    # follow the path (compiled: ~10⁴ breakpoints per plan).
    D, L, T = _trace(np.ascontiguousarray(W, dtype=float), np.asarray(g0, float),
                     np.asarray(b, float), np.asarray(e, float), float(delta_max), float(gap_tol),
                     int(max_pieces))
    # U = ½ λᵀWλ with λ linear on each piece: exact quadratic coefficients.
    dL = np.diff(L, axis=0) / np.diff(D)[:, None]
    WL = L[:-1] @ W
    c0 = 0.5 * np.einsum("ij,ij->i", WL, L[:-1])
    c1 = np.einsum("ij,ij->i", WL, dL)
    c2 = 0.5 * np.einsum("ij,ij->i", dL @ W, dL)
    return ContactPath(D, L, T, np.column_stack([c0, c1, c2]))
