"""Optimal jaw separation σ* (SPEC §4 "Exact algorithm", "ε-approximation"; paper §4.5–4.7).

Checks: analytic cases derived by hand, our exact method against the paper's
all-crossings method on random parts, both against dense sampling of Q by its
definition, the ε guarantee of the approximation, escape-path certificates, the
expanding ↔ contracting mirror symmetry, evaluation counts, and bad input.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure.errors import GraspError
from deformclosure.grasp import pieces as pc
from deformclosure.grasp.contact_graph import ContactGraph, contact_graph
from deformclosure.grasp.release import equilibrium_mask, strict_minimum_mask
from deformclosure.grasp.separation import (optimize_separation_arrays, quality_at,
                                            vertex_energies)

# --------------------------------------------------------------------------- fixtures


def _polygon(rng: np.random.Generator, p: int, kind: str) -> np.ndarray:
    """A counter-clockwise simple polygon with ``p`` perimeter nodes (m, ~5 cm)."""
    if kind == "subdivided":
        # A random convex base polygon with extra nodes along its edges, as a mesher
        # would leave them (collinear perimeter nodes).
        base = _polygon(rng, int(rng.integers(3, 6)), "convex")
        counts = rng.multinomial(p - len(base), np.full(len(base), 1 / len(base)))
        pts = []
        for i, c in enumerate(counts):
            a, b = base[i], base[(i + 1) % len(base)]
            t = np.sort(rng.uniform(0.1, 0.9, c))
            pts += [a] + [a + ti * (b - a) for ti in t]
        return np.asarray(pts)
    while True:
        ang = np.sort(rng.uniform(0.0, 2 * np.pi, p))
        if np.min(np.diff(np.r_[ang, ang[0] + 2 * np.pi])) > 0.3 / p:
            break
    r = np.ones(p) if kind == "convex" else rng.uniform(0.45, 1.0, p)
    ax = rng.uniform(0.6, 1.0) if kind == "convex" else 1.0  # ellipses too
    return 0.05 * np.stack([r * np.cos(ang), ax * r * np.sin(ang)], axis=1)


def random_problem(seed: int, p: int, kind: str, mode: str) -> dict:
    """Random part, ``sigma0`` = pairwise distances, ``k ≈ 1/sigma0`` with noise.

    The start is drawn among vertices that are strict minima somewhere in their range,
    so that the problems are not trivially ``Q ≡ 0``.
    """
    rng = np.random.default_rng(seed)
    while True:
        nodes = _polygon(rng, p, kind)
        g = contact_graph(nodes, [np.arange(p)])
        s0 = np.linalg.norm(nodes[g.pairs[:, 0]] - nodes[g.pairs[:, 1]], axis=1)
        k = 2.0 / s0 * rng.uniform(0.5, 2.0, s0.size)
        for _ in range(30):
            s = int(rng.integers(s0.size))
            f = rng.uniform(0.15, 0.9) if mode == "contracting" else rng.uniform(1.1, 1.8)
            sL = s0[s] * f
            U = vertex_energies(0.5 * (sL + s0[s]), s0, k, mode)
            if strict_minimum_mask(U, g)[s]:
                return dict(sigma0=s0, k=k, graph=g, start=s, sigma_L=sL, mode=mode)


def C_of(pr: dict) -> float:
    """Largest U_L = U_s(σ_L) (J), the energy scale of Q."""
    s = pr["start"]
    return 0.5 * pr["k"][s] * (pr["sigma0"][s] - pr["sigma_L"]) ** 2


def run(pr: dict, **kw):
    return optimize_separation_arrays(pr["sigma0"], pr["k"], pr["graph"], pr["start"],
                                      pr["sigma_L"], mode=pr["mode"], **kw)


def qual(pr: dict, sigma):
    return quality_at(sigma, pr["sigma0"], pr["k"], pr["graph"], pr["start"], pr["sigma_L"],
                      pr["mode"])


def span(pr: dict) -> tuple[float, float]:
    return tuple(sorted((pr["sigma_L"], pr["sigma0"][pr["start"]])))


PROBLEMS = [(seed, p, kind, mode)
            for seed, (p, kind) in enumerate([(8, "convex"), (11, "star"), (14, "subdivided"),
                                              (17, "star"), (20, "convex"), (12, "subdivided"),
                                              (9, "star")])
            for mode in ("contracting", "expanding")]


@pytest.fixture(scope="module")
def problems():
    return {key: random_problem(*key) for key in PROBLEMS}


# --------------------------------------------------------------------------- analytic


def path_graph():
    """Path 0 – 1 – 2 (vertex i is the node pair pairs[i])."""
    return ContactGraph.from_edges([[0, 1], [0, 2], [1, 2]], [[0, 1], [1, 2]])


@pytest.mark.parametrize("method", ["exact", "paper"])
@pytest.mark.parametrize("a,c,kk", [(1.0, 1.2, 1.0), (0.05, 0.08, 300.0), (2.0, 3.5, 0.2)])
def test_path_graph_closed_form_contracting(method, a, c, kk):
    # Start 0 (σ0 = a), saddle 1 (σ0 = c > a, same k), vertex 2 always lowest (an
    # equilibrium).  U_A = U_1 − U_0 = ½k(c − a)(c + a − 2σ) decreases in σ and
    # U_L = ½k(2aσ − σ²) (σ_L = 0) increases, so σ* solves U_A = U_L:
    # σ² − 2cσ + c² − a² = 0  →  σ* = c − a,  Q* = ½k(c − a)(3a − c)  (for c ≤ 2a).
    r = optimize_separation_arrays([a, c, 0.01 * a], [kk, kk, kk], path_graph(), 0, 0.0,
                                   method=method)
    assert r.sigma_star == pytest.approx(c - a, rel=1e-12)
    assert r.quality == pytest.approx(0.5 * kk * (c - a) * (3 * a - c), rel=1e-12)
    assert r.attained and not r.U_A_infinite
    assert r.U_A == pytest.approx(r.U_L, rel=1e-12)
    assert r.saddle == 1 and r.saddle_pair == (0, 2)
    assert r.escape_path.tolist() == [0, 1, 2]
    assert r.jumps == []


def test_path_graph_closed_form_expanding():
    # Mirror of the case above about σ = a: σ0 = (a, c < a), σ_L = 2a; shifting
    # x = 2a − σ gives the contracting case with c' = 2a − c, so σ* = a + c and
    # Q* = ½k(a − c)(a + c).
    a, c, kk = 1.0, 0.8, 2.0
    for method in ("exact", "paper"):
        r = optimize_separation_arrays([a, c, 10.0], [kk, kk, kk], path_graph(), 0, 2 * a,
                                       mode="expanding", method=method)
        assert r.sigma_star == pytest.approx(a + c, rel=1e-12)
        assert r.quality == pytest.approx(0.5 * kk * (a - c) * (a + c), rel=1e-12)


def test_infinite_release_energy():
    # Vertex 1 lies always above the start and has no other neighbour: not an
    # equilibrium, so none is reachable: U_A = ∞, Q = U_L, maximal at σ0 (no squeeze).
    g = ContactGraph.from_edges([[0, 1], [0, 2]], [[0, 1]])
    for method, kw in (("exact", {}), ("paper", {}), ("approx", {"eps": 1e-3})):
        r = optimize_separation_arrays([0.04, 0.05], [100.0, 80.0], g, 0, 0.01, method=method,
                                       **kw)
        C = 0.5 * 100.0 * 0.03 ** 2
        assert r.U_A_infinite and r.U_A is None and r.saddle is None
        assert r.escape_path is None
        assert r.sigma_star == pytest.approx(0.04, rel=1e-12)
        assert r.quality == pytest.approx(C, rel=1e-12)
        d = r.to_dict()
        json.dumps(d, allow_nan=False)
        assert d["U_A"] is None and d["U_A_infinite"] is True
        assert None in d["curve"]["U_A"]


def test_isolated_start_is_infinite():
    g = ContactGraph.from_edges([[0, 1], [0, 2]], np.zeros((0, 2), dtype=np.int64))
    r = optimize_separation_arrays([1.0, 0.5], [1.0, 1.0], g, 0, 0.5)
    assert r.U_A_infinite and r.sigma_star == pytest.approx(1.0)
    assert r.quality == pytest.approx(0.125)


@pytest.mark.parametrize("method", ["exact", "paper", "approx"])
def test_never_strict_minimum_gives_none(method):
    # Neighbour 1 (σ0 smaller, same k) is always below the start: U_A ≡ 0, Q ≡ 0.
    g = ContactGraph.from_edges([[0, 1], [0, 2]], [[0, 1]])
    kw = {"eps": 1e-3} if method == "approx" else {}
    r = optimize_separation_arrays([1.0, 0.9], [1.0, 1.0], g, 0, 0.2, method=method, **kw)
    assert r.sigma_star is None and r.quality == 0.0
    assert r.saddle is None and r.escape_path is None
    d = r.to_dict()
    json.dumps(d, allow_nan=False)
    assert d["sigma_star"] is None and d["quality"] == 0.0


def test_degenerate_range_gives_none():
    r = optimize_separation_arrays([1.0, 2.0], [1.0, 1.0], path2(), 0, 1.0)
    assert r.sigma_star is None and r.quality == 0.0 and r.n_evaluations == 0


def path2():
    return ContactGraph.from_edges([[0, 1], [0, 2]], [[0, 1]])


def jump_problem():
    # Star 0 – {1, 2}, 2 – 3.  Start 0: σ0 = 1, k = 1.  Vertex 1 (σ0 = 0.9, k = 4)
    # crosses the start where 2(0.9 − σ) = 1 − σ, σ = 0.8: above it 1 is lower than the
    # start (U_A = 0), below it higher.  The escape goes over 2 (σ0 = 3) to the
    # equilibrium 3: U_A = U_2 − U_0 = 4 − 2σ.  U_L = σ − σ²/2 (σ_L = 0) < U_A on
    # [0, 0.8), so Q = U_L increases up to the jump: sup Q = U_L(0.8) = 0.48 is
    # approached at σ = 0.8 but not attained (Q(0.8) = 0: the tie is not strict).
    g = ContactGraph.from_edges([[0, 1], [0, 2], [0, 3], [0, 4]], [[0, 1], [0, 2], [2, 3]])
    return [1.0, 0.9, 3.0, 0.5], [1.0, 4.0, 1.0, 1.0], g


@pytest.mark.parametrize("method", ["exact", "paper"])
def test_supremum_at_jump_not_attained(method):
    s0, k, g = jump_problem()
    r = optimize_separation_arrays(s0, k, g, 0, 0.0, method=method)
    assert r.sigma_star == pytest.approx(0.8, rel=1e-14)
    assert r.quality == pytest.approx(0.48, rel=1e-12)
    assert not r.attained
    assert r.U_A == pytest.approx(2.4, rel=1e-12) and r.U_L == pytest.approx(0.48, rel=1e-12)
    assert len(r.jumps) == 1
    x, left, val, right = r.jumps[0]
    assert x == pytest.approx(0.8) and left == pytest.approx(2.4) and val == 0 and right == 0
    # By definition: 0 at the tie, below 0.48 just left of it.
    Q, UA, UL = quality_at(np.array([0.8, 0.8 - 1e-9, 0.8 + 1e-9]), s0, k, g, 0, 0.0)
    assert Q[1] == pytest.approx(0.48, abs=1e-8) and Q[1] < 0.48 and Q[2] == 0.0
    assert r.to_dict()["attained"] is False


@pytest.mark.parametrize("eps", [0.2, 0.05, 0.01, 0.001])
def test_approx_sees_one_sided_limit_at_jump(eps):
    s0, k, g = jump_problem()
    r = optimize_separation_arrays(s0, k, g, 0, 0.0, method="approx", eps=eps)
    assert 0.48 - eps <= r.quality <= 0.48
    assert r.attained and r.sigma_star < 0.8
    assert quality_at(r.sigma_star, s0, k, g, 0, 0.0)[0] == pytest.approx(r.quality, abs=1e-15)
    assert r.lipschitz == pytest.approx(3.6)  # max k·σ0 = 4 × 0.9 (paper §4.7)
    assert r.step == pytest.approx(eps / 3.6)


# --------------------------------------------------------------------------- random parts


def test_exact_equals_paper(problems):
    # ≥ 10 random parts (convex, star-shaped, subdivided), contracting and expanding.
    nontrivial = 0
    for key, pr in problems.items():
        re_, rp = run(pr), run(pr, method="paper")
        assert (re_.sigma_star is None) == (rp.sigma_star is None), key
        assert re_.quality == pytest.approx(rp.quality, rel=1e-9, abs=1e-300), key
        if rp.sigma_star is not None:
            nontrivial += 1
            assert re_.sigma_star == pytest.approx(rp.sigma_star, rel=1e-9), key
            assert re_.attained == rp.attained, key
            assert re_.U_A_infinite == rp.U_A_infinite, key
        # U_A jumps only where both methods say so.
        assert [j[0] for j in re_.jumps] == pytest.approx([j[0] for j in rp.jumps], rel=1e-9)
        assert re_.n_evaluations <= rp.n_evaluations, key
    assert nontrivial >= 10


@pytest.mark.parametrize("key", PROBLEMS[:8])
def test_optimum_beats_dense_sampling(problems, key):
    pr = problems[key]
    r = run(pr)
    lo, hi = span(pr)
    sig = np.linspace(lo, hi, 2000)
    Q, UA, UL = qual(pr, sig)
    C = C_of(pr)
    assert np.all(Q <= r.quality + 1e-12 * C)
    # Q is λ-Lipschitz between jumps; the optimum cannot exceed the samples by more
    # than λ·h unless it sits at a jump (one-sided limit) — then it is one of them.
    lam = float(np.max(pr["k"] * np.maximum(np.abs(pr["sigma0"] - lo), np.abs(pr["sigma0"] - hi))))
    if r.attained or not r.jumps:
        assert r.quality <= Q.max() + lam * (hi - lo) / 1999
    if r.sigma_star is not None and r.attained:
        q = qual(pr, r.sigma_star)[0]
        assert q == pytest.approx(r.quality, rel=1e-9)


@pytest.mark.parametrize("key", PROBLEMS[:6])
def test_escape_path_certificate(problems, key):
    pr = problems[key]
    r = run(pr)
    if r.sigma_star is None or r.U_A_infinite:
        pytest.skip("no finite escape at the optimum")
    g, s = pr["graph"], pr["start"]
    U = vertex_energies(r.sigma_star, pr["sigma0"], pr["k"], pr["mode"])
    path = r.escape_path
    assert path[0] == s and path[-1] != s
    for u, v in zip(path[:-1], path[1:]):  # consecutive vertices are adjacent
        assert v in g.neighbours(int(u))
    assert equilibrium_mask(U, g)[path[-1]]
    # The path's bottleneck is the saddle, and it defines U_A.
    assert U[path].max() == pytest.approx(U[r.saddle], rel=1e-12)
    assert U[r.saddle] - U[s] == pytest.approx(r.U_A, rel=1e-9)


@pytest.mark.parametrize("key", PROBLEMS[:10])
def test_approx_within_eps(problems, key):
    # 10 problems × 3 ε ≥ 20 cases; ε in J, relative to the scale of Q, capped so that
    # the number of samples stays small.
    pr = problems[key]
    exact = run(pr)
    C = C_of(pr)
    lo, hi = span(pr)
    lam = run(pr, method="approx", eps=C).lipschitz  # λ (N) does not depend on ε
    for f in (0.3, 0.05, 0.01):
        eps = max(f * C, lam * (hi - lo) / 2000)
        r = run(pr, method="approx", eps=eps)
        assert r.epsilon == eps and r.method == "approx"
        assert exact.quality - r.quality <= eps
        assert r.quality <= exact.quality + 1e-12 * C
        if r.sigma_star is not None:
            assert qual(pr, r.sigma_star)[0] == pytest.approx(r.quality, rel=1e-12, abs=1e-15)


def test_expanding_is_mirrored_contracting(problems):
    # U depends on σ0 − σ only, so an expanding grasp with σ0' = M − σ0, σ_L' = M − σ_L
    # is the contracting one mirrored: σ*' = M − σ*, same quality and jumps mirrored.
    for key in PROBLEMS[:6:2]:
        pr = problems[key]
        M = 2.0 * float(pr["sigma0"].max())
        a = run(pr)
        b = optimize_separation_arrays(M - pr["sigma0"], pr["k"], pr["graph"], pr["start"],
                                       M - pr["sigma_L"], mode="expanding")
        assert b.quality == pytest.approx(a.quality, rel=1e-9)
        assert b.sigma_star == pytest.approx(M - a.sigma_star, rel=1e-9)
        assert [j[0] for j in b.jumps] == pytest.approx([M - j[0] for j in a.jumps[::-1]])
        for ja, jb in zip(a.jumps[::-1], b.jumps):
            assert (jb[1], jb[2], jb[3]) == pytest.approx((ja[3], ja[2], ja[1]), rel=1e-9)


def test_curve_and_report(problems):
    pr = problems[PROBLEMS[1]]
    r = run(pr)
    c = r.curve
    n = len(c["sigma"])
    assert n >= 400 and all(len(v) == n for v in c.values())
    lo, hi = span(pr)
    assert c["sigma"] == sorted(c["sigma"]) and lo <= c["sigma"][0] and c["sigma"][-1] <= hi
    for UA, UL, Q in zip(c["U_A"], c["U_L"], c["Q"]):
        assert Q == pytest.approx(UL if UA is None else min(UA, UL), abs=1e-15)
    # Samples from the closed-form pieces agree with the definition.
    idx = np.arange(3, n, n // 7)
    sig = np.asarray(c["sigma"])[idx]
    Q = qual(pr, sig)[0]
    assert Q == pytest.approx(np.asarray(c["Q"])[idx], rel=1e-9, abs=1e-12 * C_of(pr))
    d = r.to_dict()
    text = json.dumps(d, allow_nan=False)
    for key in ("sigma_star", "quality", "U_A", "U_L", "sigma_L", "sigma0", "k01", "e_max",
                "method", "epsilon", "units", "curve", "U_A_infinite", "attained", "jumps"):
        assert key in d
    assert d["units"]["energy"] == "J" and json.loads(text)["method"] == "exact"


@pytest.mark.slow
def test_exact_needs_far_fewer_evaluations_than_paper():
    # p = 30 perimeter nodes (435 vertices): the paper's method evaluates U_A at every
    # pairwise crossing; ours only where U_A can change.
    tot_e = tot_p = 0
    for seed, kind, mode in ((3, "star", "contracting"), (4, "convex", "expanding"),
                             (5, "star", "expanding")):
        pr = random_problem(seed, 30, kind, mode)
        re_, rp = run(pr), run(pr, method="paper")
        assert re_.quality == pytest.approx(rp.quality, rel=1e-9)
        assert re_.n_evaluations * 5 <= rp.n_evaluations
        tot_e += re_.n_evaluations
        tot_p += rp.n_evaluations
    assert tot_e * 10 <= tot_p


# --------------------------------------------------------------------------- pieces


@settings(max_examples=200, deadline=None)
@given(st.floats(0.01, 1.0), st.floats(0.1, 1e4), st.floats(0.01, 1.0), st.floats(0.1, 1e4))
def test_crossing_formulas_agree_and_cross(x0a, ka, x0b, kb):
    x1 = float(pc.pair_crossings(x0a, ka, x0b, kb))
    x2 = float(pc.pair_crossings_quadratic(x0a, ka, x0b, kb))
    assert math.isnan(x1) == math.isnan(x2)
    if not math.isnan(x1):
        assert x1 == pytest.approx(x2, rel=1e-9, abs=1e-12)
        # Strictly before both kinks, up to rounding when the kinks nearly coincide
        # (x0a = 0.010000000000000002, x0b = 0.01 gave x1 = 0.01).
        assert x1 < min(x0a, x0b) + 1e-12
        Ea, Eb = pc.energies(x1, np.array([x0a, x0b]), np.array([ka, kb]))
        assert Ea == pytest.approx(Eb, rel=1e-8)
    else:  # no crossing while both are active: one curve stays above the other
        xs = np.linspace(-1.0, min(x0a, x0b), 50)[:-1]
        E = pc.energies(xs, np.array([x0a, x0b]), np.array([ka, kb]))
        d = E[:, 0] - E[:, 1]
        assert np.all(d >= -1e-12 * np.abs(E).max()) or np.all(d <= 1e-12 * np.abs(E).max())


@settings(max_examples=200, deadline=None)
@given(st.floats(0.2, 2.0), st.floats(0.1, 10.0), st.floats(0.2, 3.0), st.floats(0.1, 10.0),
       st.floats(0.0, 0.9), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_piece_candidates_maximise_min_of_quadratics(x0s, ks, x0w, kw, fL, fa, fb):
    # Closed-form max of min(E_w − E_s, C − E_s) on [a, b] against a dense grid.
    x0 = np.array([x0s, x0w])
    k = np.array([ks, kw])
    lo = fL * x0s
    a, b = sorted((lo + fa * (x0s - lo), lo + fb * (x0s - lo)))
    C = 0.5 * ks * (x0s - lo) ** 2
    cand = pc.piece_candidates(a, b, 1, "finite", 0, x0, k, C)
    best = pc.piece_quality(cand, 1, "finite", 0, x0, k, C)[1].max()
    grid = np.linspace(a, b, 4001)
    dense = pc.piece_quality(grid, 1, "finite", 0, x0, k, C)[1].max()
    assert best >= dense - 1e-12 * max(C, 1.0)


def test_snapped_energies_restore_ties():
    x0 = np.array([1.0, 0.9, 0.5])
    k = np.array([1.0, 4.0, 2.0])
    x = float(pc.pair_crossings(1.0, 1.0, 0.9, 4.0))
    bp = pc.Breakpoint(x, np.array([[0, 1]]), np.array([2]))
    U = pc.snapped_energies(bp, x0, k)
    assert U[0] == U[1] and U[2] == 0.0


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("kwargs,match", [
    (dict(method="approx", eps=0.0), "eps"),
    (dict(method="approx", eps=-1.0), "eps"),
    (dict(method="approx", eps=float("nan")), "eps"),
    (dict(method="approx", eps=float("inf")), "eps"),
    (dict(method="approx"), "eps"),
    (dict(method="fast"), "method"),
    (dict(mode="sideways"), "mode"),
    (dict(start=3), "start"),
    (dict(start=-1), "start"),
    (dict(start=True), "start"),
    (dict(start=1.0), "start"),
    (dict(sigma_L=1.5), "sigma_L"),
    (dict(sigma_L=-0.1), "sigma_L"),
    (dict(sigma_L=float("nan")), "sigma_L"),
    (dict(sigma_L=0.5, mode="expanding"), "sigma_L"),
    (dict(sigma0=[1.0, 1.2]), "sigma0"),
    (dict(k=[1.0, 1.0, 1.0, 1.0]), "k"),
    (dict(k=[1.0, 0.0, 1.0]), "k"),
    (dict(sigma0=[1.0, float("inf"), 0.1]), "sigma0"),
])
def test_bad_input(kwargs, match):
    args = dict(sigma0=[1.0, 1.2, 0.1], k=[1.0, 1.0, 1.0], graph=path_graph(), start=0,
                sigma_L=0.0)
    args.update(kwargs)
    pos = [args.pop(n) for n in ("sigma0", "k", "graph", "start", "sigma_L")]
    with pytest.raises(GraspError, match=match):
        optimize_separation_arrays(*pos, **args)


def test_limits_raise(problems):
    pr = problems[PROBLEMS[8]]
    with pytest.raises(GraspError, match="max_breakpoints"):
        run(pr, method="paper", max_breakpoints=5)
    with pytest.raises(GraspError, match="max_samples"):
        run(pr, method="approx", eps=1e-9 * C_of(pr), max_samples=1000)
    with pytest.raises(GraspError, match="range"):
        qual(pr, np.array([span(pr)[1] * 1.5]))


def test_start_as_node_pair():
    g = path_graph()
    a = optimize_separation_arrays([1.0, 1.2, 0.1], [1.0, 1.0, 1.0], g, 0, 0.0)
    b = optimize_separation_arrays([1.0, 1.2, 0.1], [1.0, 1.0, 1.0], g, (1, 0), 0.0)
    assert a.sigma_star == b.sigma_star and a.quality == b.quality
    with pytest.raises(GraspError, match="not a vertex"):
        optimize_separation_arrays([1.0, 1.2, 0.1], [1.0, 1.0, 1.0], g, (0, 7), 0.0)


def short_piece_problem():
    # The jump problem plus vertex 4 (σ0 = 1.22, k = 0.25), another neighbour of the
    # start, whose sqrt-line 0.5(1.22 − σ) crosses the start's (1 − σ) at σ = 0.78: the
    # start is a strict minimum only on (0.78, 0.8), where Q = U_L ≈ 0.48; Q = 0 elsewhere.
    g = ContactGraph.from_edges([[0, 1], [0, 2], [0, 3], [0, 4], [0, 5]],
                                [[0, 1], [0, 2], [2, 3], [0, 4]])
    return [1.0, 0.9, 3.0, 0.5, 1.22], [1.0, 4.0, 1.0, 1.0, 0.25], g


def test_paper_lattice_misses_short_piece_but_pieces_grid_does_not():
    s0, k, g = short_piece_problem()
    exact = optimize_separation_arrays(s0, k, g, 0, 0.0)
    assert exact.sigma_star == pytest.approx(0.8) and not exact.attained
    assert exact.quality == pytest.approx(0.48)
    assert [j[0] for j in exact.jumps] == pytest.approx([0.78, 0.8])
    eps = 0.1  # λ = 3.6, ξ ≈ 0.0278: no lattice point j·ξ falls in (0.78, 0.8)
    lat = optimize_separation_arrays(s0, k, g, 0, 0.0, method="approx", eps=eps, grid="lattice")
    assert lat.sigma_star is None and exact.quality - lat.quality > eps
    pcs = optimize_separation_arrays(s0, k, g, 0, 0.0, method="approx", eps=eps)
    assert exact.quality - pcs.quality <= eps and 0.78 < pcs.sigma_star < 0.8


def test_lattice_grid_is_best_lattice_sample(problems):
    pr = problems[PROBLEMS[2]]
    C = C_of(pr)
    lam = 2.0 * run(pr, method="approx", eps=C).lipschitz  # a shared, larger λ
    eps = lam * (span(pr)[1] - span(pr)[0]) / 150
    r = run(pr, method="approx", eps=eps, grid="lattice", lipschitz=lam)
    assert r.lipschitz == lam and r.step == pytest.approx(eps / lam)
    lo, hi = span(pr)
    j = np.arange(math.ceil(lo / r.step), math.floor(hi / r.step) + 1)
    sig = j * r.step
    sig = sig[(sig >= lo) & (sig <= hi)]
    Q = qual(pr, sig)[0]
    assert r.n_evaluations == sig.size
    assert r.quality == pytest.approx(Q.max(), rel=1e-12)
    assert r.sigma_star == pytest.approx(sig[np.argmax(Q)], rel=1e-12)
    with pytest.raises(GraspError, match="grid"):
        run(pr, method="approx", eps=eps, grid="plain")
    with pytest.raises(GraspError, match="lipschitz"):
        run(pr, method="approx", eps=eps, lipschitz=-1.0)
