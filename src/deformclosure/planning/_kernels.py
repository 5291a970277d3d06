"""Numba kernels of the planner: the largest element strain of many jaw pairs.

Private: :func:`deformclosure.planning.plan.pair_elastic_limits` prepares the inputs and
runs chunks of pairs on Python threads (the kernels release the GIL). No numba
``parallel=True``: its threading layers are either not thread-safe (workqueue) or not
fork-safe (GNU OpenMP), and the planner runs inside Dask worker threads and forked pools.

``T`` is component-major, ``T[P, c, i]``: component ``c`` of the strain of element ``i``
under a unit force (N) at loaded node ``P`` — ``c = 0, 1, 2``: ``(ε_xx, ε_yy, γ_xy)`` for
a force along x, ``c = 3, 4, 5`` the same for a force along y (1/N). The innermost loops
run over elements on contiguous memory, so they vectorise.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["max_strain_point_jaws", "max_strain_magnitude"]


@njit(cache=True, nogil=True, fastmath=True)
def max_strain_point_jaws(T, pa, pb, k, ex, ey, lo, hi, out):  # pragma: no cover - compiled
    """Point jaws: pair ``s`` loads ``+k e`` at node ``pa[s]`` and ``−k e`` at ``pb[s]``.

    Writes ``out[s]``, ``lo <= s < hi``: the largest strain magnitude
    ``|½(εxx+εyy)| + √(¼(εxx−εyy)² + ¼γ²)`` over the elements (1/m).
    """
    m = T.shape[2]
    for s in range(lo, hi):
        A = T[pa[s]]
        B = T[pb[s]]
        cx = k[s] * ex[s]
        cy = k[s] * ey[s]
        best = 0.0
        for i in range(m):
            exx = cx * (A[0, i] - B[0, i]) + cy * (A[3, i] - B[3, i])
            eyy = cx * (A[1, i] - B[1, i]) + cy * (A[4, i] - B[4, i])
            g = cx * (A[2, i] - B[2, i]) + cy * (A[5, i] - B[5, i])
            best = max(best, abs(0.5 * (exx + eyy)) + np.sqrt(0.25 * (exx - eyy) ** 2 + 0.25 * g * g))
        out[s] = best


@njit(cache=True, nogil=True, fastmath=True)
def max_strain_magnitude(T, ptr, pos, weight, ex, ey, lo, hi, out):  # pragma: no cover - compiled
    """Any jaws: pair ``s`` loads nodes ``pos[ptr[s]:ptr[s+1]]`` with forces ``weight``
    (N per metre of approach) along its unit direction ``(ex[s], ey[s])``.

    Writes ``out[s]``, ``lo <= s < hi``, as :func:`max_strain_point_jaws`.
    """
    m = T.shape[2]
    acc = np.empty((3, m))
    for s in range(lo, hi):
        acc[:] = 0.0
        for j in range(ptr[s], ptr[s + 1]):
            A = T[pos[j]]
            cx = weight[j] * ex[s]
            cy = weight[j] * ey[s]
            for c in range(3):
                for i in range(m):
                    acc[c, i] += cx * A[c, i] + cy * A[c + 3, i]
        best = 0.0
        for i in range(m):
            exx = acc[0, i]
            eyy = acc[1, i]
            g = acc[2, i]
            best = max(best, abs(0.5 * (exx + eyy)) + np.sqrt(0.25 * (exx - eyy) ** 2 + 0.25 * g * g))
        out[s] = best
