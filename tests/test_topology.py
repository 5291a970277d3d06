"""Topology-preserving configurations D_T (paper §3.1, Fig. 2)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure import Mesh, Part, mesh_part
from deformclosure.dspace import boundary_crossings, in_dt, inverted_triangles, topology_violations

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002, "elastic_limit_strain": 0.5}


def _strip(n=40, m=3, length=1.0, width=0.1):
    """Structured mesh of a strip [0, length] x [0, width] (counter-clockwise triangles)."""
    xs, ys = np.linspace(0, length, n + 1), np.linspace(0, width, m + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    nodes = np.c_[X.ravel(), Y.ravel()]
    idx = np.arange(len(nodes)).reshape(n + 1, m + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tri = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    return Mesh.from_arrays(nodes, tri)


def _bent(mesh, total_angle, radius=0.3):
    """Wrap the strip around a circle: arc length along x becomes angle (orientation kept)."""
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    th = x / x.max() * total_angle
    r = radius - y  # y up -> towards the centre, keeps counter-clockwise triangles
    return np.c_[r * np.sin(th), radius - r * np.cos(th)]


@pytest.fixture(scope="module")
def plate():
    part = Part.from_dict({"name": "plate", "units": "m", "outer": [[0, 0], [1, 0], [1, 0.6], [0, 0.6]],
                           "holes": [[[0.4, 0.2], [0.4, 0.4], [0.6, 0.4], [0.6, 0.2]]],
                           "material": MAT, "mesh": {"max_area": 0.01}})
    return mesh_part(part)


def test_rest_and_mirror(plate):
    assert in_dt(plate, plate.nodes)
    assert not in_dt(plate, plate.nodes * [-1, 1])
    assert inverted_triangles(plate, plate.nodes * [-1, 1]).all()


def test_fold_over_is_rejected(plate):
    """Paper Fig. 2 (left) analogue: an interior node pushed across the far side of its
    star folds the triangles over."""
    tri = plate.triangles
    interior = np.setdiff1d(np.arange(plate.n_nodes), plate.perimeter_nodes)
    v = int(interior[0])
    nb = np.unique(tri[np.any(tri == v, axis=1)])
    nb = nb[nb != v]
    far = plate.nodes[nb].mean(axis=0) + 1.5 * (plate.nodes[nb[0]] - plate.nodes[v])
    q = plate.nodes.copy()
    q[v] = far
    assert not in_dt(plate, q)
    viol = topology_violations(plate, q)
    assert len(viol["inverted"]) > 0


def test_self_intersection_without_inverted_triangles_is_rejected():
    """Paper Fig. 2 (right) analogue: a strip wrapped by more than a full turn overlaps
    itself while every triangle keeps its orientation."""
    strip = _strip()
    q = _bent(strip, 2.4 * np.pi)
    assert not inverted_triangles(strip, q).any()
    assert boundary_crossings(strip, q)
    assert not in_dt(strip, q)
    viol = topology_violations(strip, q)
    assert len(viol["inverted"]) == 0 and len(viol["crossing"]) > 0


@pytest.mark.parametrize("turn", [0.5, 1.0, 1.6])
def test_valid_large_deformations_are_accepted(turn):
    """Bending the strip by up to 1.6 pi (a large deformation) stays in D_T, so do
    large rigid motions."""
    strip = _strip()
    q = _bent(strip, turn * np.pi)
    assert in_dt(strip, q)
    R = np.array([[np.cos(2.9), -np.sin(2.9)], [np.sin(2.9), np.cos(2.9)]])
    assert in_dt(strip, q @ R.T + [4.0, -7.0])


def test_hole_pushed_out_is_rejected(plate):
    """Moving the hole's nodes outside the outer ring is caught (rings cross)."""
    q = plate.nodes.copy()
    hole = plate.hole_loops[0]
    q[hole] += [0.9, 0.0]
    assert not in_dt(plate, q)


def test_batch_equals_single(plate):
    rng = np.random.default_rng(5)
    Q = plate.nodes + rng.normal(scale=0.02, size=(30,) + plate.nodes.shape)
    batch = in_dt(plate, Q)
    assert batch.dtype == bool and batch.shape == (30,)
    assert list(batch) == [in_dt(plate, q) for q in Q]
    assert in_dt(plate, Q.reshape(30, -1)).tolist() == batch.tolist()


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**20), scale=st.sampled_from([0.01, 0.03, 0.06, 0.1]))
def test_matches_shapely_validity(plate, seed, scale):
    """Independent check: D_T ⇔ all triangles positive and the deformed boundary is a
    valid polygon with holes (shapely/GEOS)."""
    rng = np.random.default_rng(seed)
    q = plate.nodes + rng.normal(scale=scale, size=plate.nodes.shape)
    areas_ok = not inverted_triangles(plate, q).any()
    poly = shapely.Polygon(q[plate.outer_loop], [q[h] for h in plate.hole_loops])
    assert in_dt(plate, q) == (areas_ok and poly.is_valid)
