"""The one piece maximiser and the one candidate ranking of ``landscape.optimum``.

Independent values: ``max min(f, g)`` of two random quadratics on a random interval,
written out here as polynomials and sampled densely (the candidates must reach every
sample, and lie in the interval); the ranking against a sort key written from its rule
(larger Q, then attained, then the least squeeze); the paper model's piece candidates
(closed forms of ``grasp.pieces``) against the same dense sampling.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings, strategies as st

from deformclosure.grasp import pieces as pc
from deformclosure.landscape.optimum import Candidate, Quadratic, better, max_min_candidates

coef = st.floats(-10.0, 10.0, allow_nan=False)
pos = st.floats(-5.0, 5.0, allow_nan=False)


def _poly(a, b, c, r):
    """``a (x − r)² + b (x − r) + c`` as a plain function (the test's own evaluation)."""
    return lambda x: a * (x - r) ** 2 + b * (x - r) + c


@settings(max_examples=400, deadline=None)
@given(coef, coef, coef, pos, coef, coef, coef, pos, pos, st.floats(1e-3, 8.0),
       st.booleans())
def test_max_min_of_two_quadratics_reaches_dense_sampling(a1, b1, c1, r1, a2, b2, c2, r2,
                                                          lo, width, pass_difference):
    hi = lo + width
    f, g = _poly(a1, b1, c1, r1), _poly(a2, b2, c2, r2)
    qf, qg = Quadratic(a1, b1, c1, r1), Quadratic(a2, b2, c2, r2)
    diff = None
    if pass_difference:          # f − g about r1, formed here from the expansion of g
        d = r1 - r2
        diff = Quadratic(a1 - a2, b1 - (2 * a2 * d + b2), c1 - (a2 * d * d + b2 * d + c2), r1)
    cand = np.asarray(max_min_candidates(qf, qg, lo, hi, difference=diff))
    assert cand[0] == lo and cand[1] == hi
    assert np.all((cand >= lo) & (cand <= hi))
    grid = np.linspace(lo, hi, 20001)
    dense = np.minimum(f(grid), g(grid)).max()
    best = np.minimum(f(cand), g(cand)).max()
    scale = max(1.0, abs(a1), abs(a2), abs(b1), abs(b2)) * (1.0 + abs(lo) + abs(hi)) ** 2
    assert best >= dense - 1e-9 * scale


@settings(max_examples=200, deadline=None)
@given(coef, coef, coef, pos, pos, st.floats(1e-3, 8.0))
def test_quadratic_through_three_points_and_shift(a, b, c, r, lo, width):
    hi = lo + width
    f = _poly(a, b, c, r)
    q = Quadratic.through(f, lo, hi)
    xs = np.linspace(lo, hi, 7)
    scale = (1.0 + abs(a) + abs(b) + abs(c)) * (1.0 + abs(lo) + abs(hi) + abs(r)) ** 2
    assert np.allclose(q(xs), f(xs), rtol=0, atol=1e-9 * scale)
    assert np.allclose(q.shifted(r)(xs), f(xs), rtol=0, atol=1e-9 * scale)


def test_max_min_candidates_examples():
    # f = −(x − 1)² + 2 and g = x on [0, 3]: f's top at 1, crossings where x² − x − 1 = 0
    f, g = Quadratic(-1.0, 0.0, 2.0, 1.0), Quadratic(0.0, 1.0, 0.0, 0.0)
    cand = max_min_candidates(f, g, 0.0, 3.0)
    assert cand[:3] == [0.0, 3.0, 1.0]
    assert np.isclose(cand[3], (1 + 5 ** 0.5) / 2, rtol=1e-15) and len(cand) == 4
    # identical curves: no crossing, just the ends and the two (equal) tops
    assert max_min_candidates(f, f, 0.0, 3.0) == [0.0, 3.0, 1.0, 1.0]
    # an empty interval: its end only
    assert max_min_candidates(f, g, 2.0, 2.0) == [2.0, 2.0]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([0.0, 1.0, 2.0]), st.sampled_from([-1.0, 0.0, 1.0]),
                          st.booleans()), min_size=1, max_size=8),
       st.sampled_from([1.0, -1.0]))
def test_ranking_is_the_documented_order(items, toward):
    # Running `better` over the candidates gives the maximum of the key (Q, attained,
    # toward·x); exact ties of all three leave the first one seen.
    best = None
    for Q, x, att in items:
        c = Candidate(Q, x, att)
        if better(c, best, toward):
            best = c
    key = max((Q, att, toward * x) for Q, x, att in items)
    assert (best.Q, best.attained, toward * best.x) == key


@settings(max_examples=300, deadline=None)
@given(st.floats(0.2, 2.0), st.floats(0.1, 10.0), st.floats(0.0, 3.0), st.floats(0.1, 10.0),
       st.floats(0.0, 0.9), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_paper_piece_candidates_on_active_pieces(x0s, ks, dw, kw, fL, fa, fb):
    # A "finite" piece of the paper model: the saddle w is above the start, so both
    # curves are active on [a, b] (x0_w ≥ x0_s); Q = min(E_w − E_s, C − E_s) sampled.
    x0w = x0s + dw
    x0 = np.array([x0s, x0w])
    k = np.array([ks, kw])
    lo = fL * x0s
    a, b = sorted((lo + fa * (x0s - lo), lo + fb * (x0s - lo)))
    C = 0.5 * ks * (x0s - lo) ** 2

    def Q(x):
        Es, Ew = 0.5 * ks * (x0s - x) ** 2, 0.5 * kw * (x0w - x) ** 2
        return np.minimum(Ew - Es, C - Es)

    cand = pc.piece_candidates(a, b, 1, "finite", 0, x0, k, C)
    assert cand[0] == a and cand[-1] == b and np.all(np.diff(cand) > 0)
    dense = Q(np.linspace(a, b, 20001)).max()
    assert Q(cand).max() >= dense - 1e-12 * max(C, 1.0) * (1 + kw + ks)
