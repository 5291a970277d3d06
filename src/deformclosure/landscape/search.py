"""The one minimax (bottleneck) escape search of every release landscape (SPEC §4, §6, §7).

A release landscape is a graph whose vertices carry an energy: the paper's node pairs
(SPEC §4), grasp axes on a ``(θ, c)`` grid (§6) or placements ``(x, y, φ)`` (§7). The
release energy ``U_A`` is the smallest, over paths from the start to a release or to
another equilibrium, of the largest energy on the path, minus the start's. This module
finds it by Dijkstra's algorithm with ``max(d, w)`` in place of ``d + w`` — the networkx
heap idiom ``heappush(fringe, (d, next(c), v))`` with a counter as tie-breaker — over a
graph given by a neighbours function and a *lazy* energy oracle: a vertex energy (a
contact problem) is computed the first time the search needs it, and only then.

The compiled twin for graphs held whole in CSR form (the paper model) is
:func:`deformclosure.landscape.kernels.minimax_search`, over a compiled vertex oracle
that may bound the energies over a cell of the landscape (the paper planner) instead of
knowing them; with the energies known, :func:`~deformclosure.landscape.kernels.bottleneck_escape`,
it finds the same barrier as this search (``tests/test_landscape_search.py``; cells:
``tests/test_landscape_cells.py``).

With friction (SPEC §9) the cost of a path is the *work* done along it, elastic energy
change plus the dissipation of each move, and :func:`dissipative_escape` is the same
best-first search on labels ``(peak work, dissipation)`` per vertex instead of one level
(``tests/test_release_work.py``).

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §4.4 (the minimax release).
P. Hansen, "Bicriterion path problems", in *Multiple Criteria Decision Making*, LNEMS 177,
1980 (label setting on Pareto labels).
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass, field
from typing import Callable, Hashable, Iterable, TypeVar

from .noise import ROUND_OFF, higher, resolved

__all__ = ["Escape", "minimax_escape", "DissipativeEscape", "dissipative_escape"]

V = TypeVar("V", bound=Hashable)


@dataclass(frozen=True, eq=False)
class Escape:
    """Result of :func:`minimax_escape`.

    Attributes
    ----------
    barrier : float
        Largest energy (J) on the path: ``U_A + U(start)`` when ``target`` is set; ``inf``
        when no target is reachable; when the search stopped early (``complete`` False),
        the level it had reached, a lower bound of the barrier.
    path : list
        Vertices from the start to the target (or to where the search stopped); empty when
        no target is reachable.
    target : str or None
        ``"released"``, ``"equilibrium"``, ``"goal"``, or ``None`` (none reachable, or
        stopped early).
    complete : bool
        False when ``stop_above`` or the evaluation budget ended the search.
    settled : list
        Vertices in the order the search settled them (each at its final level).
    levels : dict
        Minimax level (J) at which the search reached each vertex (final for settled ones).
    energies : dict
        The vertex energies (J) the search evaluated, by vertex.
    plateau : int
        With a ``distance``: the largest distance from the start of a vertex settled within
        the noise floor of the start's energy (the start's noise plateau); else 0.
    """

    barrier: float
    path: list
    target: str | None
    complete: bool
    settled: list = field(default_factory=list)
    levels: dict = field(default_factory=dict, repr=False)
    energies: dict = field(default_factory=dict, repr=False)
    plateau: int = 0

    @property
    def n_evaluations(self) -> int:
        """Number of vertex energies the search asked the oracle for."""
        return len(self.energies)


def minimax_escape(start: V, neighbours: Callable[[V], Iterable[V]],
                   energy: Callable[[V, V | None], float], *,
                   is_release: Callable[[V, float], bool] | None = None, goal: V | None = None,
                   noise: float | None = None, confirm: Callable[[V], bool] | None = None,
                   stop_above: float | None = None, max_evaluations: int | None = None,
                   evaluated: Callable[[], int] | None = None,
                   priority: Callable[[V], float] | None = None,
                   distance: Callable[[V, V], int] | None = None) -> Escape:
    """Minimax (bottleneck) path from ``start`` to the first release, goal or equilibrium.

    A path's cost is the largest vertex energy on it, the start's included. Vertices are
    settled in increasing cost; a settled vertex ``v`` ends the search when it is

    * ``goal`` (when given; then nothing else ends it), else, for ``v ≠ start``,
    * a release: ``is_release(v, U(v))``;
    * another equilibrium: with ``noise=None`` (SPEC §4) when no neighbour is lower,
      ``U(v) ≤ U(w)`` for all neighbours ``w``, and ``confirm(v)`` (when given) agrees;
      with a relative floor ``noise = τ``
      (:mod:`.noise`) when the barrier to it is beyond the floor
      (``resolved(cost − U(start), cost, τ)``), every neighbour is higher beyond it
      (``higher(U(w), U(v), max(τ, ROUND_OFF))``) and ``confirm(v)`` (when given) agrees.

    A vertex with a non-finite energy is inadmissible: no path goes through it (it may
    still be a neighbour in the equilibrium test, where it counts as higher).

    Parameters
    ----------
    start : hashable
        Start vertex.
    neighbours : callable
        ``neighbours(v)``: the vertices adjacent to ``v``.
    energy : callable
        ``energy(v, near)``: the energy (J) of ``v``; ``near`` is the settled neighbour
        whose expansion asked for it (``None`` for the start), e.g. to warm-start a contact
        solver. Called at most once per vertex and only for vertices the search reaches:
        the start and the neighbours of settled vertices.
    is_release : callable, optional
        ``is_release(v, U(v))``: whether ``v`` is released (e.g. nothing presses and the
        part can leave).
    goal : hashable, optional
        End the search here (and only here).
    noise : float, optional
        Relative noise floor ``τ`` of the equilibrium test (above); ``None``: the exact
        test of SPEC §4.
    confirm : callable, optional
        ``confirm(v)``: a last, possibly costly, test of an equilibrium (e.g. against
        neighbours the search does not expand into, a sub-landscape's cut-off ones).
    stop_above : float, optional
        Stop (``complete`` False) once the cost above the start's energy exceeds this (J).
    max_evaluations : int, optional
        Stop (``complete`` False) once more than this many energies have been evaluated.
    evaluated : callable, optional
        ``evaluated()``: the count compared with ``max_evaluations`` (default the search's
        own; a landscape shared by several searches passes its total).
    priority : callable, optional
        ``priority(v)``: breaks ties of cost before the insertion order (smaller first).
    distance : callable, optional
        ``distance(a, b)``: a distance on the graph, for :attr:`Escape.plateau`.

    Returns
    -------
    Escape
        Barrier (J), path, target, and what the search evaluated.

    Examples
    --------
    A path graph 0 – 1 – 2 – 3 with energies 1, 3, 2, 4: from 0 the escape climbs over
    vertex 1 to the equilibrium 2 (no neighbour lower), so ``U_A = 3 − 1``.

    >>> U = [1.0, 3.0, 2.0, 4.0]
    >>> nbrs = lambda v: [w for w in (v - 1, v + 1) if 0 <= w < 4]
    >>> esc = minimax_escape(0, nbrs, lambda v, near: U[v])
    >>> esc.barrier - U[0], esc.path, esc.target, sorted(esc.energies)
    (2.0, [0, 1, 2], 'equilibrium', [0, 1, 2, 3])
    """
    E: dict = {}

    def U(v, near=None) -> float:
        if v not in E:
            E[v] = float(energy(v, near))
        return E[v]

    count_evaluated = evaluated if evaluated is not None else E.__len__
    tau = 0.0 if noise is None else float(noise)
    tol = max(tau, ROUND_OFF)
    Es = U(start)
    level = {start: Es}
    parent: dict = {}
    settled: list = []
    plateau = 0
    counter = itertools.count()
    heap = [(Es, 0.0, next(counter), start)]

    def finish(b: float, v, target: str | None, complete: bool) -> Escape:
        path = [v]
        while path[-1] != start:
            path.append(parent[path[-1]])
        return Escape(b, path[::-1], target, complete, settled, level, E, plateau)

    while heap:
        b, _, _, v = heapq.heappop(heap)
        if b > level.get(v, math.inf):
            continue                                  # a stale entry
        settled.append(v)
        if distance is not None and not resolved(b - Es, b, tau):
            plateau = max(plateau, distance(v, start))
        if stop_above is not None and b - Es > stop_above:
            return finish(b, v, None, False)
        if max_evaluations is not None and count_evaluated() > max_evaluations:
            return finish(b, v, None, False)
        ws = list(neighbours(v))
        Ew = [U(w, v) for w in ws]
        if goal is not None:
            if v == goal:
                return finish(b, v, "goal", True)
        elif v != start:
            Ev = U(v)
            if is_release is not None and is_release(v, Ev):
                return finish(b, v, "released", True)
            if noise is None:
                eq = (not Ew or Ev <= min(Ew)) and (confirm is None or confirm(v))
            else:
                eq = (resolved(b - Es, b, tau) and all(higher(e, Ev, tol) for e in Ew)
                      and (confirm is None or confirm(v)))
            if eq:
                return finish(b, v, "equilibrium", True)
        for w, e in zip(ws, Ew):
            if not math.isfinite(e):
                continue                              # inadmissible: never through it
            nb = max(b, e)                            # the minimax step: max(d, w), not d + w
            if nb < level.get(w, math.inf):
                level[w] = nb
                parent[w] = v
                heapq.heappush(heap, (nb, 0.0 if priority is None else priority(w),
                                      next(counter), w))
    return Escape(math.inf, [], None, True, settled, level, E, plateau)


def cut_level(esc: Escape, full: Callable[[V], Iterable[V]],
              energy: Callable[[V, V], float]) -> float:
    """The lowest level (J) at which a path of the *full* graph can leave the vertices a
    search on a sub-graph settled: ``min over the edges v → w, v settled, w a full-graph
    neighbour the search did not settle, of max(level(v), U(w))``, an infinite ``U(w)``
    counted as ``level(v)`` (unreachable is not infinitely high); ``inf`` when no such
    edge exists.

    A lower bound of the full graph's barrier follows (SPEC §8, a sub-landscape re-solved
    at finite strain): the search settled the set ``S`` in increasing level below its
    final level ``b`` and found no target in it, so a path to a target either stays in
    the sub-graph (it climbs at least ``b``) or leaves ``S`` by a cut edge ``v → w`` (it
    climbs at least ``U(w)``, and at least ``level(v)`` to reach ``v``); the barrier is
    at least ``min(b, cut_level) − U(start)``.

    Parameters
    ----------
    esc : Escape
        The sub-graph search (its ``settled`` vertices and their ``levels``).
    full : callable
        ``full(v)``: the full graph's neighbours of ``v``.
    energy : callable
        ``energy(w, v)``: the energy (J) of ``w``, solved from ``v``'s state.
    """
    S = set(esc.settled)
    out = math.inf
    for v in esc.settled:
        lv = esc.levels[v]
        if lv >= out:
            continue                        # no edge from v can lower the bound
        for w in full(v):
            if w not in S:
                Uw = energy(w, v)
                out = min(out, max(lv, Uw) if math.isfinite(Uw) else lv)
    return out


@dataclass(frozen=True, eq=False)
class DissipativeEscape:
    """Result of :func:`dissipative_escape`.

    Attributes
    ----------
    work : float
        Release work ``U_A^μ`` (J): the least, over paths from the start to a release, of
        the largest work on the path; ``inf`` when no release is reachable; when the search
        stopped early (``complete`` False), the peak work it had reached, a lower bound.
    path : list
        Vertices from the start to the release (empty when none is reachable, or stopped).
    dissipation : float
        Total dissipation (J) of the moves along ``path`` (``nan`` when ``path`` is empty).
        Among the paths of least peak work, the one of least dissipation is returned.
    works : list of float
        Work ``W_i`` (J) at each vertex of ``path``: ``U(v_i) − U(start)`` plus the
        dissipation of the moves up to ``v_i``; ``work = max(works)``.
    complete : bool
        False when ``stop_above`` or the evaluation budget ended the search.
    energies : dict
        The vertex energies (J) the search evaluated, by vertex.
    n_labels : int
        Number of labels the search created (its work, beside the energies).
    """

    work: float
    path: list
    dissipation: float
    works: list = field(default_factory=list)
    complete: bool = True
    energies: dict = field(default_factory=dict, repr=False)
    n_labels: int = 0

    @property
    def released(self) -> bool:
        """Whether a release was reached."""
        return bool(self.path)

    @property
    def n_evaluations(self) -> int:
        """Number of vertex energies the search asked the oracle for."""
        return len(self.energies)


def dissipative_escape(start: V, neighbours: Callable[[V], Iterable[V]],
                       energy: Callable[[V, V | None], float],
                       dissipation: Callable[[V, V], float],
                       is_release: Callable[[V, float], bool], *,
                       stop_above: float | None = None,
                       max_evaluations: int | None = None) -> DissipativeEscape:
    """Least peak work from ``start`` to a release, moves dissipating (SPEC §9).

    Along a path ``start = v_0, …, v_k`` the work done at ``v_i`` is

    ``W_i = U(v_i) − U(v_0) + Σ_{j<i} D(v_j, v_{j+1})``

    (elastic energy change plus the dissipation of the moves so far), and the release work
    ``U_A^μ`` is the least, over paths ending at a release, of ``max_i W_i``. With
    ``D ≡ 0`` it is the minimax barrier of :func:`minimax_escape` above ``U(start)``.

    The peak alone is no label: two partial paths to one vertex with peaks ``P₁ < P₂``
    and dissipations ``δ₁ > δ₂`` are both needed, since the second may stay lower later.
    So every vertex keeps a Pareto front of labels ``(P, δ)`` (a label dominated in both
    by another of the vertex is dropped) and labels are settled best first by ``(P, δ)``;
    an extension ``v → w`` gives ``(max(P, U(w) − U(start) + δ + D(v, w)), δ + D(v, w))``,
    never smaller in either, so a label settled is final and the first release settled
    ends the search with the least peak (and, among those, the least dissipation). The
    walk found is a simple path: for ``D ≥ 0`` cutting a cycle out of a walk lowers no
    work after it, so simple paths attain the minimum.

    Parameters
    ----------
    start : hashable
        Start vertex (it is released itself when ``is_release`` says so: work 0).
    neighbours : callable
        ``neighbours(v)``: the vertices adjacent to ``v``.
    energy : callable
        ``energy(v, near)``: the energy (J) of ``v``, lazily as in :func:`minimax_escape`
        (at most once per vertex; ``near`` the vertex whose expansion asked, ``None`` for the
        start). A vertex with a non-finite energy is inadmissible.
    dissipation : callable
        ``dissipation(v, w)``: the energy dissipated (J, ``≥ 0``) by the move from ``v`` to
        its neighbour ``w``; ``inf`` forbids the move. Asked at most once per move, and only
        for moves out of vertices the search expands.
    is_release : callable
        ``is_release(v, U(v))``: whether ``v`` is released (the part has left the grasp).
    stop_above : float, optional
        Stop (``complete`` False) once the peak work exceeds this (J).
    max_evaluations : int, optional
        Stop (``complete`` False) once more than this many energies have been evaluated.

    Returns
    -------
    DissipativeEscape
        Release work (J), path, its dissipation (J) and the works along it.

    Raises
    ------
    ValueError
        The start's energy is not finite, or a dissipation is negative or NaN.

    Examples
    --------
    A path graph 0 – 1 – 2 – 3 with energies 1, 3, 2, 0 released at 3: without
    dissipation the work peaks at vertex 1 (``3 − 1``); with 0.5 J per move the works are
    0, 2.5, 2, 0.5, so the peak is still 2.5 at vertex 1 and 1.5 J are dissipated.

    >>> U = [1.0, 3.0, 2.0, 0.0]
    >>> nbrs = lambda v: [w for w in (v - 1, v + 1) if 0 <= w < 4]
    >>> esc = dissipative_escape(0, nbrs, lambda v, near: U[v], lambda v, w: 0.5,
    ...                          lambda v, e: v == 3)
    >>> esc.work, esc.path, esc.dissipation, esc.works
    (2.5, [0, 1, 2, 3], 1.5, [0.0, 2.5, 2.0, 0.5])
    """
    E: dict = {}

    def U(v, near=None) -> float:
        if v not in E:
            E[v] = float(energy(v, near))
        return E[v]

    Dmove: dict = {}

    def D(v, w) -> float:
        key = (v, w)
        d = Dmove.get(key)
        if d is None:
            d = Dmove[key] = float(dissipation(v, w))
            if not d >= 0.0:
                raise ValueError(f"dissipation({v!r}, {w!r}) = {d!r}: a move dissipates "
                                 "a non-negative energy (J)")
        return d

    Es = U(start)
    if not math.isfinite(Es):
        raise ValueError(f"energy({start!r}) = {Es!r}: the start needs a finite energy (J)")
    # A label: (peak P, dissipation δ, vertex, parent label id). Labels live in `labels`
    # by id; `front[v]` holds the ids of v's labels not dominated so far (dead ones are
    # skipped when popped).
    labels: list = [(0.0, 0.0, start, -1)]
    front: dict = {start: [0]}
    dead: set = set()
    heap = [(0.0, 0.0, 0)]                        # (P, δ, id): ties by insertion order

    def finish(k: int | None, peak: float, complete: bool) -> DissipativeEscape:
        if k is None:
            return DissipativeEscape(peak, [], math.nan, [], complete, E, len(labels))
        chain = []
        while k >= 0:
            chain.append(k)
            k = labels[k][3]
        chain.reverse()
        path = [labels[i][2] for i in chain]
        # works from the stored dissipations (not the peaks): W_i = U(v_i) − U_s + δ_i
        works = [E[labels[i][2]] - Es + labels[i][1] for i in chain]
        return DissipativeEscape(peak, path, labels[chain[-1]][1], works, True, E,
                                 len(labels))

    while heap:
        P, delta, k = heapq.heappop(heap)
        if k in dead:
            continue
        v = labels[k][2]
        if stop_above is not None and P > stop_above:
            return finish(None, P, False)
        if max_evaluations is not None and len(E) > max_evaluations:
            return finish(None, P, False)
        if is_release(v, U(v)):
            return finish(k, P, True)
        for w in neighbours(v):
            e = U(w, v)
            if not math.isfinite(e):
                continue                          # inadmissible: never through it
            d = D(v, w)
            if not math.isfinite(d):
                continue                          # a forbidden move
            nd = delta + d
            nP = max(P, e - Es + nd)              # the work at w: energy change + dissipation
            fw = front.setdefault(w, [])
            if any(labels[i][0] <= nP and labels[i][1] <= nd for i in fw):
                continue                          # dominated (or equal): dropped
            keep = []
            for i in fw:
                if nP <= labels[i][0] and nd <= labels[i][1]:
                    dead.add(i)                   # the new label dominates it
                else:
                    keep.append(i)
            labels.append((nP, nd, w, k))
            keep.append(len(labels) - 1)
            front[w] = keep
            heapq.heappush(heap, (nP, nd, len(labels) - 1))
    return finish(None, math.inf, True)
