"""The one minimax search (``landscape.search.minimax_escape``), its compiled CSR variant
(``landscape.kernels.bottleneck_escape``) and the noise-floor rule (``landscape.noise``).

The references are written here and share nothing with the search: the bottleneck level
of every vertex comes from growing the sublevel sets ``{v : U_v ≤ L}`` level by level and
flooding them from the start (breadth-first), and the noise floor from a hand-written
linear-interpolation quantile.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from deformclosure.landscape import noise as nz
from deformclosure.landscape.search import minimax_escape
from shared_helpers import adjacency_sets

SETTINGS = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


# --------------------------------------------------------------------------- inputs
@st.composite
def landscapes(draw, max_v=12, infinite=True):
    """A random undirected graph (adjacency lists in a random order), vertex energies with
    ties, plateaus and (optionally) inadmissible vertices, and a start vertex."""
    adj = draw(adjacency_sets(max_v))
    V = len(adj)
    order = draw(st.permutations(range(V)))
    rank = {v: i for i, v in enumerate(order)}
    nbrs = [sorted(s, key=rank.get) for s in adj]
    levels = st.sampled_from([0.0, 1.0, 2.0, 3.0])
    finite = st.floats(0.0, 10.0, allow_nan=False)
    pick = st.one_of(levels, finite, st.just(math.inf)) if infinite else st.one_of(levels, finite)
    U = draw(st.lists(pick, min_size=V, max_size=V))
    s = draw(st.integers(0, V - 1))
    if not math.isfinite(U[s]):
        U[s] = 1.5
    return nbrs, U, s


def bottleneck_levels(nbrs, U, s) -> dict[int, float]:
    """Minimax level of every vertex reachable from ``s``: the least ``L ≥ U_s`` such that
    the vertex and ``s`` are connected in the subgraph induced by ``{v : U_v ≤ L}``."""
    out: dict[int, float] = {}
    for L in sorted({u for u in U if math.isfinite(u) and u >= U[s]}):
        seen, todo = {s}, deque([s])
        while todo:
            v = todo.popleft()
            for w in nbrs[v]:
                if w not in seen and U[w] <= L:
                    seen.add(w)
                    todo.append(w)
        for v in seen:
            out.setdefault(v, L)
    return out


def check_path(nbrs, U, s, esc) -> None:
    """A returned path is a walk on the graph from ``s`` whose largest energy is the
    barrier (a certificate, networkx style)."""
    p = esc.path
    assert p[0] == s
    assert all(b in nbrs[a] for a, b in zip(p[:-1], p[1:]))
    assert max(U[v] for v in p) == esc.barrier


# --------------------------------------------------------------------------- the search
@SETTINGS
@given(landscapes())
def test_exact_search_finds_the_least_bottleneck_to_an_equilibrium(case):
    """``noise=None``: the barrier is the least bottleneck level from the start over every
    other equilibrium (``U_e ≤`` all neighbours, SPEC §4); ``inf`` with an empty path when
    none is reachable."""
    nbrs, U, s = case
    lev = bottleneck_levels(nbrs, U, s)
    eq = [e for e in lev if e != s and all(U[e] <= U[w] for w in nbrs[e])]
    esc = minimax_escape(s, lambda v: nbrs[v], lambda v, near: U[v])
    want = min((lev[e] for e in eq), default=math.inf)
    assert esc.barrier == want
    assert esc.complete
    if eq:
        assert esc.target == "equilibrium" and esc.path[-1] in eq
        check_path(nbrs, U, s, esc)
    else:
        assert esc.target is None and esc.path == []
    for v in esc.settled:                         # every settled level is the bottleneck
        assert esc.levels[v] == lev[v]


@SETTINGS
@given(landscapes(), st.sampled_from([0.0, 0.05, 0.3]))
def test_search_with_a_noise_floor_skips_unresolved_equilibria(case, tau):
    """With a floor τ an equilibrium counts only when its barrier is beyond the floor and
    every neighbour is higher beyond it (``landscape.noise``); the barrier is the least
    bottleneck level over those."""
    nbrs, U, s = case
    lev = bottleneck_levels(nbrs, U, s)
    tol = max(tau, nz.ROUND_OFF)

    def target(e: int) -> bool:
        above = all((not math.isfinite(U[w])) or U[w] - U[e] > tol * U[w] for w in nbrs[e])
        return e != s and lev[e] - U[s] > tau * lev[e] and above

    esc = minimax_escape(s, lambda v: nbrs[v], lambda v, near: U[v], noise=tau)
    assert esc.barrier == min((lev[e] for e in lev if target(e)), default=math.inf)
    if math.isfinite(esc.barrier):
        assert target(esc.path[-1])
        check_path(nbrs, U, s, esc)


@SETTINGS
@given(landscapes(), st.data())
def test_goal_and_release_end_the_search_at_their_bottleneck(case, data):
    nbrs, U, s = case
    lev = bottleneck_levels(nbrs, U, s)
    goal = data.draw(st.integers(0, len(U) - 1))
    esc = minimax_escape(s, lambda v: nbrs[v], lambda v, near: U[v], goal=goal)
    assert esc.barrier == lev.get(goal, math.inf)
    assert esc.target == ("goal" if goal in lev else None)
    released = set(data.draw(st.lists(st.integers(0, len(U) - 1), max_size=3)))
    esc = minimax_escape(s, lambda v: nbrs[v], lambda v, near: U[v],
                         is_release=lambda v, e: v in released, noise=0.0,
                         confirm=lambda v: False)       # no equilibrium counts
    want = min((lev[v] for v in released if v in lev and v != s), default=math.inf)
    assert esc.barrier == want
    if math.isfinite(want):
        assert esc.target == "released" and esc.path[-1] in released


@SETTINGS
@given(landscapes())
def test_energies_are_evaluated_lazily_once_each(case):
    """The oracle is asked once per vertex, only for the start and the neighbours of
    settled vertices, and ``near`` is the settled neighbour that asked."""
    nbrs, U, s = case
    asked: list[tuple[int, int | None]] = []

    def energy(v, near):
        asked.append((v, near))
        return U[v]

    esc = minimax_escape(s, lambda v: nbrs[v], energy)
    vs = [v for v, _ in asked]
    assert len(vs) == len(set(vs)) == esc.n_evaluations
    assert asked[0] == (s, None)
    settled = set(esc.settled)
    assert set(vs) == {s} | {w for v in settled for w in nbrs[v]}
    assert all(near in settled and v in nbrs[near] for v, near in asked[1:])


def test_a_near_equilibrium_leaves_the_far_landscape_unevaluated():
    """On a long chain the search never looks past the first valley."""
    n = 1000
    U = [1.0, 2.0, 0.5] + [5.0 + k for k in range(n - 3)]
    asked = []
    esc = minimax_escape(0, lambda v: [w for w in (v - 1, v + 1) if 0 <= w < n],
                         lambda v, near: asked.append(v) or U[v])
    assert (esc.barrier, esc.path, esc.target) == (2.0, [0, 1, 2], "equilibrium")
    assert sorted(asked) == [0, 1, 2, 3]


def chain(n: int):
    """A chain whose energy rises from the start (vertex 0) to a valley at the far end,
    the only other equilibrium."""
    U = [float(k) for k in range(n)]
    U[-1] = 0.5
    return lambda v: [w for w in (v - 1, v + 1) if 0 <= w < n], U


@pytest.mark.parametrize("budget", [0, 1, 5, 17])
def test_evaluation_budget_stops_the_search_with_a_lower_bound(budget):
    nbrs, U = chain(40)
    full = minimax_escape(0, nbrs, lambda v, near: U[v])
    assert (full.barrier, full.target, full.path) == (38.0, "equilibrium", list(range(40)))
    esc = minimax_escape(0, nbrs, lambda v, near: U[v], max_evaluations=budget)
    assert not esc.complete and esc.target is None
    # the budget is checked before a settled vertex is expanded (two neighbours here)
    assert budget < esc.n_evaluations <= max(budget, 1) + 2
    assert esc.barrier <= full.barrier and esc.path[-1] == esc.settled[-1]
    assert esc.barrier == max(U[v] for v in esc.path)
    roomy = minimax_escape(0, nbrs, lambda v, near: U[v], max_evaluations=1000)
    assert (roomy.barrier, roomy.path, roomy.complete) == (full.barrier, full.path, True)


def test_a_shared_evaluation_count_and_stop_above():
    nbrs, U = chain(40)
    total = {"n": 100}            # a landscape that solved 100 problems in earlier searches

    def energy(v, near):
        total["n"] += 1
        return U[v]

    esc = minimax_escape(0, nbrs, energy, max_evaluations=103, evaluated=lambda: total["n"])
    assert not esc.complete and esc.settled == [0, 1, 2, 3] and esc.n_evaluations == 4
    esc = minimax_escape(0, nbrs, lambda v, near: U[v], stop_above=10.5)
    assert not esc.complete and esc.target is None and esc.barrier == 11.0


def test_priority_breaks_ties_only():
    """On a plateau the priority picks the order; the barrier does not change."""
    nbrs = {0: [1, 2], 1: [0, 3], 2: [0, 4], 3: [1], 4: [2]}
    U = {0: 1.0, 1: 1.0, 2: 1.0, 3: 0.0, 4: 0.0}
    left = minimax_escape(0, nbrs.get, lambda v, near: U[v], priority=lambda v: v)
    right = minimax_escape(0, nbrs.get, lambda v, near: U[v], priority=lambda v: -v)
    assert left.barrier == right.barrier == 1.0
    assert (left.path[-1], right.path[-1]) == (3, 4)


# --------------------------------------------------------------------------- compiled
def csr(nbrs):
    indptr = np.zeros(len(nbrs) + 1, np.int64)
    indptr[1:] = np.cumsum([len(n) for n in nbrs])
    indices = np.array([w for n in nbrs for w in n], np.int64)
    return indptr, indices


@settings(max_examples=80, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(landscapes(max_v=14, infinite=False))
def test_compiled_csr_kernel_agrees_with_the_search(case):
    """``bottleneck_escape`` (numba, CSR, energies known) and ``minimax_escape`` (lazy)
    find the same barrier; each path is a valid certificate."""
    from deformclosure.landscape.kernels import bottleneck_escape

    nbrs, U, s = case
    indptr, indices = csr(nbrs)
    path = bottleneck_escape(indptr, indices, np.array(U, float), np.int64(s)).tolist()
    esc = minimax_escape(s, lambda v: nbrs[v], lambda v, near: U[v])
    got = max((U[v] for v in path), default=math.inf)
    assert got == esc.barrier
    if path:
        assert path[0] == s and all(b in nbrs[a] for a, b in zip(path[:-1], path[1:]))
        e = path[-1]
        assert e != s and all(U[e] <= U[w] for w in nbrs[e])


# --------------------------------------------------------------------------- noise rule
def quantile(x, q):
    """Linear-interpolation quantile (numpy's default), written out."""
    x = sorted(x)
    h = (len(x) - 1) * q
    lo = math.floor(h)
    hi = min(lo + 1, len(x) - 1)
    return x[lo] + (h - lo) * (x[hi] - x[lo])


@given(st.lists(st.tuples(st.floats(0, 1e3), st.floats(0, 1e3)), max_size=30))
def test_twin_floor_is_twice_the_90th_percentile_of_relative_differences(pairs):
    rel = [abs(a - b) / max(a, b) for a, b in pairs if max(a, b) > 0]
    want = 2.0 * quantile(rel, 0.9) if rel else 0.0
    U1 = [a for a, _ in pairs]
    U2 = [b for _, b in pairs]
    assert nz.twin_floor(U1, U2) == pytest.approx(want, rel=1e-12, abs=1e-300)


def test_jitter_floor_of_a_quadratic_is_zero_and_of_a_kink_is_not():
    ts = np.linspace(-0.5, 0.5, 9)
    P = nz.quadratic_residual(ts)
    assert np.abs(P @ (3 + 2 * ts - 5 * ts**2)).max() < 1e-12
    kink = 1.0 + np.abs(ts)
    r = float(np.abs(P @ kink).max())
    assert r > 0.01 and nz.jitter_floor(r, 1.0) == 4.0 * r and nz.jitter_floor(r, 0.0) == 0.0


def test_beyond_the_floor():
    assert nz.resolved(0.011, 1.0, 0.01) and not nz.resolved(0.01, 1.0, 0.01)
    assert nz.higher(math.inf, 5.0, 0.9) and not nz.higher(1.0, 1.0, 0.0)
    assert nz.higher(1.0 + 1e-6, 1.0, 0.0) and not nz.higher(1.0 + 1e-6, 1.0, 1e-5)
    assert nz.combined_floor() == 0.0 and nz.combined_floor(0.1, 0.3, 0.2) == 0.3
