"""The one elastic-limit rule (``landscape.limit``) against brute force and the paper's
closed form.

Independent values: the first crossing of a piecewise-linear strain path is found by
dense sampling of every piece (brute force, no convexity assumed); on a single piece from
rest it is the paper's ``σ_L = σ0 − e_L / e_max`` (SPEC §4); the energy to the limit of a
proportionally loaded state is ``U (s_L² − 1)`` with ``s_L = e_L / e``.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from deformclosure.elasticity.strain import principal_strains
from deformclosure.grasp.elastic_limit import elastic_limit_separation
from deformclosure.landscape.limit import (energy_to_limit_from_rest, first_limit_crossing,
                                           strain_measure)


def _measure(T):
    p = principal_strains(np.asarray(T, float).reshape(-1, 3))
    return np.abs(p).max()


@settings(max_examples=80, deadline=None)
@given(st.integers(2, 6), st.integers(1, 5), st.integers(0, 2**31 - 1),
       st.floats(0.01, 0.5))
def test_first_crossing_matches_dense_sampling(k, m, seed, e_L):
    rng = np.random.default_rng(seed)
    T = np.cumsum(rng.normal(scale=0.1, size=(k, m, 3)), axis=0)
    T[0] = 0.0 if seed % 2 else T[0] * 0.1          # from rest, or not
    hit = first_limit_crossing(T, e_L)
    # brute force: the first sample along the path at or above e_L
    first = None
    for i in range(k - 1):
        for s in np.linspace(0.0, 1.0, 4001):
            if _measure((1 - s) * T[i] + s * T[i + 1]) >= e_L:
                first = (i, s)
                break
        if first is not None:
            break
    if first is None:
        assert not hit.reached
        return
    assert hit.reached
    i, s = first
    if i == 0 and s == 0.0:
        assert hit.piece == (0, 0)
        return
    # the rule's crossing lies within one sample step before the brute-force one, and the
    # measure there is e_L (the measure is continuous and convex along a piece)
    path_pos = hit.piece[0] + hit.fraction
    assert path_pos <= i + s + 1e-12
    assert path_pos >= i + s - 1.0 / 4000 - 1e-12
    assert _measure(hit.interpolate(T)) == pytest.approx(e_L, rel=1e-9)


@settings(max_examples=40, deadline=None)
@given(st.floats(1e-3, 1.0), st.floats(1.0, 1e4), st.floats(0.01, 0.9))
def test_one_piece_from_rest_is_the_papers_closed_form(sigma0, e_max, e_L):
    """Jaws closing by δ: element strain ``e_max δ`` (1/m times m) along one piece from
    rest; the rule's crossing is the paper's σ_L."""
    delta_end = 2.0 * e_L / e_max              # the piece reaches twice the limit
    T = np.array([[[0.0, 0.0, 0.0]], [[0.0, -e_max * delta_end, 0.0]]])
    hit = first_limit_crossing(T, e_L)
    sigma_L = sigma0 - hit.interpolate(np.array([0.0, delta_end]))
    assert max(sigma_L, 0.0) == pytest.approx(elastic_limit_separation(sigma0, e_max, e_L),
                                              rel=1e-12, abs=1e-15)


def test_energy_to_the_limit_of_a_proportional_state():
    # U(s) = s² U1, e(s) = s e1: the limit at s_L = e_L / e1
    U1, e1, e_L = 2e-3, 0.04, 0.1
    s_L = e_L / e1
    assert energy_to_limit_from_rest(U1, e1, e_L) == pytest.approx(U1 * s_L**2 - U1, rel=1e-14)
    assert energy_to_limit_from_rest(U1, 0.2, e_L) == 0.0            # past the limit
    assert energy_to_limit_from_rest(0.0, 0.0, e_L) == float("inf")  # nothing loaded


def test_strain_measure_is_the_largest_absolute_principal_strain():
    T = np.array([[0.02, -0.01, 0.03], [0.0, 0.0, 0.0]])
    e = strain_measure(T)
    for t, v in zip(T, e):
        M = np.array([[t[0], t[2] / 2], [t[2] / 2, t[1]]])
        assert v == pytest.approx(np.abs(np.linalg.eigvalsh(M)).max(), abs=1e-15)
