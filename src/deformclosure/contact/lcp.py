"""The linear complementarity problem of frictionless contact at a fixed configuration
(SPEC §7: a placement among fixed fingers), by block principal pivoting.

Find ``λ ≥ 0`` with ``w = W λ + q ≥ 0`` and ``λᵀ w = 0`` for a symmetric positive
definite Delassus matrix ``W`` (m/N) and gaps ``q`` (m): the dual of
``min ½ uᵀ K u`` subject to the linearised gaps. The compiled kernel :func:`bpp_kernel` is
called from compiled callers (the placement energy's inner loop); :func:`solve_lcp` is its Python
entry, used through :func:`deformclosure.contact.solve.solve_contact`.

References
----------
J. J. Júdice and F. M. Pires, "A block principal pivoting algorithm for large-scale
strictly monotone linear complementarity problems", Computers & Operations Research
21(5), 1994. K. G. Murty, *Linear Complementarity, Linear and Nonlinear Programming*
(1988) (the single-pivot fallback that guarantees termination).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["solve_lcp", "bpp_kernel"]


@njit(cache=True, nogil=True)
def bpp_kernel(W, q, free0):  # pragma: no cover - compiled
    """Block principal pivoting for ``λ ≥ 0, w = Wλ + q ≥ 0, λᵀw = 0`` (W SPD).

    ``free0``: initial guess of the rows with ``λ > 0`` (warm start). Returns
    ``(λ, ok)``.
    """
    n = q.shape[0]
    free = free0.copy()
    lam = np.zeros(n)
    qs = 1e-300
    for i in range(n):
        qs = max(qs, abs(q[i]))
    ninf_best = n + 1
    backup = 3
    for _ in range(10 * n + 50):
        m = 0
        for i in range(n):
            if free[i]:
                m += 1
        idx = np.empty(m, np.int64)
        k = 0
        for i in range(n):
            if free[i]:
                idx[k] = i
                k += 1
        lam[:] = 0.0
        if m > 0:
            A = np.empty((m, m))
            b = np.empty(m)
            for a in range(m):
                for cc in range(m):
                    A[a, cc] = W[idx[a], idx[cc]]
                b[a] = -q[idx[a]]
            sol = np.linalg.solve(A, b)
            for a in range(m):
                lam[idx[a]] = sol[a]
        w = W @ lam + q
        ls = 1e-300
        for i in range(n):
            ls = max(ls, abs(lam[i]))
        ninf = 0
        last = -1
        for i in range(n):
            bad = (free[i] and lam[i] < -1e-12 * ls) or ((not free[i]) and w[i] < -1e-12 * qs)
            if bad:
                ninf += 1
                last = i
        if ninf == 0:
            for i in range(n):
                lam[i] = max(lam[i], 0.0)
            return lam, True
        if ninf < ninf_best:
            ninf_best = ninf
            backup = 3
            full = True
        elif backup > 0:
            backup -= 1
            full = True
        else:
            full = False
        if full:
            for i in range(n):
                if (free[i] and lam[i] < -1e-12 * ls) or ((not free[i]) and w[i] < -1e-12 * qs):
                    free[i] = not free[i]
        else:
            free[last] = not free[last]       # Murty's single pivot: finite termination
    for i in range(n):
        lam[i] = max(lam[i], 0.0)
    return lam, False


def solve_lcp(W: np.ndarray, q: np.ndarray, warm: np.ndarray | None = None
              ) -> tuple[np.ndarray, bool]:
    """``λ ≥ 0, Wλ + q ≥ 0, λᵀ(Wλ + q) = 0`` by block principal pivoting.

    Parameters
    ----------
    W : ndarray, shape (m, m)
        Symmetric positive definite (m/N).
    q : ndarray, shape (m,)
        Gaps at ``λ = 0`` (m).
    warm : ndarray of bool, shape (m,), optional
        Rows guessed to carry force (a warm start).

    Returns
    -------
    lam : ndarray, shape (m,)
        Multipliers (N).
    ok : bool
        Whether the pivoting converged (it stops after ``10 m + 50`` pivots).

    Examples
    --------
    >>> lam, ok = solve_lcp(np.array([[2.0, 0.5], [0.5, 1.0]]), np.array([-1.0, 1.0]))
    >>> lam.round(6).tolist(), ok
    ([0.5, 0.0], True)
    """
    W = np.ascontiguousarray(W, dtype=float)
    q = np.ascontiguousarray(q, dtype=float)
    free0 = np.zeros(len(q), np.bool_) if warm is None else np.asarray(warm, np.bool_).copy()
    lam, ok = bpp_kernel(W, q, free0)
    return lam, bool(ok)
