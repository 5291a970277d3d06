"""The compiled release-landscape kernels: the one compiled minimax search and the
union–find sweep, on CSR graphs.

:func:`minimax_search` is the compiled twin of
:func:`deformclosure.landscape.search.minimax_escape` for graphs held whole in CSR form:
the same Dijkstra search with ``max(d, w)`` in place of ``d + w`` and SPEC §4's exact
equilibrium test, over a *vertex oracle* — a :func:`vertex_oracle` class — that gives
each vertex's energy lazily, on the search's demand. An oracle describes a *cell* of the
landscape: the energies of the point where the search runs (:func:`cell_energy`), a lower
bound of each vertex's energy over the cell (:func:`cell_floor`), and whether an
equilibrium at that point stays one over the whole cell (:func:`cell_kept`). Its callers:

* :func:`bottleneck_escape` — a point cell (``floor = energy``, every equilibrium kept)
  of an energy vector ``U`` (:class:`VertexEnergies`): the plain escape search on the
  paper's contact graph (:mod:`deformclosure.grasp.release`, whose wrappers validate the
  inputs, SPEC §4);
* the paper planner's cells ``[x, y]`` of separations (``_Cell`` in
  :mod:`deformclosure.planning.plan`): the vertex energies ``½ k_v (σ0_v − σ)²``
  evaluated at ``x`` only where the search reaches (its work is the explored basin, not
  the graph), their values at ``y`` as the floor, an equilibrium kept when no adjacent
  crossing moves it inside the cell.

:func:`release_sweep` is the release energy of every vertex at once (the paper's
contact graph and the pads' axis grid, :mod:`deformclosure.planning.pads`, §6). The
binary heap (:func:`heap_push`, :func:`heap_pop`) and :func:`path_to` are the search's
parts. Imported where used (numba is loaded on import), so ``import
deformclosure.landscape`` stays light.

All kernels take the symmetric CSR adjacency ``(indptr, indices)`` of a graph and the
vertex energies (J); they do not check their inputs. ``cache=True`` keeps the compiled
code between runs; :func:`minimax_search` is compiled into each caller (``inline``), so
a caller's oracle and the search are cached together with the caller. (Numba checks a
cached function only against its own file: after editing this one, delete the callers'
cache files, ``__pycache__/*.nbi``, ``*.nbc``.)
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import overload

__all__ = ["bottleneck_escape", "minimax_search", "release_sweep", "neighbour_min", "path_to",
           "heap_push", "heap_pop", "vertex_oracle", "cell_energy", "cell_floor", "cell_kept",
           "VertexEnergies", "SearchWorkspace", "search_workspace", "is_equilibrium",
           "is_strict_minimum", "reaches_below"]


# --------------------------------------------------------------------------- vertex oracles
# The oracle protocol: three functions of (oracle, vertex). Compiled code reaches the
# oracle class's methods through numba overloads registered by `vertex_oracle` (resolved
# when the caller is compiled; LLVM inlines them, so an oracle costs no call); run as Python
# (NUMBA_DISABLE_JIT=1) they call the methods directly. The first parameter is named
# `self` because numba requires the overload and its implementation (the method) to
# name their parameters alike.

def cell_energy(self, v: int) -> float:
    """Energy (J) of vertex ``v`` at the point of the cell where the search runs: the
    largest it takes over the cell. ``self`` is a :func:`vertex_oracle` instance."""
    return self.energy(v)


def cell_floor(self, v: int) -> float:
    """A lower bound (J) of the energy of vertex ``v`` over the cell."""
    return self.floor(v)


def cell_kept(self, v: int) -> bool:
    """Whether ``v``, an equilibrium at the search's point, is one at every point of the
    cell."""
    return self.kept(v)


def vertex_oracle(cls: type) -> type:
    """Class decorator: make a ``NamedTuple`` class a vertex oracle of :func:`minimax_search`.

    The class holds the arrays it needs as fields and defines three methods, written in
    the numba-compilable subset of Python: ``energy(self, v)``, ``floor(self, v)`` and
    ``kept(self, v)`` (:func:`cell_energy`, :func:`cell_floor`, :func:`cell_kept`).
    Instances are built in compiled code or passed from Python.

    Raises
    ------
    TypeError
        ``cls`` is not a ``NamedTuple`` class with the three methods.
    """
    if not (isinstance(cls, type) and issubclass(cls, tuple) and hasattr(cls, "_fields")):
        raise TypeError(f"{cls!r}: a vertex oracle is a NamedTuple class")
    for proto, name in ((cell_energy, "energy"), (cell_floor, "floor"), (cell_kept, "kept")):
        method = getattr(cls, name, None)
        if not callable(method):
            raise TypeError(f"{cls.__name__}: a vertex oracle needs a method {name}(self, v)")
        _register(proto, cls, method)
    return cls


def _register(proto, cls: type, method) -> None:
    """``proto(oracle, v)`` compiles to ``method(oracle, v)`` for instances of ``cls``."""
    def typer(self, v):
        if isinstance(self, types.BaseNamedTuple) and self.instance_class is cls:
            return method
        return None

    overload(proto)(typer)


@vertex_oracle
class VertexEnergies(NamedTuple):
    """A point cell: every vertex energy known, ``U`` (J, shape (V,))."""

    U: np.ndarray

    def energy(self, v):
        return self.U[v]

    def floor(self, v):
        return self.U[v]

    def kept(self, v):
        return True


class SearchWorkspace(NamedTuple):
    """Buffers of :func:`minimax_search`, reusable by many searches on one graph: the
    vertex stamps ``seen``/``done`` (int64, the number of the search that last wrote
    them), minimax levels ``best`` (J), predecessors ``pred``, the heap ``(hk, hv)`` (one
    slot per arc and one), and for the descent tests the stamps ``bseen`` (the number of
    the test that last visited a vertex, from the counter ``ticket[0]``) and ``stack``."""

    seen: np.ndarray
    done: np.ndarray
    best: np.ndarray
    pred: np.ndarray
    hk: np.ndarray
    hv: np.ndarray
    bseen: np.ndarray
    stack: np.ndarray
    ticket: np.ndarray


@njit(cache=True, nogil=True)
def search_workspace(n_vertices, n_arcs):  # pragma: no cover - compiled
    """A :class:`SearchWorkspace` for a graph of ``n_vertices`` and ``n_arcs`` directed arcs
    (``len(indices)``); its stamps are -1, so searches are numbered from 0."""
    return SearchWorkspace(np.full(n_vertices, -1, np.int64), np.full(n_vertices, -1, np.int64),
                           np.empty(n_vertices), np.empty(n_vertices, np.int64),
                           np.empty(n_arcs + 1), np.empty(n_arcs + 1, np.int64),
                           np.full(n_vertices, -1, np.int64), np.empty(n_vertices, np.int64),
                           np.zeros(1, np.int64))


@njit(nogil=True, inline="always")
def is_equilibrium(indptr, indices, cell, v):  # pragma: no cover - compiled
    """No neighbour of ``v`` is lower (``U_v ≤ U_w`` for all neighbours, SPEC §4)."""
    uv = cell_energy(cell, v)
    for q in range(indptr[v], indptr[v + 1]):
        if cell_energy(cell, indices[q]) < uv:
            return False
    return True


@njit(nogil=True, inline="always")
def is_strict_minimum(indptr, indices, cell, v):  # pragma: no cover - compiled
    """``v`` is below all its neighbours (``U_v < U_w``: ``U_A > 0`` is possible, SPEC §4)."""
    uv = cell_energy(cell, v)
    for q in range(indptr[v], indptr[v + 1]):
        if cell_energy(cell, indices[q]) <= uv:
            return False
    return True


@njit(nogil=True, inline="always")
def reaches_below(indptr, indices, cell, e, level, s, seen, stack,
                  stamp):  # pragma: no cover - compiled
    """Whether ``s`` lies in the component of ``e`` in ``{v : floor(v) ≤ level}`` (depth
    first from ``e``; ``seen`` marks visited vertices with ``stamp``, ``stack`` holds at
    most one entry per vertex)."""
    top = 1
    stack[0] = e
    seen[e] = stamp
    while top > 0:
        top -= 1
        v = stack[top]
        for q in range(indptr[v], indptr[v + 1]):
            w = indices[q]
            if seen[w] != stamp and cell_floor(cell, w) <= level:
                if w == s:
                    return True
                seen[w] = stamp
                stack[top] = w
                top += 1
    return False


# --------------------------------------------------------------------------- the search
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


@njit(nogil=True, inline="always")
def minimax_search(indptr, indices, cell, start, ws, epoch):  # pragma: no cover - compiled
    """Minimax escape from ``start`` to the first equilibrium that stays within reach over
    a cell: ``(first, level, target)``.

    Dijkstra's search where a path's cost is the largest vertex energy on it, the
    start's included (``max(d, w)`` replaces ``d + w``; energies from ``cell``, a
    :func:`vertex_oracle`, asked only for the start and the neighbours of settled
    vertices). A settled vertex ``e ≠ start`` with no lower neighbour is an
    *equilibrium* (SPEC §4); ``first`` is the level of the first one (J). The search
    ends at the first equilibrium ``e`` that keeps an equilibrium other than ``start``
    within reach at every point of the cell:

    * ``cell_kept(cell, e)``: ``e`` stays an equilibrium over the cell, or
    * ``start`` is not in the component of ``e`` in ``{v : floor(v) ≤ U_e (1 + 1e-12)}``:
      as ``U_e`` is its largest value over the cell, descending from ``e`` at any point of
      the cell stays in that component, so it ends at an equilibrium that is not
      ``start`` (the factor absorbs rounding of the energies).

    ``level`` (J) is the minimax level of that ``e``, ``target`` its index; on a point
    cell (``floor = energy``, every equilibrium kept) ``level = first`` is the plain
    escape level of :func:`bottleneck_escape`. ``inf`` and ``-1`` where none is
    reachable. The path is ``path_to(ws.pred, target)``.

    ``ws`` is a :class:`SearchWorkspace`; ``epoch`` a number that no earlier search on
    ``ws`` used (its stamps tell this search's marks from older ones, so the buffers
    are never cleared: the work is the explored basin, not the graph).
    """
    seen, done, best, pred, hk, hv = ws.seen, ws.done, ws.best, ws.pred, ws.hk, ws.hv
    us = cell_energy(cell, start)
    first = np.inf
    level = np.inf
    target = -1
    best[start] = us
    seen[start] = epoch
    pred[start] = -1
    size = heap_push(hk, hv, 0, us, start)
    while size > 0:
        d = hk[0]
        v = hv[0]
        size = heap_pop(hk, hv, size)
        if done[v] == epoch:
            continue                                   # a stale entry
        done[v] = epoch
        if v != start and is_equilibrium(indptr, indices, cell, v):
            if d < first:
                first = d
            stays = cell_kept(cell, v)
            if not stays:
                ws.ticket[0] += 1                      # each descent test its own marks
                stays = not reaches_below(indptr, indices, cell, v,
                                          cell_energy(cell, v) * (1.0 + 1e-12), start, ws.bseen,
                                          ws.stack, ws.ticket[0])
            if stays:
                target = v
                level = d
                break
        for q in range(indptr[v], indptr[v + 1]):
            w = indices[q]
            if done[w] == epoch:
                continue
            uw = cell_energy(cell, w)
            nd = d if d >= uw else uw                  # the minimax step: max(d, w)
            if seen[w] != epoch or nd < best[w]:
                seen[w] = epoch
                best[w] = nd
                pred[w] = v
                size = heap_push(hk, hv, size, nd, w)
    return first, level, target


@njit(cache=True, nogil=True)
def bottleneck_escape(indptr, indices, U, start):  # pragma: no cover - compiled
    """Minimax path from ``start`` to the nearest other equilibrium vertex.

    :func:`minimax_search` on the point cell of the energies ``U`` (J)
    (:class:`VertexEnergies`): a path's cost is the largest ``U`` over its vertices
    (:func:`~deformclosure.landscape.search.minimax_escape` with ``noise=None``, on a
    graph held whole); it stops at the first settled vertex ``v != start`` with
    ``U[v] <= U[w]`` for all neighbours ``w``.

    Returns
    -------
    path : int64 array
        Vertex indices from ``start`` to the target; empty if no other equilibrium is
        reachable.
    """
    ws = search_workspace(U.shape[0], indices.shape[0])
    _first, _level, target = minimax_search(indptr, indices, VertexEnergies(U), start, ws, 0)
    return path_to(ws.pred, target)



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


# --------------------------------------------------------------------------- every vertex at once
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
