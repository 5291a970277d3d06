"""Element strains, principal strains and the strain magnitude (SPEC §1)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from deformclosure import element_strains, principal_strains, strain_magnitude
from deformclosure.elasticity import element_stresses


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_patch_test_linear_field_gives_exact_constant_strain(plate_mesh, seed):
    rng = np.random.default_rng(seed)
    A = rng.uniform(-1e-2, 1e-2, size=(2, 2))
    c = rng.uniform(-1e-3, 1e-3, size=2)
    u = plate_mesh.nodes @ A.T + c
    want = np.array([A[0, 0], A[1, 1], A[0, 1] + A[1, 0]])       # exx, eyy, gamma_xy
    for shape in (u, u.ravel()):
        e = element_strains(plate_mesh, shape)
        assert e.shape == (plate_mesh.n_triangles, 3)
        np.testing.assert_allclose(e, np.broadcast_to(want, e.shape), rtol=0,
                                   atol=1e-12 * np.abs(A).max())


def test_rigid_motion_has_no_strain(plate_mesh):
    theta = 1e-3   # infinitesimal rotation about an arbitrary point plus a translation
    x, y = (plate_mesh.nodes - [0.011, 0.004]).T
    u = np.column_stack([-theta * y + 2e-3, theta * x - 5e-4])
    assert np.abs(element_strains(plate_mesh, u)).max() <= 1e-12 * theta
    assert strain_magnitude(plate_mesh, u).max() <= 1e-12 * theta


def test_uniaxial_and_shear_magnitudes(plate_mesh):
    x, y = plate_mesh.nodes.T
    # Uniaxial 2% stretch with Poisson contraction 0.3: principal (0.02, -0.006).
    u = np.column_stack([0.02 * x, -0.006 * y])
    np.testing.assert_allclose(principal_strains(element_strains(plate_mesh, u)),
                               np.broadcast_to([0.02, -0.006], (plate_mesh.n_triangles, 2)),
                               atol=1e-14)
    np.testing.assert_allclose(strain_magnitude(plate_mesh, u), 0.02, rtol=1e-12)
    # Compression dominates: magnitude is the largest *absolute* principal strain.
    u = np.column_stack([0.01 * x, -0.03 * y])
    np.testing.assert_allclose(strain_magnitude(plate_mesh, u), 0.03, rtol=1e-12)
    # Simple shear gamma: principal strains ±gamma/2 at 45°.
    g = 0.04
    u = np.column_stack([g * y, 0 * x])
    np.testing.assert_allclose(principal_strains(element_strains(plate_mesh, u)),
                               np.broadcast_to([g / 2, -g / 2], (plate_mesh.n_triangles, 2)),
                               atol=1e-14)


def test_stresses_of_uniaxial_plane_stress(plate_mesh):
    mat = plate_mesh.material
    assert mat.plane == "stress"
    e = 1e-3
    x, y = plate_mesh.nodes.T
    u = np.column_stack([e * x, -mat.poisson_ratio * e * y])
    s = element_stresses(plate_mesh, u)
    want = np.broadcast_to([mat.youngs_modulus * e, 0.0, 0.0], s.shape)
    np.testing.assert_allclose(s, want, atol=1e-9 * mat.youngs_modulus * e)


def test_wrong_displacement_shape_is_refused(plate_mesh):
    with pytest.raises(ValueError, match="shape"):
        element_strains(plate_mesh, np.zeros(2 * plate_mesh.n_nodes + 1))


@settings(max_examples=30, deadline=None)
@given(arrays(np.float64, (20, 3), elements=st.floats(-1, 1)))
def test_principal_strains_are_eigenvalues_of_the_strain_tensor(strains):
    p = principal_strains(strains)
    tensors = np.stack([np.stack([strains[:, 0], strains[:, 2] / 2], -1),
                        np.stack([strains[:, 2] / 2, strains[:, 1]], -1)], -2)
    w = np.linalg.eigvalsh(tensors)[:, ::-1]        # descending
    np.testing.assert_allclose(p, w, atol=1e-12)
    assert np.all(p[:, 0] >= p[:, 1])
