"""Frictionless contact equilibrium of a free part (paper §3.3)."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import shapely

from deformclosure import Part, mesh_part, stiffness_matrix
from deformclosure.dspace import DiscFinger, HalfPlaneFinger, PointFinger, PolygonFinger, equilibrium, linear_energy

eqmod = importlib.import_module("deformclosure.dspace.equilibrium")

E, NU, T = 2e6, 0.3, 0.002


def make_mesh(outer, divisions=150, plane="stress", points=()):
    outer = np.asarray(outer, float)
    area = shapely.Polygon(outer).area
    part = Part.from_dict({"name": "t", "units": "m", "outer": outer.tolist(),
                           "material": {"youngs_modulus": E, "poisson_ratio": NU, "thickness": T,
                                        "elastic_limit_strain": 0.5, "plane": plane},
                           "mesh": {"max_area": area / divisions, "points": [list(p) for p in points]}})
    return mesh_part(part)


@pytest.mark.parametrize("plane,d", [("stress", 2e-4), ("strain", 2e-4), ("stress", 4e-3)])
def test_uniaxial_squeeze_between_parallel_jaws(plane, d):
    """A W x H rectangle squeezed by d between two frictionless parallel jaws is in
    uniaxial stress in x (free to expand in y): U = 1/2 E' t H d^2 / W with E' = E
    (plane stress) or E / (1 - nu^2) (plane strain); jaw force F = E' t H d / W.
    d = 4 mm: each jaw overlaps the part by more than 2 % of its diameter (the contact
    search radius), which once went unnoticed."""
    W, H = 0.04, 0.015
    mesh = make_mesh([[0, 0], [W, 0], [W, H], [0, H]], plane=plane)
    res = equilibrium(mesh, [HalfPlaneFinger((d / 2, 0), (1, 0)), HalfPlaneFinger((W - d / 2, 0), (-1, 0))])
    Ep = E if plane == "stress" else E / (1 - NU**2)
    assert res.converged
    assert res.energy == pytest.approx(0.5 * Ep * T * H * d**2 / W, rel=1e-9)
    F = Ep * T * H * d / W
    assert res.forces[0] == pytest.approx([F, 0.0], rel=1e-9, abs=1e-12 * F)
    assert res.forces[1] == pytest.approx([-F, 0.0], rel=1e-9, abs=1e-12 * F)
    assert res.active.all() and np.all(res.gaps >= -res.tol)
    assert res.energy == pytest.approx(linear_energy(mesh, res.q), rel=1e-12)
    assert res.max_strain == pytest.approx(d / W, rel=1e-9)     # uniform compression d/W
    # the jaw faces are flat: every left-edge node at x = d/2 exactly
    left = np.flatnonzero(np.isclose(mesh.nodes[:, 0], 0.0))
    assert np.allclose(res.q[left, 0], d / 2, atol=1e-12)


def test_touching_fingers_leave_the_part_at_rest():
    mesh = make_mesh([[0, 0], [1, 0], [1, 1], [0, 1]], divisions=40, points=[(0.5, 0), (1, 0.5)])
    res = equilibrium(mesh, [PointFinger((0.5, 0.0)), PointFinger((1.0, 0.5)), HalfPlaneFinger((0, 1), (0, -1))])
    assert res.converged and res.energy == 0.0
    assert np.abs(res.q - mesh.nodes).max() <= 1e-15
    assert res.active.all() and np.all(res.forces == 0)


def test_single_finger_pushes_the_part_away():
    """Nothing resists: the part moves rigidly out of the finger, zero energy."""
    mesh = make_mesh([[0, 0], [1, 0], [1, 1], [0, 1]], divisions=40)
    res = equilibrium(mesh, [HalfPlaneFinger((0.01, 0), (1, 0))])
    assert res.converged
    assert res.energy < 1e-12 * E * T
    assert res.gaps[0] >= -res.tol
    assert np.allclose(res.q - mesh.nodes, [0.01, 0.0], atol=1e-9)


def _random_case(rng):
    """A random star-shaped part and 3-4 fingers around it pressing by a small amount."""
    while True:
        k = int(rng.integers(5, 8))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k)) + np.linspace(0, 0.4, k)
        rad = rng.uniform(0.6, 1.0, k)
        outer = np.c_[rad * np.cos(ang), rad * np.sin(ang)] * 0.05
        poly = shapely.Polygon(outer)
        if poly.is_valid and poly.area > 0.002:
            break
    c = np.asarray(poly.centroid.coords[0])
    fingers = []
    d = 5e-4
    t1 = rng.uniform(0, 2 * np.pi)
    t2 = t1 + rng.uniform(0.8, 2.3)
    dirs = [t1, t2, t1 + np.pi + rng.uniform(-0.05, 0.05), t2 + np.pi + rng.uniform(-0.05, 0.05)]  # opposed pairs
    for i, th in enumerate(dirs):
        u = np.array([np.cos(th), np.sin(th)])
        # farthest boundary point along u from the centroid
        far = shapely.LineString([c, c + 0.2 * u]).intersection(poly.exterior)
        p = np.asarray(far.coords[0]) if far.geom_type == "Point" else np.asarray(far.geoms[-1].coords[0])
        kind = i % 4
        if kind == 0:
            fingers.append(DiscFinger(tuple(p + (0.01 - d) * u), 0.01))
        elif kind == 1:
            # a flat jaw on the support line of the part in direction u (a jaw through
            # ``p`` would cut deep into any corner sticking out beyond it)
            p = outer[int(np.argmax(outer @ u))]
            fingers.append(HalfPlaneFinger(tuple(p - d * u), tuple(-u)))
        elif kind == 2:
            t = np.array([-u[1], u[0]])
            a = p - d * u
            fingers.append(PolygonFinger((tuple(a), tuple(a + 0.01 * u + 0.006 * t), tuple(a + 0.01 * u - 0.006 * t))))
        else:
            fingers.append(PointFinger(tuple(p - d * u)))
    return outer, fingers


def _polygon_case(rng):
    """A random convex polygon (rotated, scaled) squeezed by fingers of every kind placed
    on edge midpoints in opposed pairs."""
    k = int(rng.choice([4, 6, 8]))
    ang = np.arange(k) * 2 * np.pi / k + rng.uniform(0, 2 * np.pi)
    rad = 0.04 * rng.uniform(0.8, 1.2)
    outer = np.c_[rad * np.cos(ang), rad * np.sin(ang)] * [1.0, rng.uniform(0.6, 1.0)]
    d = 3e-4
    fingers = []
    for i in (0, k // 2, 1, k // 2 + 1):
        a, b = outer[i], outer[(i + 1) % k]
        t = (b - a) / np.linalg.norm(b - a)
        nin = np.array([-t[1], t[0]])
        p = 0.5 * (a + b)  # opposite edges of a centrally symmetric polygon: collinear pairs
        kind = int(rng.integers(2))  # discs and flat jaws (corners: see the star cases)
        if kind == 0:
            fingers.append(DiscFinger(tuple(p - (0.01 - d) * nin), 0.01))
        elif kind == 1:
            fingers.append(HalfPlaneFinger(tuple(p + d * nin), tuple(nin)))
        elif kind == 2:
            c = p + d * nin
            fingers.append(PolygonFinger((tuple(c), tuple(c - 0.01 * nin - 0.005 * t), tuple(c - 0.01 * nin + 0.005 * t))))
        else:
            fingers.append(PointFinger(tuple(p + d * nin)))
    return outer, fingers


@pytest.mark.parametrize("seed", range(8))
def test_equilibrium_converges_and_balances_on_random_polygons(seed):
    rng = np.random.default_rng(200 + seed)
    outer, fingers = _polygon_case(rng)
    mesh = make_mesh(outer, divisions=120)
    res = equilibrium(mesh, fingers)
    assert res.converged
    F = res.forces
    scale = np.abs(F).max()
    assert scale > 0 and res.energy > 0
    assert np.abs(F.sum(axis=0)).max() <= 1e-8 * scale
    assert abs(res.moments.sum()) <= 1e-8 * scale * mesh.diameter
    assert np.all(res.gaps >= -res.tol)


@pytest.mark.parametrize("seed", range(6))
def test_contact_forces_balance_on_random_cases(seed):
    """Star-shaped parts pressed from four sides, several of which must turn by 5-16°
    to balance: the iteration converges within its budget and the forces balance."""
    rng = np.random.default_rng(100 + seed)
    outer, fingers = _random_case(rng)
    mesh = make_mesh(outer, divisions=120)
    res = equilibrium(mesh, fingers, max_iter=20)
    F = res.forces
    scale = max(np.abs(F).max(), 1e-300)
    assert np.abs(F.sum(axis=0)).max() <= 1e-8 * scale
    assert abs(res.moments.sum()) <= 1e-8 * scale * mesh.diameter
    # moments from the nodal forces, recomputed independently about another point
    p = np.array([0.3, -0.2])
    arm = mesh.nodes - p
    m = np.sum(arm[:, 0] * res.nodal_forces[:, 1] - arm[:, 1] * res.nodal_forces[:, 0])
    assert abs(m) <= 1e-8 * scale * mesh.diameter
    assert res.converged
    assert np.all(res.gaps >= -max(res.tol, res.accuracy))
    assert res.energy > 0
    # the energy is that of the deformation (the rigid motion is exact, not linearised)
    assert res.energy == pytest.approx(0.5 * res.displacement.ravel() @ (stiffness_matrix(mesh) @ res.displacement.ravel()),
                                       rel=1e-9)


def test_disc_pressing_between_nodes_balances():
    """A small disc pressing an edge between two nodes (disc-edge condition)."""
    W, H = 0.04, 0.01
    mesh = make_mesh([[0, 0], [W, 0], [W, H], [0, H]], divisions=30)
    res = equilibrium(mesh, [HalfPlaneFinger((0.0, 0), (1, 0)), DiscFinger((W + 0.001 - 5e-5, 0.0061), 0.001)])
    assert res.converged and res.energy > 0
    assert res.forces[0, 0] == pytest.approx(-res.forces[1, 0], rel=1e-9)
    assert abs(res.moments.sum()) <= 1e-9 * abs(res.forces[0, 0]) * W
