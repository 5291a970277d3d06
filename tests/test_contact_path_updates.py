"""The contact path by factor updates gives the pieces of an independent reference
(issue 25, item 2): ``trace_contact_path`` (a Cholesky factor kept across the pieces,
rows added and removed as contacts join and leave) against
``tests/contact_path_reference.py`` (plain numpy: every breakpoint's derivative problem
solved from scratch by enumerating the touching rows' active sets). Compared: the
breakpoints, each piece's active set, the multipliers and the part's translation at the
breakpoints, and the energy on every piece.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from deformclosure.contact.path import trace_contact_path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from contact_path_reference import reference_path  # noqa: E402

RTOL = 1e-9


def _random_problem(rng, r):
    """Two rigid pads closing on a compliant part: rows of pad A (``e > 0``, ``b = 0``)
    and of pad B (``e < 0``, ``b > 0``), gaps and rates of mixed sizes; ``W`` SPD (m/N)."""
    A = rng.normal(size=(r, r))
    W = (A @ A.T + 0.3 * np.eye(r)) * 1e-3
    nA = int(rng.integers(1, r))
    onB = np.arange(r) >= nA
    mag = rng.uniform(0.5, 1.5, r)
    e = np.where(onB, -mag, mag)
    b = np.where(onB, rng.uniform(0.5, 1.5, r), 0.0)
    g0 = rng.uniform(0.0, 1e-3, r)
    return W, g0, b, e


def _active_sets(lam, tol):
    """Rows with ``λ > 0`` inside each piece (at its midpoint)."""
    mid = 0.5 * (lam[:-1] + lam[1:])
    return [np.flatnonzero(row > tol) for row in mid]


def assert_same_path(W, g0, b, e, delta_max, gap_tol):
    got = trace_contact_path(W, g0, b, e, delta_max, gap_tol=gap_tol)
    ref = reference_path(W, g0, b, e, delta_max)
    dscale = max(abs(delta_max), np.abs(ref.delta).max())
    lscale = max(np.abs(ref.lam).max(), 1e-300)
    assert got.delta.shape == ref.delta.shape, (got.delta, ref.delta)
    np.testing.assert_allclose(got.delta, ref.delta, rtol=0, atol=RTOL * dscale)
    np.testing.assert_allclose(got.lam, ref.lam, rtol=0, atol=RTOL * lscale)
    tscale = max(np.abs(ref.t).max(), dscale)
    np.testing.assert_allclose(got.t, ref.t, rtol=0, atol=RTOL * tscale)
    got_sets = _active_sets(got.lam, 1e-9 * lscale)
    assert [list(s) for s in got_sets] == [list(s) for s in ref.active]
    # energy: at the breakpoints and inside every piece, against ½ λᵀWλ of the reference
    probes = np.concatenate([ref.delta[1:], 0.5 * (ref.delta[:-1] + ref.delta[1:]),
                             ref.delta[:-1] + 0.25 * np.diff(ref.delta)])
    E_ref = np.array([ref.energy(float(d), W) for d in probes])
    E_got = got.energy(probes)
    escale = max(np.abs(E_ref).max(), 1e-300)
    np.testing.assert_allclose(E_got, E_ref, rtol=0, atol=RTOL * escale)
    return got, ref


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 12), st.integers(0, 2**31 - 1))
def test_random_delassus_paths_match_the_reference(r, seed):
    rng = np.random.default_rng(seed)
    W, g0, b, e = _random_problem(rng, r)
    assert_same_path(W, g0, b, e, 5e-3, 1e-15)


def test_a_real_pad_path_matches_the_reference():
    """The pads' own problem: the README rectangle (about 800 nodes) squeezed by 4 mm
    round-ended pads along a skew axis, far enough that contacts join and leave."""
    import deformclosure as dc
    import deformclosure.contact.solve as solve_mod
    from deformclosure.pads import GraspAxis, Pad
    from deformclosure.pads.contact import PadContact

    mm = 1e-3
    examples = Path(__file__).resolve().parent.parent / "examples"
    mesh = dc.mesh_part(dc.Part.from_file(examples / "rectangle.json"), max_area=3e-7)
    pc = PadContact(mesh)
    problems = []
    original = solve_mod.trace_contact_path

    def keep(W, g0, b, e, delta_max, **kw):
        problems.append((np.array(W, float), np.array(g0, float), np.array(b, float),
                         np.array(e, float), float(delta_max), kw["gap_tol"]))
        return original(W, g0, b, e, delta_max, **kw)

    solve_mod.trace_contact_path = keep
    try:
        ax = GraspAxis.at(np.array([6.0, 10.0]) * mm, math.radians(60), tuple(pc.centroid))
        pc.curve(ax, Pad(4 * mm, 1 * mm), 6 * mm)
    finally:
        solve_mod.trace_contact_path = original
    assert problems
    W, g0, b, e, dmax, tol = max(problems, key=lambda p: len(p[1]))
    got, ref = assert_same_path(W, g0, b, e, dmax, tol)
    assert len(ref.delta) >= 4            # several pieces: contacts joined (and left)
