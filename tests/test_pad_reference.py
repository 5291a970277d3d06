"""Checks of the independent full-stiffness pad-contact reference (tests/pad_reference.py)
against values predicted without it: closed-form uniaxial compression, rigid-motion
invariance, and the contact conditions recomputed here from the returned displacements."""

from __future__ import annotations

import numpy as np
import pytest

from deformclosure import Part, mesh_part

from pad_reference import pad_profile, reference_pad_solution

MM = 1e-3


def _block(plane: str = "stress", nu: float = 0.3, max_area: float = 0.5, points=()):
    part = Part.from_dict({
        "name": "block", "units": "mm",
        "outer": [[0, 0], [12, 0], [12, 20], [0, 20]], "holes": [],
        "material": {"youngs_modulus": 2e6, "poisson_ratio": nu, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": plane},
        "mesh": {"max_area": max_area, "min_angle": 30,
                 "points": [list(map(float, p)) for p in points]},
    })
    return mesh_part(part)


@pytest.fixture(scope="module")
def block_stress():
    return _block("stress", points=[[0, 10], [12, 10]])


# --------------------------------------------------------------------------- 1. uniaxial
@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_uniaxial_squeeze_between_wide_flat_pads(plane):
    nu = 0.3
    mesh = _block(plane, nu=nu)
    E, t, L, w = 2e6, 1 * MM, 20 * MM, 12 * MM
    Eeff = E if plane == "stress" else E / (1 - nu**2)
    for sigma in (11.5 * MM, 10 * MM):
        r = reference_pad_solution(mesh, 0.0, 10 * MM, 30 * MM, 1 * MM, sigma)
        assert r["sigma0_nodes"] == pytest.approx(w, rel=1e-12)
        delta = w - sigma
        assert r["energy"] == pytest.approx(0.5 * Eeff * t * L / w * delta**2, rel=1e-6)
        F = Eeff * t * L * delta / w
        assert r["A"]["axial_force"] == pytest.approx(F, rel=1e-6)
        assert r["B"]["axial_force"] == pytest.approx(-F, rel=1e-6)
        # Whole faces are in contact, nothing else is.
        xs = mesh.nodes[:, 0]
        assert set(r["A"]["nodes"]) == set(np.flatnonzero(np.abs(xs) < 1e-9))
        assert set(r["B"]["nodes"]) == set(np.flatnonzero(np.abs(xs - w) < 1e-9))
        # Uniform strain: u_x linear in x with slope -delta/w.
        u = r["u"].reshape(-1, 2)
        slope = np.polyfit(xs, u[:, 0], 1)[0]
        # (not exact: the lumped-area rotation constraint is off by the mesh's lumped
        # product of inertia, which the energy feels only to second order)
        assert slope == pytest.approx(-delta / w, rel=1e-5)
    # Open pads: no energy.
    r = reference_pad_solution(mesh, 0.0, 10 * MM, 30 * MM, 1 * MM, 12.5 * MM)
    assert r["energy"] == 0.0 and len(r["A"]["nodes"]) == 0


# --------------------------------------------------------------------------- 2. invariance
def test_rigid_motion_invariance(block_stress):
    rng = np.random.default_rng(20240611)
    mesh = block_stress
    angle, offset, width, radius = 0.25, 9.3 * MM, 2 * MM, 1.5 * MM
    r0 = reference_pad_solution(mesh, angle, offset, width, radius, 1.0)   # open: σ0 only
    assert r0["energy"] == 0.0
    sigma = r0["sigma0_nodes"] - 1.2 * MM
    r0 = reference_pad_solution(mesh, angle, offset, width, radius, sigma)
    assert r0["energy"] > 0
    for _ in range(2):
        phi = rng.uniform(-np.pi, np.pi)
        T = rng.uniform(-50, 50, size=2) * MM
        moved = mesh.rotated(phi).translated(T)
        ang = angle + phi
        nv = np.array([-np.sin(ang), np.cos(ang)])
        r1 = reference_pad_solution(moved, ang, offset + nv @ T, width, radius, sigma)
        assert r1["sigma0_nodes"] == pytest.approx(r0["sigma0_nodes"], rel=1e-12)
        assert r1["energy"] == pytest.approx(r0["energy"], rel=1e-8)
        R = np.array([[np.cos(phi), -np.sin(phi)], [np.sin(phi), np.cos(phi)]])
        u0 = r0["u"].reshape(-1, 2) @ R.T
        u1 = r1["u"].reshape(-1, 2)
        assert np.abs(u1 - u0).max() <= 1e-7 * np.abs(u0).max()
        assert set(r1["A"]["nodes"]) == set(r0["A"]["nodes"])
        assert r1["A"]["axial_force"] == pytest.approx(r0["A"]["axial_force"], rel=1e-8)


# --------------------------------------------------------------------------- 3. contact conditions
def test_round_pads_feasible_complementary_balanced(block_stress):
    mesh = block_stress
    angle, offset, width, radius = 0.0, 10 * MM, 0.0, 2 * MM
    a = np.array([np.cos(angle), np.sin(angle)])
    nv = np.array([-np.sin(angle), np.cos(angle)])
    outer = mesh.loops[0]
    x = mesh.nodes[outer] @ nv - offset
    s = mesh.nodes[outer] @ a
    cand = outer[np.abs(x) < width / 2 + radius]
    d, dp = pad_profile(x[np.abs(x) < width / 2 + radius], width, radius)
    sc = mesh.nodes[cand] @ a
    zA = (sc + d).min()
    sigma0 = (sc - d).max() - zA
    assert sigma0 == pytest.approx(12 * MM, rel=1e-12)   # nodes forced at (0,10), (12,10)

    energies, sigmas = [], sigma0 - np.array([0.05, 0.3, 0.8, 1.5, 2.5]) * MM
    for sigma in sigmas:
        r = reference_pad_solution(mesh, angle, offset, width, radius, sigma)
        assert r["sigma0_nodes"] == pytest.approx(sigma0, rel=1e-12)
        u = r["u"].reshape(-1, 2)[cand]
        gA = sc - zA + d + u @ a + dp * (u @ nv)
        gB = zA + sigma + d - sc - u @ a + dp * (u @ nv)
        assert gA.min() >= -1e-12 and gB.min() >= -1e-12
        work = 0.0
        for key, g, sgn in (("A", gA, 1.0), ("B", gB, -1.0)):
            pad = r[key]
            assert len(pad["nodes"]) >= 1
            pos = np.searchsorted(cand, pad["nodes"]) if np.all(np.diff(cand) > 0) else \
                np.array([int(np.flatnonzero(cand == i)[0]) for i in pad["nodes"]])
            assert np.all(np.abs(g[pos]) <= 1e-12)                 # forces only where touching
            f = pad["forces"]
            normal = sgn * a[None, :] + dp[pos, None] * nv[None, :]
            cross = f[:, 0] * normal[:, 1] - f[:, 1] * normal[:, 0]
            assert np.all(np.abs(cross) <= 1e-9 * np.linalg.norm(f, axis=1))  # along the normal
            assert np.all(sgn * (f @ a) > 0)                       # pads push, never pull
            assert pad["axial_force"] == pytest.approx((f @ a).sum(), rel=1e-12)
            work += 0.5 * float(np.sum(f * r["u"].reshape(-1, 2)[pad["nodes"]]))
        FA, FB = r["A"]["axial_force"], r["B"]["axial_force"]
        assert abs(FA + FB) <= 1e-9 * abs(FA)                       # balance along a
        assert work == pytest.approx(r["energy"], rel=1e-9)         # Clapeyron
        energies.append(r["energy"])
    # U(σ) is convex and increasing with the squeeze.
    e = np.array(energies)
    assert np.all(np.diff(e) > 0)
    slopes = np.diff(e) / np.diff(sigmas)
    # σ decreases along the list, so the chord slopes of a convex U must not increase.
    assert np.all(np.diff(slopes) <= 1e-9 * np.abs(slopes).max())
