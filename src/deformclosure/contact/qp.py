"""The frictionless contact problem with balance constraints, as a convex QP in the
multipliers (the dual of ``min ½ uᵀ K u`` under linearised gaps), solved by an
interior-point method and *polished* to exact complementarity on its active set.

    minimise ½ λᵀ W λ + gᵀ λ   subject to  λ ≥ 0,  B λ = 0,

``W`` the Delassus matrix (m/N, or scaled), ``g`` the gaps at zero force, ``B λ = 0`` the
force and moment balance of a free part (the multipliers ``y`` of the balance rows are the
part's rigid motion). Clarabel (through qpsolvers) gives an interior solution; the KKT
system on its active set, solved by least squares, releases rows with a negative
multiplier one at a time.

References
----------
P. Wriggers, *Computational Contact Mechanics*, 2nd ed., Springer 2006 (frictionless
node-to-surface contact, dual formulation).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import DeformClosureError

__all__ = ["solve_balanced_dual"]


def solve_balanced_dual(W: np.ndarray, g: np.ndarray, B: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The balanced dual QP (module docstring), polished.

    Parameters
    ----------
    W : ndarray, shape (r, r)
        Symmetric positive semi-definite contact compliance.
    g : ndarray, shape (r,)
        Gaps at zero force.
    B : ndarray, shape (m, r)
        Balance rows (``m`` may be 0).

    Returns
    -------
    lam, y : ndarray
        Multipliers of the rows and of the balance.
    N : ndarray, shape (m, k)
        Basis of the balance multipliers that leave every active gap unchanged (the rigid
        motions the active contacts do not fix).
    active : ndarray of bool, shape (r,)

    Raises
    ------
    DeformClosureError
        When the interior-point solver fails.

    Examples
    --------
    Two opposite unit contacts squeezed by 1 and balanced:

    >>> lam, y, N, act = solve_balanced_dual(np.eye(2), np.array([-1.0, -1.0]),
    ...                                      np.array([[1.0, -1.0]]))
    >>> lam.round(9).tolist(), act.tolist()
    ([1.0, 1.0], [True, True])
    """
    lam, y = _solve_dual(W, g, B)
    return _polish(W, g, B, lam, y)


def _solve_dual(W: np.ndarray, g: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clarabel on ``min 1/2 l^T W l + g^T l, l >= 0, B l = 0``; returns ``(l, y)``."""
    import scipy.sparse as sp
    from qpsolvers import Problem, solve_problem

    r = len(g)
    P = sp.csc_matrix(0.5 * (W + W.T) + 1e-14 * np.trace(W) / max(r, 1) * np.eye(r))
    prob = Problem(P, g, -sp.eye(r, format="csc"), np.zeros(r), sp.csc_matrix(B) if len(B) else None,
                   np.zeros(len(B)) if len(B) else None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = solve_problem(prob, solver="clarabel", tol_gap_abs=1e-11, tol_gap_rel=1e-11, tol_feas=1e-11,
                            max_iter=200)
    if sol.x is None or not np.all(np.isfinite(sol.x)):
        raise DeformClosureError("the contact problem could not be solved (Clarabel failed); "
                                 "check the finger placement")
    lam = np.maximum(np.asarray(sol.x), 0.0)
    y = np.asarray(sol.y) if sol.y is not None and len(B) else np.zeros(len(B))
    return lam, y


def _polish(W: np.ndarray, g: np.ndarray, B: np.ndarray, lam: np.ndarray, y: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact complementarity on the active set of a dual QP solution.

    Rows are active where the multiplier exceeds the slack (interior-point solutions
    separate the two). The equality-constrained KKT system on the active set is solved
    by least squares; rows with a negative multiplier are released one at a time.

    Returns
    -------
    lam, y : the polished multipliers,
    N : basis of the rigid multipliers that leave every active gap unchanged,
    active : bool mask of the active rows.
    """
    r, m = len(g), len(B)
    slack = W @ lam + g + (B.T @ y if m else 0.0)
    active = lam > np.maximum(slack, 1e-13)
    lam_p = np.zeros(r)
    y_p = np.zeros(m)
    for _ in range(r + 1):
        A = np.flatnonzero(active)
        lam_p = np.zeros(r)
        if len(A) == 0:
            y_p = np.zeros(m)
            break
        KKT = np.block([[W[np.ix_(A, A)], B[:, A].T], [B[:, A], np.zeros((m, m))]])
        rhs = np.r_[-g[A], np.zeros(m)]
        sol = np.linalg.lstsq(KKT, rhs, rcond=1e-13)[0]
        lam_p[A] = sol[: len(A)]
        y_p = sol[len(A):]
        worst = int(np.argmin(lam_p[A]))
        if lam_p[A][worst] >= -1e-13:
            lam_p = np.maximum(lam_p, 0.0)
            break
        active[A[worst]] = False
    A = np.flatnonzero(active)
    if m and len(A):
        _, S, Vt = np.linalg.svd(B[:, A].T, full_matrices=True)
        rank = int(np.sum(S > 1e-10 * max(S.max(initial=0.0), 1e-300)))
        N = Vt[rank:].T
    else:
        N = np.eye(m)
    return lam_p, y_p, N, active
