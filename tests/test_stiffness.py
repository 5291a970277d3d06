"""CST stiffness: against scikit-fem, rigid modes, patch test, uniaxial bar, frame invariance."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from deformclosure import (FreeBodySolver, Material, Mesh, Part, StiffnessError, mesh_part,
                           rigid_modes, stiffness_matrix)
from deformclosure.elasticity import constitutive_matrix, element_stiffness


# --------------------------------------------------------------------------- helpers
def skfem_stiffness(mesh: Mesh, material: Material) -> sp.csr_matrix:
    """K assembled by scikit-fem, permuted to our DOF order ``[x0, y0, x1, y1, ...]``."""
    from skfem import Basis, ElementTriP1, ElementVector, MeshTri
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    lam, mu = lame_parameters(material.youngs_modulus, material.poisson_ratio)
    if material.plane == "stress":
        lam = 2 * lam * mu / (lam + 2 * mu)      # plane-stress λ*
    basis = Basis(MeshTri(mesh.nodes.T.copy(), mesh.triangles.T.copy()),
                  ElementVector(ElementTriP1()))
    K = linear_elasticity(lam, mu).assemble(basis) * material.thickness
    # skfem numbers DOFs its own way: nodal_dofs[c, i] is component c of node i.
    perm = np.empty(2 * mesh.n_nodes, dtype=np.int64)
    perm[0::2] = basis.nodal_dofs[0]
    perm[1::2] = basis.nodal_dofs[1]
    return sp.csr_matrix(K)[perm][:, perm]


def rotation_blocks(angle: float, n: int) -> sp.csr_matrix:
    c, s = np.cos(angle), np.sin(angle)
    return sp.block_diag([np.array([[c, -s], [s, c]])] * n, format="csr")


def rectangle(make_part, L=30.0, H=8.0, max_area=4.0, **material):
    """An L × H mm rectangle, x along the length."""
    return make_part([[0, 0], [L, 0], [L, H], [0, H]], max_area=max_area, **material)


def material(plane="stress", nu=0.3, E=5e6, t=2e-3):
    return Material(E, nu, t, 0.5, plane)


# --------------------------------------------------------------------------- scikit-fem
@pytest.mark.parametrize("example", ["plate_with_hole", "l_shape", "ring", "c_shape"])
@pytest.mark.parametrize("plane, nu", [("stress", 0.3), ("strain", 0.3), ("stress", -0.4),
                                       ("strain", 0.45)])
def test_matches_scikit_fem(examples_dir, example, plane, nu):
    mesh = mesh_part(Part.from_file(examples_dir / f"{example}.json"))
    mat = material(plane, nu, E=3.3e6, t=1.7e-3)
    K = stiffness_matrix(mesh, mat)
    Ks = skfem_stiffness(mesh, mat)
    assert K.shape == Ks.shape == (2 * mesh.n_nodes,) * 2
    scale = abs(Ks).max()
    assert abs(K - Ks).max() <= 1e-10 * scale


def test_matches_scikit_fem_on_a_graded_random_mesh(make_part):
    rng = np.random.default_rng(7)
    pts = rng.uniform([1, 1], [29, 7], size=(15, 2))
    mesh = mesh_part(rectangle(make_part, points=pts, max_area=3.0), min_angle=20)
    for plane in ("stress", "strain"):
        mat = material(plane, 0.2)
        Ks = skfem_stiffness(mesh, mat)
        assert abs(stiffness_matrix(mesh, mat) - Ks).max() <= 1e-10 * abs(Ks).max()


def test_mesh_material_is_the_default(plate_mesh):
    K = stiffness_matrix(plate_mesh)
    Ks = skfem_stiffness(plate_mesh, plate_mesh.material)
    assert abs(K - Ks).max() <= 1e-10 * abs(Ks).max()


def test_no_material_is_an_error():
    mesh = Mesh.from_arrays([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]])
    with pytest.raises(StiffnessError, match="material"):
        stiffness_matrix(mesh)


# --------------------------------------------------------------------------- structure
@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_symmetric_psd_with_exactly_three_zero_modes(plate_part, plane):
    mesh = mesh_part(plate_part, max_area=8e-6)
    assert 40 < mesh.n_nodes < 400
    K = stiffness_matrix(mesh, material(plane, 0.35))
    assert sp.isspmatrix_csr(K) or isinstance(K, sp.csr_array)
    Kd = K.toarray()
    assert np.array_equal(Kd, Kd.T) or abs(Kd - Kd.T).max() <= 1e-14 * abs(Kd).max()
    w = np.linalg.eigvalsh(0.5 * (Kd + Kd.T))
    top = w.max()
    assert w.min() >= -1e-11 * top
    zero = np.abs(w) <= 1e-10 * top
    assert zero.sum() == 3
    # The fourth eigenvalue is well separated from round-off.
    assert np.sort(w)[3] > 1e-6 * top
    # And the zero modes are the rigid modes.
    R = rigid_modes(mesh.nodes) / np.array([1.0, 1.0, mesh.diameter])
    assert abs(K @ R).max() <= 1e-11 * top


def test_stiffness_scales_with_e_and_t_and_not_with_size(plate_mesh):
    base = material("stress", 0.25, E=1e6, t=1e-3)
    K = stiffness_matrix(plate_mesh, base)
    K2 = stiffness_matrix(plate_mesh, Material(7e6, 0.25, 3e-3, 0.5))
    assert abs(K2 - 21 * K).max() <= 1e-12 * abs(K2).max()
    # In 2-D a CST stiffness is invariant under uniform scaling of the geometry.
    big = Mesh.from_arrays(plate_mesh.nodes * 13.0, plate_mesh.triangles)
    assert abs(stiffness_matrix(big, base) - K).max() <= 1e-12 * abs(K).max()


def test_single_right_triangle_closed_form():
    # Unit right triangle, plane stress, nu = 0: D = E diag(1, 1, 1/2), area 1/2.
    # Worked by hand: B = [[-1,0,1,0,0,0], [0,-1,0,0,0,1], [-1,-1,0,1,1,0]], Ke = t A BᵀDB.
    E, t = 4.0, 1.0
    Ke = element_stiffness(np.array([[0.0, 0], [1, 0], [0, 1]]), np.array([[0, 1, 2]]),
                           Material(E, 0.0, t, 1.0))[0]
    want = (E * t / 4) * np.array([
        [3, 1, -2, -1, -1, 0],
        [1, 3, 0, -1, -1, -2],
        [-2, 0, 2, 0, 0, 0],
        [-1, -1, 0, 1, 1, 0],
        [-1, -1, 0, 1, 1, 0],
        [0, -2, 0, 0, 0, 2],
    ], float)
    np.testing.assert_allclose(Ke, want, rtol=0, atol=1e-14)


def test_constitutive_matrices():
    E, nu = 2.0, 0.25
    Ds = constitutive_matrix(Material(E, nu, 1.0, 1.0, "stress"))
    De = constitutive_matrix(Material(E, nu, 1.0, 1.0, "strain"))
    # Plane stress: uniaxial stress gives Young's modulus and the Poisson contraction.
    strain = np.linalg.solve(Ds, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(strain, [1 / E, -nu / E, 0.0], rtol=1e-14, atol=1e-16)
    # Plane strain = 3-D isotropic law restricted to eps_zz = 0.
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    np.testing.assert_allclose(De, [[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]],
                               rtol=1e-14)
    np.testing.assert_allclose(Ds[2, 2], mu, rtol=1e-14)


# --------------------------------------------------------------------------- patch tests
def test_linear_field_loads_only_boundary_nodes(plate_mesh):
    """Patch test (equilibrium form): constant stress has zero divergence, so the nodal
    forces ``K u`` of a linear field vanish at interior nodes and are the consistent
    traction loads ``t ∫ σ·n N_i ds`` on the boundary."""
    A = np.array([[1.3e-3, -0.4e-3], [0.7e-3, -2.1e-3]])
    u = (plate_mesh.nodes @ A.T + [1e-4, -3e-4]).ravel()
    K = stiffness_matrix(plate_mesh)
    f = (K @ u).reshape(-1, 2)
    interior = plate_mesh.loop_of() < 0
    scale = np.abs(f).max()
    assert interior.sum() > 10 and scale > 0
    assert np.abs(f[interior]).max() <= 1e-10 * scale
    # Boundary loads from the constant stress, edge by edge (half to each end node).
    eps = np.array([A[0, 0], A[1, 1], A[0, 1] + A[1, 0]])
    sxx, syy, sxy = constitutive_matrix(plate_mesh.material) @ eps
    S = np.array([[sxx, sxy], [sxy, syy]])
    want = np.zeros_like(f)
    for a, b in plate_mesh.boundary_edges:
        d = plate_mesh.nodes[b] - plate_mesh.nodes[a]
        n_len = np.array([d[1], -d[0]])         # outward normal × length (interior on the left)
        traction = plate_mesh.material.thickness * S @ n_len
        want[a] += traction / 2
        want[b] += traction / 2
    np.testing.assert_allclose(f, want, atol=1e-10 * scale)


def _uniaxial_energy(mesh: Mesh, K: sp.spmatrix, L: float,
                     delta: float) -> tuple[float, np.ndarray]:
    """Stretch by ``delta`` along x: ``u_x = 0`` at x = 0, ``u_x = delta`` at x = L, one
    ``u_y`` fixed; all other DOFs free. Returns the energy ½ uᵀKu and ``u``."""
    x = mesh.nodes[:, 0]
    tol = 1e-9 * L
    left, right = np.flatnonzero(np.abs(x) < tol), np.flatnonzero(np.abs(x - L) < tol)
    n2 = 2 * mesh.n_nodes
    u = np.zeros(n2)
    fixed = np.concatenate([2 * left, 2 * right, [2 * left[0] + 1]])
    u[2 * right] = delta
    free = np.setdiff1d(np.arange(n2), fixed)
    K = sp.csr_matrix(K)
    u[free] = spla.spsolve(K[free][:, free].tocsc(), -K[free][:, fixed] @ u[fixed])
    return 0.5 * u @ (K @ u), u


@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_uniaxial_tension_energy(make_part, plane):
    L, H, t_mm, E, nu, delta = 30.0, 8.0, 2.0, 5e6, 0.3, 0.15e-3
    part = rectangle(make_part, L, H, max_area=3.0, youngs_modulus=E, poisson_ratio=nu,
                     thickness=t_mm, plane=plane)
    mesh = mesh_part(part)
    K = stiffness_matrix(mesh)
    U, u = _uniaxial_energy(mesh, K, L * 1e-3, delta)
    E_eff = E if plane == "stress" else E / (1 - nu**2)
    A = H * 1e-3 * t_mm * 1e-3
    assert U == pytest.approx(0.5 * E_eff * A * delta**2 / (L * 1e-3), rel=1e-9)
    # The solution is the exact linear field: lateral contraction with the effective ratio.
    nu_eff = nu if plane == "stress" else nu / (1 - nu)
    uy = u[1::2] - u[1::2].mean()
    want = -nu_eff * delta / (L * 1e-3) * (mesh.nodes[:, 1] - mesh.nodes[:, 1].mean())
    np.testing.assert_allclose(uy, want, atol=1e-9 * delta)


# --------------------------------------------------------------------------- frame invariance
@pytest.mark.parametrize("angle", [0.3, 2.0, -np.pi / 2])
def test_frame_invariance(plate_mesh, angle):
    """Paper Thm 2: energies do not depend on the frame. K₂ = T K₁ Tᵀ."""
    K1 = stiffness_matrix(plate_mesh)
    moved = plate_mesh.rotated(angle, center=[0.01, -0.02]).translated([0.5, -1.25])
    K2 = stiffness_matrix(moved)
    T = rotation_blocks(angle, plate_mesh.n_nodes)
    scale = abs(K1).max()
    assert abs(K2 - T @ K1 @ T.T).max() <= 1e-9 * scale
    rng = np.random.default_rng(3)
    u1 = rng.standard_normal(2 * plate_mesh.n_nodes) * 1e-4
    u2 = T @ u1
    assert u2 @ (K2 @ u2) == pytest.approx(u1 @ (K1 @ u1), rel=1e-9)
    # Not a tautology: an unrotated displacement on the rotated part has another energy.
    assert abs(u1 @ (K2 @ u1) - u1 @ (K1 @ u1)) > 1e-3 * (u1 @ (K1 @ u1))


# --------------------------------------------------------------------------- free-body solves
def test_free_body_solver_on_every_example(examples_dir):
    rng = np.random.default_rng(1)
    for f in sorted(examples_dir.glob("*.json")):
        mesh = mesh_part(Part.from_file(f))
        K = stiffness_matrix(mesh)
        solver = FreeBodySolver(K, mesh.nodes)
        R = rigid_modes(mesh.nodes)
        F = rng.standard_normal((2 * mesh.n_nodes, 3))
        F -= R @ np.linalg.lstsq(R, F, rcond=None)[0]
        U = solver.solve(F)
        np.testing.assert_allclose(K @ U, F, atol=1e-9 * np.abs(F).max(), err_msg=f.name)
        assert np.all(np.einsum("ij,ij->j", F, U) > 0)
        # Rigid part of u is irrelevant: removing it changes neither fᵀu nor K u.
        V = solver.project_out_rigid(U)
        np.testing.assert_allclose(np.einsum("ij,ij->j", F, V), np.einsum("ij,ij->j", F, U),
                                   rtol=1e-10)
        np.testing.assert_allclose(R.T @ V, 0, atol=1e-12 * np.abs(R.T @ U).max() + 1e-30)


# --------------------------------------------------------------------------- second algorithms
def test_closed_form_element_stiffness_equals_t_a_bt_d_b(plate_mesh):
    from deformclosure.elasticity import element_b_matrices

    for plane in ("stress", "strain"):
        mat = material(plane, 0.3)
        B, area = element_b_matrices(plate_mesh.nodes, plate_mesh.triangles)
        D = constitutive_matrix(mat)
        want = np.einsum("mji,jk,mkl->mil", B, D, B) * (mat.thickness * np.abs(area))[:, None, None]
        got = element_stiffness(plate_mesh.nodes, plate_mesh.triangles, mat)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * np.abs(want).max())


def _dense_assembly(triangles, Ke, n):
    """Reference: the textbook loop over elements into a dense matrix."""
    K = np.zeros((2 * n, 2 * n))
    for tri, ke in zip(triangles, Ke):
        dofs = np.ravel([[2 * i, 2 * i + 1] for i in tri])
        K[np.ix_(dofs, dofs)] += ke
    return K


def _assert_canonical(K):
    """Sorted, duplicate-free column indices in every row (checked independently)."""
    for i in range(K.shape[0]):
        cols = K.indices[K.indptr[i]:K.indptr[i + 1]]
        assert np.all(np.diff(cols) > 0)


def test_assembly_against_the_textbook_loop(make_part):
    from deformclosure.elasticity import assemble

    mesh = mesh_part(make_part([[0, 0], [10, 0], [10, 6], [4, 9], [0, 6]], max_area=3.0))
    Ke = element_stiffness(mesh.nodes, mesh.triangles, mesh.material)
    want = _dense_assembly(mesh.triangles, Ke, mesh.n_nodes)
    K = stiffness_matrix(mesh)
    np.testing.assert_allclose(K.toarray(), want, rtol=0, atol=1e-13 * np.abs(want).max())
    _assert_canonical(K)
    # The general assembler with non-symmetric element matrices (orientation of every
    # local edge matters then).
    rng = np.random.default_rng(5)
    R = rng.standard_normal(Ke.shape)
    Kr = assemble(mesh.triangles, R, mesh.n_nodes)
    np.testing.assert_allclose(Kr.toarray(), _dense_assembly(mesh.triangles, R, mesh.n_nodes),
                               rtol=0, atol=1e-12)
    _assert_canonical(Kr)
    # The pattern is the graph of the mesh: a 2×2 block per node and per edge direction.
    n_edges = len({tuple(sorted((int(t[i]), int(t[(i + 1) % 3])))) for t in mesh.triangles
                   for i in range(3)})
    assert K.nnz == 4 * (mesh.n_nodes + 2 * n_edges)


def test_repeated_assembly_reuses_the_pattern_and_agrees(plate_mesh):
    K1 = stiffness_matrix(plate_mesh)
    K2 = stiffness_matrix(plate_mesh, material("strain", 0.2))
    fresh = Mesh.from_arrays(plate_mesh.nodes, plate_mesh.triangles)
    K3 = stiffness_matrix(fresh, material("strain", 0.2))
    assert abs(K2 - K3).max() == 0.0
    assert abs(K1 - stiffness_matrix(plate_mesh)).max() == 0.0
    assert abs(K1 - K2).max() > 0
