"""Slices of D-space: one node moves, all others stay (paper §3.2, Fig. 3; SPEC §2).

``dfree_slice`` sweeps one node over a grid of positions while every other node keeps
its position in a base configuration ``q`` and returns, as images, membership in
``D_T``, in every D-obstacle and in ``D_free``, and the energy.

Only what depends on the moving node is recomputed per pixel (vectorised over the
grid): the orientation of the triangles incident to the node, the (at most two)
boundary edges at the node tested against the other boundary edges (pruned by bounding
box) and, for every finger, the contributions of those two edges to the obstacle test
(crossing parity, hits, distances; :mod:`.obstacles`). The linear energy is the exact
quadratic ``U(q + e_v d) = U(q) + (K X)_v . d + 1/2 d^T K_vv d``; the corotational one
adds the incident elements' energies to those of the others. Every pixel equals a
direct call of :func:`.obstacles.in_dfree` / :func:`.energy.strain_energy` on the full
configuration (tested).

The pixels are processed in blocks of rows, and the fixed boundary edges are tested
against each other once (candidate pairs from an R-tree, not all E² pairs), so the
working memory does not grow with the resolution or the boundary; only the images do
(at most :data:`deformclosure.limits.MAX_SLICE_RESOLUTION` pixels per axis).

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.2 and Fig. 3.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import DeformClosureError
from .energy import EnergyKind, _ElementModel, as_configurations
from .fingers import Finger
from .obstacles import _collides, _edge_terms, touch_tolerance
from .topology import DEFAULT_MIN_AREA_RATIO, _folded, _segments_meet, _signed_areas, loop_edges

__all__ = ["SliceResult", "dfree_slice"]

UNITS = {"length": "m", "energy": "J"}


@dataclass(frozen=True)
class SliceResult:
    """D-space slice images (row ``iy`` = ``ys[iy]``, column ``ix`` = ``xs[ix]``).

    Attributes
    ----------
    node : int
        The moving node.
    xs, ys : ndarray (nx,), (ny,)
        Grid coordinates of the moving node (m), pixel centres.
    free : ndarray (ny, nx) of bool
        Membership in ``D_free``.
    in_dt : ndarray (ny, nx) of bool
        Membership in ``D_T``.
    obstacles : ndarray (n_fingers, ny, nx) of bool
        Membership in each finger's D-obstacle.
    energy : ndarray (ny, nx)
        Elastic energy (J) of each configuration, ``energy_kind``.
    energy_kind : str
        ``"linear"`` or ``"corotational"``.
    q : ndarray (n, 2)
        The base configuration (m); the moving node's own entry is its base position.
    """

    node: int
    xs: np.ndarray
    ys: np.ndarray
    free: np.ndarray
    in_dt: np.ndarray
    obstacles: np.ndarray
    energy: np.ndarray
    energy_kind: str
    q: np.ndarray = field(repr=False)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` of the pixel centres (m)."""
        return float(self.xs[0]), float(self.xs[-1]), float(self.ys[0]), float(self.ys[-1])

    def configuration(self, ix: int, iy: int) -> np.ndarray:
        """The full configuration ``(n, 2)`` (m) of pixel ``(iy, ix)``."""
        x = self.q.copy()
        x[self.node] = (self.xs[ix], self.ys[iy])
        return x

    def to_dict(self) -> dict:
        """JSON-ready dict (SI units; images as nested lists, row = y)."""
        return {
            "node": int(self.node),
            "xs": self.xs.tolist(),
            "ys": self.ys.tolist(),
            "base_position": self.q[self.node].tolist(),
            "free": self.free.astype(int).tolist(),
            "in_dt": self.in_dt.astype(int).tolist(),
            "obstacles": self.obstacles.astype(int).tolist(),
            "energy": self.energy.tolist(),
            "energy_kind": self.energy_kind,
            "free_fraction": float(self.free.mean()),
            "units": dict(UNITS),
        }

    def save(self, path: str | Path) -> None:
        """Write ``.npz`` (arrays) or ``.json`` (:meth:`to_dict`), chosen by the suffix."""
        from ..outputs import atomic_path

        path = Path(path)
        if path.suffix.lower() == ".json":
            with atomic_path(path) as tmp:
                tmp.write_text(json.dumps(self.to_dict()) + "\n")
            return
        if path.suffix.lower() != ".npz":
            path = path.with_name(path.name + ".npz")      # what numpy would write
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            self._save_npz(fh)

    def _save_npz(self, fh) -> None:
        np.savez_compressed(
            fh, node=self.node, xs=self.xs, ys=self.ys, free=self.free, in_dt=self.in_dt,
            obstacles=self.obstacles, energy=self.energy, energy_kind=self.energy_kind, q=self.q,
            base_position=self.q[self.node], units=json.dumps(UNITS),
        )


def _resolution(resolution: Any) -> tuple[int, int]:
    r = np.atleast_1d(np.asarray(resolution))
    if r.size == 1:
        r = np.repeat(r, 2)
    if r.size != 2 or not np.all(r == np.round(r)) or np.any(r < 2):
        raise DeformClosureError(f"resolution = {resolution!r}: give an int >= 2 or (nx, ny)")
    return int(r[0]), int(r[1])


def dfree_slice(
    mesh: Any,
    q: Any,
    node: int,
    fingers: Sequence[Finger],
    extent: Sequence[float] | None = None,
    resolution: int | tuple[int, int] = 200,
    *,
    energy: EnergyKind = "linear",
    stiffness: Any = None,
    tol: float | None = None,
    min_area_ratio: float = DEFAULT_MIN_AREA_RATIO,
) -> SliceResult:
    """D_free membership and energy while one node moves and the others stay (paper Fig. 3).

    Parameters
    ----------
    mesh : Mesh
        The part (rest configuration ``q0 = mesh.nodes``, m) with its material.
    q : array_like (n, 2) or (2n,), or None
        Base configuration (m); ``None`` for the rest configuration.
    node : int
        The moving node.
    fingers : sequence of Finger
    extent : (xmin, xmax, ymin, ymax), optional
        Region swept by the node (m). Default: a square centred on the node's base
        position, half-width twice its longest incident edge.
    resolution : int or (nx, ny)
        Number of pixel centres per axis (the extent's edges are pixel centres).
    energy : {"linear", "corotational"}
        Which energy the image shows.
    stiffness : sparse matrix, optional
        ``K`` (N/m) for the linear energy; assembled from the mesh when omitted.
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter``.
    min_area_ratio : float
        ``D_T`` triangle-area threshold (see :func:`.topology.in_dt`).

    Returns
    -------
    SliceResult

    Raises
    ------
    DeformClosureError
        Bad node id, extent or resolution.
    """
    nodes0 = np.asarray(mesh.nodes, dtype=float)
    n = len(nodes0)
    x = nodes0.copy() if q is None else as_configurations(q, n)[0][0].copy()
    if isinstance(node, bool) or not isinstance(node, (int, np.integer)) or not 0 <= int(node) < n:
        raise DeformClosureError(f"node = {node!r}: must be a node id in 0..{n - 1}")
    v = int(node)
    if energy not in ("linear", "corotational"):
        raise DeformClosureError(f"energy = {energy!r}: use 'linear' or 'corotational'")
    tri = np.asarray(mesh.triangles, dtype=np.int64)
    inc = np.flatnonzero(np.any(tri == v, axis=1))
    if extent is None:
        nb = np.unique(tri[inc])
        h = float(np.linalg.norm(x[nb] - x[v], axis=1).max())
        extent = (x[v, 0] - 2 * h, x[v, 0] + 2 * h, x[v, 1] - 2 * h, x[v, 1] + 2 * h)
    ext = np.asarray(extent, dtype=float).ravel()
    if ext.size != 4 or not np.all(np.isfinite(ext)) or ext[1] <= ext[0] or ext[3] <= ext[2]:
        raise DeformClosureError(f"extent = {extent!r}: give (xmin, xmax, ymin, ymax) with xmin < xmax, ymin < ymax")
    nx, ny = _resolution(resolution)
    from ..limits import MAX_SLICE_RESOLUTION

    if nx * ny > MAX_SLICE_RESOLUTION**2:
        raise DeformClosureError(f"resolution = {resolution!r}: {nx} x {ny} pixels, more than "
                                 f"{MAX_SLICE_RESOLUTION} x {MAX_SLICE_RESOLUTION}; lower it")
    xs = np.linspace(ext[0], ext[1], nx)
    ys = np.linspace(ext[2], ext[3], ny)
    P = nx * ny
    tol = touch_tolerance(mesh) if tol is None else float(tol)
    fingers = list(fingers)

    # --- D_T: triangles (what does not depend on the moving node, once)
    rest_area = _signed_areas(nodes0[None], tri)[0]
    areas_fixed = _signed_areas(x[None], tri)[0]
    fixed_tri = np.ones(len(tri), bool)
    fixed_tri[inc] = False
    ok_fixed = bool(np.all(areas_fixed[fixed_tri] > min_area_ratio * rest_area[fixed_tri]))
    kk, jj = np.nonzero(tri[inc] == v)

    # --- D_T: boundary rings. Fixed edges against each other once (candidate pairs from an
    # R-tree of their bounding boxes: no E² table), the moving edges per pixel.
    edges = loop_edges(mesh.loops)
    moving = np.flatnonzero(np.any(edges == v, axis=1))
    adj = _adjacent_triples(edges)
    is_mov = np.zeros(len(edges), bool)
    is_mov[moving] = True
    fixed_edges = np.flatnonzero(~is_mov)
    ok_rings = not _fixed_ring_problems(x, edges, fixed_edges, adj[~np.any(adj == v, axis=1)])
    fold_triples = adj[np.any(adj == v, axis=1)] if len(moving) else adj[:0]
    # moving edges against the non-adjacent fixed edges, pruned by the grid's bounding box
    lo_g = np.array([ext[0], ext[2]])
    hi_g = np.array([ext[1], ext[3]])
    meet_tests = []
    for e in moving:
        other = int(edges[e, 0] if edges[e, 1] == v else edges[e, 1])
        cand = np.flatnonzero(~is_mov & ~np.any(np.isin(edges, edges[e]), axis=1))
        lo = np.minimum(lo_g, x[other])
        hi = np.maximum(hi_g, x[other])
        ea, eb = x[edges[cand, 0]], x[edges[cand, 1]]
        box = np.all((np.minimum(ea, eb) <= hi) & (np.maximum(ea, eb) >= lo), axis=1)
        cand = cand[box]
        if len(cand):
            meet_tests.append((other, x[edges[cand, 0]][None], x[edges[cand, 1]][None]))

    # --- D-obstacles: the fixed edges' terms once per finger
    if len(moving) == 0:
        a, b = x[edges[:, 0]], x[edges[:, 1]]
        static = np.array([bool(_collides(f, _edge_terms(f, a[None], b[None], tol), tol)[0])
                           for f in fingers], dtype=bool)
        t_fixed = []
    else:
        fa_, fb_ = x[edges[fixed_edges, 0]][None], x[edges[fixed_edges, 1]][None]
        t_fixed = [_edge_terms(f, fa_, fb_, tol) for f in fingers]

    # --- energy: what does not depend on the moving node
    if energy == "linear":
        if stiffness is None:
            from ..elasticity.stiffness import stiffness_matrix

            stiffness = stiffness_matrix(mesh)
        X = (x - nodes0).ravel()
        KX = stiffness @ X
        U0 = 0.5 * float(X @ KX)
        dofs = [2 * v, 2 * v + 1]
        Kvv = stiffness[dofs][:, dofs].toarray()
    else:
        model = _ElementModel(mesh)
        e_all = model.energies(x[None], "corotational")[0]
        base = float(e_all[fixed_tri].sum())

    # --- per pixel, in blocks of rows: the working arrays stay small at any resolution
    free = np.empty(P, bool)
    in_dt = np.empty(P, bool)
    obstacles = np.zeros((len(fingers), P), dtype=bool)
    U = np.empty(P)
    n_cand = sum(t[1].shape[1] for t in meet_tests)
    per_px = 8 * (12 * len(inc) + 20 * n_cand + 16 * len(moving) + 32)
    rows = max(1, min(ny, int(_SLICE_BLOCK_BYTES // max(per_px * nx, 1))))
    for r0 in range(0, ny, rows):
        gy = ys[r0:r0 + rows]
        G = np.stack(np.meshgrid(xs, gy), axis=-1).reshape(-1, 2)   # row-major in y
        sl = slice(r0 * nx, r0 * nx + len(G))
        pts = np.broadcast_to(x[tri[inc]], (len(G), len(inc), 3, 2)).copy()
        pts[:, kk, jj, :] = G[:, None, :]
        d1 = pts[..., 1, :] - pts[..., 0, :]
        d2 = pts[..., 2, :] - pts[..., 0, :]
        ar = 0.5 * (d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0])
        del pts, d1, d2
        ok = np.all(ar > min_area_ratio * rest_area[inc], axis=1) & ok_fixed & ok_rings
        for a_, b_, c_ in fold_triples:
            pa = G if a_ == v else np.broadcast_to(x[a_], G.shape)
            pb = G if b_ == v else np.broadcast_to(x[b_], G.shape)
            pc = G if c_ == v else np.broadcast_to(x[c_], G.shape)
            ok &= ~_folded(pa, pb, pc)
        for other, ca, cb in meet_tests:
            oa = np.broadcast_to(x[other], G.shape)[:, None, :]
            ok &= ~_segments_meet(G[:, None, :], oa, ca, cb).any(axis=1)
        in_dt[sl] = ok
        if len(moving) == 0:
            obstacles[:, sl] = static[:, None]
        else:
            ma = np.empty((len(G), len(moving), 2))
            mb = np.empty((len(G), len(moving), 2))
            for j, e in enumerate(moving):
                ma[:, j] = G if edges[e, 0] == v else x[edges[e, 0]]
                mb[:, j] = G if edges[e, 1] == v else x[edges[e, 1]]
            for i, f in enumerate(fingers):
                obstacles[i, sl] = _collides(f, _edge_terms(f, ma, mb, tol).combine(t_fixed[i]), tol)
        free[sl] = ok & ~np.any(obstacles[:, sl], axis=0)
        if energy == "linear":
            d = G - x[v]
            U[sl] = U0 + d @ KX[dofs] + 0.5 * np.einsum("pi,ij,pj->p", d, Kvv, d)
        else:
            # only the incident triangles' node positions matter: build them directly
            U[sl] = base + _incident_energies(model, x, v, inc, G).sum(axis=1)
    shape = (ny, nx)
    return SliceResult(
        node=v, xs=xs, ys=ys, free=free.reshape(shape), in_dt=in_dt.reshape(shape),
        obstacles=obstacles.reshape((len(fingers),) + shape), energy=U.reshape(shape),
        energy_kind=energy, q=x,
    )


#: Working memory of one block of slice pixels (bytes): the slice is computed in blocks of
#: rows so that a 2000 x 2000 slice needs no more than its images.
_SLICE_BLOCK_BYTES = 64e6


def _adjacent_triples(edges: np.ndarray) -> np.ndarray:
    """Consecutive edges ``(u, v), (v, w)`` along the loops as ``(u, v, w)`` rows, O(E)."""
    if not len(edges):
        return np.zeros((0, 3), np.int64)
    start_of = np.full(int(edges.max()) + 1, -1, dtype=np.int64)
    start_of[edges[:, 0]] = np.arange(len(edges))
    k2 = start_of[edges[:, 1]]
    return np.stack([edges[:, 0], edges[:, 1], edges[k2, 1]], axis=1)


def _fixed_ring_problems(x: np.ndarray, edges: np.ndarray, subset: np.ndarray,
                         adj: np.ndarray) -> bool:
    """Do the boundary edges ``subset`` meet each other (non-adjacent pairs), or do the
    consecutive edges ``adj`` fold back, in configuration ``x``?

    Only pairs whose bounding boxes overlap can meet: they come from an R-tree query, so
    no table of all E² pairs is built (a 6 000-edge boundary took gigabytes)."""
    import shapely

    bad = False
    if len(adj):
        bad |= bool(np.any(_folded(x[adj[:, 0]], x[adj[:, 1]], x[adj[:, 2]])))
    if bad or len(subset) < 2:
        return bad
    e = edges[subset]
    pa, pb = x[e[:, 0]], x[e[:, 1]]
    lo, hi = np.minimum(pa, pb), np.maximum(pa, pb)
    boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
    i, j = shapely.STRtree(boxes).query(boxes)
    keep = i < j
    i, j = i[keep], j[keep]
    share = ((e[i, 0] == e[j, 0]) | (e[i, 0] == e[j, 1]) | (e[i, 1] == e[j, 0])
             | (e[i, 1] == e[j, 1]))
    i, j = i[~share], j[~share]
    return bool(len(i)) and bool(np.any(_segments_meet(pa[i], pb[i], pa[j], pb[j])))


def _incident_energies(model: _ElementModel, x: np.ndarray, v: int, inc: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Corotational energies ``(P, k)`` of the triangles incident to ``v`` for every pixel."""
    tri = model.triangles[inc]
    p = np.broadcast_to(x[tri], (len(G),) + tri.shape + (2,)).copy()  # (P, k, 3, 2)
    kk, jj = np.nonzero(tri == v)
    p[:, kk, jj, :] = G[:, None, :]
    ds = np.stack([p[..., 1, :] - p[..., 0, :], p[..., 2, :] - p[..., 0, :]], axis=-1)
    F = ds @ model.dm_inv[inc]
    from .energy import _strains_from_F

    eps = _strains_from_F(F, "corotational")
    return 0.5 * model.t * model.areas[inc] * np.einsum("...i,ij,...j->...", eps, model.D, eps)
