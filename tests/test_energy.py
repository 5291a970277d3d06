"""Energies of configurations (paper §3.1) and frame invariance (paper Thm 2)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure import FreeBodySolver, Part, mesh_part, stiffness_matrix
from deformclosure.dspace import (corotational_energy, deformation_gradients, element_energies, linear_energy,
                                  polar_rotation, strain_energy)
from deformclosure.errors import DeformClosureError

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002, "elastic_limit_strain": 0.5}


@pytest.fixture(scope="module")
def mesh():
    """An L-shaped plate with a hole-free reflex corner, ~150 nodes."""
    part = Part.from_dict({"name": "L", "units": "m", "outer": [[0, 0], [0.04, 0], [0.04, 0.02], [0.02, 0.02],
                                                                [0.02, 0.04], [0, 0.04]],
                           "material": MAT, "mesh": {"max_area": 1.2e-5}})
    return mesh_part(part)


def _rot(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def _deformed(mesh, rng, amp=2e-3):
    return mesh.nodes + amp * rng.standard_normal(mesh.nodes.shape) * 0.1


def test_linear_energy_equals_half_XKX(mesh):
    rng = np.random.default_rng(1)
    K = stiffness_matrix(mesh)
    Q = np.stack([_deformed(mesh, rng) for _ in range(4)])
    X = (Q - mesh.nodes).reshape(4, -1)
    ref = 0.5 * np.einsum("bi,ib->b", X, K @ X.T)
    assert np.allclose(linear_energy(mesh, Q), ref, rtol=1e-12)
    assert np.allclose(linear_energy(mesh, Q.reshape(4, -1), stiffness=K), ref, rtol=1e-12)
    assert linear_energy(mesh, Q[0]) == pytest.approx(ref[0], rel=1e-12)
    assert element_energies(mesh, Q).shape == (4, mesh.n_triangles)
    assert strain_energy(mesh, Q[0], "corotational") == pytest.approx(corotational_energy(mesh, Q[0]))


def test_energies_agree_to_second_order(mesh):
    """|U_cr - U_lin| = O(|X|^3) while U = O(|X|^2): log-log slopes 3 and 2."""
    rng = np.random.default_rng(2)
    D = rng.standard_normal(mesh.nodes.shape) * 1e-3
    eps = np.logspace(-4, -1, 7)
    Q = mesh.nodes + eps[:, None, None] * D
    Ul, Uc = linear_energy(mesh, Q), corotational_energy(mesh, Q)
    slope_U = np.polyfit(np.log(eps), np.log(Ul), 1)[0]
    slope_d = np.polyfit(np.log(eps), np.log(np.abs(Uc - Ul)), 1)[0]
    assert slope_U == pytest.approx(2.0, abs=0.01)
    assert slope_d == pytest.approx(3.0, abs=0.15)
    assert abs(Uc[0] - Ul[0]) < 1e-3 * Ul[0]


@settings(max_examples=40, deadline=None)
@given(angle=st.floats(-np.pi, np.pi), tx=st.floats(-1.0, 1.0), ty=st.floats(-1.0, 1.0), seed=st.integers(0, 2**16))
def test_corotational_energy_is_invariant_to_finite_rigid_motions(mesh, angle, tx, ty, seed):
    rng = np.random.default_rng(seed)
    q = _deformed(mesh, rng)
    q2 = q @ _rot(angle).T + [tx, ty]
    U1, U2 = corotational_energy(mesh, q), corotational_energy(mesh, q2)
    assert abs(U2 - U1) <= 1e-10 * U1


@pytest.mark.parametrize("angle", [np.pi / 2, np.pi, -2.5])
def test_corotational_invariance_at_large_angles_and_linear_is_not(mesh, angle):
    """Documented: the linear energy of a rigid rotation is not zero (it grows like
    (1 - cos phi)^2); the corotational one is zero and invariant."""
    rng = np.random.default_rng(3)
    q = _deformed(mesh, rng)
    q2 = q @ _rot(angle).T + [0.3, -0.7]
    assert abs(corotational_energy(mesh, q2) - corotational_energy(mesh, q)) <= 1e-10 * corotational_energy(mesh, q)
    rigid = mesh.nodes @ _rot(angle).T
    assert corotational_energy(mesh, rigid) < 1e-20
    assert linear_energy(mesh, rigid) > 1e12 * max(corotational_energy(mesh, rigid), 1e-30)
    assert linear_energy(mesh, rigid) > 0.1  # J: a finite rotation strains the linear model
    assert linear_energy(mesh, q2) > 2 * linear_energy(mesh, q)


def test_polar_decomposition():
    rng = np.random.default_rng(4)
    F = np.eye(2) + 0.3 * rng.standard_normal((50, 2, 2))
    F = F[np.linalg.det(F) > 0]
    ang, S = polar_rotation(F)
    R = np.stack([_rot(a) for a in ang])
    assert np.allclose(R @ S, F)
    assert np.allclose(S, np.swapaxes(S, 1, 2))
    assert np.all(np.linalg.eigvalsh(S) > 0)


def test_deformation_gradient_of_affine_map(mesh):
    A = np.array([[1.1, 0.2], [-0.05, 0.9]])
    F = deformation_gradients(mesh.nodes, mesh.triangles, mesh.nodes @ A.T + 3.0)
    assert np.allclose(F, A)


def test_bad_kind_and_shape(mesh):
    with pytest.raises(DeformClosureError, match="corotational"):
        element_energies(mesh, mesh.nodes, kind="nonlinear")
    with pytest.raises(DeformClosureError, match="shape"):
        linear_energy(mesh, np.zeros((3, 2)))


# ----------------------------------------------------------------------------- Thm 2


@pytest.mark.parametrize("angle,shift", [(0.7, (0.1, -0.2)), (np.pi, (0.0, 0.0)), (-2.0, (5.0, 3.0))])
def test_theorem2_stiffness_in_a_rotated_frame(mesh, angle, shift):
    """Paper Thm 2: K assembled in a rotated (and translated) frame is T K Tᵀ, and
    energies and displacements are frame invariant."""
    R = _rot(angle)
    mesh2 = mesh.rotated(angle).translated(np.asarray(shift))
    K1, K2 = stiffness_matrix(mesh), stiffness_matrix(mesh2)
    n = mesh.n_nodes
    import scipy.sparse as sp

    T = sp.kron(sp.eye(n), sp.csr_matrix(R)).tocsr()
    diff = K2 - T @ K1 @ T.T
    assert abs(diff).max() <= 1e-12 * abs(K1).max()
    # a self-equilibrated load: a pair of opposite forces between two perimeter nodes
    a, b = mesh.outer_loop[0], mesh.outer_loop[len(mesh.outer_loop) // 2]
    d = mesh.nodes[b] - mesh.nodes[a]
    d /= np.linalg.norm(d)
    f1 = np.zeros(2 * n)
    f1[2 * a:2 * a + 2] = -d
    f1[2 * b:2 * b + 2] = d
    f2 = T @ f1
    s1, s2 = FreeBodySolver(K1, mesh.nodes), FreeBodySolver(K2, mesh2.nodes)
    u1 = s1.project_out_rigid(s1.solve(f1))
    u2 = s2.project_out_rigid(s2.solve(f2))
    assert np.allclose(u2, T @ u1, atol=1e-10 * np.abs(u1).max())
    assert f2 @ u2 == pytest.approx(f1 @ u1, rel=1e-10)
    # energies of configurations: linear and corotational
    q1 = mesh.nodes + u1.reshape(-1, 2)
    q2 = mesh2.nodes + u2.reshape(-1, 2)
    assert linear_energy(mesh2, q2) == pytest.approx(linear_energy(mesh, q1), rel=1e-10)
    assert corotational_energy(mesh2, q2) == pytest.approx(corotational_energy(mesh, q1), rel=1e-10)
