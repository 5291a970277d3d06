"""The contact graph of two-jaw grasps (SPEC §4; paper §4.3–4.4).

A vertex of the graph is an unordered pair ``{a, b}`` of perimeter nodes where two
frictionless point jaws may touch the part. Two vertices ``{a, b}`` and ``{a, c}`` that
share the node ``a`` are joined when the jaw at the other node can move from ``b`` to
``c`` while the jaw at ``a`` stays put:

*slide*
    ``b`` and ``c`` are neighbours on ``b``'s boundary loop (the jaw slides along one
    boundary edge);
*swing*
    the part rotates about ``a``; relative to the part the jaw at ``b`` travels along the
    circle of radius ``|b - a|`` about ``a`` (rest geometry), leaves ``b`` into the
    exterior and first meets the boundary again on an edge ``(c, c')``; ``{a, b}`` is
    joined to ``{a, c}`` and ``{a, c'}``.

Everything here is rest geometry: the graph does not depend on the jaw separation σ.

Array conventions follow ``docs/internal_contract.md``: ``nodes`` is ``(n, 2)`` float64
in metres, ``loops[0]`` is the outer boundary loop (counter-clockwise) and ``loops[1:]``
are holes (clockwise), each an int64 array of node ids listed once; walking a loop in its
order the part's interior is on the left.

References
----------
.. [1] K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure Grasps of
   Deformable Parts", Int. J. Robotics Research 24(11), 2005, §4.3–4.4.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from ..errors import GraspError
from ..geometry import point_set_diameter, signed_area, touch_tolerance

__all__ = [
    "SLIDE",
    "SWING",
    "ContactGraph",
    "contact_graph",
    "swing_targets",
    "pulling_pairs",
    "part_diameter",
]

#: Bit of :attr:`ContactGraph.kinds` marking a slide edge.
SLIDE: int = 1
#: Bit of :attr:`ContactGraph.kinds` marking a swing edge.
SWING: int = 2

_KIND_NAMES = ((SLIDE, "slide"), (SWING, "swing"))

# (pivot, mover, edge) candidates whose circle/segment intersections are computed in one
# vectorised batch; bounds the memory of the swing search (~100 MB at most).
_CANDIDATES_PER_BATCH = 200_000

_TWO_PI = 2.0 * np.pi


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


# ---------------------------------------------------------------------------------------
# The graph container
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ContactGraph:
    """Contact graph of jaw pairs (SPEC §4, paper §4.4).

    Attributes
    ----------
    pairs : ndarray of int64, shape (V, 2)
        Graph vertices: node-id pairs ``(a, b)`` with ``a < b``, sorted
        lexicographically. Vertex ``v`` of every other array is row ``v`` of ``pairs``.
    edges : ndarray of int64, shape (E, 2)
        Unique undirected edges as vertex indices ``(u, v)``, ``u < v``, sorted.
    kinds : ndarray of uint8, shape (E,)
        Bitmask per edge: ``SLIDE`` (1), ``SWING`` (2), or both (3).
    indptr, indices : ndarray of int64
        Symmetric adjacency in CSR form: the neighbours of vertex ``v`` are
        ``indices[indptr[v]:indptr[v + 1]]`` (ascending).

    Notes
    -----
    Build it with :func:`contact_graph` from a part's boundary, or with
    :meth:`from_edges` from explicit arrays. The arrays are read-only.

    Examples
    --------
    >>> g = ContactGraph.from_edges([[0, 1], [0, 2], [1, 2]], [[1, 0], [2, 1], [0, 1]],
    ...                             [SLIDE, SWING, SWING])
    >>> g.edges.tolist(), g.kinds.tolist(), g.neighbours(1).tolist()   # repeats merged
    ([[0, 1], [1, 2]], [3, 2], [0, 2])
    """

    pairs: np.ndarray
    edges: np.ndarray
    kinds: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray

    def __post_init__(self) -> None:
        V = self.pairs.shape[0] if self.pairs.ndim == 2 else -1
        if self.pairs.ndim != 2 or self.pairs.shape[1] != 2:
            raise GraspError(f"pairs must have shape (V, 2), got {self.pairs.shape}")
        if self.edges.ndim != 2 or self.edges.shape[1] != 2:
            raise GraspError(f"edges must have shape (E, 2), got {self.edges.shape}")
        if self.kinds.shape != (self.edges.shape[0],):
            raise GraspError(f"kinds must have shape ({self.edges.shape[0]},), "
                             f"got {self.kinds.shape}")
        if self.indptr.shape != (V + 1,) or self.indices.shape != (2 * self.edges.shape[0],):
            raise GraspError("indptr/indices do not describe the symmetric adjacency of "
                             "edges; build the graph with ContactGraph.from_edges")

    # -- construction -------------------------------------------------------------------

    @classmethod
    def from_edges(cls, pairs: np.ndarray, edges: np.ndarray,
                   kinds: np.ndarray | None = None) -> "ContactGraph":
        """Build a graph from its vertex pairs and (possibly repeated) edges.

        Parameters
        ----------
        pairs : array_like of int, shape (V, 2)
            Node-id pairs ``a < b``, unique and sorted lexicographically.
        edges : array_like of int, shape (E, 2)
            Vertex-index pairs in any order; repeats are merged (their kinds OR-ed).
        kinds : array_like of uint8, shape (E,), optional
            Edge kind bits; default ``SLIDE | SWING`` is *not* assumed: the default is 0
            (no kind), for graphs that are not built from geometry.

        Returns
        -------
        ContactGraph

        Raises
        ------
        GraspError
            On malformed pairs or edges, self-loops or out-of-range vertex indices.
        """
        pairs = np.asarray(pairs)
        if pairs.ndim != 2 or pairs.shape[1] != 2 or (
                pairs.size and not np.issubdtype(pairs.dtype, np.integer)):
            raise GraspError(f"pairs must be an integer array of shape (V, 2), "
                             f"got {pairs.dtype} {pairs.shape}")
        pairs = pairs.astype(np.int64).reshape(-1, 2)
        V = len(pairs)
        if V and (np.any(pairs[:, 0] >= pairs[:, 1]) or np.any(pairs < 0)):
            raise GraspError("pairs must hold non-negative node ids with a < b in each row")
        if V > 1:
            d0 = np.diff(pairs[:, 0])
            d1 = np.diff(pairs[:, 1])
            if np.any((d0 < 0) | ((d0 == 0) & (d1 <= 0))):
                raise GraspError("pairs must be unique and sorted lexicographically")
        edges = np.asarray(edges)
        if edges.size == 0:
            edges = np.zeros((0, 2), dtype=np.int64)
        if edges.ndim != 2 or edges.shape[1] != 2 or not np.issubdtype(edges.dtype, np.integer):
            raise GraspError(f"edges must be an integer array of shape (E, 2), "
                             f"got {edges.dtype} {edges.shape}")
        edges = edges.astype(np.int64)
        if kinds is None:
            kinds = np.zeros(len(edges), dtype=np.uint8)
        kinds = np.asarray(kinds).astype(np.uint8).reshape(-1)
        if kinds.shape != (len(edges),):
            raise GraspError(f"kinds must have one entry per edge ({len(edges)}), "
                             f"got {kinds.shape[0]}")
        if len(edges) and (edges.min() < 0 or edges.max() >= V):
            raise GraspError(f"edge endpoints must be vertex indices in [0, {V})")
        lo = np.minimum(edges[:, 0], edges[:, 1])
        hi = np.maximum(edges[:, 0], edges[:, 1])
        if np.any(lo == hi):
            raise GraspError(f"self-loop at vertex {int(lo[lo == hi][0])}; a vertex cannot "
                             "be its own neighbour")
        key = lo * max(V, 1) + hi
        order = np.argsort(key, kind="stable")
        key = key[order]
        first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]]) if len(key) else \
            np.zeros(0, dtype=np.int64)
        kinds_u = (np.bitwise_or.reduceat(kinds[order], first) if len(first)
                   else np.zeros(0, dtype=np.uint8)).astype(np.uint8)
        e = np.stack([lo[order][first], hi[order][first]], axis=1)
        src = np.concatenate([e[:, 0], e[:, 1]])
        dst = np.concatenate([e[:, 1], e[:, 0]])
        o = np.lexsort((dst, src))
        indptr = np.zeros(V + 1, dtype=np.int64)
        np.cumsum(np.bincount(src, minlength=V), out=indptr[1:])
        return cls(pairs=_readonly(pairs), edges=_readonly(e), kinds=_readonly(kinds_u),
                   indptr=_readonly(indptr), indices=_readonly(dst[o].astype(np.int64)))

    # -- queries -------------------------------------------------------------------------

    @property
    def n_vertices(self) -> int:
        """Number of vertices ``V``."""
        return int(self.pairs.shape[0])

    @property
    def n_edges(self) -> int:
        """Number of undirected edges ``E``."""
        return int(self.edges.shape[0])

    @property
    def vertex_nodes(self) -> np.ndarray:
        """Sorted node ids that appear in some vertex pair, shape ``(m,)``."""
        return np.unique(self.pairs)

    @cached_property
    def _keys(self) -> np.ndarray:
        base = int(self.pairs.max()) + 1 if self.pairs.size else 1
        return self.pairs[:, 0] * base + self.pairs[:, 1]

    def vertex_indices(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Vertex indices of many node pairs at once (order within a pair irrelevant).

        Parameters
        ----------
        a, b : array_like of int
            Node ids, broadcast together.

        Returns
        -------
        ndarray of int64
            Vertex index of each pair.

        Raises
        ------
        GraspError
            If some pair is not a vertex of the graph.
        """
        a, b = np.broadcast_arrays(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64))
        lo = np.minimum(a, b)
        hi = np.maximum(a, b)
        base = int(self.pairs.max()) + 1 if self.pairs.size else 1
        ok = (lo >= 0) & (hi < base) & (lo != hi)
        key = np.where(ok, lo * base + hi, -1)
        idx = np.searchsorted(self._keys, key)
        idx_c = np.minimum(idx, max(len(self._keys) - 1, 0))
        found = ok & (idx < len(self._keys))
        if len(self._keys):
            found &= self._keys[idx_c] == key
        if not np.all(found):
            bad = np.flatnonzero(~found.ravel())[0]
            raise GraspError(f"nodes ({int(a.ravel()[bad])}, {int(b.ravel()[bad])}) are not "
                             "a vertex of the contact graph: jaws must sit at two distinct "
                             "perimeter nodes of the graph's loops")
        return idx.astype(np.int64)

    def vertex_index(self, a: int, b: int) -> int:
        """Index of the vertex ``{a, b}`` (order of ``a`` and ``b`` irrelevant).

        Raises
        ------
        GraspError
            If ``{a, b}`` is not a vertex (equal nodes, or a node off the vertex loops).
        """
        return int(self.vertex_indices(np.int64(a), np.int64(b)))

    def neighbours(self, v: int) -> np.ndarray:
        """Neighbouring vertex indices of vertex ``v`` (ascending)."""
        v = int(v)
        if not 0 <= v < self.n_vertices:
            raise GraspError(f"vertex index {v} out of range [0, {self.n_vertices})")
        return self.indices[self.indptr[v]:self.indptr[v + 1]]

    def degrees(self) -> np.ndarray:
        """Number of neighbours of every vertex, shape ``(V,)``."""
        return np.diff(self.indptr)

    def to_dict(self, sigma0: np.ndarray, k: np.ndarray,
                pulls: np.ndarray | None = None) -> dict[str, Any]:
        """Export in the SPEC §5 contact-graph format (SI units).

        Parameters
        ----------
        sigma0 : array_like, shape (V,)
            Rest distance of every vertex pair (m).
        k : array_like, shape (V,)
            Pair stiffness of every vertex (N/m).
        pulls : array_like of bool, shape (V,), optional
            Per vertex, whether a jaw would have to pull (see :func:`pulling_pairs`);
            adds a ``"pulls"`` key to each vertex when given.

        Returns
        -------
        dict
            ``{"vertices": [{"a", "b", "sigma0", "k"[, "pulls"]}, ...],
            "edges": [{"u": [a, b], "v": [a, c], "kinds": [...]}, ...], "units": {...}}``
            (``sigma0`` in m, ``k`` in N/m). Node ids are
            mesh node ids; in each edge the node shared by both vertices (the jaw that
            stays put) is listed first. Non-finite numbers become ``None`` (JSON has no
            infinity).
        """
        V = self.n_vertices

        def _col(x: Any, name: str, dtype: type) -> np.ndarray:
            arr = np.asarray(x, dtype=dtype).reshape(-1)
            if arr.shape != (V,):
                raise GraspError(f"{name} must have one value per vertex ({V}), "
                                 f"got {arr.shape[0]}")
            return arr

        s0 = _col(sigma0, "sigma0", float)
        kk = _col(k, "k", float)
        pl = None if pulls is None else _col(pulls, "pulls", bool)

        def _num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        vertices = []
        for v in range(V):
            d: dict[str, Any] = {"a": int(self.pairs[v, 0]), "b": int(self.pairs[v, 1]),
                                 "sigma0": _num(s0[v]), "k": _num(kk[v])}
            if pl is not None:
                d["pulls"] = bool(pl[v])
            vertices.append(d)
        edges = []
        for (u, w), kind in zip(self.edges.tolist(), self.kinds.tolist()):
            pu = self.pairs[u].tolist()
            pw = self.pairs[w].tolist()
            shared = set(pu) & set(pw)
            if len(shared) == 1:
                s = shared.pop()
                pu = [s, pu[1] if pu[0] == s else pu[0]]
                pw = [s, pw[1] if pw[0] == s else pw[0]]
            names = [name for bit, name in _KIND_NAMES if kind & bit]
            edges.append({"u": pu, "v": pw, "kinds": names})
        return {"vertices": vertices, "edges": edges, "units": {"length": "m", "stiffness": "N/m"}}


# ---------------------------------------------------------------------------------------
# Input checks and small geometry helpers
# ---------------------------------------------------------------------------------------


def _check_nodes(nodes: Any) -> np.ndarray:
    X = np.asarray(nodes, dtype=float)
    if X.ndim != 2 or X.shape[1] != 2:
        raise GraspError(f"nodes must have shape (n, 2), got {X.shape}")
    if not np.all(np.isfinite(X)):
        raise GraspError("nodes contain NaN or infinite coordinates")
    return X


def _check_loops(loops: Sequence[Any], n: int) -> list[np.ndarray]:
    if isinstance(loops, np.ndarray) and loops.ndim == 1 and loops.dtype != object:
        raise GraspError("loops must be a sequence of node-id arrays (outer loop first), "
                         "not a single array")
    out = []
    for i, lp in enumerate(loops):
        arr = np.asarray(lp)
        if arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
            raise GraspError(f"loop {i} must be a 1-D array of integer node ids")
        arr = arr.astype(np.int64)
        if arr.size < 3:
            raise GraspError(f"loop {i} has {arr.size} nodes; a boundary loop needs >= 3")
        if arr.min() < 0 or arr.max() >= n:
            raise GraspError(f"loop {i} refers to node ids outside [0, {n})")
        out.append(arr)
    if not out:
        raise GraspError("no boundary loops given; loops[0] must be the outer loop")
    allids = np.concatenate(out)
    u, c = np.unique(allids, return_counts=True)
    if np.any(c > 1):
        raise GraspError(f"node {int(u[c > 1][0])} appears more than once in the boundary "
                         "loops; loops must list each node once")
    return out


def part_diameter(nodes: np.ndarray, loops: Sequence[np.ndarray]) -> float:
    """Largest distance between two boundary nodes (m): the part's diameter
    (:func:`deformclosure.geometry.point_set_diameter` of the loop nodes).

    Parameters
    ----------
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).
    loops : sequence of int arrays
        Boundary loops (node ids).

    Returns
    -------
    float

    Examples
    --------
    >>> part_diameter(np.array([[0., 0.], [3., 0.], [3., 4.], [0., 4.]]), [np.arange(4)])
    5.0
    """
    X = _check_nodes(nodes)
    return point_set_diameter(X[np.unique(np.concatenate(
        [np.asarray(lp, dtype=np.int64) for lp in loops]))])


def _ccw_angle(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Counter-clockwise angle from vectors ``u`` to ``w`` in ``[0, 2π)``."""
    cr = u[..., 0] * w[..., 1] - u[..., 1] * w[..., 0]
    dt = u[..., 0] * w[..., 0] + u[..., 1] * w[..., 1]
    return np.mod(np.arctan2(cr, dt), _TWO_PI)


class _Boundary:
    """Loop bookkeeping shared by the graph builders."""

    def __init__(self, nodes: Any, loops: Sequence[Any], vertex_loops: Sequence[int],
                 tol: float | None) -> None:
        X = _check_nodes(nodes)
        loops_ = _check_loops(loops, len(X))
        vl = [int(i) for i in np.atleast_1d(np.asarray(vertex_loops, dtype=np.int64))]
        if not vl:
            raise GraspError("vertex_loops is empty; use (0,) for contracting grasps or "
                             "all loops for expanding grasps")
        for i in vl:
            if not 0 <= i < len(loops_):
                raise GraspError(f"vertex_loops entry {i} is not a loop index in "
                                 f"[0, {len(loops_)})")
        if len(set(vl)) != len(vl):
            raise GraspError(f"vertex_loops has repeated entries: {vl}")
        for i, lp in enumerate(loops_):
            A = signed_area(X[lp])
            if i == 0 and not A > 0:
                raise GraspError(f"outer loop 0 must be counter-clockwise (signed area {A:g})")
            if i > 0 and not A < 0:
                raise GraspError(f"hole loop {i} must be clockwise (signed area {A:g})")
        seg_p = np.concatenate(loops_)
        seg_q = np.concatenate([np.roll(lp, -1) for lp in loops_])
        L = np.hypot(*(X[seg_q] - X[seg_p]).T)
        if np.any(L == 0):
            j = int(np.flatnonzero(L == 0)[0])
            raise GraspError(f"boundary edge ({int(seg_p[j])}, {int(seg_q[j])}) has zero "
                             "length (duplicate nodes)")
        n = len(X)
        prev_of = np.full(n, -1, dtype=np.int64)
        next_of = np.full(n, -1, dtype=np.int64)
        next_of[seg_p] = seg_q
        prev_of[seg_q] = seg_p
        diam = part_diameter(X, loops_)
        tol = touch_tolerance(diam) if tol is None else float(tol)
        if not (np.isfinite(tol) and tol >= 0):
            raise GraspError(f"tol must be a finite length >= 0 (m), got {tol}")
        vn = np.sort(np.concatenate([loops_[i] for i in vl]))
        local = np.full(n, -1, dtype=np.int64)
        local[vn] = np.arange(len(vn))
        self.X = X
        self.loops = loops_
        self.vertex_loops = vl
        self.seg_p = seg_p
        self.seg_q = seg_q
        self.prev_of = prev_of
        self.next_of = next_of
        self.tol = tol
        self.diameter = diam
        self.vn = vn
        self.local = local


def _pair_index(i: np.ndarray, j: np.ndarray, m: int) -> np.ndarray:
    """Index of the pair of local node indices ``{i, j}`` (``i != j``) in triu order."""
    lo = np.minimum(i, j)
    hi = np.maximum(i, j)
    return lo * m - (lo * (lo + 1)) // 2 + (hi - lo - 1)


# ---------------------------------------------------------------------------------------
# Edge rules
# ---------------------------------------------------------------------------------------


def _slide_triples(bd: _Boundary) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All (a, b, c): b, c loop neighbours on a vertex loop, a another vertex node."""
    b = np.concatenate([bd.loops[i] for i in bd.vertex_loops])
    c = np.concatenate([np.roll(bd.loops[i], -1) for i in bd.vertex_loops])
    b, c = np.concatenate([b, c]), np.concatenate([c, b])
    a = np.repeat(bd.vn, len(b))
    b = np.tile(b, len(bd.vn))
    c = np.tile(c, len(bd.vn))
    keep = (a != b) & (a != c)
    return a[keep], b[keep], c[keep]


def _enter_flags(bp: np.ndarray, r: np.ndarray, e1: np.ndarray, e0: np.ndarray,
                 beta: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Whether the swing arc enters the part at ``b`` first, for CCW and CW motion.

    ``bp = b - a`` (…, 2); ``e1``/``e0`` point from ``b`` to its next/previous loop node;
    ``beta`` is the interior angle at ``b`` (CCW from ``e1`` to ``e0``). The interior is
    the open wedge CCW from ``e1`` to ``e0``. A tangent exactly along an edge (within
    ``tol``) is decided by curvature: the arc bends towards ``a``, i.e. to the left for
    CCW motion and to the right for CW motion.
    """
    t = np.stack([-bp[..., 1], bp[..., 0]], axis=-1)  # CCW tangent, length r
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = np.where(r > 0, r, 1.0)

        def along(e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            cr = (t[..., 0] * e[..., 1] - t[..., 1] * e[..., 0]) / rs
            dt = t[..., 0] * e[..., 0] + t[..., 1] * e[..., 1]
            on = np.abs(cr) <= tol
            return on & (dt > 0), on & (dt < 0)

        e1_ccw, e1_cw = along(e1)
        e0_ccw, e0_cw = along(e0)
    alpha = _ccw_angle(e1, t)
    alpha_cw = np.mod(alpha + np.pi, _TWO_PI)
    in_ccw = (alpha > 0) & (alpha < beta)
    in_cw = (alpha_cw > 0) & (alpha_cw < beta)
    # Along e1 the interior is on the left, along e0 on the right.
    enter_ccw = e1_ccw | (~e0_ccw & in_ccw)
    enter_cw = e0_cw | (~e1_cw & in_cw)
    return enter_ccw, enter_cw


def _swing_candidates(bd: _Boundary, ia: int, P: np.ndarray, D: np.ndarray,
                      L2: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """(mover, edge) candidates of pivot ``vn[ia]``: edges whose distance range from the
    pivot contains the mover's radius (± margin); movers sorted by radius, one
    ``searchsorted`` per edge bound."""
    pb = bd.X[bd.vn]
    pa = bd.X[bd.vn[ia]]
    r = np.hypot(pb[:, 0] - pa[0], pb[:, 1] - pa[1])
    order = np.argsort(r)
    rs = r[order]
    Pa = P - pa
    Qa = Pa + D
    dmax = np.maximum(np.hypot(Pa[:, 0], Pa[:, 1]), np.hypot(Qa[:, 0], Qa[:, 1]))
    sf = np.clip(-(Pa[:, 0] * D[:, 0] + Pa[:, 1] * D[:, 1]) / L2, 0.0, 1.0)
    dmin = np.hypot(Pa[:, 0] + sf * D[:, 0], Pa[:, 1] + sf * D[:, 1])
    lo = np.searchsorted(rs, dmin - margin, side="left")
    hi = np.searchsorted(rs, dmax + margin, side="right")
    cnt = hi - lo
    ee = np.repeat(np.arange(len(P)), cnt)
    first = np.cumsum(cnt) - cnt
    pos = np.arange(ee.size) - np.repeat(first - lo, cnt)
    bb = order[pos]
    keep = (bb != ia) & (r[bb] > bd.tol)  # a mover on top of the pivot has no arc
    return bb[keep], ee[keep]


def _circle_segment_roots(Pc: np.ndarray, Dc: np.ndarray, Lc: np.ndarray, L2: np.ndarray,
                          r: np.ndarray, bpc: np.ndarray, b_is_p: np.ndarray,
                          b_is_q: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Where the swing circles meet boundary edges: edge parameters of the meeting points.

    Candidate ``k`` is the circle of radius ``r[k]`` about the pivot ``a`` (coordinates
    relative to ``a``) through the mover ``b`` (``bpc[k] = b - a``), and the edge
    ``P + s D``, ``s`` in ``[0, 1]``.

    Parameters
    ----------
    Pc, Dc : ndarray, shape (K, 2)
        Edge start relative to the pivot, and edge vector (m).
    Lc, L2 : ndarray, shape (K,)
        Edge length (m) and its square (m²).
    r : ndarray, shape (K,)
        Circle radius ``|b - a|`` (m).
    bpc : ndarray, shape (K, 2)
        Mover relative to the pivot, ``b - a`` (m).
    b_is_p, b_is_q : ndarray of bool, shape (K,)
        The edge starts / ends at the mover ``b`` (an edge incident to the mover).
    tol : float
        Touching tolerance (m): a line within ``tol`` of tangency touches at its foot.

    Returns
    -------
    s : ndarray, shape (K, 2)
        Edge parameters of the two meeting points (dimensionless, not clipped).
    ok : ndarray of bool, shape (K, 2)
        Whether each meeting exists (range ``[0, 1]`` not yet checked).

    Notes
    -----
    ``|P + s D|² = r²`` is ``L² s² + 2 β s + C = 0`` with ``β = P·D``,
    ``C = |P|² - r²`` and discriminant ``β² - L² C = L² (r² - h²)`` (Lagrange's
    identity; ``h = |P × D| / L`` is the distance from ``a`` to the edge's line).

    *Tangency.* A line within ``tol`` of tangency (``|r - h| <= tol``) touches the
    circle at its foot ``s = -β / L²`` (one double root). Near tangency the two roots
    are ill-conditioned: a rounding error ``δ`` in ``r - h`` moves them by
    ``√(2 r δ)``, e.g. 1e-10 m for ``δ`` = 1e-18 m, above the tolerance, so an exact
    touch at a node (a symmetric part) would become a crossing of one of its edges.

    *Crossings* (``r - h > tol``): the roots are taken in the numerically stable form
    ``q = -(β + sign(β) √disc)``, ``s = q / L²`` and ``s = C / q`` (their product is
    ``C / L²``), so neither suffers cancellation between ``β`` and ``√disc``.

    *Edges incident to the mover* are met by the circle at ``b`` itself, where the jaw
    starts, and at most once more: with ``P = b - a`` (``C = 0`` exactly) the roots are
    ``0`` and ``-2 β / L²``, and symmetrically ``1`` and ``1 - 2 (b - a)·D / L²`` when
    the edge ends at ``b``. Only that far root can be a meeting; it is computed from
    ``b - a`` directly, without a square root. Solving the generic quadratic there
    instead leaves a near-zero discriminant whenever the edge is tangent to the circle
    at ``b`` (e.g. a face perpendicular to ``b - a``): its square root put a root at
    ``b`` ~1e-8 rad past the start, above the tolerance, and that hit at the mover's
    own node hid the true first meeting.
    """
    cr = Pc[:, 0] * Dc[:, 1] - Pc[:, 1] * Dc[:, 0]
    h = np.abs(cr) / Lc
    beta = Pc[:, 0] * Dc[:, 0] + Pc[:, 1] * Dc[:, 1]
    sfoot = -beta / L2
    disc = L2 * (r - h) * (r + h)  # factored: no cancellation in r² - h²
    tangent = h - r >= -tol  # within tol of tangency: double root at the foot
    q = -(beta + np.copysign(np.sqrt(np.clip(disc, 0.0, None)), beta))
    nP = np.hypot(Pc[:, 0], Pc[:, 1])
    C = (nP - r) * (nP + r)
    with np.errstate(divide="ignore", invalid="ignore"):
        s1 = np.where(tangent, sfoot, q / L2)
        # q = 0 only if β = 0 and disc = 0, a tangency already handled
        s2 = np.where(tangent | (q == 0.0), s1, C / np.where(q == 0.0, 1.0, q))
    s = np.stack([s1, s2], axis=1)
    ok = np.repeat((h - r <= tol)[:, None], 2, axis=1)
    # Edges incident to the mover: only the far root (see Notes).
    far_p = -2.0 * beta / L2
    far_q = 1.0 - 2.0 * (bpc[:, 0] * Dc[:, 0] + bpc[:, 1] * Dc[:, 1]) / L2
    inc = b_is_p | b_is_q
    s[:, 0] = np.where(b_is_p, far_p, np.where(b_is_q, far_q, s[:, 0]))
    ok[inc, 0] = True
    ok[inc, 1] = False
    return s, ok


class _SwingEdges:
    """The boundary edges ``P + s D`` (``|D| = L``) and the wedge at every vertex node
    (edges ``e1``/``e0`` to its next/previous loop node, interior angle ``beta``), for
    the swing search."""

    def __init__(self, bd: _Boundary) -> None:
        X, vn = bd.X, bd.vn
        self.P = X[bd.seg_p]
        self.D = X[bd.seg_q] - self.P
        self.L = np.hypot(self.D[:, 0], self.D[:, 1])
        self.L2 = self.L * self.L
        self.pb = X[vn]
        self.e1 = X[bd.next_of[vn]] - self.pb
        self.e0 = X[bd.prev_of[vn]] - self.pb
        self.beta = _ccw_angle(self.e1, self.e0)
        # 2 tol: a tangential touch counts up to tol beyond the edge's end; plus round-off.
        self.margin = 2.0 * bd.tol + 1e-13 * bd.diameter


def _arc_meetings(bd: _Boundary, ed: _SwingEdges, pac: np.ndarray, bpc: np.ndarray,
                  rr: np.ndarray, ee: np.ndarray, mover: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where each candidate's circle meets its edge, relative to the pivot.

    Candidate ``k``: pivot at ``pac[k]``, mover ``mover[k]`` at ``bpc[k]`` from it
    (radius ``rr[k]``), edge ``ee[k]``. Four meetings per candidate: the two roots of
    :func:`_circle_segment_roots` (within ``tol`` of the edge) and the edge's two end
    nodes when they lie on the circle within ``tol`` (an arc through a node). Returns
    the points ``(K, 4, 2)`` (m, relative to the pivot), which are valid — not the
    start point ``b`` itself — and the node each is at (-1 inside an edge).
    """
    tol = bd.tol
    Pc = ed.P[ee] - pac
    Dc = ed.D[ee]
    Lc = ed.L[ee]
    sp_ = bd.seg_p[ee]
    sq_ = bd.seg_q[ee]
    s, v_root = _circle_segment_roots(Pc, Dc, Lc, ed.L2[ee], rr, bpc, sp_ == mover,
                                      sq_ == mover, tol)
    eps = (tol / Lc)[:, None]
    v_root &= (s >= -eps) & (s <= 1.0 + eps)
    s = np.clip(s, 0.0, 1.0)
    Xr = Pc[:, None, :] + s[..., None] * Dc[:, None, :]
    sl = s * Lc[:, None]
    node_r = np.where(sl <= tol, sp_[:, None],
                      np.where(Lc[:, None] - sl <= tol, sq_[:, None], -1))
    # Nodes lying on the circle within tol are hits too (arc through a node).
    Qc = Pc + Dc
    v_end = np.stack([np.abs(np.hypot(Pc[:, 0], Pc[:, 1]) - rr) <= tol,
                      np.abs(np.hypot(Qc[:, 0], Qc[:, 1]) - rr) <= tol], axis=1)
    Xh = np.concatenate([Xr, np.stack([Pc, Qc], axis=1)], axis=1)  # (K, 4, 2), rel. a
    valid = np.concatenate([v_root, v_end], axis=1)
    node = np.concatenate([node_r, np.stack([sp_, sq_], axis=1)], axis=1)
    # Ignore the start point b itself (node b, and meetings within tol of it).
    near_b = np.hypot(Xh[..., 0] - bpc[:, None, 0], Xh[..., 1] - bpc[:, None, 1]) <= tol
    valid &= ~near_b & (node != mover[:, None])
    return Xh, valid, node


def _first_hits(phi: np.ndarray, enter: np.ndarray, valid: np.ndarray, key: np.ndarray,
                n_keys: int, rr: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The meetings first along the arc of their (pivot, mover) ``key``: smallest arc
    angle ``phi``, and all within ``tol`` of arc length of it; none for the arcs that
    ``enter`` the part at once. Returns their (candidate, meeting) indices."""
    ph = np.where(valid, phi, np.inf)
    gmin = np.full(n_keys, np.inf)
    np.minimum.at(gmin, key, ph.min(axis=1))
    gmin[enter.ravel()] = np.inf  # first motion enters the part: skipped
    gk = gmin[key]
    with np.errstate(invalid="ignore"):
        first = valid & np.isfinite(gk)[:, None] & (rr[:, None] * (ph - gk[:, None]) <= tol)
    return np.nonzero(first)


def _swing_batch(bd: _Boundary, ed: _SwingEdges, piv: list[int],
                 cands: list[tuple[np.ndarray, np.ndarray]]) -> list[tuple[np.ndarray, ...]]:
    """Swing triples ``(a, b, c, direction)`` of a batch of pivots (local indices
    ``piv``) with their (mover, edge) candidates, vectorised over the batch."""
    vn, m = bd.vn, len(bd.vn)
    nbat = len(piv)
    rows = np.repeat(np.arange(nbat), [len(b) for b, _ in cands])
    bb = np.concatenate([b for b, _ in cands])
    ee = np.concatenate([e for _, e in cands])
    if bb.size == 0:
        return []
    A = vn[np.asarray(piv)]
    pa = bd.X[A]
    bpd = ed.pb[None, :, :] - pa[:, None, :]  # (nbat, m, 2) dense pivot × mover
    rd = np.hypot(bpd[..., 0], bpd[..., 1])
    thd = np.arctan2(bpd[..., 1], bpd[..., 0])
    enter_ccw, enter_cw = _enter_flags(bpd, rd, ed.e1[None], ed.e0[None], ed.beta[None], bd.tol)
    rr = rd[rows, bb]
    Xh, valid, node = _arc_meetings(bd, ed, pa[rows], bpd[rows, bb], rr, ee, vn[bb])
    dth = np.arctan2(Xh[..., 1], Xh[..., 0]) - thd[rows, bb][:, None]
    out = []
    for direction, (phi, enter) in enumerate(((np.mod(dth, _TWO_PI), enter_ccw),
                                              (np.mod(-dth, _TWO_PI), enter_cw))):
        kr, kh = _first_hits(phi, enter, valid, rows * m + bb, nbat * m, rr, bd.tol)
        nd = node[kr, kh]
        isn = nd >= 0
        # Hit at (within tol of) a node c: the arc meets every edge there.
        rn = kr[isn]
        cn = nd[isn]
        # Hit inside an edge (crossing or tangential touch): both its end nodes.
        re_ = kr[~isn]
        krow = np.concatenate([rn, rn, rn, re_, re_])
        c = np.concatenate([cn, bd.prev_of[cn], bd.next_of[cn], bd.seg_p[ee[re_]],
                            bd.seg_q[ee[re_]]])
        out.append((A[rows[krow]], vn[bb[krow]], c, np.full(krow.size, direction, dtype=np.int64)))
    return out


def _swing_triples(bd: _Boundary, pivots: np.ndarray | None = None,
                   mover: int | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """All (a, b, c, direction) such that {a, b} -- {a, c} is a swing edge.

    ``a`` is the pivot, the jaw at ``b`` moves, ``direction`` is 0 for counter-clockwise
    and 1 for clockwise motion of the jaw about ``a``. ``pivots`` (local indices into
    ``bd.vn``) and ``mover`` (one local index) restrict the search.

    For every pivot ``a``, an edge can meet the circle of radius ``r = |b - a|`` only if
    ``dmin <= r <= dmax`` (distances from ``a`` to the edge, with a margin): with the
    movers sorted by radius, each edge's candidate movers are one contiguous range
    (:func:`_swing_candidates`). The exact circle/segment intersections are then
    computed, vectorised, for batches of (pivot, mover, edge) candidates from several
    pivots (:func:`_swing_batch`; :func:`_circle_segment_roots`: stable quadratic roots,
    tangency within ``tol`` as one touch at the foot, and only the far meeting on the
    mover's own edges).
    """
    ed = _SwingEdges(bd)
    m = len(bd.vn)
    out: list[tuple[np.ndarray, ...]] = []
    piv: list[int] = []
    cands: list[tuple[np.ndarray, np.ndarray]] = []
    total = 0
    for ia in (range(m) if pivots is None else (int(x) for x in pivots)):
        b, e = _swing_candidates(bd, ia, ed.P, ed.D, ed.L2, ed.margin)
        if mover is not None:
            sel = b == mover
            b, e = b[sel], e[sel]
        piv.append(ia)
        cands.append((b, e))
        total += b.size
        if total >= _CANDIDATES_PER_BATCH or len(piv) * m >= _CANDIDATES_PER_BATCH:
            out += _swing_batch(bd, ed, piv, cands)
            piv, cands, total = [], [], 0
    if piv:
        out += _swing_batch(bd, ed, piv, cands)
    if not out:
        z = np.zeros(0, dtype=np.int64)
        return z, z, z, z
    a, b, c, d = (np.concatenate(x) for x in zip(*out))
    keep = (bd.local[c] >= 0) & (c != a) & (c != b)
    return a[keep], b[keep], c[keep], d[keep]


def contact_graph(nodes: np.ndarray, loops: Sequence[np.ndarray],
                  vertex_loops: Sequence[int] = (0,), *,
                  tol: float | None = None) -> ContactGraph:
    """Contact graph of two-jaw grasps of a part at rest (SPEC §4, paper §4.3–4.4).

    Parameters
    ----------
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).
    loops : sequence of int arrays
        Boundary loops; ``loops[0]`` outer (counter-clockwise), ``loops[1:]`` holes
        (clockwise); interior on the left.
    vertex_loops : sequence of int, default ``(0,)``
        Loops whose nodes form the vertex pairs: ``(0,)`` for contracting grasps (jaws
        squeeze the outer boundary), all loops for expanding grasps.
    tol : float, optional
        Touching tolerance (m); default the SPEC's, ``1e-9 ×`` the part's diameter
        (:func:`deformclosure.geometry.touch_tolerance`).

    Returns
    -------
    ContactGraph
        Vertices: all unordered pairs of distinct nodes on the vertex loops. Edges
        ``{a, b} -- {a, c}`` (either node may be the one that stays put):

        * *slide* (bit 1): ``b`` and ``c`` are neighbours on ``b``'s loop;
        * *swing* (bit 2): rotating the part about ``a``, the jaw at ``b`` moves along
          the circle of radius ``|b - a|`` about ``a``. Both directions are tried; a
          direction whose first motion enters the part is skipped (interior angle at
          ``b``; a tangent along a boundary edge is decided by the arc's curvature,
          which bends towards ``a``). The first intersection of the arc with any
          boundary edge of any loop (smallest positive arc angle; the start point ``b``
          itself is ignored: ``b``'s own edges count only where the circle meets them
          a second time) gives the edge's end nodes as ``c``. If that first meeting is
          within ``tol`` of a node ``c``, ``c`` and both its loop neighbours are
          targets; if several edges are met within ``tol`` of the first hit (along the
          arc), or an edge is touched tangentially (its line within ``tol`` of tangency
          to the circle, crossing it or not: one touch at the foot of the
          perpendicular from ``a``), the end nodes of every such edge are. Targets
          must be vertex nodes other than ``a`` and ``b``.

    Raises
    ------
    GraspError
        On malformed nodes or loops (shape, range, repeats, orientation, zero-length
        edges), bad ``vertex_loops`` or ``tol``.

    Notes
    -----
    Cost: per pivot, the movers are sorted by radius and each boundary edge selects the
    contiguous range of movers whose circle can meet it (``O((m + p) log m)``, ``m``
    vertex nodes, ``p`` boundary edges); the exact intersections are computed,
    vectorised over batches of pivots, only for those (pivot, mover, edge) candidates
    (about 4 per arc on smooth parts). About 0.6 s for ``p = 245`` (30 000 vertices)
    and 2 s for ``p = 480`` (115 000 vertices).

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0., 0.], [1., 0.], [1., 1.], [0., 1.]])
    >>> g = contact_graph(sq, [np.arange(4)])
    >>> g.pairs.tolist()
    [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    >>> g.vertex_index(3, 1)
    4

    References
    ----------
    .. [1] Gopalakrishnan & Goldberg (2005), §4.3–4.4; SPEC §4 "Contact graph".
    """
    bd = _Boundary(nodes, loops, vertex_loops, tol)
    ii, jj = np.triu_indices(len(bd.vn), 1)
    pairs = np.stack([bd.vn[ii], bd.vn[jj]], axis=1).astype(np.int64)
    return ContactGraph.from_edges(pairs, *_rule_edges(bd))


def _rule_edges(bd: _Boundary) -> tuple[np.ndarray, np.ndarray]:
    """Edges ``{a, b} -- {a, c}`` of the slide and swing rules as vertex-index pairs in
    triu order, with their kind bits (repeats are merged by ``from_edges``)."""
    m = len(bd.vn)
    us, vs, ks = [], [], []
    for kind, (a, b, c) in ((SLIDE, _slide_triples(bd)), (SWING, _swing_triples(bd)[:3])):
        la, lb, lc = bd.local[a], bd.local[b], bd.local[c]
        us.append(_pair_index(la, lb, m))
        vs.append(_pair_index(la, lc, m))
        ks.append(np.full(len(a), kind, dtype=np.uint8))
    return np.stack([np.concatenate(us), np.concatenate(vs)], axis=1), np.concatenate(ks)


def swing_targets(nodes: np.ndarray, loops: Sequence[np.ndarray], a: int, b: int,
                  vertex_loops: Sequence[int] = (0,), *,
                  tol: float | None = None) -> dict[str, np.ndarray | None]:
    """Where the jaw at ``b`` lands when the part rotates about ``a`` (SPEC §4 swing rule).

    The single-pair view of the swing edges of :func:`contact_graph`, for inspection and
    plots.

    Parameters
    ----------
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).
    loops : sequence of int arrays
        Boundary loops (outer counter-clockwise first, holes clockwise).
    a, b : int
        Pivot node (the jaw that stays put) and moving node; both on ``vertex_loops``.
    vertex_loops : sequence of int, default ``(0,)``
        As in :func:`contact_graph`.
    tol : float, optional
        Touching tolerance (m); default ``1e-9 ×`` the part's diameter.

    Returns
    -------
    dict
        ``{"ccw": targets or None, "cw": targets or None}`` for the jaw moving
        counter-clockwise / clockwise about ``a``. ``None``: that direction's first
        motion enters the part (skipped). Otherwise a sorted int64 array of the nodes
        ``c`` with a swing edge ``{a, b} -- {a, c}`` (empty when the arc meets the
        boundary only at ``b`` itself, or only at non-vertex nodes).

    Raises
    ------
    GraspError
        If ``a`` or ``b`` is not a node of the vertex loops, or ``a == b``.

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0., 0.], [1., 0.], [1., 1.], [0., 1.]])
    >>> t = swing_targets(sq, [np.arange(4)], 0, 1)  # CCW swing enters the square
    >>> t["ccw"], t["cw"].tolist()   # CW: around the outside to node 3 (a node hit)
    (None, [2, 3])
    """
    bd = _Boundary(nodes, loops, vertex_loops, tol)
    a, b = int(a), int(b)
    for name, x in (("a", a), ("b", b)):
        if not (0 <= x < len(bd.X)) or bd.local[x] < 0:
            raise GraspError(f"{name}={x} is not a node of the vertex loops {bd.vertex_loops}")
    if a == b:
        raise GraspError(f"a and b must be distinct nodes, got {a} twice")
    ia, ib = int(bd.local[a]), int(bd.local[b])
    pb = bd.X[b]
    bp = (pb - bd.X[a])[None]
    e1 = (bd.X[bd.next_of[b]] - pb)[None]
    e0 = (bd.X[bd.prev_of[b]] - pb)[None]
    enter = _enter_flags(bp, np.hypot(bp[:, 0], bp[:, 1]), e1, e0, _ccw_angle(e1, e0),
                         bd.tol)
    _, _, c, d = _swing_triples(bd, pivots=np.array([ia]), mover=ib)
    out: dict[str, np.ndarray | None] = {}
    for direction, name in enumerate(("ccw", "cw")):
        out[name] = None if enter[direction][0] else np.unique(c[d == direction])
    return out


def pulling_pairs(nodes: np.ndarray, loops: Sequence[np.ndarray], pairs: np.ndarray, *,
                  expanding: bool = False, tol: float | None = None) -> np.ndarray:
    """Flag jaw pairs whose jaw line leaves the part at a jaw (SPEC §4 "Model limits").

    A contracting jaw at ``a`` pushes the part towards ``b`` (force along ``b - a``), an
    expanding one away from ``b`` (along ``a - b``). If at either jaw that force points
    strictly into the exterior (outside the interior wedge at the node, by more than
    ``tol``), the jaw would have to pull.

    Parameters
    ----------
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).
    loops : sequence of int arrays
        Boundary loops (contract orientation).
    pairs : ndarray of int, shape (V, 2)
        Jaw node pairs, e.g. :attr:`ContactGraph.pairs`.
    expanding : bool, default False
        Jaws push outwards (from inside holes) instead of squeezing.
    tol : float, optional
        Tolerance (m); default ``1e-9 ×`` the part's diameter.

    Returns
    -------
    ndarray of bool, shape (V,)
    """
    bd = _Boundary(nodes, loops, range(len(loops)), tol)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) and (pairs.min() < 0 or pairs.max() >= len(bd.X)
                       or (bd.local[pairs.ravel()] < 0).any()):
        raise GraspError("pairs refer to nodes that are on no boundary loop")
    if np.any(pairs[:, 0] == pairs[:, 1]):
        raise GraspError("pairs must hold two distinct nodes")
    X = bd.X
    sign = -1.0 if expanding else 1.0
    out = np.zeros(len(pairs), dtype=bool)
    for j, o in ((0, 1), (1, 0)):
        a = pairs[:, j]
        f = sign * (X[pairs[:, o]] - X[a])
        fl = np.hypot(f[:, 0], f[:, 1])
        e1 = X[bd.next_of[a]] - X[a]
        e0 = X[bd.prev_of[a]] - X[a]
        beta = _ccw_angle(e1, e0)
        alpha = _ccw_angle(e1, f)

        def along(e: np.ndarray) -> np.ndarray:
            # the far end of edge e lies within tol of the jaw line
            cr = (f[:, 0] * e[:, 1] - f[:, 1] * e[:, 0]) / fl
            return (np.abs(cr) <= bd.tol) & ((f * e).sum(1) > 0)

        out |= ~(along(e1) | along(e0)) & (alpha > beta)
    return out
