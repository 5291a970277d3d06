"""Independent full-stiffness reference solver for frictionless pad contact (SPEC §6).

Used by tests to check the package's fast (condensed) pad solver. It shares NO code with
``deformclosure.elasticity`` or ``deformclosure.pads``: the stiffness is assembled here with
scikit-fem (P1 vector elements, isotropic linear elasticity) and the contact problem is one
convex QP on all ``2n`` displacement DOFs, solved with Clarabel (interior point), then
polished on the identified active set with a direct sparse KKT solve, and its KKT conditions
are checked before returning.

Model (all SI): axis ``a = (cos θ, sin θ)``, cross direction ``n = (-sin θ, cos θ)``; for a
node ``p``: ``s = a·p``, ``x = n·p - offset``. Pad profile ``d(x)`` is 0 on the flat
``|x| <= W/2`` and ``ρ - sqrt(ρ² - ξ²)`` (``ξ = |x| - W/2``) on the rounded ends; nodes with
``|x| >= W/2 + ρ`` cannot touch. Pad A occupies ``s <= zA - d(x)``, pad B ``s >= zB + d(x)``,
``zB = zA + σ``. Linearised gaps in the displacement ``u_i`` of node ``i``::

    gA_i = s_i - zA + d(x_i) + ( a + d'(x_i) n)·u_i >= 0
    gB_i = zB + d(x_i) - s_i + (-a + d'(x_i) n)·u_i >= 0

Candidates are the outer-loop nodes with ``|x| < W/2 + ρ sin 75°`` (contact enforced where
the surface is within 75° of the face, as the package does). ``zA = zA0 = min(s + d)`` over
the candidates, ``σ0 = max(s - d) - zA0``. Placement: with lumped nodal areas ``w_i`` and
their centroid ``c``, ``Σ w_i n·u_i = 0`` (the exact mean cross-axis displacement) and the
area-weighted mean of the rotation field ``ω = ½(∂u_y/∂x − ∂u_x/∂y)`` is zero (SPEC §6; the
element gradients from the inverse Jacobian of each triangle); the mean axial translation
is free. Minimise ``½ uᵀ K u``.

Displacements ``u`` are interleaved: ``u[2 i] , u[2 i + 1]`` = x, y of node ``i``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import clarabel
from skfem import Basis, ElementTriP1, ElementVector, MeshTri, asm
from skfem.models.elasticity import linear_elasticity

__all__ = ["reference_pad_solution", "stiffness_matrix", "pad_profile", "lumped_weights"]

# KKT acceptance thresholds, in the scaled (dimensionless) problem: lengths in units of the
# part's size, forces in units of E·t·size.
_FEAS_TOL = 1e-12      # gaps >= -tol, equality residual <= tol
_COMPL_TOL = 1e-12     # |λ_i g_i| <= tol * max(λ) (scaled)
_STAT_TOL = 1e-9       # ||K u - Cᵀ y|| <= tol * max(||K u||, tiny)
_DUAL_TOL = 1e-12      # λ_i >= -tol * max(λ)


# --------------------------------------------------------------------------- pieces
def stiffness_matrix(mesh) -> sp.csr_matrix:
    """Global stiffness ``K`` (N/m), shape ``(2n, 2n)``, interleaved DOFs, via scikit-fem.

    In 2-D the P1 stiffness is invariant under a change of length unit, so it is assembled
    on the nodes scaled to O(1) with unit modulus and multiplied by ``E·t``.
    """
    mat = mesh.material
    if mat is None:
        raise ValueError("mesh has no material")
    E, nu, t = float(mat.youngs_modulus), float(mat.poisson_ratio), float(mat.thickness)
    return E * t * _unit_stiffness(mesh.nodes, mesh.triangles, nu, mat.plane)


def _unit_stiffness(nodes: np.ndarray, triangles: np.ndarray, nu: float, plane: str
                    ) -> sp.csr_matrix:
    """Stiffness for ``E = 1``, ``t = 1`` (dimensionless in 2-D), interleaved DOFs."""
    mu = 1.0 / (2.0 * (1.0 + nu))
    if plane == "stress":
        lam = nu / (1.0 - nu**2)
    elif plane == "strain":
        lam = nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    else:
        raise ValueError(f"unknown plane {plane!r}")
    ell = float(np.ptp(nodes, axis=0).max())
    p = (nodes - nodes.mean(0)) / ell
    m = MeshTri(np.ascontiguousarray(p.T), np.ascontiguousarray(triangles.T))
    basis = Basis(m, ElementVector(ElementTriP1()))
    A = asm(linear_elasticity(lam, mu), basis).tocsr()
    nd = basis.nodal_dofs  # (2, n): skfem DOF of (component, node)
    n = len(nodes)
    perm = np.empty(2 * n, dtype=np.int64)  # my dof -> skfem dof
    perm[0::2] = nd[0]
    perm[1::2] = nd[1]
    if A.shape != (2 * n, 2 * n):
        raise RuntimeError("unexpected scikit-fem DOF count")
    K = A[perm][:, perm]
    K = 0.5 * (K + K.T)
    return K.tocsr()


def lumped_weights(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Nodal area weights (m²): a third of each adjacent triangle's area."""
    P = nodes[triangles]
    d1, d2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    w = np.zeros(len(nodes))
    np.add.at(w, triangles.ravel(), np.repeat(area / 3.0, 3))
    return w


def mean_curl_row(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Row ``r`` (1/m) with ``r·u = Σ_e A_e ω_e / Σ_e A_e``, ``ω = ½(∂u_y/∂x − ∂u_x/∂y)``.

    Hat-function gradients from the inverse Jacobian ``J⁻ᵀ ∇̂N`` of each triangle (the
    reference gradients ``∇̂N = [[-1, -1], [1, 0], [0, 1]]``)."""
    r = np.zeros(2 * len(nodes))
    ref = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    total = 0.0
    for t in triangles:
        P = nodes[t]
        J = np.column_stack([P[1] - P[0], P[2] - P[0]])
        A = 0.5 * abs(np.linalg.det(J))
        grads = ref @ np.linalg.inv(J)          # row a: ∇N_a
        for a, i in enumerate(t):
            r[2 * i + 1] += 0.5 * A * grads[a, 0]
            r[2 * i] -= 0.5 * A * grads[a, 1]
        total += A
    return r / total


def pad_profile(x: np.ndarray, width: float, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Pad height ``d(x)`` and slope ``d'(x)`` (valid for ``|x| < W/2 + ρ``)."""
    x = np.asarray(x, float)
    xi = np.maximum(np.abs(x) - 0.5 * width, 0.0)
    root = np.sqrt(np.maximum(radius**2 - xi**2, 0.0))
    d = radius - root
    with np.errstate(divide="ignore", invalid="ignore"):
        dp = np.where(xi > 0.0, np.sign(x) * xi / root, 0.0)
    return d, dp


# --------------------------------------------------------------------------- solver
def reference_pad_solution(mesh, angle: float, offset: float, width: float, radius: float,
                           sigma: float) -> dict:
    """Frictionless two-pad contact on the full stiffness (one QP on all DOFs).

    Parameters
    ----------
    mesh : deformclosure.mesh.Mesh
        With ``material`` set.
    angle : float
        Axis angle θ (rad).
    offset : float
        Axis offset (m): the axis is the line ``n·p = offset``.
    width, radius : float
        Pad flat width ``W >= 0`` and end radius ``ρ > 0`` (m).
    sigma : float
        Distance between the pads ``zB - zA`` (m).

    Returns
    -------
    dict
        ``energy`` (J); ``u`` (2n,) interleaved displacements (m); ``sigma0_nodes`` (m);
        ``zA``, ``zB`` (m, along ``a``); ``axis_dir`` ``a``; ``cross_dir`` ``n``;
        ``A`` and ``B``: dicts with ``nodes`` (node ids in contact: multiplier > tiny),
        ``forces`` (k, 2) force vectors on the part at those nodes (N), ``axial_force``
        (N; ``a``-component of the pad's total force on the part: ≥ 0 for A, ≤ 0 for B),
        ``candidates`` (candidate node ids), ``gaps`` (linearised gaps at the solution, m,
        per candidate), ``multipliers`` (N, per candidate); ``kkt``: residuals of the
        checks (scaled units) and ``energy_ipm`` (J, Clarabel's energy before polishing).

    Raises
    ------
    RuntimeError
        If the QP solve fails or its KKT conditions are not met to the tolerances.
    """
    if not (radius > 0 and width >= 0):
        raise ValueError("need radius > 0 and width >= 0")
    nodes = np.asarray(mesh.nodes, float)
    tri = np.asarray(mesh.triangles, np.int64)
    n_nodes = len(nodes)
    mat = mesh.material
    Et = float(mat.youngs_modulus) * float(mat.thickness)
    ell = float(np.ptp(nodes, axis=0).max())  # length unit of the scaled problem

    a = np.array([np.cos(angle), np.sin(angle)])
    nv = np.array([-np.sin(angle), np.cos(angle)])
    s_all = nodes @ a
    x_all = nodes @ nv - offset

    outer = np.asarray(mesh.loops[0], np.int64)
    # Contact is enforced where the pad surface is within 75° of its face (SPEC §6 as
    # implemented; see deformclosure.pads.geometry): |x| < W/2 + ρ sin 75°.
    reach = 0.5 * width + radius * np.sin(np.radians(75.0))
    cand = outer[np.abs(x_all[outer]) < reach]
    if len(cand) == 0:
        raise ValueError("the axis misses the part: no outer-boundary node within reach of the pads")
    s_c = s_all[cand]
    d_c, dp_c = pad_profile(x_all[cand], width, radius)
    zA = float(np.min(s_c + d_c))
    zB0 = float(np.max(s_c - d_c))
    sigma0 = zB0 - zA
    zB = zA + float(sigma)

    # Gradients of the gaps w.r.t. the node's displacement.
    gradA = a[None, :] + dp_c[:, None] * nv[None, :]
    gradB = -a[None, :] + dp_c[:, None] * nv[None, :]
    g0A = s_c - zA + d_c
    g0B = zB + d_c - s_c
    k = len(cand)

    def _empty_result(u: np.ndarray) -> dict:
        gA = g0A + np.einsum("ij,ij->i", gradA, u.reshape(-1, 2)[cand])
        gB = g0B + np.einsum("ij,ij->i", gradB, u.reshape(-1, 2)[cand])
        pad = lambda g: {"nodes": np.zeros(0, np.int64), "forces": np.zeros((0, 2)),  # noqa: E731
                         "axial_force": 0.0, "candidates": cand.copy(), "gaps": g,
                         "multipliers": np.zeros(k)}
        return {"energy": 0.0, "u": u, "sigma0_nodes": sigma0, "zA": zA, "zB": zB,
                "axis_dir": a, "cross_dir": nv, "A": pad(gA), "B": pad(gB),
                "kkt": {"energy_ipm": 0.0}}

    if sigma >= sigma0:
        return _empty_result(np.zeros(2 * n_nodes))

    # ---------------------------------------------------------------- scaled problem
    Kh = _unit_stiffness(nodes, tri, float(mat.poisson_ratio), mat.plane)  # K = Et * Kh
    N = 2 * n_nodes
    # Inequalities G u + g0 >= 0, rows normalised to unit gradient.
    gnA = np.linalg.norm(gradA, axis=1)
    gnB = np.linalg.norm(gradB, axis=1)
    rows = np.repeat(np.arange(2 * k), 2)
    cols = np.concatenate([np.column_stack([2 * cand, 2 * cand + 1]).ravel()] * 2)
    vals = np.concatenate([(gradA / gnA[:, None]).ravel(), (gradB / gnB[:, None]).ravel()])
    G = sp.csr_matrix((vals, (rows, cols)), shape=(2 * k, N))
    gnorm = np.concatenate([gnA, gnB])
    g0 = np.concatenate([g0A, g0B]) / gnorm / ell  # scaled, per unit gradient
    # Equalities: mean cross translation and mean rotation (weights normalised).
    w = lumped_weights(nodes, tri)
    c = (w[:, None] * nodes).sum(0) / w.sum()
    wn = w / w.sum()
    Erow1 = np.column_stack([wn * nv[0], wn * nv[1]]).ravel()
    Erow2 = mean_curl_row(nodes, tri) * ell
    Eq = np.vstack([Erow1, Erow2])
    Eq /= np.linalg.norm(Eq, axis=1, keepdims=True)
    Eq = sp.csr_matrix(Eq)

    # Clarabel: min ½ xᵀ P x  s.t.  Eq x + s = 0 (s in zero cone), -G x + s = g0 (s >= 0).
    P = sp.triu(Kh, format="csc")
    Acl = sp.vstack([Eq, -G], format="csc")
    bcl = np.concatenate([np.zeros(2), g0])
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = 1e-13
    settings.tol_gap_rel = 1e-13
    settings.tol_feas = 1e-13
    settings.tol_ktratio = 1e-10
    settings.max_iter = 400
    settings.iterative_refinement_reltol = 1e-14
    settings.iterative_refinement_abstol = 1e-14
    settings.iterative_refinement_max_iter = 50
    cones = [clarabel.ZeroConeT(2), clarabel.NonnegativeConeT(2 * k)]
    solver = clarabel.DefaultSolver(P, np.zeros(N), Acl, bcl, cones, settings)
    sol = solver.solve()
    status = str(sol.status)
    if "Solved" not in status:  # Solved or AlmostSolved
        raise RuntimeError(f"clarabel failed: {status}")
    x_ipm = np.asarray(sol.x)
    z_ipm = np.asarray(sol.z)
    lam_ipm = z_ipm[2:]
    energy_ipm = 0.5 * float(x_ipm @ (Kh @ x_ipm)) * Et * ell**2
    gap_ipm = g0 + G @ x_ipm

    # ---------------------------------------------------------------- active-set polish
    active = lam_ipm > gap_ipm
    xh, lam, mu = None, None, None
    for _ in range(50):
        xh, lam, mu = _solve_active(Kh, Eq, G, g0, active)
        gap = g0 + G @ xh
        lmax = max(float(np.max(lam, initial=0.0)), 1e-300)
        neg = active & (lam < -_DUAL_TOL * lmax)
        viol = ~active & (gap < -_FEAS_TOL)
        if not neg.any() and not viol.any():
            break
        active = (active & ~neg) | viol
    else:
        raise RuntimeError("active-set polishing did not converge")

    # ---------------------------------------------------------------- KKT checks
    gap = g0 + G @ xh
    lmax = max(float(np.max(lam)), 1e-300)
    Ku = Kh @ xh
    stat = Ku - G.T @ lam - Eq.T @ mu
    res = {
        "min_gap": float(gap.min()),
        "eq_residual": float(np.abs(Eq @ xh).max()),
        "min_multiplier": float(lam.min() / lmax),
        "complementarity": float(np.abs(lam * gap).max() / lmax),
        "stationarity": float(np.linalg.norm(stat) / max(np.linalg.norm(Ku), 1e-300)),
    }
    eh = 0.5 * float(xh @ Ku)
    eh_dual = -0.5 * float(lam @ g0)  # = ½ uᵀKu at a KKT point
    res["energy_dual_gap"] = abs(eh - eh_dual) / max(abs(eh), 1e-300)
    res["energy_ipm"] = energy_ipm
    energy = eh * Et * ell**2
    res["ipm_vs_polished"] = abs(energy_ipm - energy) / max(energy, 1e-300)
    ok = (res["min_gap"] >= -_FEAS_TOL and res["eq_residual"] <= _FEAS_TOL
          and res["min_multiplier"] >= -_DUAL_TOL and res["complementarity"] <= _COMPL_TOL
          and res["stationarity"] <= _STAT_TOL and res["energy_dual_gap"] <= 1e-9
          and res["ipm_vs_polished"] <= 1e-6 and eh > 0)
    if not ok:
        raise RuntimeError(f"KKT check failed: {res}")

    # ---------------------------------------------------------------- unscale, report
    u = xh * ell
    lam_true = lam / gnorm * Et * ell  # N, per unit of the raw gradient
    lam_true[~active] = 0.0
    tiny = 1e-12 * max(float(lam_true.max()), 1e-300)
    uu = u.reshape(-1, 2)

    def _pad(sl: slice, grad: np.ndarray, g0raw: np.ndarray) -> dict:
        lm = lam_true[sl]
        on = lm > tiny
        f = lm[on, None] * grad[on]
        return {"nodes": cand[on], "forces": f, "axial_force": float((f @ a).sum()),
                "candidates": cand.copy(),
                "gaps": g0raw + np.einsum("ij,ij->i", grad, uu[cand]),
                "multipliers": lm.copy()}

    return {"energy": energy, "u": u, "sigma0_nodes": sigma0, "zA": zA, "zB": zB,
            "axis_dir": a, "cross_dir": nv,
            "A": _pad(slice(0, k), gradA, g0A), "B": _pad(slice(k, 2 * k), gradB, g0B),
            "kkt": res}


def _solve_active(Kh: sp.csr_matrix, Eq: sp.csr_matrix, G: sp.csr_matrix, g0: np.ndarray,
                  active: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Equality-constrained QP on an active set: [K Cᵀ; C 0] [u; -y] = [0; b]."""
    idx = np.flatnonzero(active)
    C = sp.vstack([Eq, G[idx]], format="csr")
    b = np.concatenate([np.zeros(Eq.shape[0]), -g0[idx]])
    N = Kh.shape[0]
    m = C.shape[0]
    M = sp.bmat([[Kh, C.T], [C, None]], format="csc")
    rhs = np.concatenate([np.zeros(N), b])
    try:
        lu = spla.splu(M)
    except RuntimeError as err:
        raise RuntimeError("singular KKT system on the active set (linearly dependent active "
                           "constraints, e.g. one node touched by both pads: squeeze too large)"
                           ) from err
    sol = lu.solve(rhs)
    # One step of iterative refinement.
    sol += lu.solve(rhs - M @ sol)
    x = sol[:N]
    y = -sol[N:]  # K x = Cᵀ y
    mu = y[:Eq.shape[0]]
    lam = np.zeros(G.shape[0])
    lam[idx] = y[Eq.shape[0]:]
    assert m == len(y)
    return x, lam, mu
