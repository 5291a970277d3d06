"""Topology-preserving configurations ``D_T`` (paper §3.1, Fig. 2; SPEC §2).

A configuration ``q`` is in ``D_T`` when

1. every triangle keeps positive orientation and a non-tiny area: its deformed signed
   area exceeds ``min_area_ratio`` times its rest area (default ``1e-6``); and
2. the deformed boundary rings form a valid polygon with holes: no two boundary edges
   meet except consecutive edges at their shared node, and consecutive edges do not
   fold back onto each other. Touching counts as meeting (a self-touching ring is not
   a valid polygon).

Why these two tests suffice: for a piecewise-linear map that preserves the orientation
of every triangle, the number of preimages of a point off the boundary equals the
winding number of the image of the boundary around it (degree theory). If the image
rings are simple and pairwise disjoint, that winding number is 0 or 1 (the outer ring
turns counter-clockwise, holes clockwise, so a hole outside the outer ring or inside
another hole would give ``-1`` preimages, which is impossible), hence the deformed
mesh is injective: no fold-over and no self-intersection (the two failure modes of
paper Fig. 2). All tests are vectorised over triangles, edge pairs and configurations.

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.1 and Fig. 2.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .energy import as_configurations

__all__ = [
    "DEFAULT_MIN_AREA_RATIO",
    "loop_edges",
    "signed_areas",
    "inverted_triangles",
    "boundary_crossings",
    "in_dt",
    "topology_violations",
]

#: Default minimum ratio of deformed to rest triangle area for ``D_T``.
DEFAULT_MIN_AREA_RATIO = 1e-6

_CHUNK = 4_000_000  # elements of the largest temporary array in pair tests


def loop_edges(loops: Any) -> np.ndarray:
    """Boundary edges ``(E, 2)`` in loop order, interior on the left of ``u -> w``.

    Parameters
    ----------
    loops : sequence of int arrays
        ``mesh.loops`` (outer counter-clockwise first, holes clockwise).
    """
    parts = [np.stack([np.asarray(lp), np.roll(np.asarray(lp), -1)], axis=1) for lp in loops]
    return np.concatenate(parts).astype(np.int64) if parts else np.zeros((0, 2), np.int64)


def signed_areas(mesh: Any, q: Any) -> np.ndarray:
    """Signed area (m²) of every deformed triangle, ``(m,)`` or ``(b, m)``."""
    qb, batched = as_configurations(q, len(mesh.nodes))
    a = _signed_areas(qb, np.asarray(mesh.triangles))
    return a if batched else a[0]


def _signed_areas(qb: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    p = qb[:, triangles]
    d1 = p[..., 1, :] - p[..., 0, :]
    d2 = p[..., 2, :] - p[..., 0, :]
    return 0.5 * (d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0])


def _rest_areas(mesh: Any) -> np.ndarray:
    return _signed_areas(np.asarray(mesh.nodes, float)[None], np.asarray(mesh.triangles))[0]


def inverted_triangles(mesh: Any, q: Any, min_area_ratio: float = DEFAULT_MIN_AREA_RATIO) -> np.ndarray:
    """Mask of triangles whose deformed area is not above ``min_area_ratio`` x rest area.

    Returns
    -------
    ndarray of bool, shape (m,) or (b, m)
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    bad = _signed_areas(qb, np.asarray(mesh.triangles)) <= min_area_ratio * _rest_areas(mesh)
    return bad if batched else bad[0]


def _cross(ax: Any, ay: Any, bx: Any, by: Any) -> Any:
    return ax * by - ay * bx


def _segments_meet(p1: np.ndarray, p2: np.ndarray, p3: np.ndarray, p4: np.ndarray) -> np.ndarray:
    """Whether closed segments ``p1p2`` and ``p3p4`` share a point (broadcast over ``...``)."""
    d1 = _cross(p4[..., 0] - p3[..., 0], p4[..., 1] - p3[..., 1], p1[..., 0] - p3[..., 0], p1[..., 1] - p3[..., 1])
    d2 = _cross(p4[..., 0] - p3[..., 0], p4[..., 1] - p3[..., 1], p2[..., 0] - p3[..., 0], p2[..., 1] - p3[..., 1])
    d3 = _cross(p2[..., 0] - p1[..., 0], p2[..., 1] - p1[..., 1], p3[..., 0] - p1[..., 0], p3[..., 1] - p1[..., 1])
    d4 = _cross(p2[..., 0] - p1[..., 0], p2[..., 1] - p1[..., 1], p4[..., 0] - p1[..., 0], p4[..., 1] - p1[..., 1])
    straddle = (d1 * d2 <= 0) & (d3 * d4 <= 0)
    collinear = (d1 == 0) & (d2 == 0)
    # collinear segments meet iff their bounding boxes overlap
    lo1, hi1 = np.minimum(p1, p2), np.maximum(p1, p2)
    lo2, hi2 = np.minimum(p3, p4), np.maximum(p3, p4)
    boxes = np.all((lo1 <= hi2) & (lo2 <= hi1), axis=-1)
    return np.where(collinear, boxes, straddle & boxes)


def _folded(a: np.ndarray, v: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Consecutive edges ``a-v`` and ``v-b`` overlap (fold back) when collinear and on the same side."""
    ax, ay = a[..., 0] - v[..., 0], a[..., 1] - v[..., 1]
    bx, by = b[..., 0] - v[..., 0], b[..., 1] - v[..., 1]
    return (_cross(ax, ay, bx, by) == 0) & (ax * bx + ay * by > 0)


def _edge_pairs(edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Non-adjacent edge pairs ``(P, 2)`` and adjacent pairs ``(A, 3)`` as ``(a, v, b)`` nodes."""
    E = len(edges)
    i, j = np.triu_indices(E, k=1)
    share = (
        (edges[i, 0] == edges[j, 0]) | (edges[i, 0] == edges[j, 1])
        | (edges[i, 1] == edges[j, 0]) | (edges[i, 1] == edges[j, 1])
    )
    pairs = np.stack([i[~share], j[~share]], axis=1)
    # consecutive edges (u, v), (v, w) along a loop
    nxt = {int(u): k for k, u in enumerate(edges[:, 0])}
    k2 = np.array([nxt[int(v)] for v in edges[:, 1]], dtype=np.int64) if E else np.zeros(0, np.int64)
    adj = np.stack([edges[:, 0], edges[:, 1], edges[k2, 1]], axis=1) if E else np.zeros((0, 3), np.int64)
    return pairs, adj


def boundary_crossings(mesh: Any, q: Any) -> np.ndarray:
    """Mask over configurations: do the deformed boundary rings meet themselves or each other?

    Returns
    -------
    bool or ndarray of bool, shape (b,)
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    edges = loop_edges(mesh.loops)
    pairs, adj = _edge_pairs(edges)
    bad = _crossings(qb, edges, pairs, adj)
    return bad if batched else bool(bad[0])


def _crossings(qb: np.ndarray, edges: np.ndarray, pairs: np.ndarray, adj: np.ndarray) -> np.ndarray:
    b = len(qb)
    bad = np.zeros(b, dtype=bool)
    if len(adj):
        bad |= np.any(_folded(qb[:, adj[:, 0]], qb[:, adj[:, 1]], qb[:, adj[:, 2]]), axis=1)
    if len(pairs) == 0:
        return bad
    step = max(1, _CHUNK // max(1, b))
    for s in range(0, len(pairs), step):
        pr = pairs[s : s + step]
        e1, e2 = edges[pr[:, 0]], edges[pr[:, 1]]
        meet = _segments_meet(qb[:, e1[:, 0]], qb[:, e1[:, 1]], qb[:, e2[:, 0]], qb[:, e2[:, 1]])
        bad |= meet.any(axis=1)
    return bad


def in_dt(mesh: Any, q: Any, min_area_ratio: float = DEFAULT_MIN_AREA_RATIO) -> bool | np.ndarray:
    """Membership of configuration(s) ``q`` in ``D_T`` (topology preserving).

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        ``(n, 2)``/``(2n,)`` or a batch ``(b, n, 2)``/``(b, 2n)`` of node positions (m).
    min_area_ratio : float
        A triangle must keep more than this fraction of its rest area.

    Returns
    -------
    bool or ndarray of bool, shape (b,)

    Examples
    --------
    The rest configuration is in ``D_T``; mirroring it inverts every triangle:

    >>> in_dt(mesh, mesh.nodes)                     # doctest: +SKIP
    True
    >>> in_dt(mesh, mesh.nodes * [-1, 1])           # doctest: +SKIP
    False
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    ok = ~np.any(_signed_areas(qb, np.asarray(mesh.triangles)) <= min_area_ratio * _rest_areas(mesh), axis=1)
    if ok.any():
        edges = loop_edges(mesh.loops)
        pairs, adj = _edge_pairs(edges)
        idx = np.flatnonzero(ok)
        ok[idx] = ~_crossings(qb[idx], edges, pairs, adj)
    return ok if batched else bool(ok[0])


def topology_violations(mesh: Any, q: Any, min_area_ratio: float = DEFAULT_MIN_AREA_RATIO) -> dict:
    """Why a single configuration is not in ``D_T``.

    Returns
    -------
    dict
        ``{"inverted": triangle ids, "crossing": (k, 2) boundary-edge index pairs that
        meet, "folded": node ids where consecutive boundary edges fold back}``; all empty
        when ``q`` is in ``D_T``.
    """
    qb, _ = as_configurations(q, len(mesh.nodes))
    inverted = np.flatnonzero(_signed_areas(qb, np.asarray(mesh.triangles))[0] <= min_area_ratio * _rest_areas(mesh))
    edges = loop_edges(mesh.loops)
    pairs, adj = _edge_pairs(edges)
    x = qb[0]
    if len(pairs):
        e1, e2 = edges[pairs[:, 0]], edges[pairs[:, 1]]
        meet = _segments_meet(x[e1[:, 0]], x[e1[:, 1]], x[e2[:, 0]], x[e2[:, 1]])
    else:
        meet = np.zeros(0, bool)
    folded = _folded(x[adj[:, 0]], x[adj[:, 1]], x[adj[:, 2]]) if len(adj) else np.zeros(0, bool)
    return {"inverted": inverted, "crossing": pairs[meet], "folded": adj[folded, 1]}
