"""The one contact solver entry (``contact.solve``): each method against brute force.

Independent reference: for a small problem, every active set ``A`` is tried — solve the
equality KKT system on ``A`` (with the balance rows) and keep the one whose multipliers
are ``≥ 0`` and whose gaps are ``≥ 0`` off ``A``. For an SPD ``W`` the solution of the
complementarity problem is unique, so every method must find it. The exact squeeze path
must equal the one-configuration solve at every squeeze.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from deformclosure.contact import ContactProblem, solve_contact, trace_contact
from deformclosure.contact.lcp import solve_lcp
from deformclosure.contact.qp import solve_balanced_dual


def _brute_force(W, q, B):
    r, m = len(q), len(B)
    for k in range(r + 1):
        for A in itertools.combinations(range(r), k):
            A = list(A)
            KKT = np.block([[W[np.ix_(A, A)], B[:, A].T], [B[:, A], np.zeros((m, m))]]) \
                if m else W[np.ix_(A, A)]
            rhs = np.r_[-q[A], np.zeros(m)]
            try:
                sol = np.linalg.solve(KKT, rhs) if len(rhs) else np.zeros(0)
            except np.linalg.LinAlgError:
                continue
            lam = np.zeros(r)
            lam[A] = sol[:k]
            y = sol[k:]
            g = q + W @ lam + (B.T @ y if m else 0.0)
            scale = max(np.abs(q).max(), 1e-300)
            if np.all(lam >= -1e-10 * max(np.abs(lam).max(), 1.0)) and np.all(g >= -1e-10 * scale):
                return lam, y
    raise AssertionError("no active set solves the problem")


def _spd(rng, r):
    A = rng.normal(size=(r, r))
    return A @ A.T + 0.3 * np.eye(r)


def _two_bodies(rng, r):
    """Two rigid bodies closing on a compliant part: ``(W, g0, b, e)`` with rows of A
    (``e = 1``, ``b = 0``) then rows of B (``e = −1``, ``b = 1``), ``W`` SPD (m/N), gaps up
    to 1 mm."""
    nA = max(1, r // 2)
    W = _spd(rng, r) * 1e-3
    onB = np.arange(r) >= nA
    e = np.where(onB, -1.0, 1.0)
    b = np.where(onB, 1.0, 0.0)
    g0 = rng.uniform(0.0, 1e-3, r)
    return W, g0, b, e


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 6), st.integers(0, 2**31 - 1))
def test_pivoting_lcp_matches_brute_force(r, seed):
    rng = np.random.default_rng(seed)
    W, q = _spd(rng, r), rng.normal(size=r)
    lam_ref, _ = _brute_force(W, q, np.zeros((0, r)))
    lam, ok = solve_lcp(W, q)
    assert ok
    assert np.allclose(lam, lam_ref, atol=1e-9 * max(1.0, np.abs(lam_ref).max()))
    sol = solve_contact(ContactProblem(W, q))
    assert np.allclose(sol.lam, lam_ref, atol=1e-9 * max(1.0, np.abs(lam_ref).max()))


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 6), st.integers(0, 2**31 - 1))
def test_balanced_dual_matches_brute_force(r, seed):
    """With one balance row of mixed signs (two opposed bodies, like two pads)."""
    rng = np.random.default_rng(seed)
    W = _spd(rng, r)
    e = np.where(np.arange(r) < r // 2, 1.0, -1.0) * rng.uniform(0.5, 1.5, r)
    q = rng.normal(size=r) - 0.5
    B = e[None, :]
    lam_ref, y_ref = _brute_force(W, q, B)
    lam, y, _, active = solve_balanced_dual(W, q, B)
    tol = 1e-7 * max(1.0, np.abs(lam_ref).max())
    assert np.allclose(lam, lam_ref, atol=tol)
    if np.any(lam_ref > tol):
        assert np.allclose(y, y_ref, atol=1e-6 * max(1.0, np.abs(y_ref).max()))
    sol = solve_contact(ContactProblem(W, q, balance=B))
    assert np.allclose(sol.lam, lam_ref, atol=tol)


@settings(max_examples=25, deadline=None)
@given(st.integers(2, 7), st.integers(0, 2**31 - 1))
def test_squeeze_path_equals_the_solve_at_each_squeeze(r, seed):
    """``trace_contact`` (parametric active set) against ``solve_contact`` (dual QP) at
    squeezes along the path: two rigid bodies (rows of A: e > 0, b = 0; rows of B:
    e < 0, b > 0) closing on a compliant part."""
    W, g0, b, e = _two_bodies(np.random.default_rng(seed), r)
    problem = ContactProblem(W, g0, balance=e[None, :], rate=b)
    path = trace_contact(problem, 5e-3, gap_tol=1e-15)
    for delta in np.linspace(path.delta[0], 5e-3, 9)[1:]:
        lam_path = path.multipliers(float(delta))
        lam_ref, _ = _brute_force(W, g0 - delta * b, e[None, :])
        assert np.allclose(lam_path, lam_ref, atol=1e-8 * max(1.0, np.abs(lam_ref).max()))
        E = 0.5 * lam_ref @ W @ lam_ref
        assert path.energy_at(float(delta)) == pytest.approx(E, rel=1e-9, abs=1e-300)


def test_rows_carry_tangents_for_friction():
    n = np.array([[1.0, 0.0], [0.6, 0.8]])
    t = ContactProblem(np.eye(2), np.zeros(2), normals=n).tangents()
    assert np.allclose(np.einsum("ij,ij->i", n, t), 0.0)
    assert np.allclose(np.linalg.norm(t, axis=1), 1.0)
    assert np.allclose(n[:, 0] * t[:, 1] - n[:, 1] * t[:, 0], 1.0)   # counter-clockwise


# ------------------------------------------------- the factored path against the dense one
def _dense_trace(W, g0, b, e, delta_max, gap_tol, max_pieces=10000):
    """The squeeze path as ``contact.path._trace`` computed it before its derivative QPs
    shared one kept Cholesky factor: every active-set iteration of every piece solves a
    new dense KKT system (``_derivative_qp``, LU). Kept here as the reference (Python
    loop over the pieces; the compiled QP of each piece)."""
    from deformclosure.contact.path import _derivative_qp

    m = len(g0)
    t = -min(g0[i] / e[i] for i in range(m) if e[i] > 0)
    delta = min((g0[i] + e[i] * t) / b[i] for i in range(m) if e[i] < 0)
    lam = np.zeros(m)
    D, L, T = [delta], [lam.copy()], [t]
    reg = np.trace(W) * 1e-13 / max(m, 1)
    for _ in range(max_pieces):
        if delta >= delta_max or delta_max - delta <= 1e-11 * abs(delta_max):
            break
        g = g0 - delta * b + W @ lam + e * t
        lam_scale = max(np.abs(lam).max(), 1e-300)
        strong = lam > 1e-12 * lam_scale
        touching = ~strong & (g <= gap_tol)
        J = np.flatnonzero(strong | touching)
        Wj = 0.5 * (W[np.ix_(J, J)] + W[np.ix_(J, J)].T) + reg * np.eye(len(J))
        x, dt = _derivative_qp(Wj, b[J].copy(), e[J].copy(), touching[J].copy())
        dlam = np.zeros(m)
        dlam[J] = x
        dg = W @ dlam + e * dt - b
        xs = max(np.abs(x).max(initial=0.0), 1e-300)
        stays = np.zeros(m, bool)
        stays[J] = strong[J] | (x > 1e-12 * xs)
        h = delta_max - delta
        for i in range(m):
            if dlam[i] < 0:
                h = min(h, lam[i] / -dlam[i])
            elif dlam[i] == 0 and dg[i] < 0 and not stays[i]:
                h = min(h, max(g[i], 0.0) / -dg[i])
        h = max(h, 0.0)
        lam = np.maximum(lam + h * dlam, 0.0)
        lam[(dlam < 0) & (np.abs(lam) <= 1e-12 * lam_scale)] = 0.0
        t += h * dt
        delta += h
        if h > 0 or delta >= delta_max:
            D.append(delta), L.append(lam.copy()), T.append(t)
    return np.array(D), np.array(L), np.array(T)


def _same_path(new, ref, scale_delta):
    D0, L0, T0 = ref
    D1, L1, T1 = new
    assert D1.shape == D0.shape
    lam_scale = max(np.abs(L0).max(), 1e-300)
    assert np.abs(D1 - D0).max() <= 1e-10 * scale_delta
    assert np.abs(L1 - L0).max() <= 1e-10 * lam_scale


@settings(max_examples=25, deadline=None)
@given(st.integers(2, 12), st.integers(0, 2**31 - 1))
def test_factored_squeeze_path_is_the_dense_one(r, seed):
    """The kept-factor derivative QPs (rows entering and leaving the Cholesky factor)
    give the breakpoints and multipliers of the dense per-iteration solves, on random
    two-body problems."""
    from deformclosure.contact.path import _trace

    args = (*_two_bodies(np.random.default_rng(seed), r), 5e-3, 1e-15)
    _same_path(_trace(*args, 10000), _dense_trace(*args), 5e-3)


def test_factored_squeeze_path_is_the_dense_one_on_pad_curves():
    """The same on the pads' own contact problems: the 12 x 20 mm block (about 800 nodes)
    between flat 36 mm pads and 4 mm round-ended pads, at axes all round the part — many
    rows touching at once (a flat face) and rows leaving (an end's corner)."""
    import math

    import deformclosure as dc
    import deformclosure.contact.solve as solve_mod
    from deformclosure.pads import GraspAxis, Pad
    from deformclosure.pads.contact import PadContact

    mm = 1e-3
    mesh = dc.mesh_part(dc.Part.from_file("examples/rectangle.json"), max_area=3e-7)
    pc = PadContact(mesh)
    problems = []
    original = solve_mod.trace_contact_path

    def keep(W, g0, b, e, delta_max, **kw):
        problems.append((np.ascontiguousarray(W), g0, b, e, float(delta_max), kw["gap_tol"]))
        return original(W, g0, b, e, delta_max, **kw)

    solve_mod.trace_contact_path = keep
    try:
        for angle in range(0, 180, 30):
            for width, rho in ((36, 0.5), (4, 1)):
                ax = GraspAxis.at(np.array([6.0, 10.0]) * mm, math.radians(angle),
                                  tuple(pc.centroid))
                pc.curve(ax, Pad(width * mm, rho * mm), 6 * mm)
    finally:
        solve_mod.trace_contact_path = original
    from deformclosure.contact.path import _trace

    assert len(problems) >= 12 and max(len(p[1]) for p in problems) > 40
    for W, g0, b, e, dmax, tol in problems:
        _same_path(_trace(W, g0, b, e, dmax, tol, 10000), _dense_trace(W, g0, b, e, dmax, tol),
                   dmax)
