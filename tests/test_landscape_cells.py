"""The one compiled minimax search (``landscape.kernels.minimax_search``) over cells of a
landscape — vertex energies known only within bounds — against brute force.

A *cell* gives each vertex an energy interval ``[lo_v, hi_v]`` (``hi`` at the point where
the search runs, the largest over the cell) and says which equilibria stay equilibria
over the whole cell (``kept``). The references below are written from the definitions and
share nothing with the search: the minimax level of a vertex is the least ``L`` for which
it is connected to the start in the subgraph ``{v : hi_v ≤ L}`` (grown level by level,
flooded breadth-first); an equilibrium ``e`` is *stable* on the cell when it is kept or
the start lies outside its component in ``{v : lo_v ≤ hi_e (1 + 1e-12)}``. The search must
return the least minimax level over all equilibria (``first``) and over the stable ones
(``level``), with a path that certifies the latter (networkx style).

The paper planner's cell (``planning.plan._Cell``, energies ``½ k (x0 − x)²``) is checked
against the same search on intervals the test computes from the energies and crossing
lists itself.
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from typing import NamedTuple

import numpy as np
from hypothesis import HealthCheck, given, settings, strategies as st

from deformclosure.landscape import kernels
from shared_helpers import adjacency_sets

SETTINGS = settings(max_examples=200, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@kernels.vertex_oracle
class IntervalCell(NamedTuple):
    """Energies known within ``[lo, hi]`` (J), ``kept`` per vertex: the test's oracle."""

    hi: np.ndarray
    lo: np.ndarray
    kept_: np.ndarray

    def energy(self, v):
        return self.hi[v]

    def floor(self, v):
        return self.lo[v]

    def kept(self, v):
        return self.kept_[v]


# --------------------------------------------------------------------------- inputs
@st.composite
def cells(draw, max_v=12):
    """A random graph (CSR in a random neighbour order, and its adjacency sets), interval
    energies with ties and plateaus (``lo = hi`` on some vertices), random ``kept`` flags."""
    adj = draw(adjacency_sets(max_v))
    V = len(adj)
    order = draw(st.permutations(range(V)))
    rank = {v: i for i, v in enumerate(order)}
    indptr = np.zeros(V + 1, np.int64)
    indptr[1:] = np.cumsum([len(a) for a in adj])
    indices = np.array([w for a in adj for w in sorted(a, key=rank.get)], np.int64)
    level = st.one_of(st.sampled_from([0.0, 1.0, 2.0, 3.0]), st.floats(0.0, 10.0))
    hi = np.array(draw(st.lists(level, min_size=V, max_size=V)), float)
    drop = np.array(draw(st.lists(st.one_of(st.just(0.0), st.sampled_from([1.0, 2.0]),
                                            st.floats(0.0, 10.0)), min_size=V, max_size=V)))
    lo = hi - drop
    kept = np.array(draw(st.lists(st.booleans(), min_size=V, max_size=V)), np.bool_)
    return indptr, indices, adj, hi, lo, kept


# --------------------------------------------------------------------------- references
def flood(adj, seed, admit) -> set[int]:
    """The component of ``seed`` in the subgraph of the vertices ``admit`` accepts (the
    seed always in)."""
    seen, todo = {seed}, deque([seed])
    while todo:
        v = todo.popleft()
        for w in adj[v]:
            if w not in seen and admit(w):
                seen.add(w)
                todo.append(w)
    return seen


def minimax_levels(adj, hi, s) -> dict[int, float]:
    """Least ``L ≥ hi_s`` connecting each vertex to ``s`` within ``{v : hi_v ≤ L}``."""
    out: dict[int, float] = {}
    for L in sorted({float(u) for u in hi if u >= hi[s]}):
        for v in flood(adj, s, lambda w: hi[w] <= L):
            out.setdefault(v, L)
    return out


def equilibrium(adj, hi, e) -> bool:
    return all(hi[e] <= hi[w] for w in adj[e])


def stable(adj, hi, lo, kept, s, e) -> bool:
    return bool(kept[e]) or s not in flood(adj, e, lambda w: lo[w] <= hi[e] * (1.0 + 1e-12))


def reference(adj, hi, lo, kept, s) -> tuple[float, float]:
    """``(first, level)``: least minimax level over the equilibria ``≠ s``, and over the
    stable ones (``inf`` when there are none)."""
    levels = minimax_levels(adj, hi, s)
    eqs = [e for e in levels if e != s and equilibrium(adj, hi, e)]
    first = min((levels[e] for e in eqs), default=math.inf)
    level = min((levels[e] for e in eqs if stable(adj, hi, lo, kept, s, e)), default=math.inf)
    return first, level


def check_certificate(adj, hi, lo, kept, s, level, path) -> None:
    """The path walks the graph from ``s`` to a stable equilibrium and its largest energy
    is the level found."""
    if math.isinf(level):
        assert path == []
        return
    assert path[0] == s and path[-1] != s
    assert all(b in adj[a] for a, b in zip(path[:-1], path[1:]))
    assert max(hi[v] for v in path) == level
    e = path[-1]
    assert equilibrium(adj, hi, e) and stable(adj, hi, lo, kept, s, e)


# --------------------------------------------------------------------------- the search
@SETTINGS
@given(cells())
def test_search_on_interval_energies_matches_brute_force(case):
    """Every start of the graph, one after another on one reused workspace (the epoch
    stamps must keep the searches apart)."""
    indptr, indices, adj, hi, lo, kept = case
    ws = kernels.search_workspace(len(adj), len(indices))
    for s in range(len(adj)):
        first, level, target = kernels.minimax_search(indptr, indices, IntervalCell(hi, lo, kept),
                                                      np.int64(s), ws, np.int64(s))
        want_first, want_level = reference(adj, hi, lo, kept, s)
        assert (first, level) == (want_first, want_level)
        assert (target < 0) == math.isinf(level)
        path = kernels.path_to(ws.pred, np.int64(target)).tolist()
        check_certificate(adj, hi, lo, kept, s, level, path)


@SETTINGS
@given(cells())
def test_a_point_cell_is_the_plain_escape_search(case):
    """``lo = hi`` and every equilibrium kept: ``level = first`` = the least minimax level
    to another equilibrium, which ``bottleneck_escape`` (the point cell of an energy
    vector) finds too."""
    indptr, indices, adj, hi, _lo, _kept = case
    point = IntervalCell(hi, hi.copy(), np.ones(len(adj), np.bool_))
    for s in range(len(adj)):
        ws = kernels.search_workspace(len(adj), len(indices))
        first, level, _t = kernels.minimax_search(indptr, indices, point, np.int64(s), ws, np.int64(0))
        want, _ = reference(adj, hi, hi, np.ones(len(adj), bool), s)
        assert first == level == want
        path = kernels.bottleneck_escape(indptr, indices, hi, np.int64(s)).tolist()
        assert max((hi[v] for v in path), default=math.inf) == want


# --------------------------------------------------------------------------- the planner's cell
def _e(x0, k, x):
    d = x0 - x
    return 0.5 * k * d * d if d > 0 else 0.0


@settings(max_examples=100, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=cells(), seed=st.integers(0, 2**32 - 1), xs=st.tuples(st.floats(-1, 1), st.floats(0, 1)))
def test_the_planners_cell_is_the_search_on_its_interval_energies(data, seed, xs):
    """``plan._k_escape`` on a cell ``[x, y]`` = the search on the intervals
    ``[U_v(y), U_v(x)]`` with ``kept`` = energy 0 at ``x`` or no listed crossing of ``v`` in
    ``[x − tol, y − tol]`` — computed here from the definitions; ``strict`` = ``U_s(x)``
    below every neighbour's."""
    from deformclosure.planning.plan import _k_escape

    indptr, indices, adj, *_ = data
    V = len(adj)
    rng = np.random.default_rng(seed)
    x0 = rng.choice([-0.5, 0.0, 0.5, 1.0], V) + (rng.random(V) < 0.5) * rng.random(V)
    k = rng.choice([1.0, 2.0], V) * (1 + (rng.random(V) < 0.5) * rng.random(V))
    x, y = xs[0], xs[0] + xs[1]
    tol = 1e-3
    lists = [sorted(rng.uniform(-1.5, 2.5, rng.integers(0, 4)).tolist()) for _ in range(V)]
    cr_ptr = np.concatenate([[0], np.cumsum([len(c) for c in lists])]).astype(np.int64)
    cr_x = np.array([c for cs in lists for c in cs], float)
    hi = np.array([_e(x0[v], k[v], x) for v in range(V)])
    lo = np.array([_e(x0[v], k[v], y) for v in range(V)])
    kept = np.array([hi[v] == 0.0 or bisect.bisect_left(lists[v], x - tol)
                     == bisect.bisect_right(lists[v], y - tol) for v in range(V)])
    ws = kernels.search_workspace(V, len(indices))
    for s in range(V):
        strict, first, level, path = _k_escape(indptr, indices, x0, k, np.int64(s), x, y, cr_ptr,
                                               cr_x, x - tol, y - tol, *ws, np.int64(s))
        assert strict == all(hi[s] < hi[w] for w in adj[s])
        assert (first, level) == reference(adj, hi, lo, kept, s)
        check_certificate(adj, hi, lo, kept, s, level, path.tolist())
