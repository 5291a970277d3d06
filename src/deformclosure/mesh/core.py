"""The triangle mesh of a part: validated, immutable, with its boundary loops (SPEC §1).

Conventions used everywhere in the package:

- ``nodes``: ``(n, 2)`` float64 coordinates in metres;
- ``triangles``: ``(m, 3)`` int64 node ids, counter-clockwise;
- ``loops``: boundary loops as int64 arrays of node ids, each listed once; ``loops[0]``
  is the outer loop (counter-clockwise), ``loops[1:]`` are holes (clockwise). Walking a
  loop in its order, the part's interior is on the left.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import MeshError
from ..part import Material

__all__ = ["Mesh", "triangle_areas", "boundary_loops"]


def triangle_areas(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Signed areas of triangles (m²), positive for counter-clockwise ones.

    Parameters
    ----------
    nodes : ndarray, shape (n, 2)
    triangles : ndarray, shape (m, 3)

    Returns
    -------
    ndarray, shape (m,)
    """
    p = nodes[triangles]
    d1 = p[:, 1] - p[:, 0]
    d2 = p[:, 2] - p[:, 0]
    return 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])


def _directed_edges(triangles: np.ndarray) -> np.ndarray:
    return np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])


def boundary_loops(nodes: np.ndarray, triangles: np.ndarray) -> list[np.ndarray]:
    """Recover ordered boundary loops of a valid counter-clockwise triangle mesh.

    A directed edge ``(i, j)`` of a counter-clockwise triangle whose reverse ``(j, i)``
    belongs to no triangle is a boundary edge with the interior on its left; chaining
    them gives the loops in the orientation of the module docstring.

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
    """
    n = len(nodes)
    e = _directed_edges(triangles)
    key = e[:, 0] * n + e[:, 1]
    rkey = e[:, 1] * n + e[:, 0]
    is_bnd = ~np.isin(key, rkey)
    be = e[is_bnd]
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
    # Cycles of the successor permutation restricted to boundary nodes.
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
    areas = [_ring_area(nodes[lp]) for lp in loops]
    outer = int(np.argmax(areas))
    if areas[outer] <= 0:
        raise MeshError("triangles: mesh has no counter-clockwise outer boundary loop")
    holes = [lp for i, lp in enumerate(loops) if i != outer]
    holes.sort(key=lambda lp: int(lp.min()))
    return [loops[outer]] + holes


def _ring_area(ring: np.ndarray) -> float:
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


@dataclass(frozen=True)
class Mesh:
    """A validated linear-triangle (CST) mesh of a planar part.

    Build it with :meth:`from_arrays` (validates and recovers the boundary loops),
    :func:`deformclosure.mesh_part` or :func:`deformclosure.read_mesh`.

    Attributes
    ----------
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).
    triangles : ndarray, shape (m, 3)
        Counter-clockwise triangles.
    loops : tuple of ndarray
        Boundary loops, outer (CCW) first, then holes (CW).
    material : Material or None
        Material of the part, if known.
    """

    nodes: np.ndarray
    triangles: np.ndarray
    loops: tuple[np.ndarray, ...]
    material: Material | None = None
    name: str = "part"
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    # ------------------------------------------------------------------ creation
    @classmethod
    def from_arrays(cls, nodes: np.ndarray, triangles: np.ndarray,
                    material: Material | None = None, name: str = "part") -> "Mesh":
        """Validate node and triangle arrays and recover the boundary loops.

        A mesh whose triangles are all clockwise is reoriented; mixed orientation
        (inverted triangles), degenerate triangles, unused nodes, non-manifold edges or
        vertices and several connected components are refused.

        Raises
        ------
        MeshError
        """
        nodes = np.asarray(nodes, dtype=float)
        tri = np.asarray(triangles)
        if nodes.ndim != 2 or nodes.shape[1] != 2 or len(nodes) < 3:
            raise MeshError(f"nodes: expected an (n, 2) array with n >= 3, got shape {nodes.shape}")
        if not np.all(np.isfinite(nodes)):
            bad = int(np.argwhere(~np.isfinite(nodes))[0, 0])
            raise MeshError(f"nodes[{bad}]: coordinate is not finite; fix the mesh file")
        if np.any(np.abs(nodes) > 1e12):
            bad = int(np.argwhere(np.abs(nodes) > 1e12)[0, 0])
            raise MeshError(f"nodes[{bad}]: coordinate is larger than 1e12 m in magnitude; "
                            "check the units")
        if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
            raise MeshError(f"triangles: expected an (m, 3) array with m >= 1, got shape {tri.shape}")
        if not np.issubdtype(tri.dtype, np.integer):
            if not np.all(np.isfinite(tri)) or not np.all(tri == np.round(tri)):
                raise MeshError("triangles: node ids must be integers")
        tri = tri.astype(np.int64)
        n = len(nodes)
        if tri.min() < 0 or tri.max() >= n:
            raise MeshError(f"triangles: node ids must be in 0..{n - 1}")
        if np.any((tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2])):
            bad = int(np.flatnonzero((tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2])
                                     | (tri[:, 0] == tri[:, 2]))[0])
            raise MeshError(f"triangles[{bad}]: repeats a node (degenerate triangle)")
        used = np.zeros(n, bool)
        used[tri.ravel()] = True
        if not used.all():
            raise MeshError(f"nodes[{int(np.flatnonzero(~used)[0])}]: node is used by no triangle; "
                            "remove unused nodes")
        diam = float(np.ptp(nodes, axis=0).max())
        area = triangle_areas(nodes, tri)
        tiny = 1e-12 * diam**2
        if np.all(area < -tiny):
            tri = tri[:, [0, 2, 1]]
            area = -area
        if np.any(np.abs(area) <= tiny):
            bad = int(np.flatnonzero(np.abs(area) <= tiny)[0])
            raise MeshError(f"triangles[{bad}]: zero area (degenerate triangle); remesh")
        if np.any(area < 0):
            bad = int(np.flatnonzero(area < 0)[0])
            raise MeshError(f"triangles[{bad}]: inverted (clockwise while others are "
                            "counter-clockwise); fix its node order")
        # Each undirected edge may belong to at most two triangles, with opposite
        # directions (consistent orientation).
        e = _directed_edges(tri)
        und = np.sort(e, axis=1)
        _, counts = np.unique(und, axis=0, return_counts=True)
        if np.any(counts > 2):
            raise MeshError("triangles: mesh has a non-manifold edge (shared by more than two "
                            "triangles); remesh")
        _, dcounts = np.unique(e, axis=0, return_counts=True)
        if np.any(dcounts > 1):
            raise MeshError("triangles: mesh has overlapping triangles (an edge used twice in one "
                            "direction); remesh")
        adj = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
        ncomp, _ = connected_components(adj, directed=False)
        if ncomp != 1:
            raise MeshError(f"triangles: mesh has {ncomp} separate pieces; a part must be one "
                            "connected piece (mesh each piece as its own part)")
        loops = boundary_loops(nodes, tri)
        return cls(nodes, tri, tuple(loops), material, name)

    def with_material(self, material: Material) -> "Mesh":
        """A copy of this mesh with ``material``."""
        return replace(self, material=material, _cache={})

    def translated(self, offset: np.ndarray) -> "Mesh":
        """A copy moved by ``offset`` (m)."""
        return replace(self, nodes=self.nodes + np.asarray(offset, float), _cache={})

    def rotated(self, angle: float, center: np.ndarray | None = None) -> "Mesh":
        """A copy rotated by ``angle`` (rad) about ``center`` (default origin)."""
        c = np.zeros(2) if center is None else np.asarray(center, float)
        R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        return replace(self, nodes=(self.nodes - c) @ R.T + c, _cache={})

    # ------------------------------------------------------------------ properties
    @property
    def n_nodes(self) -> int:
        """Number of nodes ``n``."""
        return len(self.nodes)

    @property
    def n_triangles(self) -> int:
        """Number of triangles ``m``."""
        return len(self.triangles)

    @property
    def outer_loop(self) -> np.ndarray:
        """Outer boundary loop (CCW node ids)."""
        return self.loops[0]

    @property
    def hole_loops(self) -> tuple[np.ndarray, ...]:
        """Hole boundary loops (CW node ids)."""
        return self.loops[1:]

    @property
    def perimeter_nodes(self) -> np.ndarray:
        """All nodes on a boundary loop, outer loop first then holes."""
        return np.concatenate(self.loops)

    @property
    def boundary_edges(self) -> np.ndarray:
        """Directed boundary edges ``(k, 2)``, interior on the left, loop by loop."""
        return np.concatenate([np.column_stack([lp, np.roll(lp, -1)]) for lp in self.loops])

    @property
    def areas(self) -> np.ndarray:
        """Triangle areas (m²), all positive."""
        return triangle_areas(self.nodes, self.triangles)

    @property
    def area(self) -> float:
        """Total area (m²)."""
        return float(self.areas.sum())

    @property
    def centroid(self) -> np.ndarray:
        """Area centroid (m)."""
        a = self.areas
        c = self.nodes[self.triangles].mean(axis=1)
        return (a[:, None] * c).sum(0) / a.sum()

    @property
    def diameter(self) -> float:
        """Largest distance between two boundary nodes (m)."""
        if "diameter" not in self._cache:
            from ..geometry import point_set_diameter

            self._cache["diameter"] = point_set_diameter(self.nodes[self.outer_loop])
        return self._cache["diameter"]

    def min_angles(self) -> np.ndarray:
        """Smallest interior angle of each triangle (degrees)."""
        p = self.nodes[self.triangles]
        a = np.linalg.norm(p[:, 1] - p[:, 2], axis=1)
        b = np.linalg.norm(p[:, 2] - p[:, 0], axis=1)
        c = np.linalg.norm(p[:, 0] - p[:, 1], axis=1)
        cosA = (b**2 + c**2 - a**2) / (2 * b * c)
        cosB = (a**2 + c**2 - b**2) / (2 * a * c)
        cosC = (a**2 + b**2 - c**2) / (2 * a * b)
        ang = np.degrees(np.arccos(np.clip(np.stack([cosA, cosB, cosC], 1), -1, 1)))
        return ang.min(axis=1)

    def find_node(self, xy: np.ndarray, tol: float | None = None) -> int:
        """Id of the node at ``xy`` (m), within ``tol`` (default 1e-6 × diameter).

        Raises
        ------
        MeshError
            If no node lies within ``tol``.
        """
        xy = np.asarray(xy, float)
        d = np.linalg.norm(self.nodes - xy, axis=1)
        i = int(np.argmin(d))
        tol = 1e-6 * self.diameter if tol is None else tol
        if d[i] > tol:
            raise MeshError(f"no mesh node at ({xy[0]:.6g}, {xy[1]:.6g}) m (nearest is node {i}, "
                            f"{d[i]:.3g} m away); insert the point with mesh.points")
        return i

    def loop_of(self) -> np.ndarray:
        """Loop index of every node (-1 for interior nodes), shape (n,)."""
        lab = np.full(self.n_nodes, -1, dtype=np.int64)
        for i, lp in enumerate(self.loops):
            lab[lp] = i
        return lab

    def summary(self) -> str:
        """One-paragraph human description."""
        ang = self.min_angles().min()
        return (f"{self.name}: {self.n_nodes} nodes, {self.n_triangles} triangles, "
                f"{len(self.outer_loop)} outer-perimeter nodes, {len(self.hole_loops)} hole(s), "
                f"area {self.area:.6g} m², min angle {ang:.1f}°")
