"""Numba kernel of the planner: the largest element strain of many jaw pairs.

Private: :func:`deformclosure.planning.plan.pair_elastic_limits` prepares the inputs and
runs chunks of pairs on Python threads (the kernel releases the GIL). No numba
``parallel=True``: its threading layers are either not thread-safe (workqueue) or not
fork-safe (GNU OpenMP), and the planner runs inside Dask worker threads and forked pools.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["max_strain_magnitude"]


@njit(cache=True, nogil=True, fastmath=True)
def max_strain_magnitude(T, ptr, pos, weight, ex, ey, lo, hi, out):  # pragma: no cover - compiled
    """``e_max`` of every pair: ``max_i |ε_i|`` with ``ε_i = Σ_j w_j T[P_j, :, i, :]·e``.

    Parameters
    ----------
    T : float64 (q, m, 6)
        ``T[P, i, 3c:3c+3]``: strain ``(ε_xx, ε_yy, γ_xy)`` of element ``i`` under a unit
        force (N) at loaded node ``P`` in direction x (c = 0) or y (c = 1) (1/N).
    ptr, pos, weight : CSR of the pairs
        Pair ``s`` loads nodes ``pos[ptr[s]:ptr[s+1]]`` with forces ``weight`` (N per
        metre of approach) along its unit direction ``(ex[s], ey[s])``.

    lo, hi : int
        Pairs ``lo … hi − 1`` are computed.
    out : float64 (n_pairs,)
        Receives the largest strain magnitude ``|½(εxx+εyy)| + √(¼(εxx−εyy)² + ¼γ²)``
        (1/m) of each computed pair.
    """
    m = T.shape[1]
    for s in range(lo, hi):
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
