"""Pair stiffness k_ab, the condensed compliance, finite-width jaws and e_max.

Independent references: the paper's per-pair Dirichlet solve (§4.2), a dense
pseudo-inverse of K, and a direct sparse KKT solve of the jaw constraints.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import deformclosure as dc
from deformclosure.elasticity import rigid_modes
from deformclosure.elasticity.condense import CondensedCompliance
from deformclosure.elasticity.strain import strain_magnitude
from deformclosure.errors import GraspError
from deformclosure.grasp.elastic_limit import elastic_limit
from deformclosure.grasp.jaws import jaw_patches
from deformclosure.grasp.pair_stiffness import all_pairs, pair_stiffness, pair_stiffness_paper

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1.0,
       "elastic_limit_strain": 0.5, "plane": "stress"}


def _part(outer, holes=(), max_area=4.0, plane="stress"):
    return dc.Part.from_dict({"units": "mm", "outer": outer, "holes": list(holes),
                              "material": {**MAT, "plane": plane},
                              "mesh": {"max_area": max_area, "min_angle": 28}})


@pytest.fixture(scope="module")
def l_mesh():
    return dc.mesh_part(_part([[0, 0], [10, 0], [10, 4], [4, 4], [4, 10], [0, 10]], max_area=3.0))


@pytest.fixture(scope="module")
def holed_mesh():
    hole = [[4, 3], [4, 5], [6, 5], [6, 3]]
    return dc.mesh_part(_part([[0, 0], [10, 0], [10, 8], [0, 8]], [hole], max_area=3.0,
                              plane="strain"))


@pytest.mark.parametrize("which", ["l_mesh", "holed_mesh"])
def test_fast_equals_per_pair_dirichlet_for_all_pairs(which, request):
    mesh = request.getfixturevalue(which)
    K = dc.stiffness_matrix(mesh)
    loops = tuple(range(len(mesh.loops)))
    fast = pair_stiffness(mesh, K, loops=loops)
    assert len(fast.pairs) == len(np.concatenate(mesh.loops)) * (len(np.concatenate(mesh.loops)) - 1) // 2
    slow = pair_stiffness_paper(mesh, K, fast.pairs)
    np.testing.assert_allclose(fast.k, slow, rtol=1e-9)
    np.testing.assert_allclose(fast.sigma0, np.linalg.norm(
        mesh.nodes[fast.pairs[:, 0]] - mesh.nodes[fast.pairs[:, 1]], axis=1), rtol=1e-15)


def test_condensed_compliance_matches_dense_pseudo_inverse(holed_mesh):
    mesh = holed_mesh
    K = dc.stiffness_matrix(mesh)
    bnd = np.concatenate(mesh.loops)
    cc = CondensedCompliance(K, mesh.nodes, mesh.triangles, bnd)
    Kp = np.linalg.pinv(K.toarray(), rcond=1e-10)
    rng = np.random.default_rng(1)
    R = rigid_modes(mesh.nodes)
    dofs = np.column_stack([2 * bnd, 2 * bnd + 1]).ravel()
    Rb = R[dofs]
    for _ in range(5):
        f = rng.normal(size=len(dofs))
        f -= Rb @ np.linalg.lstsq(Rb, f, rcond=None)[0]   # self-equilibrated on the boundary
        full = np.zeros(K.shape[0])
        full[dofs] = f
        assert abs(f @ cc.C @ f - full @ Kp @ full) <= 1e-8 * abs(full @ Kp @ full)
        # and the full-field solve reproduces K u = f
        u = cc.solve(full)
        np.testing.assert_allclose(K @ u, full, atol=1e-9 * np.abs(full).max())


def test_stiffness_is_frame_invariant(l_mesh):
    K1 = dc.stiffness_matrix(l_mesh)
    moved = l_mesh.rotated(0.7, center=np.array([0.003, -0.002])).translated([0.05, 0.01])
    K2 = dc.stiffness_matrix(moved)
    a = pair_stiffness(l_mesh, K1)
    b = pair_stiffness(moved, K2)
    np.testing.assert_allclose(a.k, b.k, rtol=1e-9)


def _direct_wide_jaw_k(mesh, K, a, b, width):
    """Sparse KKT with the full K: normal displacements of each patch tied to its jaw."""
    e = mesh.nodes[b] - mesh.nodes[a]
    e /= np.linalg.norm(e)
    Ja, Jb = jaw_patches(mesh.nodes, mesh.loops, np.array([a, b]), width)
    n2 = K.shape[0]
    rows, cols, vals = [], [], []
    r = 0
    for J, jaw_col in ((Ja, n2), (Jb, n2 + 1)):
        for i in J:
            rows += [r, r, r]
            cols += [2 * i, 2 * i + 1, jaw_col]
            vals += [e[0], e[1], -1.0]
            r += 1
    rows += [r, r]
    cols += [n2, n2 + 1]
    vals += [-1.0, 1.0]
    Cm = sp.csr_matrix((vals, (rows, cols)), shape=(r + 1, n2 + 2))
    Kx = sp.block_diag([K, sp.csr_matrix((2, 2))])
    A = sp.bmat([[Kx, Cm.T], [Cm, None]]).toarray()
    rhs = np.zeros(A.shape[0])
    rhs[-1] = -1.0
    x = np.linalg.lstsq(A, rhs, rcond=None)[0]
    u = x[:n2]
    return float(u @ K @ u)


def test_wide_jaws_match_direct_constrained_solve():
    mesh = dc.mesh_part(_part([[0, 0], [12, 0], [12, 10], [0, 10]], max_area=0.6))
    K = dc.stiffness_matrix(mesh)
    a = mesh.find_node([0.0, 0.005], tol=1e-3)
    b = mesh.find_node([0.012, 0.005], tol=1e-3)
    width = 4e-3
    Ja, Jb = jaw_patches(mesh.nodes, mesh.loops, np.array([a, b]), width)
    assert len(Ja) >= 3 and len(Jb) >= 3
    pairs = np.array([[min(a, b), max(a, b)]])
    k = pair_stiffness(mesh, K, pairs=pairs, jaw_width=width).k[0]
    assert k == pytest.approx(_direct_wide_jaw_k(mesh, K, min(a, b), max(a, b), width), rel=1e-8)
    # A wider flat jaw constrains more: stiffer than a point jaw.
    assert k > pair_stiffness(mesh, K, pairs=pairs).k[0]


def test_width_smaller_than_edges_is_point_jaw(l_mesh):
    K = dc.stiffness_matrix(l_mesh)
    pairs = all_pairs(l_mesh.outer_loop)[:50]
    tiny = 1e-9
    np.testing.assert_allclose(pair_stiffness(l_mesh, K, pairs=pairs, jaw_width=tiny).k,
                               pair_stiffness(l_mesh, K, pairs=pairs).k, rtol=1e-10)


def test_e_max_equals_strain_of_dirichlet_solution(l_mesh):
    mesh = l_mesh
    K = dc.stiffness_matrix(mesh)
    cc = CondensedCompliance(K, mesh.nodes, mesh.triangles, np.concatenate(mesh.loops))
    a, b = int(mesh.outer_loop[0]), int(mesh.outer_loop[len(mesh.outer_loop) // 2])
    lim = elastic_limit(mesh, cc, a, b)
    # Independent: paper-style Dirichlet solve u_a = 0, u_b = -e (unit approach).
    lo, hi = min(a, b), max(a, b)
    e = mesh.nodes[hi] - mesh.nodes[lo]
    e /= np.linalg.norm(e)
    fixed = np.array([2 * lo, 2 * lo + 1, 2 * hi, 2 * hi + 1])
    uc = np.array([0.0, 0.0, -e[0], -e[1]])
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    import scipy.sparse.linalg as spla
    u = np.zeros(K.shape[0])
    u[fixed] = uc
    u[free] = spla.spsolve(K[free][:, free].tocsc(), -(K[free][:, fixed] @ uc))
    ref = strain_magnitude(mesh, u)
    assert lim.e_max == pytest.approx(ref.max(), rel=1e-9)
    assert lim.sigma_L == pytest.approx(max(0.0, lim.sigma0 - 0.5 / lim.e_max), rel=1e-12)
    exp = elastic_limit(mesh, cc, a, b, mode="expanding")
    assert exp.sigma_L == pytest.approx(lim.sigma0 + 0.5 / lim.e_max, rel=1e-12)


def test_pair_stiffness_rejects_bad_requests(l_mesh):
    K = dc.stiffness_matrix(l_mesh)
    with pytest.raises(GraspError, match="method"):
        pair_stiffness(l_mesh, K, method="magic")
    with pytest.raises(GraspError, match="width"):
        pair_stiffness(l_mesh, K, jaw_width=-1.0)
    interior = np.setdiff1d(np.arange(l_mesh.n_nodes), np.concatenate(l_mesh.loops))[0]
    with pytest.raises(GraspError, match="perimeter|boundary"):
        pair_stiffness(l_mesh, K, pairs=np.array([[l_mesh.outer_loop[0], interior]]))
