"""The compiled kernels (``landscape/kernels.py``, ``planning/_kernels.py`` and the planner's
strictness test) against plain Python/numpy references written here, on random inputs.

The kernels are private and the redesign may move them, so each is looked up inside its
test among the modules that may hold it. Sizes are small and examples few: the cost is
the JIT compilation (cached on disk by ``cache=True``).
"""

from __future__ import annotations

import importlib
import math
from collections import deque

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from shared_helpers import adjacency_sets

SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def kernel(name: str, *homes: str):
    """The compiled function ``name`` from the first of ``homes`` that defines it."""
    for home in homes:
        try:
            mod = importlib.import_module(f"deformclosure.{home}")
        except ImportError:
            continue
        if hasattr(mod, name):
            return getattr(mod, name)
    pytest.fail(f"kernel {name} not found in any of {homes}; update tests/test_kernels.py")


GRASP = ("landscape.kernels", "planning._kernels", "planning.plan")
PLAN = ("planning._kernels", "planning.plan", "landscape.kernels")


# --------------------------------------------------------------------------- inputs
@st.composite
def graphs(draw, max_v=14):
    """A random undirected graph as symmetric CSR ``(indptr, indices)`` (int64), and its
    adjacency as Python sets."""
    adj = draw(adjacency_sets(max_v))
    V = len(adj)
    indptr = np.zeros(V + 1, np.int64)
    indptr[1:] = np.cumsum([len(s) for s in adj])
    order = draw(st.permutations(range(V)))          # neighbour order must not matter
    rank = {v: i for i, v in enumerate(order)}
    indices = np.array([w for s in adj for w in sorted(s, key=rank.get)], np.int64)
    return indptr, indices, adj


energies = st.one_of(st.sampled_from([0.0, 1.0, 2.0, 3.0]),        # ties and plateaus
                     st.floats(0.0, 10.0, allow_nan=False))


@st.composite
def graph_and_energies(draw, max_v=14):
    indptr, indices, adj = draw(graphs(max_v))
    U = np.array(draw(st.lists(energies, min_size=len(adj), max_size=len(adj))), float)
    return indptr, indices, adj, U


# --------------------------------------------------------------------------- references
def ref_equilibrium(U, adj, v):
    return all(U[v] <= U[w] for w in adj[v])


def ref_strict(U, adj, v):
    return all(U[v] < U[w] for w in adj[v])


def ref_component(U, adj, s, level):
    seen, todo = {s}, deque([s])
    while todo:
        v = todo.popleft()
        for w in adj[v]:
            if w not in seen and U[w] <= level:
                seen.add(w)
                todo.append(w)
    return seen


def ref_escape_level(U, adj, s):
    """Smallest level ``L`` such that ``s`` reaches another equilibrium through
    vertices of energy ``<= L`` (the minimax path cost, both ends included); inf if none."""
    for L in sorted({float(u) for u in U if u >= U[s]}):
        comp = ref_component(U, adj, s, L)
        if any(e != s and ref_equilibrium(U, adj, e) for e in comp):
            return L
    return math.inf


def ref_release(U, adj, s):
    if not ref_strict(U, adj, s):
        return 0.0
    return ref_escape_level(U, adj, s) - U[s]


def ref_strain_magnitude(exx, eyy, g):
    return np.abs(0.5 * (exx + eyy)) + np.sqrt(0.25 * (exx - eyy) ** 2 + 0.25 * g ** 2)


# --------------------------------------------------------------------------- grasp kernels
@SETTINGS
@given(data=graph_and_energies())
def test_neighbour_min(data):
    indptr, indices, adj, U = data
    got = kernel("neighbour_min", *GRASP)(indptr, indices, U)
    want = [min((U[w] for w in adj[v]), default=math.inf) for v in range(len(adj))]
    np.testing.assert_array_equal(got, want)


@SETTINGS
@given(data=st.data())
def test_path_to(data):
    """A random forest as a predecessor array: the path is the chain of predecessors from
    the root (``-1`` above it) to the target."""
    n = data.draw(st.integers(1, 30))
    order = data.draw(st.permutations(range(n)))
    pred = np.full(n, -1, np.int64)
    for i in range(1, n):
        if data.draw(st.booleans()) or i < 2:
            pred[order[i]] = order[data.draw(st.integers(0, i - 1))]
    target = data.draw(st.integers(0, n - 1))
    want = [target]
    while pred[want[-1]] != -1:
        want.append(int(pred[want[-1]]))
    got = kernel("path_to", *GRASP)(pred, np.int64(target))
    assert got.dtype == np.int64
    assert got.tolist() == want[::-1]


@SETTINGS
@given(data=graph_and_energies(), pick=st.integers(0, 10**6))
def test_bottleneck_escape(data, pick):
    indptr, indices, adj, U = data
    s = pick % len(adj)
    path = kernel("bottleneck_escape", *GRASP)(indptr, indices, U, np.int64(s))
    level = ref_escape_level(U, adj, s)
    if math.isinf(level):
        assert path.size == 0
        return
    p = path.tolist()
    assert p[0] == s and p[-1] != s
    assert ref_equilibrium(U, adj, p[-1])
    assert all(b in adj[a] for a, b in zip(p, p[1:])), "consecutive vertices must be adjacent"
    assert len(set(p)) == len(p)
    assert max(U[p]) == level


@SETTINGS
@given(data=graph_and_energies())
def test_release_sweep(data):
    indptr, indices, adj, U = data
    V = len(adj)
    nmin = np.array([min((U[w] for w in adj[v]), default=math.inf) for v in range(V)])
    got = kernel("release_sweep", *GRASP)(indptr, indices, U, np.argsort(U, kind="stable"),
                                          U <= nmin, U < nmin)
    want = [ref_release(U, adj, v) for v in range(V)]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(data=graph_and_energies())
def test_public_release_energies_agree_with_the_reference(data):
    """The same through the public functions (a contact graph built from its edges)."""
    from deformclosure import ContactGraph, release_energies, release_energy

    indptr, indices, adj, U = data
    V = len(adj)
    edges = [(a, b) for a in range(V) for b in adj[a] if a < b]
    g = ContactGraph.from_edges([(0, v + 1) for v in range(V)],
                                np.array(edges, np.int64).reshape(-1, 2))
    want = [ref_release(U, adj, v) for v in range(V)]
    np.testing.assert_allclose(release_energies(U, g), want, rtol=0, atol=1e-12)
    for v in range(V):
        assert release_energy(U, g, v).value == pytest.approx(want[v], abs=1e-12)


def test_release_on_a_hand_example():
    """Path 0-1-2-3-4 with U = 0, 2, 1, 3, 0.5: vertex 0 escapes over 2 to the
    equilibrium 2 (U_A = 2), vertex 2 over 2 to 0 (U_A = 1), vertex 4 over 3 (U_A = 2.5)."""
    adj = [{1}, {0, 2}, {1, 3}, {2, 4}, {3}]
    indptr = np.array([0, 1, 3, 5, 7, 8], np.int64)
    indices = np.array([1, 0, 2, 1, 3, 2, 4, 3], np.int64)
    U = np.array([0.0, 2.0, 1.0, 3.0, 0.5])
    nmin = kernel("neighbour_min", *GRASP)(indptr, indices, U)
    out = kernel("release_sweep", *GRASP)(indptr, indices, U, np.argsort(U), U <= nmin, U < nmin)
    np.testing.assert_array_equal(out, [2.0, 0.0, 1.0, 0.0, 2.5])
    assert [ref_release(U, adj, v) for v in range(5)] == [2.0, 0.0, 1.0, 0.0, 2.5]
    path = kernel("bottleneck_escape", *GRASP)(indptr, indices, U, np.int64(4))
    assert path.tolist() == [4, 3, 2]


# --------------------------------------------------------------------------- strictness
def _e(x0, k, x):
    d = x0 - x
    return 0.5 * k * d * d if d > 0 else 0.0


@SETTINGS
@given(data=graphs(), seed=st.integers(0, 2**32 - 1), pick=st.integers(0, 10**6),
       x=st.floats(-1.0, 1.0))
def test_strict_at(data, seed, pick, x):
    """Vertex ``s`` is a strict minimum at σ = x when its energy ½k(x0 − x)² (0 once
    x ≥ x0) is below every neighbour's."""
    indptr, indices, adj = data
    rng = np.random.default_rng(seed)
    V = len(adj)
    x0 = rng.choice([-0.5, 0.0, 0.5, 1.0], V) + (rng.random(V) < 0.5) * rng.random(V)
    k = rng.choice([1.0, 2.0], V) * (1 + (rng.random(V) < 0.5) * rng.random(V))
    s = pick % V
    es = _e(x0[s], k[s], x)
    want = all(_e(x0[w], k[w], x) > es for w in adj[s])
    strict_at = kernel("_strict_at", *PLAN)
    assert bool(strict_at(indptr, indices, x0, k, np.int64(s), float(x))) == want


# --------------------------------------------------------------------------- planner strains
@st.composite
def strain_tables(draw):
    P = draw(st.integers(2, 6))
    m = draw(st.integers(1, 12))
    n = draw(st.integers(1, 8))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    T = rng.normal(size=(P, 6, m)) * 10.0 ** rng.integers(-3, 4)
    lo = draw(st.integers(0, n - 1))
    hi = draw(st.integers(lo, n))
    return T, n, lo, hi, rng


@SETTINGS
@given(data=strain_tables())
def test_max_strain_point_jaws(data):
    T, n, lo, hi, rng = data
    P = T.shape[0]
    pa = rng.integers(0, P, n).astype(np.int64)
    pb = rng.integers(0, P, n).astype(np.int64)
    k = rng.random(n) * 100
    ang = rng.random(n) * 2 * np.pi
    ex, ey = np.cos(ang), np.sin(ang)
    out = np.full(n, -7.0)
    kernel("max_strain_point_jaws", *PLAN)(T, pa, pb, k, ex, ey, lo, hi, out)
    for s in range(n):
        if not lo <= s < hi:
            assert out[s] == -7.0            # outside the chunk: untouched
            continue
        eps = k[s] * (ex[s] * (T[pa[s], 0:3] - T[pb[s], 0:3])
                      + ey[s] * (T[pa[s], 3:6] - T[pb[s], 3:6]))
        want = max(0.0, ref_strain_magnitude(*eps).max())
        assert out[s] == pytest.approx(want, rel=1e-9, abs=1e-300)


@SETTINGS
@given(data=strain_tables())
def test_max_strain_magnitude(data):
    T, n, lo, hi, rng = data
    P = T.shape[0]
    counts = rng.integers(0, 4, n)                       # 0 loaded nodes: zero strain
    ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    pos = rng.integers(0, P, ptr[-1]).astype(np.int64)
    weight = rng.normal(size=ptr[-1])
    ang = rng.random(n) * 2 * np.pi
    ex, ey = np.cos(ang), np.sin(ang)
    out = np.full(n, -7.0)
    kernel("max_strain_magnitude", *PLAN)(T, ptr, pos, weight, ex, ey, lo, hi, out)
    for s in range(n):
        if not lo <= s < hi:
            assert out[s] == -7.0
            continue
        eps = np.zeros((3, T.shape[2]))
        for j in range(ptr[s], ptr[s + 1]):
            eps += weight[j] * (ex[s] * T[pos[j], 0:3] + ey[s] * T[pos[j], 3:6])
        want = max(0.0, ref_strain_magnitude(*eps).max())
        assert out[s] == pytest.approx(want, rel=1e-9, abs=1e-300)


def test_point_jaws_is_the_two_node_case_of_any_jaws():
    """``max_strain_point_jaws`` = ``max_strain_magnitude`` with weights +k at a, −k at b."""
    rng = np.random.default_rng(3)
    T = rng.normal(size=(5, 6, 9))
    n = 7
    pa, pb = rng.integers(0, 5, n), rng.integers(0, 5, n)
    k = rng.random(n) + 0.1
    ex, ey = np.cos(np.arange(n)), np.sin(np.arange(n))
    a, b = np.zeros(n), np.zeros(n)
    kernel("max_strain_point_jaws", *PLAN)(T, pa, pb, k, ex, ey, 0, n, a)
    ptr = np.arange(0, 2 * n + 1, 2, dtype=np.int64)
    pos = np.stack([pa, pb], 1).ravel().astype(np.int64)
    weight = np.stack([k, -k], 1).ravel()
    kernel("max_strain_magnitude", *PLAN)(T, ptr, pos, weight, ex, ey, 0, n, b)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * b.max())
