"""Numba kernel of the planner: the largest element strain of many jaw pairs.

Private: :func:`deformclosure.planning.plan.pair_elastic_limits` prepares the inputs.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["max_strain_magnitude"]


@njit(cache=True, parallel=True)
def max_strain_magnitude(T, ptr, pos, weight, ex, ey):  # pragma: no cover - compiled
    """``e_max`` of every pair: ``max_i |ε_i|`` with ``ε_i = Σ_j w_j T[P_j, :, i, :]·e``.

    Parameters
    ----------
    T : float64 (q, 2, m, 3)
        Strain ``(ε_xx, ε_yy, γ_xy)`` of element ``i`` under a unit force (N) at
        condensed node ``P`` in direction x (0) or y (1) (1/N).
    ptr, pos, weight : CSR of the pairs
        Pair ``s`` loads nodes ``pos[ptr[s]:ptr[s+1]]`` with forces ``weight`` (N per
        metre of approach) along its unit direction ``(ex[s], ey[s])``.

    Returns
    -------
    float64 (n_pairs,)
        Largest strain magnitude ``|½(εxx+εyy)| + √(¼(εxx−εyy)² + ¼γ²)`` (1/m).
    """
    n = len(ptr) - 1
    m = T.shape[2]
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
                exx += wx * T[p, 0, i, 0] + wy * T[p, 1, i, 0]
                eyy += wx * T[p, 0, i, 1] + wy * T[p, 1, i, 1]
                g += wx * T[p, 0, i, 2] + wy * T[p, 1, i, 2]
            mag = abs(0.5 * (exx + eyy)) + np.sqrt(0.25 * (exx - eyy) ** 2 + 0.25 * g * g)
            if mag > best:
                best = mag
        out[s] = best
    return out
