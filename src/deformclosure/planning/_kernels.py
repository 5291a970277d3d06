"""Numba kernel of the planner: the largest element strain of many jaw pairs.

Private: :func:`deformclosure.planning.plan.pair_elastic_limits` prepares the inputs.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["max_strain_magnitude"]


@njit(cache=True, parallel=True, fastmath=True)
def max_strain_magnitude(T, ptr, pos, weight, ex, ey):  # pragma: no cover - compiled
    """``e_max`` of every pair: ``max_i |ε_i|`` with ``ε_i = Σ_j w_j T[P_j, :, i, :]·e``.

    Parameters
    ----------
    T : float64 (q, m, 6)
        ``T[P, i, 3c:3c+3]``: strain ``(ε_xx, ε_yy, γ_xy)`` of element ``i`` under a unit
        force (N) at loaded node ``P`` in direction x (c = 0) or y (c = 1) (1/N).
    ptr, pos, weight : CSR of the pairs
        Pair ``s`` loads nodes ``pos[ptr[s]:ptr[s+1]]`` with forces ``weight`` (N per
        metre of approach) along its unit direction ``(ex[s], ey[s])``.

    Returns
    -------
    float64 (n_pairs,)
        Largest strain magnitude ``|½(εxx+εyy)| + √(¼(εxx−εyy)² + ¼γ²)`` (1/m).
    """
    n = len(ptr) - 1
    m = T.shape[1]
    out = np.empty(n)
    for s in prange(n):
        best = 0.0
        for i in range(m):
            exx = 0.0
            eyy = 0.0
            g = 0.0
            for j in range(ptr[s], ptr[s + 1]):
                p = pos[j]
                wx = weight[j] * ex[s]
                wy = weight[j] * ey[s]
                exx += wx * T[p, i, 0] + wy * T[p, i, 3]
                eyy += wx * T[p, i, 1] + wy * T[p, i, 4]
                g += wx * T[p, i, 2] + wy * T[p, i, 5]
            mag = abs(0.5 * (exx + eyy)) + np.sqrt(0.25 * (exx - eyy) ** 2 + 0.25 * g * g)
            if mag > best:
                best = mag
        out[s] = best
    return out
