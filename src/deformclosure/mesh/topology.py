"""Geometry and topology of a triangle list: signed areas, directed edges, boundary loops.

Pure functions of ``nodes`` ``(n, 2)`` (m) and ``triangles`` ``(m, 3)`` (node ids), used by
the :class:`~deformclosure.mesh.core.Mesh` container to validate itself and recover its
boundary (SPEC §1: perimeter node = node on a boundary loop).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import MeshError
from ..geometry import signed_area

__all__ = ["triangle_areas", "directed_edges", "boundary_loops"]


def triangle_areas(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Signed areas of triangles (m²), positive for counter-clockwise ones.

    Parameters
    ----------
    nodes : ndarray, shape (n, 2)
    triangles : ndarray, shape (m, 3)

    Returns
    -------
    ndarray, shape (m,)

    Examples
    --------
    >>> triangle_areas(np.array([[0., 0.], [1., 0.], [0., 1.]]), np.array([[0, 1, 2], [0, 2, 1]]))
    array([ 0.5, -0.5])
    """
    p = nodes[triangles]
    d1 = p[:, 1] - p[:, 0]
    d2 = p[:, 2] - p[:, 0]
    return 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])


def directed_edges(triangles: np.ndarray) -> np.ndarray:
    """The three directed edges ``(i, j)`` of every triangle, shape ``(3m, 2)``: all first
    edges, then all second, then all third."""
    return np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])


def _boundary_successors(triangles: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Directed boundary edges (interior on the left) and each node's successor on them.

    A directed edge ``(i, j)`` of a counter-clockwise triangle whose reverse ``(j, i)``
    belongs to no triangle is a boundary edge.
    """
    e = directed_edges(triangles)
    key = e[:, 0] * n + e[:, 1]
    rkey = e[:, 1] * n + e[:, 0]
    be = e[~np.isin(key, rkey)]
    if len(be) == 0:
        raise MeshError("triangles: mesh has no boundary; a planar part mesh must have one")
    starts, counts = np.unique(be[:, 0], return_counts=True)
    if np.any(counts > 1):
        bad = int(starts[counts > 1][0])
        raise MeshError(f"triangles: mesh boundary touches itself at node {bad} (non-manifold "
                        "vertex); remesh so that every boundary node has two boundary neighbours")
    succ = np.full(n, -1, dtype=np.int64)
    succ[be[:, 0]] = be[:, 1]
    if np.any(succ[be[:, 1]] < 0):
        raise MeshError("triangles: mesh boundary is not closed; check for missing triangles")
    return be, succ


def _walk_cycles(be: np.ndarray, succ: np.ndarray, n: int) -> list[np.ndarray]:
    """The cycles of the successor map on the boundary nodes, each from its smallest id."""
    g = sp.coo_matrix((np.ones(len(be)), (be[:, 0], be[:, 1])), shape=(n, n))
    _, labels = connected_components(g, directed=True, connection="weak")
    loops: list[np.ndarray] = []
    for lab in np.unique(labels[be[:, 0]]):
        members = np.flatnonzero((labels == lab))
        start = int(members.min())
        order = np.empty(len(members), dtype=np.int64)
        # Walking a cycle is inherently sequential; it is O(p) once per mesh.
        cur = start
        for i in range(len(members)):
            order[i] = cur
            cur = succ[cur]
        if cur != start:
            raise MeshError("triangles: mesh boundary is not a set of simple closed loops")
        loops.append(order)
    return loops


def boundary_loops(nodes: np.ndarray, triangles: np.ndarray) -> list[np.ndarray]:
    """Recover ordered boundary loops of a valid counter-clockwise triangle mesh.

    A directed edge ``(i, j)`` of a counter-clockwise triangle whose reverse ``(j, i)``
    belongs to no triangle is a boundary edge with the interior on its left; chaining
    them gives the loops in the orientation of :mod:`deformclosure.mesh.core`.

    Returns
    -------
    list of ndarray
        Outer loop first (largest positive signed area), then holes sorted by their
        smallest node id. Each loop starts at its smallest node id.

    Raises
    ------
    MeshError
        If a boundary node has more than one outgoing boundary edge (the mesh touches
        itself at a node) or the boundary is not a set of closed loops.

    Examples
    --------
    >>> sq = np.array([[0., 0.], [1., 0.], [1., 1.], [0., 1.]])
    >>> boundary_loops(sq, np.array([[0, 1, 2], [0, 2, 3]]))
    [array([0, 1, 2, 3])]
    """
    n = len(nodes)
    be, succ = _boundary_successors(triangles, n)
    loops = _walk_cycles(be, succ, n)
    areas = [signed_area(nodes[lp]) for lp in loops]
    outer = int(np.argmax(areas))
    if areas[outer] <= 0:
        raise MeshError("triangles: mesh has no counter-clockwise outer boundary loop")
    holes = [lp for i, lp in enumerate(loops) if i != outer]
    holes.sort(key=lambda lp: int(lp.min()))
    return [loops[outer]] + holes
