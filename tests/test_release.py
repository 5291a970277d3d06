"""Equilibria and release energy on the contact graph (SPEC §4; paper §4.4).

The fast searches are checked against a brute force that knows nothing of heaps or
union–find: raise a threshold through the sorted distinct energies and ask scipy's
``connected_components`` whether the start's component of the induced subgraph holds
another equilibrium. Returned paths are re-verified independently (certificates).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse.csgraph import connected_components

from deformclosure.errors import GraspError
from deformclosure.grasp.contact_graph import ContactGraph, contact_graph
from deformclosure.grasp.release import (
    Release,
    equilibrium_mask,
    is_strict_minimum,
    release_energies,
    release_energy,
    strict_minimum_mask,
)

# --------------------------------------------------------------------------- helpers


def make_graph(V: int, edges: np.ndarray) -> ContactGraph:
    """A contact graph with V synthetic vertices (the release code ignores geometry)."""
    m = 2
    while m * (m - 1) // 2 < V:
        m += 1
    i, j = np.triu_indices(m, 1)
    pairs = np.stack([i, j], axis=1)[:V]
    return ContactGraph.from_edges(pairs, np.asarray(edges, dtype=np.int64).reshape(-1, 2))


def brute_equilibria(U: np.ndarray, V: int, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(equilibrium, strict minimum) masks from an explicit neighbour scan."""
    nbrs: list[set[int]] = [set() for _ in range(V)]
    for u, v in edges:
        if u != v:
            nbrs[u].add(int(v))
            nbrs[v].add(int(u))
    eq = np.array([all(U[v] <= U[w] for w in nbrs[v]) for v in range(V)], dtype=bool)
    strict = np.array([all(U[v] < U[w] for w in nbrs[v]) for v in range(V)], dtype=bool)
    return eq, strict


def brute_release(U: np.ndarray, V: int, edges: np.ndarray) -> np.ndarray:
    """Release energy by increasing threshold + connected components (SPEC §4 def.)."""
    eq, strict = brute_equilibria(U, V, edges)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    out = np.zeros(V)
    for s in range(V):
        if not strict[s]:
            continue
        out[s] = np.inf
        for L in np.unique(U[U >= U[s]]):
            keep = U <= L
            e = edges[keep[edges[:, 0]] & keep[edges[:, 1]]]
            A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(V, V))
            _, lab = connected_components(A, directed=False)
            others = keep & eq & (lab == lab[s])
            others[s] = False
            if others.any():
                out[s] = L - U[s]
                break
    return out


def check_certificate(U: np.ndarray, V: int, edges: np.ndarray, r: Release) -> None:
    """Re-verify a returned escape path without the search code."""
    eq, _ = brute_equilibria(U, V, edges)
    eset = {frozenset((int(u), int(v))) for u, v in edges}
    path = [int(x) for x in r.path]
    assert path[0] == r.start
    assert path[-1] == r.target != r.start
    assert eq[r.target]
    for x, y in zip(path[:-1], path[1:]):
        assert frozenset((x, y)) in eset, f"{x}-{y} is not an edge"
    assert len(set(path)) == len(path)  # simple path
    top = max(U[x] for x in path)
    assert r.value == top - U[r.start]
    assert U[r.saddle] == top and r.saddle in path


def random_case(rng: np.random.Generator) -> tuple[int, np.ndarray, np.ndarray]:
    V = int(rng.integers(1, 36))
    p = rng.uniform(0.03, 0.35)
    i, j = np.triu_indices(V, 1)
    sel = rng.random(i.size) < p
    edges = np.stack([i[sel], j[sel]], axis=1)
    if rng.random() < 0.5 and len(edges):  # repeated edges in the input are merged
        edges = np.concatenate([edges, edges[:, ::-1][: len(edges) // 3]])
    kind = rng.integers(4)
    if kind == 0:  # continuous, no ties
        U = rng.random(V)
    elif kind == 1:  # few levels: many ties and plateaus
        U = rng.integers(0, 3, V).astype(float)
    elif kind == 2:  # zero plateau as for σ past σ0, plus quadratic-looking values
        U = np.where(rng.random(V) < 0.4, 0.0, 0.5 * rng.integers(1, 5, V) ** 2 * 1e-3)
    else:
        U = np.round(rng.random(V), 1)
    return V, edges, U


# --------------------------------------------------------------------------- tests


def test_docstring_example_and_fields() -> None:
    g = make_graph(3, [[0, 1], [1, 2]])
    r = release_energy(np.array([0.0, 2.0, 1.0]), g, 0)
    assert (r.value, r.saddle, r.target, r.strict_minimum, r.start) == (2.0, 1, 2, True, 0)
    assert r.path.tolist() == [0, 1, 2]
    assert not r.infinite
    d = r.to_dict(g)
    assert d["value"] == 2.0 and d["path"] == [0, 1, 2]
    assert d["start_nodes"] == g.pairs[0].tolist()


def test_not_strict_minimum_gives_zero() -> None:
    g = make_graph(3, [[0, 1], [1, 2]])
    r = release_energy(np.array([1.0, 1.0, 0.0]), g, 0)  # tie with neighbour
    assert r.value == 0.0 and not r.strict_minimum
    assert r.path is None and r.saddle is None and r.target is None
    r = release_energy(np.array([1.0, 0.0, 2.0]), g, 0)  # lower neighbour
    assert r.value == 0.0 and not r.strict_minimum


def test_no_other_equilibrium_is_infinite() -> None:
    g = make_graph(4, [[0, 1], [1, 2], [2, 3]])
    U = np.array([0.0, 1.0, 2.0, 3.0])  # 0 is the only equilibrium
    r = release_energy(U, g, 0)
    assert r.strict_minimum and r.infinite and r.path is None
    assert r.to_dict() == {"start": 0, "value": None, "infinite": True,
                           "strict_minimum": True, "saddle": None, "target": None,
                           "path": None}
    assert np.array_equal(release_energies(U, g), [np.inf, 0, 0, 0])


def test_isolated_start_is_vacuous_strict_minimum() -> None:
    g = make_graph(3, [[1, 2]])
    U = np.array([5.0, 0.0, 1.0])
    assert is_strict_minimum(U, g, 0)
    assert release_energy(U, g, 0).infinite  # nothing reachable
    assert equilibrium_mask(U, g).tolist() == [True, True, False]


def test_plateau_target_and_ties_on_path() -> None:
    # 0 (strict min) - 1 (U=2) - 2 (U=2) - 3 (U=1, eq) ; 0 - 4 (U=3) - 5 (U=0, eq)
    g = make_graph(6, [[0, 1], [1, 2], [2, 3], [0, 4], [4, 5]])
    U = np.array([0.5, 2.0, 2.0, 1.0, 3.0, 0.0])
    r = release_energy(U, g, 0)
    assert r.value == 1.5 and r.target == 3 and r.path.tolist() == [0, 1, 2, 3]
    assert r.saddle == 1  # first vertex of largest U along the path
    # plateau: vertex 2 ties with 1 and is below 3, so it is a (non-strict) equilibrium
    g2 = make_graph(4, [[0, 1], [1, 2], [2, 3]])
    U2 = np.array([0.0, 1.0, 1.0, 2.0])
    assert equilibrium_mask(U2, g2).tolist() == [True, False, True, False]
    assert release_energy(U2, g2, 0).value == 1.0
    U3 = np.array([0.0, 1.0, 0.5, 0.5])
    assert equilibrium_mask(U3, g2).tolist() == [True, False, True, True]
    assert strict_minimum_mask(U3, g2).tolist() == [True, False, False, False]
    assert release_energy(U3, g2, 0).value == 1.0
    assert release_energies(U3, g2).tolist() == [1.0, 0.0, 0.0, 0.0]


def test_start_as_node_pair() -> None:
    g = make_graph(3, [[0, 1], [1, 2]])
    a, b = g.pairs[2]
    U = np.array([1.0, 2.0, 0.0])
    assert release_energy(U, g, (int(b), int(a))).start == 2


def test_random_graphs_against_brute_force() -> None:
    rng = np.random.default_rng(20240611)
    n_strict = 0
    for _ in range(300):
        V, edges, U = random_case(rng)
        g = make_graph(V, edges)
        ref = brute_release(U, V, edges)
        eq, strict = brute_equilibria(U, V, edges)
        assert np.array_equal(equilibrium_mask(U, g), eq)
        assert np.array_equal(strict_minimum_mask(U, g), strict)
        allv = release_energies(U, g)
        assert np.array_equal(allv, ref)
        for s in range(V):
            r = release_energy(U, g, s)
            assert r.value == ref[s]
            assert r.strict_minimum == strict[s] == is_strict_minimum(U, g, s)
            if r.strict_minimum and np.isfinite(r.value):
                check_certificate(U, V, edges, r)
                n_strict += 1
    assert n_strict > 200  # the generator does produce many finite escapes


@st.composite
def graphs(draw):  # type: ignore[no-untyped-def]
    V = draw(st.integers(1, 14))
    pairs = [(i, j) for i in range(V) for j in range(i + 1, V)]
    chosen = draw(st.lists(st.sampled_from(pairs), max_size=30) if pairs else st.just([]))
    U = draw(st.lists(st.sampled_from([0.0, 0.0, 1.0, 2.0, 2.5, 7.0]), min_size=V,
                      max_size=V))
    return V, np.array(chosen, dtype=np.int64).reshape(-1, 2), np.array(U)


@settings(max_examples=150, deadline=None)
@given(graphs())
def test_hypothesis_release_matches_brute_force(case) -> None:  # type: ignore[no-untyped-def]
    V, edges, U = case
    g = make_graph(V, edges)
    ref = brute_release(U, V, edges)
    assert np.array_equal(release_energies(U, g), ref)
    for s in range(V):
        r = release_energy(U, g, s)
        assert r.value == ref[s]
        if r.path is not None:
            check_certificate(U, V, edges, r)


def test_on_a_real_contact_graph() -> None:
    """Contracting square grasp energies U = ½k(σ0 − σ)² (k = 1) on the geometric graph."""
    t = np.linspace(0, 1, 5)[:-1]
    sq = np.concatenate([np.c_[t, 0 * t], np.c_[1 + 0 * t, t], np.c_[1 - t, 1 + 0 * t],
                         np.c_[0 * t, 1 - t]]) * 0.02
    g = contact_graph(sq, [np.arange(16)])
    s0 = np.hypot(*(sq[g.pairs[:, 0]] - sq[g.pairs[:, 1]]).T)
    for sigma in (0.005, 0.012, 0.019, 0.025):
        U = np.where(s0 > sigma, 0.5 * (s0 - sigma) ** 2, 0.0)
        ref = brute_release(U, g.n_vertices, g.edges)
        assert np.array_equal(release_energies(U, g), ref)
        for s in np.flatnonzero(strict_minimum_mask(U, g)):
            r = release_energy(U, g, int(s))
            assert r.value == ref[s]
            if r.path is not None:
                check_certificate(U, g.n_vertices, g.edges, r)


@pytest.mark.parametrize("bad, msg", [
    (np.zeros(5), "expected shape"),
    (np.zeros((6, 1)), "expected shape"),
    (np.array([0, 1, np.nan, 0, 0, 0.0]), "non-finite"),
    (np.array([0, 1, np.inf, 0, 0, 0.0]), "non-finite"),
])
def test_bad_energies(bad: np.ndarray, msg: str) -> None:
    g = make_graph(6, [[0, 1]])
    for f in (lambda: release_energy(bad, g, 0), lambda: release_energies(bad, g),
              lambda: equilibrium_mask(bad, g), lambda: is_strict_minimum(bad, g, 0)):
        with pytest.raises(GraspError, match=msg):
            f()


def test_bad_start() -> None:
    g = make_graph(3, [[0, 1]])
    U = np.zeros(3)
    with pytest.raises(GraspError, match="out of range"):
        release_energy(U, g, 3)
    with pytest.raises(GraspError, match="vertex index"):
        release_energy(U, g, 1.5)  # type: ignore[arg-type]
    with pytest.raises(GraspError, match="not a vertex"):
        release_energy(U, g, (0, 7))
