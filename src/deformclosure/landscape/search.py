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

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §4.4 (the minimax release).
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass, field
from typing import Callable, Hashable, Iterable, TypeVar

from .noise import ROUND_OFF, higher, resolved

__all__ = ["Escape", "minimax_escape"]

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
      ``U(v) ≤ U(w)`` for all neighbours ``w``; with a relative floor ``noise = τ``
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
        ``confirm(v)``: a last, possibly costly, test of an equilibrium found with a floor.
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
                eq = not Ew or Ev <= min(Ew)
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
