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
from ..geometry import point_set_diameter
from ..part import Material, check_coordinates
from .topology import boundary_loops, directed_edges, triangle_areas

__all__ = ["Mesh", "triangle_areas", "boundary_loops"]

# --------------------------------------------------------------------------- validation
def _checked_nodes(nodes: np.ndarray) -> np.ndarray:
    """``nodes`` as an ``(n, 2)`` float array of finite, bounded coordinates."""
    nodes = np.asarray(nodes, dtype=float)
    if nodes.ndim != 2 or nodes.shape[1] != 2 or len(nodes) < 3:
        raise MeshError(f"nodes: expected an (n, 2) array with n >= 3, got shape {nodes.shape}")
    return check_coordinates(nodes, "nodes", MeshError)


def _checked_triangles(triangles: np.ndarray, n: int) -> np.ndarray:
    """``triangles`` as ``(m, 3)`` int64 ids of three distinct nodes, every node used."""
    tri = np.asarray(triangles)
    if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
        raise MeshError(f"triangles: expected an (m, 3) array with m >= 1, got shape {tri.shape}")
    if not np.issubdtype(tri.dtype, np.integer):
        if not np.all(np.isfinite(tri)) or not np.all(tri == np.round(tri)):
            raise MeshError("triangles: node ids must be integers")
    tri = tri.astype(np.int64)
    if tri.min() < 0 or tri.max() >= n:
        raise MeshError(f"triangles: node ids must be in 0..{n - 1}")
    repeats = (tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2])
    if np.any(repeats):
        raise MeshError(f"triangles[{int(np.flatnonzero(repeats)[0])}]: repeats a node "
                        "(degenerate triangle)")
    used = np.zeros(n, bool)
    used[tri.ravel()] = True
    if not used.all():
        raise MeshError(f"nodes[{int(np.flatnonzero(~used)[0])}]: node is used by no triangle; "
                        "remove unused nodes")
    return tri


def _counter_clockwise(nodes: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """``tri`` with every triangle counter-clockwise: an all-clockwise mesh is reversed;
    zero-area (below ``1e-12 ×`` the bounding box's larger side squared) or inverted
    triangles are refused."""
    size = float(np.ptp(nodes, axis=0).max())
    area = triangle_areas(nodes, tri)
    tiny = 1e-12 * size**2
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
    return tri


def _check_manifold_and_connected(tri: np.ndarray, n: int) -> None:
    """Each undirected edge in at most two triangles, with opposite directions
    (consistent orientation), and one connected piece."""
    e = directed_edges(tri)
    # edges as sorted integer keys (a 1-D sort; np.unique over rows sorted structured
    # records, 1.6 s of an 80k-node optimize): an undirected key three times in a row is
    # a non-manifold edge, a directed key twice an overlap
    a, b = e[:, 0].astype(np.int64), e[:, 1].astype(np.int64)
    und = np.sort(np.minimum(a, b) * n + np.maximum(a, b))
    if np.any(und[2:] == und[:-2]):
        raise MeshError("triangles: mesh has a non-manifold edge (shared by more than two "
                        "triangles); remesh")
    directed = np.sort(a * n + b)
    if np.any(directed[1:] == directed[:-1]):
        raise MeshError("triangles: mesh has overlapping triangles (an edge used twice in one "
                        "direction); remesh")
    adj = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    ncomp, _ = connected_components(adj, directed=False)
    if ncomp != 1:
        raise MeshError(f"triangles: mesh has {ncomp} separate pieces; a part must be one "
                        "connected piece (mesh each piece as its own part)")


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

    Examples
    --------
    A unit square of two triangles (given clockwise: reoriented):

    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 2, 1], [0, 3, 2]])
    >>> mesh.n_nodes, mesh.n_triangles, mesh.outer_loop.tolist(), mesh.area
    (4, 2, [0, 1, 2, 3], 1.0)
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
        nodes = _checked_nodes(nodes)
        tri = _checked_triangles(triangles, len(nodes))
        tri = _counter_clockwise(nodes, tri)
        _check_manifold_and_connected(tri, len(nodes))
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
        """Largest distance between two boundary nodes (m), from the outer loop by
        :func:`deformclosure.geometry.point_set_diameter` (as for the part)."""
        if "diameter" not in self._cache:
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
