"""Strain averaged over a critical distance (SPEC §6, "Elastic limit over a critical distance").

Every test compares with a value predicted independently of the code under test: exact
homogeneous strains, hand-computed disc weights, the global area-weighted mean, the norm
inequality, beam theory and the corner-singularity growth of the element strains.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure import Part, mesh_part
from deformclosure.elasticity import (FreeBodySolver, averaged_strain_magnitude, averaged_strains,
                                      averaging_operator, default_critical_distance,
                                      element_strains, stiffness_matrix)
from deformclosure.errors import GraspError
from deformclosure.mesh.core import Mesh

MM = 1e-3

#: L-shaped part (mm): 20 × 20 with an 12 × 12 square removed; re-entrant (270°) corner at
#: (8, 8). Diameter 20√2 mm (between (20, 0) and (0, 20)).
L_OUTER = [[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]
L_CORNER = np.array([8.0, 8.0]) * MM


def _l_part() -> Part:
    return Part.from_dict({
        "name": "L", "units": "mm", "outer": L_OUTER,
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": "stress"},
    })


def _magnitude(strains: np.ndarray) -> np.ndarray:
    """Largest absolute eigenvalue of the 2×2 strain tensor, from numpy's eigvalsh."""
    e = np.asarray(strains).reshape(-1, 3)
    T = np.empty((len(e), 2, 2))
    T[:, 0, 0], T[:, 1, 1] = e[:, 0], e[:, 1]
    T[:, 0, 1] = T[:, 1, 0] = 0.5 * e[:, 2]
    return np.abs(np.linalg.eigvalsh(T)).max(axis=1).reshape(np.shape(strains)[:-1])


# --------------------------------------------------------------------------- defaults, errors
def test_default_is_two_percent_of_the_diameter():
    part = _l_part()
    assert part.diameter == pytest.approx(20 * math.sqrt(2) * MM, rel=1e-12)
    assert default_critical_distance(part.diameter) == pytest.approx(0.4 * math.sqrt(2) * MM,
                                                                     rel=1e-12)
    assert default_critical_distance(0.5) == pytest.approx(0.01, rel=1e-15)


@pytest.mark.parametrize("bad", [-1e-6, -np.inf, np.inf, np.nan])
def test_invalid_critical_distance_is_refused(plate_mesh, bad):
    with pytest.raises(GraspError, match="critical_distance") as info:
        averaging_operator(plate_mesh, bad)
    assert "\n" not in str(info.value)
    e = np.zeros((plate_mesh.n_triangles, 3))
    with pytest.raises(GraspError, match="critical_distance"):
        averaged_strains(plate_mesh, e, bad)
    with pytest.raises(GraspError, match="critical_distance"):
        averaged_strain_magnitude(plate_mesh, e, bad)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_invalid_diameter_is_refused(bad):
    with pytest.raises(GraspError, match="diameter"):
        default_critical_distance(bad)


# --------------------------------------------------------------------------- 1. patch test
@pytest.mark.parametrize("seed", [0, 1])
def test_homogeneous_strain_is_unchanged_by_averaging(plate_mesh, seed):
    rng = np.random.default_rng(seed)
    A = rng.uniform(-1e-2, 1e-2, size=(2, 2))
    u = plate_mesh.nodes @ A.T + rng.uniform(-1e-3, 1e-3, size=2)
    want = np.array([A[0, 0], A[1, 1], A[0, 1] + A[1, 0]])     # exx, eyy, gamma_xy
    # The largest absolute eigenvalue of the symmetric part of A.
    want_mag = np.abs(np.linalg.eigvalsh(0.5 * (A + A.T))).max()
    e = element_strains(plate_mesh, u)
    m = plate_mesh.n_triangles
    diam = plate_mesh.diameter
    for ell in (0.0, 1e-4, default_critical_distance(diam), 0.2 * diam, 2.0 * diam):
        avg = averaged_strains(plate_mesh, e, ell)
        assert avg.shape == (m, 3)
        np.testing.assert_allclose(avg, np.broadcast_to(want, (m, 3)), rtol=0,
                                   atol=1e-12 * np.abs(A).max(), err_msg=f"ell = {ell}")
        np.testing.assert_allclose(averaged_strain_magnitude(plate_mesh, e, ell), want_mag,
                                   rtol=1e-10, err_msg=f"ell = {ell}")
    # A stack of two homogeneous fields (the second doubled) with a reused operator.
    W = averaging_operator(plate_mesh, 0.1 * diam)
    stack = np.stack([e, 2.0 * e])
    avg = averaged_strains(plate_mesh, stack, None, operator=W)
    assert avg.shape == (2, m, 3)
    np.testing.assert_allclose(avg[1], np.broadcast_to(2.0 * want, (m, 3)), rtol=0,
                               atol=1e-12 * np.abs(A).max())
    mag = averaged_strain_magnitude(plate_mesh, stack, None, operator=W)
    assert mag.shape == (2, m)
    np.testing.assert_allclose(mag, np.array([[want_mag], [2 * want_mag]]) * np.ones((2, m)),
                               rtol=1e-10)


# --------------------------------------------------------------------------- 2. the operator
@pytest.mark.parametrize("frac", [0.0, 0.005, 0.02, 0.1])
def test_operator_is_row_stochastic_with_positive_diagonal(plate_mesh, frac):
    ell = frac * plate_mesh.diameter
    W = averaging_operator(plate_mesh, ell)
    m = plate_mesh.n_triangles
    assert W.shape == (m, m)
    np.testing.assert_allclose(np.asarray(W.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-13)
    assert W.data.min() >= 0.0
    assert W.diagonal().min() > 0.0
    if ell == 0.0:
        np.testing.assert_array_equal(W.toarray(), np.eye(m))
    else:
        # Non-zeros are exactly the centroid pairs within ell (brute force distances).
        c = plate_mesh.nodes[plate_mesh.triangles].mean(axis=1)
        d = np.linalg.norm(c[:, None] - c[None], axis=-1)
        np.testing.assert_array_equal(W.toarray() > 0, d <= ell)


def test_operator_weights_on_a_hand_computed_mesh():
    # Quadrilateral (0,0),(2,0),(1,1),(0,1) cut along (0,0)-(1,1): areas 1 and 1/2,
    # centroids (1, 1/3) and (1/3, 2/3), √5/3 ≈ 0.745 apart.
    mesh = Mesh.from_arrays(np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
                            np.array([[0, 1, 2], [0, 2, 3]]))
    gap = math.sqrt(5) / 3
    np.testing.assert_allclose(averaging_operator(mesh, gap - 1e-9).toarray(), np.eye(2))
    np.testing.assert_allclose(averaging_operator(mesh, gap + 1e-9).toarray(),
                               [[2 / 3, 1 / 3], [2 / 3, 1 / 3]], rtol=1e-14)
    e = np.array([[0.03, 0.0, 0.0], [0.0, 0.0, 0.06]])        # uniaxial x, pure shear
    avg = averaged_strains(mesh, e, 1.0)
    np.testing.assert_allclose(avg, [[0.02, 0.0, 0.02]] * 2, rtol=1e-14)
    # Tensor [[0.02, 0.01], [0.01, 0]]: eigenvalues 0.01 ± √2·0.01.
    np.testing.assert_allclose(averaged_strain_magnitude(mesh, e, 1.0),
                               0.01 * (1 + math.sqrt(2)), rtol=1e-14)


# --------------------------------------------------------------------------- 3. properties
@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), log_scale=st.floats(-6, 0),
       frac=st.floats(0.0, 0.3), spikes=st.integers(0, 5))
def test_averaged_magnitude_never_exceeds_the_element_maximum(plate_mesh, seed, log_scale,
                                                               frac, spikes):
    rng = np.random.default_rng(seed)
    m = plate_mesh.n_triangles
    e = rng.normal(size=(m, 3)) * 10.0**log_scale
    if spikes:   # a few large, singular-looking elements
        e[rng.integers(0, m, spikes)] *= rng.uniform(10, 1000, size=(spikes, 1))
    bound = _magnitude(e).max()
    mag = averaged_strain_magnitude(plate_mesh, e, frac * plate_mesh.diameter)
    assert mag.shape == (m,)
    assert mag.max() <= bound * (1 + 1e-12), (mag.max(), bound)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(1, 3), over=st.floats(1.0, 10.0))
def test_disc_larger_than_the_part_gives_the_global_area_weighted_mean(plate_mesh, seed, k,
                                                                         over):
    rng = np.random.default_rng(seed)
    m = plate_mesh.n_triangles
    e = rng.normal(size=(k, m, 3)) * 1e-2
    p = plate_mesh.nodes[plate_mesh.triangles]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))
    mean = np.einsum("m,kmc->kc", area, e) / area.sum()          # (k, 3)
    ell = over * plate_mesh.diameter
    avg = averaged_strains(plate_mesh, e, ell)
    assert avg.shape == (k, m, 3)
    np.testing.assert_allclose(avg, np.broadcast_to(mean[:, None, :], (k, m, 3)),
                               rtol=0, atol=1e-14)
    single = averaged_strains(plate_mesh, e[0], ell)
    np.testing.assert_allclose(single, np.broadcast_to(mean[0], (m, 3)), rtol=0, atol=1e-14)
    mag = averaged_strain_magnitude(plate_mesh, e, ell)
    assert mag.shape == (k, m)
    np.testing.assert_allclose(mag, np.broadcast_to(_magnitude(mean)[:, None], (k, m)),
                               rtol=1e-10)


# --------------------------------------------------------------------------- 4. convergence
def _opening_load(mesh, total: float) -> np.ndarray:
    """Pull the two arm ends of the L apart along the line joining their mid-points.

    Force ``total`` (N) on the end edge x = 20 mm in direction (1, -1)/√2 and on the end
    edge y = 20 mm in direction (-1, 1)/√2, each spread over the edge's nodes in
    proportion to their tributary length (a uniform traction, whose resultant passes
    through the edge mid-point): zero net force and moment, independent of the mesh.
    """
    x = mesh.nodes
    be = mesh.boundary_edges
    f = np.zeros((mesh.n_nodes, 2))
    d = np.array([1.0, -1.0]) / math.sqrt(2)
    for axis, sign in ((0, 1.0), (1, -1.0)):
        on = np.all(np.abs(x[be, axis] - 20 * MM) < 1e-9 * MM, axis=1)
        edges = be[on]
        length = np.linalg.norm(x[edges[:, 1]] - x[edges[:, 0]], axis=1)
        trib = np.bincount(edges.ravel(), np.repeat(0.5 * length, 2), minlength=mesh.n_nodes)
        assert trib.sum() == pytest.approx(8 * MM, rel=1e-12)
        f += sign * total * (trib / trib.sum())[:, None] * d
    return f.ravel()


def test_averaged_strain_converges_at_a_reentrant_corner_while_element_maximum_grows():
    """SPEC §6: element max strain at the inside corner of an L diverges under refinement
    (like h^(λ-1), λ = 0.5445 for a 270° corner: ×1.37 per halving of h); the strain averaged
    over ℓ = 2 % of the diameter converges."""
    part = _l_part()
    ell = default_critical_distance(part.diameter)                      # 0.566 mm
    total = 0.1                                                          # N
    max_areas_mm2 = [0.8, 0.2, 0.05, 0.0125]                             # h halves each time
    elem_max, avg_max, nodes, per_disc = [], [], [], []
    for a in max_areas_mm2:
        mesh = mesh_part(part, max_area=a * MM**2)
        f = _opening_load(mesh, total)
        fx, fy = f[0::2], f[1::2]
        x, y = mesh.nodes.T
        assert abs(fx.sum()) + abs(fy.sum()) < 1e-12 * total
        assert abs((x * fy - y * fx).sum()) < 1e-12 * total * part.diameter
        u = FreeBodySolver(stiffness_matrix(mesh), mesh.nodes).solve(f)
        e = element_strains(mesh, u)
        W = averaging_operator(mesh, ell)
        elem = _magnitude(e)
        avg = averaged_strain_magnitude(mesh, e, ell, operator=W)
        centroids = mesh.nodes[mesh.triangles].mean(axis=1)
        # Both maxima sit at the re-entrant corner.
        assert np.linalg.norm(centroids[elem.argmax()] - L_CORNER) < 1.0 * MM
        assert np.linalg.norm(centroids[avg.argmax()] - L_CORNER) < 2.0 * ell
        elem_max.append(elem.max())
        avg_max.append(avg.max())
        nodes.append(mesh.n_nodes)
        per_disc.append(W.nnz / mesh.n_triangles)
    elem_max, avg_max = np.array(elem_max), np.array(avg_max)
    report = (f"ell = {ell / MM:.4f} mm, max_area = {max_areas_mm2} mm², nodes = {nodes}, "
              f"elements per disc = {np.round(per_disc, 1).tolist()}, "
              f"element max = {np.round(elem_max, 5).tolist()}, "
              f"averaged max = {np.round(avg_max, 5).tolist()}")
    assert per_disc[-1] > 20, report
    growth = elem_max[1:] / elem_max[:-1]
    assert np.all(growth > 1.15), f"element max growth per halving {growth}; {report}"
    diffs = np.abs(np.diff(avg_max))
    assert np.all(diffs[1:] < diffs[:-1]), f"averaged max differences {diffs}; {report}"
    rel = diffs[-1] / avg_max[-1]
    assert rel < 0.05, f"final relative change {rel:.4f}; {report}"
    # Independent scale: beam theory at the section y = 8 mm of the vertical arm (depth
    # b = 8 mm, t = 1 mm). The load line x + y = 24 mm passes 12/√2 mm from the section
    # centroid (4, 8) mm: bending M = total·8.485 mm plus axial total/√2, so the nominal
    # strain at the inside fibre is (6M/(t b²) + N/(t b)) / E. The corner concentrates
    # it, the disc average stays finite: between 1 and 3 times the nominal strain.
    b, t, E = 8 * MM, 1 * MM, 2e6
    M = total * 12 / math.sqrt(2) * MM
    nominal = (6 * M / (t * b**2) + total / math.sqrt(2) / (t * b)) / E      # ≈ 0.044
    assert nominal < avg_max[-1] < 3 * nominal, f"nominal {nominal:.4f}; {report}"
    assert elem_max[-1] > 3 * nominal, f"nominal {nominal:.4f}; {report}"
