"""The compiled release-landscape kernels: CSR graphs with all vertex energies known.

The landscape package's variant of :func:`deformclosure.landscape.search.minimax_escape`
for graphs held whole — the paper's contact graph (:mod:`deformclosure.grasp.release`,
whose wrappers validate the inputs, SPEC §4) and the pads' axis grid
(:mod:`deformclosure.planning.pads`, §6): :func:`bottleneck_escape` is the same minimax search
with SPEC §4's exact equilibrium test, :func:`release_sweep` the release energy of every
vertex at once. The binary heap (:func:`heap_push`, :func:`heap_pop`) and :func:`path_to`
serve the paper planner's branch-and-bound search as well
(:mod:`deformclosure.planning.plan`). Imported where used (numba is loaded on import), so
``import deformclosure.landscape`` stays light.

All kernels take the symmetric CSR adjacency ``(indptr, indices)`` of a graph and the
vertex energies ``U`` (J); they do not check their inputs. ``cache=True`` keeps the
compiled code between runs.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["bottleneck_escape", "release_sweep", "neighbour_min", "path_to", "heap_push",
           "heap_pop"]


@njit(cache=True, nogil=True, inline="always")
def _heap_move(keys, vals, dst, src):  # pragma: no cover - compiled
    """Entry ``src`` of the binary heap ``(keys, vals)`` moves to slot ``dst``."""
    keys[dst] = keys[src]
    vals[dst] = vals[src]


@njit(cache=True, nogil=True, inline="always")
def _heap_put(keys, vals, i, key, val):  # pragma: no cover - compiled
    """Slot ``i`` of the heap takes the entry ``(key, val)``."""
    keys[i] = key
    vals[i] = val


@njit(cache=True, nogil=True)
def heap_push(keys, vals, size, key, val):  # pragma: no cover - compiled
    """Add ``(key, val)`` (sift up from the end); returns the new size."""
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if keys[p] <= key:
            break
        _heap_move(keys, vals, i, p)
        i = p
    _heap_put(keys, vals, i, key, val)
    return size + 1


@njit(cache=True, nogil=True)
def heap_pop(keys, vals, size):  # pragma: no cover - compiled
    """Remove the root (sift the last entry down); returns the new size (the root must
    be read before)."""
    size -= 1
    if size == 0:
        return 0
    key = keys[size]
    val = vals[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and keys[c + 1] < keys[c]:
            c += 1
        if keys[c] >= key:
            break
        _heap_move(keys, vals, i, c)
        i = c
    _heap_put(keys, vals, i, key, val)
    return size


@njit(cache=True, nogil=True)
def neighbour_min(indptr, indices, U):  # pragma: no cover - compiled
    """Smallest neighbour energy of every vertex (``inf`` for isolated vertices)."""
    V = U.shape[0]
    out = np.full(V, np.inf)
    for v in range(V):
        m = np.inf
        for k in range(indptr[v], indptr[v + 1]):
            u = U[indices[k]]
            if u < m:
                m = u
        out[v] = m
    return out


@njit(cache=True, nogil=True)
def bottleneck_escape(indptr, indices, U, start):  # pragma: no cover - compiled
    """Minimax path from ``start`` to the nearest other equilibrium vertex.

    A Dijkstra search where a path's cost is the largest ``U`` over its vertices
    (``max`` replaces ``+``; :func:`~deformclosure.landscape.search.minimax_escape` with
    ``noise=None``, on a graph held whole); it stops at the first settled vertex ``v != start`` with
    ``U[v] <= U[w]`` for all neighbours ``w``. Equilibria are tested lazily, only on
    settled vertices.

    Returns
    -------
    path : int64 array
        Vertex indices from ``start`` to the target; empty if no other equilibrium is
        reachable.
    """
    V = U.shape[0]
    best = np.full(V, np.inf)
    pred = np.full(V, -1, np.int64)
    done = np.zeros(V, np.bool_)
    cap = indices.shape[0] + 1
    hk = np.empty(cap, np.float64)
    hv = np.empty(cap, np.int64)
    size = 0
    best[start] = U[start]
    size = heap_push(hk, hv, size, U[start], start)
    target = -1
    while size > 0:
        d = hk[0]
        v = hv[0]
        size = heap_pop(hk, hv, size)
        if done[v]:
            continue
        done[v] = True
        if v != start:
            uv = U[v]
            eq = True
            for k in range(indptr[v], indptr[v + 1]):
                if U[indices[k]] < uv:
                    eq = False
                    break
            if eq:
                target = v
                break
        for k in range(indptr[v], indptr[v + 1]):
            w = indices[k]
            if done[w]:
                continue
            uw = U[w]
            nd = d if d >= uw else uw
            if nd < best[w]:
                best[w] = nd
                pred[w] = v
                size = heap_push(hk, hv, size, nd, w)
    if target < 0:
        return np.empty(0, np.int64)
    return path_to(pred, target)


@njit(cache=True, nogil=True)
def path_to(pred, target):  # pragma: no cover - compiled
    """The path start → ``target`` recorded by a search's predecessor array (-1 at the
    start)."""
    n = 0
    x = target
    while x != -1:
        n += 1
        x = pred[x]
    path = np.empty(n, np.int64)
    x = target
    for i in range(n - 1, -1, -1):
        path[i] = x
        x = pred[x]
    return path


@njit(cache=True, nogil=True)
def _find(parent, x):  # pragma: no cover - compiled
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True, nogil=True)
def release_sweep(indptr, indices, U, order, eq, strict):  # pragma: no cover - compiled
    """Release energy of every vertex by one union–find sweep in increasing ``U``.

    Vertices are added in ``order`` (ascending ``U``); adding ``v`` at level
    ``L = U[v]`` unites it with its already-added neighbours. A component keeps the
    number of equilibria it holds and, while it holds exactly one and that one is a
    strict minimum, that vertex as *pending*. When a union makes the count reach two,
    the pending minima of both parts get ``L - U[pending]``. Minima still pending at the
    end never meet another equilibrium: ``inf``. Non-strict vertices get 0.
    """
    V = U.shape[0]
    parent = np.arange(V)
    csize = np.ones(V, np.int64)
    count = np.zeros(V, np.int64)
    pending = np.full(V, -1, np.int64)
    out = np.zeros(V)
    for v in range(V):
        if eq[v]:
            count[v] = 1
        if strict[v]:
            pending[v] = v
            out[v] = np.inf
    added = np.zeros(V, np.bool_)
    for t in range(V):
        v = order[t]
        added[v] = True
        L = U[v]
        for k in range(indptr[v], indptr[v + 1]):
            w = indices[k]
            if not added[w]:
                continue
            ra = _find(parent, v)
            rb = _find(parent, w)
            if ra == rb:
                continue
            if csize[ra] < csize[rb]:
                ra, rb = rb, ra
            parent[rb] = ra
            csize[ra] += csize[rb]
            c = count[ra] + count[rb]
            if c >= 2:
                p = pending[ra]
                if p >= 0:
                    out[p] = L - U[p]
                p = pending[rb]
                if p >= 0:
                    out[p] = L - U[p]
                pending[ra] = -1
                c = 2  # saturate: only "one" vs "several" matters
            elif pending[ra] < 0:
                pending[ra] = pending[rb]
            count[ra] = c
    return out
