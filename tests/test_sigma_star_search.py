"""The one σ*-search (``landscape.optimum.maximise_quality``) against brute force.

Independent value: ``Q(σ) = min(U_A, U_L)`` sampled densely on ``[σ_L, σ0]`` for random
piecewise-quadratic start and saddle curves (two saddles, the lower one winning, so the
saddle changes inside the range, and the start stops being a strict minimum where it
crosses a saddle's curve — given to the search, as its contract asks); the search's
optimum must be at least every sample and attained: ``Q`` evaluated by its definition at the returned σ* equals the returned Q*.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings, strategies as st
from scipy.optimize import brentq

from deformclosure.landscape.optimum import maximise_quality


def _piecewise(rng, lo, hi, k):
    """A continuous piecewise quadratic on [lo, hi] growing as σ falls (a squeeze), with
    kinks at ``k`` random places; returns (f, kinks)."""
    kinks = np.sort(rng.uniform(lo, hi, k))
    knots = np.r_[lo, kinks, hi]
    slopes = rng.uniform(0.5, 3.0, len(knots) - 1)

    def f(x):
        x = float(x)
        v = 0.0
        for a, b, c in zip(knots[:-1], knots[1:], slopes):   # integrate c (hi - x) pieces
            if x < b:
                u0, u1 = max(x, a), b
                v += c * ((hi - u0) ** 2 - (hi - u1) ** 2) / 2
        return v

    return f, kinks


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_search_matches_dense_sampling(seed):
    rng = np.random.default_rng(seed)
    lo, hi = 0.0, 1.0
    Us, ks = _piecewise(rng, lo, hi, 2)
    W1, k1 = _piecewise(rng, lo, hi, 1)
    W2, k2 = _piecewise(rng, lo, hi, 1)
    a1, a2 = rng.uniform(1.2, 3.0, 2)
    U1 = lambda x: a1 * W1(x)            # noqa: E731 - saddles above the start
    U2 = lambda x: a2 * W2(x)            # noqa: E731
    U_sL = Us(lo)

    def release(x):
        b1, b2 = U1(x) - Us(x), U2(x) - Us(x)
        w = 1 if b1 <= b2 else 2
        UA = min(b1, b2)
        strict = UA > 0
        return UA, (strict, w if strict else None, False)

    def evaluate(x):
        UA, key = release(x)
        UA = max(UA, 0.0)
        return SimpleNamespace(Q=min(UA, U_sL - Us(x)), key=key)

    curves = {1: (U1, k1), 2: (U2, k2)}
    # the search's contract: the caller gives every σ where the class of the release can
    # change — here the crossings of the start with its neighbours — among the kinks
    cross = []
    for U in (U1, U2):
        xs = np.linspace(lo, hi, 2001)
        d = np.array([U(x) - Us(x) for x in xs])
        for i in np.flatnonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0):
            cross.append(brentq(lambda x: U(x) - Us(x), xs[i], xs[i + 1], xtol=1e-15))
    kinks = np.sort(np.r_[ks, cross])
    best, ev = maximise_quality(evaluate, Us, kinks, lambda w: curves[w], U_sL, lo, hi, 8)
    xs = np.linspace(lo, hi, 4001)
    Q = np.array([evaluate(x).Q for x in xs])
    if Q.max() <= 0:
        assert best is None
        return
    assert best is not None
    Qstar, sstar = best
    assert Qstar >= Q.max() - 1e-12 * max(1.0, Q.max())
    assert abs(evaluate(sstar).Q - Qstar) <= 1e-9 * Qstar          # attained, by definition
