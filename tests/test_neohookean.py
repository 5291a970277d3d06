"""Neo-Hookean law of linear triangles (SPEC §8), each check against an independent value:
finite differences of the energy and the gradient, a homogeneous patch with tractions from
the closed-form stress, the linear CST stiffness at u = 0, a rigid motion of the deformed
configuration, the closed-form uniaxial compression (lateral stretches solved here with
brentq), inversion and bad input. Also ``material.model`` in part files.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from deformclosure import (DeformClosureError, Material, Mesh, Part, PartError, StiffnessError,
                           mesh_part, stiffness_matrix)
from deformclosure.elasticity import NeoHookean, lame_constants
from deformclosure.mesh import mesh_from_dict, mesh_to_dict

PLANES = ("stress", "strain")
E_RUBBER, T = 2e6, 1e-3          # Pa, m


# --------------------------------------------------------------------------- helpers
def block(L=20.0, H=10.0, max_area=8.0, holes=(), plane="stress", nu=0.3) -> Mesh:
    """Unstructured mesh of an L × H mm block (optionally with holes), x along L."""
    part = Part.from_dict({
        "units": "mm", "outer": [[0, 0], [L, 0], [L, H], [0, H]], "holes": list(holes),
        "material": {"youngs_modulus": E_RUBBER, "poisson_ratio": nu, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": plane},
        "mesh": {"max_area": max_area, "min_angle": 25}})
    return mesh_part(part)


_MESHES: dict = {}


def cached_block(**kw) -> Mesh:
    key = tuple(sorted((k, str(v)) for k, v in kw.items()))
    if key not in _MESHES:
        _MESHES[key] = block(**kw)
    return _MESHES[key]


def with_material(mesh: Mesh, plane: str, nu: float) -> Mesh:
    return mesh.with_material(Material(E_RUBBER, nu, T, 0.8, plane))


def homogeneous(mesh: Mesh, F: np.ndarray) -> np.ndarray:
    """u = (F − I) X, shape (2n,)."""
    X = mesh.nodes
    return (X @ (np.asarray(F) - np.eye(2)).T).ravel()


def random_state(mesh: Mesh, seed: int, amplitude: float, roughness: float) -> np.ndarray:
    """A homogeneous deformation of size ``amplitude`` plus nodal noise of ``roughness``
    times the smallest element size (bounded: elements stay uninverted for small noise)."""
    rng = np.random.default_rng(seed)
    F = np.eye(2) + amplitude * rng.uniform(-1, 1, (2, 2))
    h = np.sqrt(mesh.areas.min())
    return homogeneous(mesh, F) + roughness * h * rng.uniform(-1, 1, 2 * mesh.n_nodes)


def thickness_stretch(mu: float, lam: float, J2: float) -> float:
    """Plane stress F33 of this test: the root of S33 ∝ μ(s² − 1) + λ ln(J2 s) = 0 that is
    stable (dS33/ds > 0; the larger one when λ < 0), by brentq."""
    h = lambda s: mu * (s * s - 1.0) + lam * np.log(J2 * s)          # noqa: E731
    lo = np.sqrt(max(-lam / (2 * mu), 0.0)) * (1 + 1e-12) + 1e-300      # h increasing above
    return brentq(h, lo, 1e3, xtol=1e-16, rtol=4 * np.finfo(float).eps, maxiter=500)


def first_piola(mu: float, lam: float, F: np.ndarray, s: float) -> np.ndarray:
    """In-plane P = ∂W/∂F = μF + (λ ln J − μ) F⁻ᵀ of W = μ/2 (I₁ − 3 − 2 ln J) + λ/2 ln²J."""
    J = np.linalg.det(F) * s
    return mu * F + (lam * np.log(J) - mu) * np.linalg.inv(F).T


def fd_gradient(law: NeoHookean, u: np.ndarray, v: np.ndarray, h: float) -> float:
    """Richardson-extrapolated central difference of the energy along v (error O(h⁴))."""
    d = lambda e: (law.energy(u + e * v) - law.energy(u - e * v)) / (2 * e)   # noqa: E731
    return (4 * d(h / 2) - d(h)) / 3


def fd_tangent(law: NeoHookean, u: np.ndarray, v: np.ndarray, h: float) -> np.ndarray:
    """Richardson-extrapolated central difference of the gradient along v."""
    d = lambda e: (law.gradient(u + e * v) - law.gradient(u - e * v)) / (2 * e)   # noqa: E731
    return (4 * d(h / 2) - d(h)) / 3


# --------------------------------------------------------------------------- 1. derivatives
@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31), amplitude=st.floats(0.0, 0.4), roughness=st.floats(0, 0.15),
       plane=st.sampled_from(PLANES), nu=st.sampled_from([-0.3, 0.0, 0.1, 0.3, 0.45]))
def test_gradient_and_tangent_match_finite_differences(seed, amplitude, roughness, plane, nu):
    mesh = with_material(cached_block(max_area=12.0), plane, nu)
    law = NeoHookean(mesh)
    u = random_state(mesh, seed, amplitude, roughness)
    J = np.linalg.det(law.deformation_gradients(u))
    assume(J.min() > 0.2)                         # bounded deformations, far from inversion
    E, g, K = law.energy_gradient_tangent(u)
    assume(np.isfinite(E))                        # ν < 0: S33 = 0 may have no root
    v = np.random.default_rng(seed + 1).standard_normal(law.n_dofs)
    h = 1e-4 * np.sqrt(mesh.areas.min())          # m
    Kv, fd = K @ v, fd_tangent(law, u, v, h)
    # abs: the round-off of the difference quotient, eps E / h with E ≈ ½ h² vᵀKv at rest.
    assert fd_gradient(law, u, v, h) == pytest.approx(
        g @ v, rel=1e-8, abs=1e-9 * np.abs(g) @ np.abs(v) + 1e-6 * h * abs(v @ Kv))
    assert np.linalg.norm(fd - Kv) <= 1e-7 * np.linalg.norm(Kv)
    # The one-pass results are the separate calls'.
    assert E == law.energy(u) and np.array_equal(g, law.gradient(u))
    assert abs(K - law.tangent(u)).max() == 0


@pytest.mark.parametrize("plane", PLANES)
def test_every_entry_of_gradient_and_tangent_matches_finite_differences(plane):
    """Full Jacobians, column by column, on a coarse mesh at a 30 % deformation."""
    mesh = with_material(block(L=6.0, H=4.0, max_area=4.0), plane, 0.4)
    law = NeoHookean(mesh)
    u = random_state(mesh, 7, 0.3, 0.1)
    g, K = law.gradient(u), law.tangent(u).toarray()
    h = 1e-4 * np.sqrt(mesh.areas.min())
    eye = np.eye(law.n_dofs)
    g_fd = np.array([fd_gradient(law, u, e, h) for e in eye])
    K_fd = np.column_stack([fd_tangent(law, u, e, h) for e in eye])
    assert np.abs(g_fd - g).max() <= 1e-8 * np.abs(g).max()
    assert np.abs(K_fd - K).max() <= 1e-7 * np.abs(K).max()
    assert np.array_equal(K, K.T)                 # exactly symmetric


# --------------------------------------------------------------------------- 2. patch test
@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), size=st.floats(0.0, 0.45), plane=st.sampled_from(PLANES),
       nu=st.sampled_from([-0.3, 0.2, 0.45]))
def test_homogeneous_deformation_is_reproduced(seed, size, plane, nu):
    """u = (F − I)X on an unstructured mesh with a hole: every element has F; forces vanish
    at interior nodes; boundary forces are the tractions of the closed-form P (s by brentq)."""
    mesh = with_material(cached_block(holes=([[8, 3], [8, 7], [12, 7], [12, 3]],),
                                      max_area=6.0), plane, nu)
    rng = np.random.default_rng(seed)
    F = np.eye(2) + size * rng.uniform(-1, 1, (2, 2))
    assume(np.linalg.det(F) > 0.3)
    law = NeoHookean(mesh)
    u = homogeneous(mesh, F)
    mu, lam = lame_constants(mesh.material)
    s = 1.0 if plane == "strain" else thickness_stretch(mu, lam, np.linalg.det(F))
    assume(np.isfinite(law.energy(u)))
    assert np.abs(law.deformation_gradients(u) - F).max() <= 1e-12
    assert np.abs(law.out_of_plane_stretch(u) - s).max() <= 1e-12
    C = F.T @ F
    assert np.abs(law.right_cauchy_green(u) - [C[0, 0], C[1, 1], C[0, 1]]).max() <= 1e-12
    # Boundary nodal forces: each boundary edge (reference length ℓ, outward normal N)
    # carries t ℓ P N, half to each end.
    P = first_piola(mu, lam, F, s)
    f_ref = np.zeros((mesh.n_nodes, 2))
    for a, b in mesh.boundary_edges:
        d = mesh.nodes[b] - mesh.nodes[a]                 # loops: outer CCW, holes CW
        N_len = np.array([d[1], -d[0]])                   # outward normal times length
        f_ref[[a, b]] += 0.5 * T * (P @ N_len)
    f = law.gradient(u).reshape(-1, 2)
    scale = np.abs(f_ref).max() + mu * T * np.sqrt(mesh.areas.min())   # + unit-strain force
    interior = np.setdiff1d(np.arange(mesh.n_nodes), mesh.perimeter_nodes)
    assert np.abs(f[interior]).max() <= 1e-12 * scale          # homogeneous stress: no residual
    assert np.abs(f - f_ref).max() <= 1e-12 * scale
    lnJ = np.log(np.linalg.det(F) * s)
    W_ref = mu / 2 * (np.trace(C) + s * s - 3 - 2 * lnJ) + lam / 2 * lnJ**2
    volume = T * mesh.area
    assert law.energy(u) == pytest.approx(W_ref * volume, rel=1e-10, abs=1e-14 * mu * volume)


@pytest.mark.parametrize("plane", PLANES)
def test_rotation_is_stress_free(plane):
    """F = R (closed-form stress-free): zero energy, zero force everywhere, F33 = 1."""
    mesh = with_material(cached_block(max_area=6.0), plane, 0.3)
    law = NeoHookean(mesh)
    c, s = np.cos(0.7), np.sin(0.7)
    u = homogeneous(mesh, [[c, -s], [s, c]])
    mu = lame_constants(mesh.material)[0]
    assert abs(law.energy(u)) <= 1e-14 * mu * T * mesh.area
    assert np.abs(law.gradient(u)).max() <= 1e-13 * mu * T * mesh.diameter
    assert np.abs(law.out_of_plane_stretch(u) - 1).max() <= 1e-14


# --------------------------------------------------------------------------- 3. small strain
@pytest.mark.parametrize("plane", PLANES)
@pytest.mark.parametrize("nu", [-0.4, 0.0, 0.1, 0.3, 0.49])
def test_tangent_at_rest_is_the_cst_stiffness(plane, nu):
    mesh = with_material(cached_block(holes=([[8, 3], [8, 7], [12, 7], [12, 3]],),
                                      max_area=6.0), plane, nu)
    law = NeoHookean(mesh)
    K0, Klin = law.tangent(np.zeros(law.n_dofs)), stiffness_matrix(mesh)
    assert abs(K0 - Klin).max() <= 1e-10 * abs(Klin).max()
    assert law.energy(np.zeros(law.n_dofs)) == 0.0
    assert np.array_equal(law.gradient(np.zeros(law.n_dofs)), np.zeros(law.n_dofs))
    # The same CSR structure as the CST stiffness, for any u (reusable factorisation).
    Ku = law.tangent(random_state(mesh, 3, 0.2, 0.05))
    for A in (K0, Ku):
        assert np.array_equal(A.indptr, Klin.indptr) and np.array_equal(A.indices, Klin.indices)


@pytest.mark.parametrize("plane", PLANES)
def test_small_strain_energy_is_the_linear_energy(plane):
    """Ψ(εv)/(½ ε² vᵀKv) → 1 at rate O(ε): the energy keeps its precision at small strain."""
    mesh = with_material(cached_block(max_area=6.0), plane, 0.3)
    law = NeoHookean(mesh)
    v = random_state(mesh, 11, 1.0, 0.2)
    K = stiffness_matrix(mesh)
    errs = []
    for eps in (1e-3, 1e-4, 1e-5, 1e-6):
        lin = 0.5 * eps**2 * v @ (K @ v)
        errs.append(abs(law.energy(eps * v) / lin - 1))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 8) & (ratios < 12)), errs          # first order in ε
    assert errs[-1] < 1e-5


# --------------------------------------------------------------------------- 4. frame invariance
@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), angle=st.floats(-np.pi, np.pi),
       shift=st.tuples(st.floats(-0.05, 0.05), st.floats(-0.05, 0.05)),
       plane=st.sampled_from(PLANES))
def test_rigid_motion_of_the_deformed_part(seed, angle, shift, plane):
    mesh = with_material(cached_block(max_area=12.0), plane, 0.35)
    law = NeoHookean(mesh)
    u = random_state(mesh, seed, 0.3, 0.1)
    assume(np.linalg.det(law.deformation_gradients(u)).min() > 0.2)
    E, g, K = law.energy_gradient_tangent(u)
    assume(np.isfinite(E))
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s], [s, c]])
    X = mesh.nodes
    x = X + u.reshape(-1, 2)
    u_rot = (x @ R.T + np.asarray(shift) - X).ravel()           # x → R x + b
    E2, g2, K2 = law.energy_gradient_tangent(u_rot)
    assert E2 == pytest.approx(E, rel=1e-12)
    assert np.abs(g2.reshape(-1, 2) - g.reshape(-1, 2) @ R.T).max() <= 1e-10 * np.abs(g).max()
    Rb = sp.block_diag([R] * mesh.n_nodes, format="csr")
    assert abs(K2 - Rb @ K @ Rb.T).max() <= 1e-10 * abs(K).max()


# --------------------------------------------------------------------------- 5. uniaxial
def uniaxial_closed_form(plane: str, mu: float, lam: float, l1: float):
    """Lateral stretches of a uniaxial stretch l1 with stress-free sides, from the principal
    stresses P_i = ∂W/∂λ_i = μλ_i + (λ ln J − μ)/λ_i (J = λ1 λ2 λ3), by brentq. Plane
    strain: λ3 = 1, P2 = 0. Plane stress: P2 = P3 = 0, λ3 solved inside for each λ2 (no
    symmetry assumed). Returns (λ2, λ3, W, P1)."""
    P = lambda li, J: mu * li + (lam * np.log(J) - mu) / li                  # noqa: E731
    tight = dict(xtol=1e-16, rtol=4 * np.finfo(float).eps, maxiter=500)

    def l3_of(l2):
        if plane == "strain":
            return 1.0
        return brentq(lambda l3: P(l3, l1 * l2 * l3), 0.05, 20.0, **tight)

    l2 = brentq(lambda l2: P(l2, l1 * l2 * l3_of(l2)), 0.05, 20.0, **tight)
    l3 = l3_of(l2)
    J = l1 * l2 * l3
    W = mu / 2 * (l1**2 + l2**2 + l3**2 - 3 - 2 * np.log(J)) + lam / 2 * np.log(J) ** 2
    return l2, l3, W, P(l1, J)


@pytest.mark.parametrize("plane", PLANES)
@pytest.mark.parametrize("nu", [0.1, 0.3, 0.45])
@pytest.mark.parametrize("compression", [0.01, 0.1, 0.25, 0.4])
def test_uniaxial_compression_closed_form(plane, nu, compression):
    L, H = 20.0, 10.0
    mesh = with_material(cached_block(L=L, H=H, max_area=8.0), plane, nu)
    law = NeoHookean(mesh)
    mu, lam = lame_constants(mesh.material)
    l1 = 1.0 - compression
    l2, l3, W, P1 = uniaxial_closed_form(plane, mu, lam, l1)
    u = homogeneous(mesh, np.diag([l1, l2]))
    volume = T * (L * 1e-3) * (H * 1e-3)
    assert law.energy(u) == pytest.approx(W * volume, rel=1e-10)
    assert np.abs(law.out_of_plane_stretch(u) - l3).max() <= 1e-12
    f = law.gradient(u).reshape(-1, 2)
    X = mesh.nodes
    right = np.isclose(X[:, 0], L * 1e-3, atol=1e-9)
    left = np.isclose(X[:, 0], 0.0, atol=1e-9)
    axial = P1 * T * H * 1e-3                    # nominal stress × reference cross-section (N)
    assert f[right, 0].sum() == pytest.approx(axial, rel=1e-10)
    assert f[left, 0].sum() == pytest.approx(-axial, rel=1e-10)
    # Stress-free sides: no y-force anywhere (to round-off of the axial force).
    assert np.abs(f[:, 1]).max() <= 1e-10 * abs(axial)
    assert P1 < 0                                # compression needs a compressive force


# --------------------------------------------------------------------------- 6. bad cases
@pytest.mark.parametrize("plane", PLANES)
def test_inverted_element_gives_infinite_energy(plane):
    mesh = with_material(cached_block(max_area=12.0), plane, 0.3)
    law = NeoHookean(mesh)
    interior = np.setdiff1d(np.arange(mesh.n_nodes), mesh.perimeter_nodes)
    u = np.zeros(law.n_dofs)
    node = interior[0]
    u[2 * node: 2 * node + 2] = 0.02                          # 20 mm: across its neighbours
    x = mesh.nodes + u.reshape(-1, 2)
    p = x[mesh.triangles]
    area2 = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
             - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    inverted = area2 <= 0                                     # deformed orientation, here
    assert inverted.any()
    assert law.energy(u) == np.inf
    We = law.element_energies(u)
    assert np.array_equal(np.isinf(We), inverted) and np.all(We[~inverted] >= 0)
    E, g, K = law.energy_gradient_tangent(u)                  # no exception
    assert E == np.inf and np.isnan(g).any() and np.isnan(K.data).any()
    assert np.isfinite(g[np.setdiff1d(np.arange(law.n_dofs),
                                      2 * mesh.triangles[inverted].ravel()[:, None]
                                      + [0, 1])]).all()


@pytest.mark.parametrize("mild", [0.8, 0.71])
def test_plane_stress_without_a_thickness_root_is_infinite(mild):
    """ν < 0 (λ < 0): under strong equibiaxial compression μ(s² − 1) + λ ln(J2 s) > 0 for
    every s, so there is no plane-stress state: energy inf. A milder one has two roots and
    the stable (larger) one is taken; at 0.71 the linearised start lies left of the
    minimum of the condition."""
    mesh = with_material(cached_block(max_area=12.0), "stress", -0.5)
    law = NeoHookean(mesh)
    mu, lam = lame_constants(mesh.material)
    s = np.geomspace(1e-6, 1e3, 20001)
    hard = 0.6
    assert np.all(mu * (s * s - 1) + lam * np.log(hard**2 * s) > 0)
    assert law.energy(homogeneous(mesh, hard * np.eye(2))) == np.inf
    u = homogeneous(mesh, mild * np.eye(2))
    assert np.isfinite(law.energy(u))
    assert law.out_of_plane_stretch(u) == pytest.approx(thickness_stretch(mu, lam, mild**2),
                                                        rel=1e-13)


def test_bad_material_and_input_use_the_package_errors():
    with pytest.raises(PartError, match=r"material\.poisson_ratio = 0\.5"):
        Material(E_RUBBER, 0.5, T, 0.8)
    with pytest.raises(PartError, match=r"material\.poisson_ratio"):
        Material.from_dict({"youngs_modulus": 2e6, "poisson_ratio": -1.0,
                            "elastic_limit_strain": 0.8})
    bare = Mesh.from_arrays([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]])
    with pytest.raises(StiffnessError, match="no material"):
        NeoHookean(bare)
    law = NeoHookean(bare, Material(E_RUBBER, 0.3, T, 0.8))
    with pytest.raises(DeformClosureError, match=r"^u: shape \(4,\), expected \(6,\)"):
        law.energy(np.zeros(4))


# --------------------------------------------------------------------------- part files
def _part_dict(**material):
    return {"units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
            "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1,
                         "elastic_limit_strain": 0.8, **material}}


def test_material_model_parses_and_defaults_to_linear():
    assert Part.from_dict(_part_dict()).material.model == "linear"
    part = Part.from_dict(_part_dict(model="neo-hookean"))
    assert part.material.model == "neo-hookean"
    assert Material(E_RUBBER, 0.3, T, 0.8).model == "linear"


def test_material_model_round_trips_and_linear_is_not_written():
    linear = Part.from_dict(_part_dict())
    assert "model" not in linear.material.to_dict()           # old files/reports unchanged
    neo = Part.from_dict(_part_dict(model="neo-hookean"))
    d = neo.to_dict()
    assert d["material"]["model"] == "neo-hookean"
    back = Part.from_dict(json.loads(json.dumps(d)))
    assert back.material == neo.material
    mesh = mesh_part(Part.from_dict(_part_dict(model="neo-hookean")), max_area=20e-6)
    assert mesh_from_dict(json.loads(json.dumps(mesh_to_dict(mesh)))).material.model \
        == "neo-hookean"
    assert dataclasses.replace(neo.material, model="linear") == linear.material


@pytest.mark.parametrize("value", ["neo_hookean", "Linear", 1, None])
def test_bad_material_model_is_one_line_naming_the_field(value):
    with pytest.raises(PartError) as err:
        Part.from_dict(_part_dict(model=value))
    msg = str(err.value)
    assert msg == f"material.model = {value!r}: choose one of linear, neo-hookean"
    with pytest.raises(PartError, match=r"^material\.model = 'rubber': choose one of linear, "
                                         r"neo-hookean$"):
        Material(E_RUBBER, 0.3, T, 0.8, model="rubber")


# ----------------------------------------------------------------- compiled vs numpy form
@pytest.mark.parametrize("plane,nu", [("stress", 0.3), ("strain", 0.45), ("stress", -0.3),
                                      ("strain", 0.0)])
@given(seed=st.integers(0, 2**31 - 1), amplitude=st.sampled_from([1e-9, 1e-3, 0.05, 0.3]))
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_compiled_law_equals_the_numpy_reference(plane, nu, seed, amplitude):
    """The compiled element loop against the vectorised numpy form it replaced
    (tests/neohookean_reference.py, written and tested independently before it): energy,
    force and every tangent entry, relative to their largest magnitude."""
    from neohookean_reference import NumpyNeoHookean
    mesh = with_material(cached_block(max_area=12.0), plane, nu)
    law, ref = NeoHookean(mesh), NumpyNeoHookean(mesh)
    u = random_state(mesh, seed, amplitude, 0.5 * amplitude)
    E, f, K = law.energy_gradient_tangent(u)
    E0, f0, K0 = ref.energy_gradient_tangent(u)
    assume(np.isfinite(E0))
    assert E == pytest.approx(E0, rel=1e-12, abs=0)
    # the reference forms μ(F − Q) with F, Q ≈ I: its force carries a round-off of
    # ~eps μ t A |∇N| per element, which the compiled form avoids
    floor = 64 * np.finfo(float).eps * law.mu * (law._vol[:, None] * np.abs(law._g).max(2)).max()
    assert np.abs(f - f0).max() <= 1e-11 * np.abs(f0).max() + floor
    assert (K.indptr == K0.indptr).all() and (K.indices == K0.indices).all()
    assert np.abs(K.data - K0.data).max() <= 1e-12 * np.abs(K0.data).max()
    assert abs(K - K.T).max() == 0.0                      # exactly symmetric
    assert np.array_equal(law.element_energies(u) > 0, ref.element_energies(u) > 0)
    np.testing.assert_allclose(law.element_energies(u), ref.element_energies(u), rtol=1e-12,
                               atol=0)
    np.testing.assert_allclose(law.out_of_plane_stretch(u), ref.out_of_plane_stretch(u),
                               rtol=1e-14)
    np.testing.assert_allclose(law.right_cauchy_green(u), ref.right_cauchy_green(u),
                               rtol=1e-14)
    Eg, fg = law.energy_gradient(u)
    assert Eg == E and np.array_equal(fg, f)


def test_small_strain_force_keeps_its_relative_precision():
    """The internal force's deviation from the linear K₀u is the law's nonlinearity, O(δ),
    down to strains of 1e-11: the same ratio deviation/δ at δ = 1e-7, 1e-9, 1e-11 (the
    cancellation-free F − Q). The numpy form μ(F − Q) carries ~eps μ of round-off, 7e-8
    relative at δ = 1e-9 and ~7e-6 at 1e-11, where the ratio would be 600 times off."""
    mesh = with_material(cached_block(max_area=12.0), "stress", 0.3)
    law, K0 = NeoHookean(mesh), stiffness_matrix(mesh)
    ratios = []
    for amplitude in (1e-7, 1e-9, 1e-11):
        u = random_state(mesh, 7, amplitude, 0.5 * amplitude)
        f_lin = K0 @ u
        ratios.append(np.abs(law.gradient(u) - f_lin).max() / np.abs(f_lin).max() / amplitude)
    assert 0.5 < ratios[1] / ratios[0] < 2 and 0.5 < ratios[2] / ratios[0] < 2, ratios
