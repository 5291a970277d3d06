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
from .fingers import Finger, as_fingers
from .obstacles import _collides, _edge_terms, resolve_tolerance
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
        from ..outputs import atomic_path, output_target, write_json

        path = Path(path)
        if path.suffix.lower() == ".json":
            write_json(path, self.to_dict(), "slice", indent=None)
            return
        if path.suffix.lower() != ".npz" and output_target(path)[0] == "file":
            path = path.with_name(path.name + ".npz")      # what numpy would write
        with atomic_path(path, "slice") as tmp, open(tmp, "wb") as fh:
            self._save_npz(fh)

    def _save_npz(self, fh) -> None:
        np.savez_compressed(
            fh, node=self.node, xs=self.xs, ys=self.ys, free=self.free, in_dt=self.in_dt,
            obstacles=self.obstacles, energy=self.energy, energy_kind=self.energy_kind, q=self.q,
            base_position=self.q[self.node], units=json.dumps(UNITS),
        )


def _resolution(resolution: Any) -> tuple[int, int]:
    try:
        r = np.atleast_1d(np.asarray(resolution, dtype=float))
    except (TypeError, ValueError):
        r = np.zeros(0)
    if r.size == 1:
        r = np.repeat(r, 2)
    if r.size != 2 or not np.all(np.isfinite(r)) or not np.all(r == np.round(r)) or np.any(r < 2):
        raise DeformClosureError(f"resolution = {resolution!r}: give an int >= 2 or (nx, ny)")
    return int(r[0]), int(r[1])


def dfree_slice(mesh: Any, q: Any, node: int, fingers: Sequence[Finger], extent: Sequence[float] | None = None,
                resolution: int | tuple[int, int] = 200, *, energy: EnergyKind = "linear", stiffness: Any = None,
                tol: float | None = None, min_area_ratio: float = DEFAULT_MIN_AREA_RATIO) -> SliceResult:
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
        Fixed fingers (m).
    extent : (xmin, xmax, ymin, ymax), optional
        Region swept by the node (m). Default: a square centred on the node's base
        position, half-width twice its longest incident edge.
    resolution : int or (nx, ny)
        Number of pixel centres per axis (the extent's edges are pixel centres).
    energy : {"linear", "corotational"}
        Which energy the image shows (J).
    stiffness : sparse matrix, optional
        ``K`` (N/m) for the linear energy; assembled from the mesh when omitted.
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter`` (SPEC §3).
    min_area_ratio : float
        ``D_T`` triangle-area threshold (see :func:`.topology.in_dt`).

    Returns
    -------
    SliceResult
        Images ``(ny, nx)`` of ``D_free``, ``D_T``, each D-obstacle and the energy (J),
        with the pixel coordinates (m).

    Raises
    ------
    FingerError
        ``fingers`` is not a sequence of fingers.
    DeformClosureError
        Bad node id, extent, resolution, energy kind or ``tol``.

    Examples
    --------
    The node at the middle of the base of a triangular part, a point finger 1 mm below
    it; at its base position (the centre pixel) the node is free and the energy is zero:

    >>> from deformclosure import Part, mesh_part
    >>> from deformclosure.dspace import PointFinger, dfree_slice
    >>> tri = Part.from_dict(dict(units="m", outer=[[0, 0], [0.04, 0], [0.02, 0.03]],
    ...                           material=dict(youngs_modulus=5e6, poisson_ratio=0.3, elastic_limit_strain=0.4),
    ...                           mesh=dict(max_area=4e-5, points=[[0.02, 0]])))
    >>> mesh = mesh_part(tri)
    >>> v = mesh.find_node([0.02, 0.0])
    >>> res = dfree_slice(mesh, None, v, [PointFinger((0.02, -0.001))], resolution=21)
    >>> res.free.shape, bool(res.free[10, 10]), float(res.energy[10, 10])
    ((21, 21), True, 0.0)
    """
    fingers = list(as_fingers(fingers))
    x, v, ext, (nx, ny) = _slice_inputs(mesh, q, node, energy, extent, resolution)
    xs = np.linspace(ext[0], ext[1], nx)
    ys = np.linspace(ext[2], ext[3], ny)
    tol = resolve_tolerance(mesh, tol)
    topo = _SliceTopology(mesh, x, v, ext, min_area_ratio)
    obst = _SliceObstacles(x, v, topo.edges, topo.moving, fingers, tol)
    ener = _SliceEnergy(mesh, x, v, topo.inc, energy, stiffness)
    free, in_dt, obstacles, U = _sweep(xs, ys, topo, obst, ener, len(fingers))
    shape = (ny, nx)
    return SliceResult(
        node=v, xs=xs, ys=ys, free=free.reshape(shape), in_dt=in_dt.reshape(shape),
        obstacles=obstacles.reshape((len(fingers),) + shape), energy=U.reshape(shape),
        energy_kind=energy, q=x,
    )


def _slice_inputs(mesh: Any, q: Any, node: Any, energy: Any, extent: Any,
                  resolution: Any) -> tuple[np.ndarray, int, np.ndarray, tuple[int, int]]:
    """Validated base configuration ``(n, 2)``, node id, extent and resolution."""
    nodes0 = np.asarray(mesh.nodes, dtype=float)
    n = len(nodes0)
    x = nodes0.copy() if q is None else as_configurations(q, n)[0][0].copy()
    if isinstance(node, bool) or not isinstance(node, (int, np.integer)) or not 0 <= int(node) < n:
        raise DeformClosureError(f"node = {node!r}: must be a node id in 0..{n - 1}")
    v = int(node)
    if energy not in ("linear", "corotational"):
        raise DeformClosureError(f"energy = {energy!r}: use 'linear' or 'corotational'")
    if extent is None:
        tri = np.asarray(mesh.triangles, dtype=np.int64)
        nb = np.unique(tri[np.any(tri == v, axis=1)])
        h = float(np.linalg.norm(x[nb] - x[v], axis=1).max())
        extent = (x[v, 0] - 2 * h, x[v, 0] + 2 * h, x[v, 1] - 2 * h, x[v, 1] + 2 * h)
    try:
        ext = np.asarray(extent, dtype=float).ravel()
    except (TypeError, ValueError):
        ext = np.zeros(0)
    if ext.size != 4 or not np.all(np.isfinite(ext)) or ext[1] <= ext[0] or ext[3] <= ext[2]:
        raise DeformClosureError(f"extent = {extent!r}: give (xmin, xmax, ymin, ymax) with xmin < xmax, ymin < ymax")
    nx, ny = _resolution(resolution)
    from ..limits import MAX_SLICE_RESOLUTION

    if nx * ny > MAX_SLICE_RESOLUTION**2:
        raise DeformClosureError(f"resolution = {resolution!r}: {nx} x {ny} pixels, more than "
                                 f"{MAX_SLICE_RESOLUTION} x {MAX_SLICE_RESOLUTION}; lower it")
    return x, v, ext, (nx, ny)


class _SliceTopology:
    """``D_T`` of the slice: what does not depend on the moving node ``v`` once, the rest
    per pixel (:meth:`in_dt`). Fixed boundary edges are tested against each other once
    (candidate pairs from an R-tree of their bounding boxes: no E² table), the moving
    edges per pixel against the non-adjacent fixed edges, pruned by the grid's box."""

    def __init__(self, mesh: Any, x: np.ndarray, v: int, ext: np.ndarray, min_area_ratio: float):
        nodes0 = np.asarray(mesh.nodes, dtype=float)
        self.x, self.v, self.min_area_ratio = x, v, min_area_ratio
        self.tri = tri = np.asarray(mesh.triangles, dtype=np.int64)
        self.inc = inc = np.flatnonzero(np.any(tri == v, axis=1))
        # triangles
        self.rest_area = _signed_areas(nodes0[None], tri)[0]
        areas_fixed = _signed_areas(x[None], tri)[0]
        fixed_tri = np.ones(len(tri), bool)
        fixed_tri[inc] = False
        self.ok_fixed = bool(np.all(areas_fixed[fixed_tri] > min_area_ratio * self.rest_area[fixed_tri]))
        self.kk, self.jj = np.nonzero(tri[inc] == v)
        # boundary rings
        self.edges = edges = loop_edges(mesh.loops)
        self.moving = moving = np.flatnonzero(np.any(edges == v, axis=1))
        adj = _adjacent_triples(edges)
        is_mov = np.zeros(len(edges), bool)
        is_mov[moving] = True
        self.ok_rings = not _fixed_ring_problems(x, edges, np.flatnonzero(~is_mov), adj[~np.any(adj == v, axis=1)])
        self.fold_triples = adj[np.any(adj == v, axis=1)] if len(moving) else adj[:0]
        self.meet_tests = self._meet_tests(is_mov, np.array([ext[0], ext[2]]), np.array([ext[1], ext[3]]))

    def _meet_tests(self, is_mov: np.ndarray, lo_g: np.ndarray, hi_g: np.ndarray) -> list:
        """Per moving edge: its fixed end and the fixed edges its sweep may meet."""
        x, edges, v = self.x, self.edges, self.v
        out = []
        for e in self.moving:
            other = int(edges[e, 0] if edges[e, 1] == v else edges[e, 1])
            cand = np.flatnonzero(~is_mov & ~np.any(np.isin(edges, edges[e]), axis=1))
            lo = np.minimum(lo_g, x[other])
            hi = np.maximum(hi_g, x[other])
            ea, eb = x[edges[cand, 0]], x[edges[cand, 1]]
            box = np.all((np.minimum(ea, eb) <= hi) & (np.maximum(ea, eb) >= lo), axis=1)
            cand = cand[box]
            if len(cand):
                out.append((other, x[edges[cand, 0]][None], x[edges[cand, 1]][None]))
        return out

    def in_dt(self, G: np.ndarray) -> np.ndarray:
        """``D_T`` membership with the moving node at each of the positions ``G (P, 2)``."""
        x, v, inc = self.x, self.v, self.inc
        pts = np.broadcast_to(x[self.tri[inc]], (len(G), len(inc), 3, 2)).copy()
        pts[:, self.kk, self.jj, :] = G[:, None, :]
        d1 = pts[..., 1, :] - pts[..., 0, :]
        d2 = pts[..., 2, :] - pts[..., 0, :]
        ar = 0.5 * (d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0])
        del pts, d1, d2
        ok = np.all(ar > self.min_area_ratio * self.rest_area[inc], axis=1) & self.ok_fixed & self.ok_rings
        for a_, b_, c_ in self.fold_triples:
            pa = G if a_ == v else np.broadcast_to(x[a_], G.shape)
            pb = G if b_ == v else np.broadcast_to(x[b_], G.shape)
            pc = G if c_ == v else np.broadcast_to(x[c_], G.shape)
            ok &= ~_folded(pa, pb, pc)
        for other, ca, cb in self.meet_tests:
            oa = np.broadcast_to(x[other], G.shape)[:, None, :]
            ok &= ~_segments_meet(G[:, None, :], oa, ca, cb).any(axis=1)
        return ok


class _SliceObstacles:
    """D-obstacle membership of the slice: the fixed boundary edges' terms once per
    finger, the (at most two) moving edges' per pixel (:meth:`masks`)."""

    def __init__(self, x: np.ndarray, v: int, edges: np.ndarray, moving: np.ndarray, fingers: list[Finger],
                 tol: float):
        self.x, self.v, self.edges, self.moving, self.fingers, self.tol = x, v, edges, moving, fingers, tol
        if len(moving) == 0:
            a, b = x[edges[:, 0]], x[edges[:, 1]]
            self.static = np.array([bool(_collides(_edge_terms(f, a[None], b[None], tol), tol)[0])
                                    for f in fingers], dtype=bool)
            self.t_fixed: list = []
        else:
            fixed = np.setdiff1d(np.arange(len(edges)), moving)
            fa_, fb_ = x[edges[fixed, 0]][None], x[edges[fixed, 1]][None]
            self.t_fixed = [_edge_terms(f, fa_, fb_, tol) for f in fingers]

    def masks(self, G: np.ndarray) -> np.ndarray:
        """Membership ``(n_fingers, P)`` in each D-obstacle for the positions ``G (P, 2)``."""
        if len(self.moving) == 0:
            return np.broadcast_to(self.static[:, None], (len(self.fingers), len(G)))
        x, v, edges = self.x, self.v, self.edges
        ma = np.empty((len(G), len(self.moving), 2))
        mb = np.empty((len(G), len(self.moving), 2))
        for j, e in enumerate(self.moving):
            ma[:, j] = G if edges[e, 0] == v else x[edges[e, 0]]
            mb[:, j] = G if edges[e, 1] == v else x[edges[e, 1]]
        out = np.zeros((len(self.fingers), len(G)), dtype=bool)
        for i, f in enumerate(self.fingers):
            out[i] = _collides(_edge_terms(f, ma, mb, self.tol).combine(self.t_fixed[i]), self.tol)
        return out


class _SliceEnergy:
    """The slice's energy (J): the linear one as the exact quadratic in the node's move,
    the corotational one as the fixed elements' sum plus the incident elements'."""

    def __init__(self, mesh: Any, x: np.ndarray, v: int, inc: np.ndarray, kind: str, stiffness: Any):
        self.x, self.v, self.inc, self.kind = x, v, inc, kind
        if kind == "linear":
            if stiffness is None:
                from ..elasticity.stiffness import stiffness_matrix

                stiffness = stiffness_matrix(mesh)
            X = (x - np.asarray(mesh.nodes, dtype=float)).ravel()
            self.KX = stiffness @ X
            self.U0 = 0.5 * float(X @ self.KX)
            self.dofs = [2 * v, 2 * v + 1]
            self.Kvv = stiffness[self.dofs][:, self.dofs].toarray()
        else:
            self.model = _ElementModel(mesh)
            e_all = self.model.energies(x[None], "corotational")[0]
            fixed_tri = np.ones(len(e_all), bool)
            fixed_tri[inc] = False
            self.base = float(e_all[fixed_tri].sum())

    def values(self, G: np.ndarray) -> np.ndarray:
        """Energy (J) with the moving node at each of the positions ``G (P, 2)``."""
        if self.kind == "linear":
            d = G - self.x[self.v]
            return self.U0 + d @ self.KX[self.dofs] + 0.5 * np.einsum("pi,ij,pj->p", d, self.Kvv, d)
        # only the incident triangles' node positions matter: build them directly
        return self.base + _incident_energies(self.model, self.x, self.v, self.inc, G).sum(axis=1)


def _sweep(xs: np.ndarray, ys: np.ndarray, topo: _SliceTopology, obst: _SliceObstacles, ener: _SliceEnergy,
           n_fingers: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The images (flat, row-major in y) computed in blocks of rows: the working arrays
    stay small at any resolution."""
    nx, ny = len(xs), len(ys)
    P = nx * ny
    free = np.empty(P, bool)
    in_dt = np.empty(P, bool)
    obstacles = np.zeros((n_fingers, P), dtype=bool)
    U = np.empty(P)
    n_cand = sum(t[1].shape[1] for t in topo.meet_tests)
    per_px = 8 * (12 * len(topo.inc) + 20 * n_cand + 16 * len(topo.moving) + 32)
    rows = max(1, min(ny, int(_SLICE_BLOCK_BYTES // max(per_px * nx, 1))))
    for r0 in range(0, ny, rows):
        G = np.stack(np.meshgrid(xs, ys[r0:r0 + rows]), axis=-1).reshape(-1, 2)   # row-major in y
        sl = slice(r0 * nx, r0 * nx + len(G))
        ok = topo.in_dt(G)
        in_dt[sl] = ok
        obstacles[:, sl] = obst.masks(G)
        free[sl] = ok & ~np.any(obstacles[:, sl], axis=0)
        U[sl] = ener.values(G)
    return free, in_dt, obstacles, U


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
