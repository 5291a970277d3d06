"""Equilibrium vertices and release energy on the contact graph (SPEC §4; paper §4.4).

Given the energy ``U`` (J) of every contact-graph vertex at one jaw separation σ:

* a vertex ``v`` is an *equilibrium* when ``U[v] <= U[w]`` for every neighbour ``w``;
* the *release energy* of a start vertex ``s`` is 0 unless ``s`` is a strict local
  minimum (``U[s] < U[w]`` for every neighbour); otherwise it is the smallest, over paths
  from ``s`` to another equilibrium vertex, of the largest ``U`` on the path (both ends
  included), minus ``U[s]`` — a minimax (bottleneck) path problem. With no other
  equilibrium reachable it is ``+inf``.

The paper computes it with a Dijkstra-like search whose printed initialisation
``U(n0,n1) − U(n0,n1)`` is a typo for ``U(a,b) − U(n0,n1)`` (SPEC §4).
:func:`release_energy` is that search (with a heap; ``max`` replaces ``+``);
:func:`release_energies` gives every vertex's value from one union–find sweep.

References
----------
.. [1] K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure Grasps of
   Deformable Parts", Int. J. Robotics Research 24(11), 2005, §4.4.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import GraspError
from ..landscape import kernels
from .contact_graph import ContactGraph

__all__ = [
    "Release",
    "equilibrium_mask",
    "strict_minimum_mask",
    "is_strict_minimum",
    "release_energy",
    "release_energies",
]


def _check_energies(U: Any, graph: ContactGraph) -> np.ndarray:
    U = np.asarray(U, dtype=float)
    V = graph.n_vertices
    if U.ndim != 1 or U.shape[0] != V:
        raise GraspError(f"U must hold one energy (J) per contact-graph vertex: expected "
                         f"shape ({V},), got {U.shape}")
    if not np.all(np.isfinite(U)):
        bad = np.flatnonzero(~np.isfinite(U))
        a, b = graph.pairs[bad[0]]
        raise GraspError(f"U has {bad.size} non-finite value(s) ({U[bad[0]]} at vertex "
                         f"{int(bad[0])} = nodes ({int(a)}, {int(b)})); energies must be "
                         "finite numbers in J")
    return np.ascontiguousarray(U)


def _check_vertex(graph: ContactGraph, v: Any) -> int:
    if isinstance(v, (tuple, list, np.ndarray)) and np.size(v) == 2:
        a, b = np.asarray(v).ravel()
        return graph.vertex_index(int(a), int(b))
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
        raise GraspError(f"start must be a vertex index (int) or a node pair (a, b), "
                         f"got {v!r}")
    v = int(v)
    if not 0 <= v < graph.n_vertices:
        raise GraspError(f"start vertex {v} out of range [0, {graph.n_vertices})")
    return v


def _neighbour_min(U: np.ndarray, graph: ContactGraph) -> np.ndarray:
    """Smallest neighbour energy per vertex, ``inf`` where a vertex has no neighbour."""
    indptr = graph.indptr
    out = np.full(graph.n_vertices, np.inf)
    nz = indptr[1:] > indptr[:-1]
    if np.any(nz):
        # reduceat over the starts of non-empty rows only: each such row then runs up to
        # the next non-empty row's start, i.e. exactly its own entries.
        out[nz] = np.minimum.reduceat(U[graph.indices], indptr[:-1][nz])
    return out


def _below_neighbours(U: Any, graph: ContactGraph, strict: bool) -> np.ndarray:
    """``U[v] < U[w]`` (``strict``) or ``U[v] <= U[w]`` for every neighbour ``w``, per vertex
    (true for isolated vertices: the condition is vacuous)."""
    U = _check_energies(U, graph)
    nmin = _neighbour_min(U, graph)
    return U < nmin if strict else U <= nmin


def equilibrium_mask(U: np.ndarray, graph: ContactGraph) -> np.ndarray:
    """Equilibrium vertices: ``U[v] <= U[w]`` for every neighbour ``w`` (SPEC §4).

    Parameters
    ----------
    U : array_like, shape (V,)
        Energy of every vertex (J).
    graph : ContactGraph

    Returns
    -------
    ndarray of bool, shape (V,)
        Isolated vertices are equilibria (the condition is vacuous).

    Raises
    ------
    GraspError
        If ``U`` has the wrong length or non-finite values.
    """
    return _below_neighbours(U, graph, strict=False)


def strict_minimum_mask(U: np.ndarray, graph: ContactGraph) -> np.ndarray:
    """Strict local minima: ``U[v] < U[w]`` for every neighbour ``w``; arguments, result
    and errors as :func:`equilibrium_mask`."""
    return _below_neighbours(U, graph, strict=True)


def _is_strict_at(U: np.ndarray, graph: ContactGraph, v: int) -> bool:
    """Whether vertex ``v`` is below all its neighbours (checked ``U``, index ``v``)."""
    nb = graph.indices[graph.indptr[v]:graph.indptr[v + 1]]
    return bool(np.all(U[v] < U[nb]))


def is_strict_minimum(U: np.ndarray, graph: ContactGraph, v: int) -> bool:
    """Whether vertex ``v`` is a strict local minimum of ``U`` on the graph.

    Parameters
    ----------
    U : array_like, shape (V,)
        Energy of every vertex (J).
    graph : ContactGraph
    v : int or (int, int)
        Vertex index, or a node pair ``(a, b)``.

    Returns
    -------
    bool
        ``U[v] < U[w]`` for every neighbour ``w`` (true for an isolated vertex).
    """
    U = _check_energies(U, graph)
    return _is_strict_at(U, graph, _check_vertex(graph, v))


@dataclass(frozen=True, eq=False)
class Release:
    """Release energy of one start vertex, with its escape path (SPEC §4).

    Attributes
    ----------
    value : float
        Release energy ``U_A`` (J): ``0.0`` when the start is not a strict minimum,
        ``inf`` when no other equilibrium vertex is reachable.
    saddle : int or None
        Bottleneck vertex: the first vertex of largest ``U`` on the escape path.
    target : int or None
        The equilibrium vertex the escape path ends at.
    path : ndarray of int64 or None
        Vertex indices from the start to ``target``.
    strict_minimum : bool
        Whether the start is a strict local minimum (deform closure on the graph).
    start : int
        The start vertex.
    """

    value: float
    saddle: int | None
    target: int | None
    path: np.ndarray | None
    strict_minimum: bool
    start: int = -1

    @property
    def infinite(self) -> bool:
        """True when no other equilibrium is reachable (``value == inf``)."""
        return bool(np.isinf(self.value))

    def to_dict(self, graph: ContactGraph | None = None) -> dict[str, Any]:
        """JSON-ready summary; an infinite value is ``None`` with ``"infinite": true``.

        Parameters
        ----------
        graph : ContactGraph, optional
            When given, vertices are also reported as node pairs (``*_nodes`` keys).
        """
        d: dict[str, Any] = {
            "start": self.start,
            "value": None if self.infinite else float(self.value),
            "infinite": self.infinite,
            "strict_minimum": self.strict_minimum,
            "saddle": self.saddle,
            "target": self.target,
            "path": None if self.path is None else [int(x) for x in self.path],
        }
        if graph is not None:
            def nodes(v: int | None) -> list[int] | None:
                return None if v is None else [int(x) for x in graph.pairs[v]]
            d["start_nodes"] = nodes(self.start)
            d["saddle_nodes"] = nodes(self.saddle)
            d["target_nodes"] = nodes(self.target)
        return d


def release_energy(U: np.ndarray, graph: ContactGraph, start: int) -> Release:
    """Release energy ``U_A`` of one start vertex (SPEC §4; paper §4.4).

    Parameters
    ----------
    U : array_like, shape (V,)
        Energy of every vertex at one jaw separation (J).
    graph : ContactGraph
    start : int or (int, int)
        Start vertex index ``s``, or its node pair ``(n0, n1)``.

    Returns
    -------
    Release
        ``value = min over paths s → e of max(U on path) − U[s]`` for equilibria
        ``e ≠ s``; ``0.0`` (and no path) if ``s`` is not a strict minimum; ``inf`` (and
        no path) if no other equilibrium is reachable. Ties count: a neighbour with
        the same energy makes ``s`` non-strict, and an equal-energy plateau vertex
        whose neighbours are all no lower is an equilibrium.

    Raises
    ------
    GraspError
        If ``U`` has the wrong length or non-finite values, or ``start`` is not a
        vertex.

    Notes
    -----
    A Dijkstra search with ``max`` in place of ``+`` (a binary heap, numba), stopped at
    the first settled equilibrium; equilibria are tested only on settled vertices, so
    the work grows with the explored basin, not the graph. Measured after JIT: ≈ 0.1 ms
    for typical starts on a 30 000-vertex contact graph; ≈ 11 ms (realistic graph,
    ``E = 134 000``) to 18 ms (random graph, ``E = 220 000``) when the whole graph must
    be explored.

    Examples
    --------
    >>> import numpy as np
    >>> from deformclosure.grasp.contact_graph import ContactGraph
    >>> g = ContactGraph.from_edges([[0, 1], [0, 2], [1, 2]], [[0, 1], [1, 2]])
    >>> r = release_energy(np.array([0.0, 2.0, 1.0]), g, 0)
    >>> r.value, r.saddle, r.target, r.path.tolist()
    (2.0, 1, 2, [0, 1, 2])
    >>> release_energy(np.array([1.0, 1.0, 0.0]), g, 0).value  # not strict
    0.0
    """
    U = _check_energies(U, graph)
    s = _check_vertex(graph, start)
    if not _is_strict_at(U, graph, s):
        return Release(0.0, None, None, None, False, s)
    path = kernels.bottleneck_escape(graph.indptr, graph.indices, U, np.int64(s))
    if path.size == 0:
        return Release(float(np.inf), None, None, None, True, s)
    up = U[path]
    k = int(np.argmax(up))
    path.setflags(write=False)
    return Release(float(up[k] - U[s]), int(path[k]), int(path[-1]), path, True, s)


def release_energies(U: np.ndarray, graph: ContactGraph) -> np.ndarray:
    """Release energy of every vertex at once (SPEC §4).

    One sweep over the vertices in increasing ``U`` with union–find: a strict minimum's
    value is the level at which its component first merges with a component holding
    another equilibrium, minus its own energy.

    Parameters
    ----------
    U : array_like, shape (V,)
        Energy of every vertex (J).
    graph : ContactGraph

    Returns
    -------
    ndarray, shape (V,)
        ``U_A`` per vertex (J): 0 for vertices that are not strict minima, ``inf`` for
        strict minima that never meet another equilibrium. Equal to
        ``release_energy(U, graph, v).value`` for every ``v``.

    Raises
    ------
    GraspError
        If ``U`` has the wrong length or non-finite values.

    Examples
    --------
    On the path ``0 – 1 – 2`` with energies ``(0, 2, 1)`` J, vertex 0 escapes over the
    saddle 1 to the equilibrium 2; vertex 2 would climb 1 J to reach 0:

    >>> from deformclosure.grasp.contact_graph import ContactGraph
    >>> g = ContactGraph.from_edges([[0, 1], [0, 2], [1, 2]], [[0, 1], [1, 2]])
    >>> release_energies(np.array([0.0, 2.0, 1.0]), g)
    array([2., 0., 1.])
    """
    U = _check_energies(U, graph)
    nmin = kernels.neighbour_min(graph.indptr, graph.indices, U)
    # Any order of equal energies gives the same result: the components of the sublevel
    # set {U <= L} after all vertices of level L are added do not depend on it, and every
    # merge at level L assigns L − U[p]. So the faster unstable sort is fine.
    order = np.argsort(U)
    return kernels.release_sweep(graph.indptr, graph.indices, U, order, U <= nmin, U < nmin)
