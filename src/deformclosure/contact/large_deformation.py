"""Frictionless contact of rigid capsules with a part at finite strain (SPEC §8).

At one position of the rigid bodies the part's displacement ``u`` (m, DOFs
``[x0, y0, x1, y1, …]``) solves

    min Ψ(u)   subject to   g_j(u) = dist(X_j + u_j, body_j) ≥ 0   and   G u = 0,

with ``Ψ`` the stored energy of any material law that gives its energy, gradient and
tangent (:class:`deformclosure.elasticity.neohookean.NeoHookean`, or the linear law
:class:`deformclosure.elasticity.linear_energy.LinearEnergy`), ``g_j`` the *exact*
signed distance of boundary node ``j``'s current position to a rigid capsule (no
linearisation: sliding along a round pad and contact on its flanks are right at any
squeeze) and ``G`` the gauge's linear functionals (SPEC §6/§8: mean cross-axis
displacement and mean rotation ω on a grasp axis). The stationarity conditions

    ∇Ψ(u) − Σ_j λ_j ∇g_j(u) − Gᵀ μ = 0,   G u = 0,   λ ≥ 0, g ≥ 0, λ_j g_j = 0

are solved by a primal–dual active-set Newton method (Hintermüller, Ito & Kunisch,
SIAM J. Optim. 13 (2003), the semismooth Newton method for ``min(λ, c g) = 0``) with a
backtracking line search on the residual; ``λ_j`` is the normal force (N) of row ``j``
(its direction ``∇g_j``, unit: frictionless). Each Newton step solves one sparse KKT
system of the tangent ``K_T − Σ λ_j ∇²g_j`` (the second term: the curvature of the pad's
surface under a sliding node), the active rows and the gauge: by a sparse LDLᵀ without
pivoting (qdldl, when installed: its symbolic factorisation reused for every step of a
fixed pattern) of the system shifted by ``±ε`` on its diagonal, with iterative
refinement on the true system, else (qdldl absent, or a system the refinement does not
solve to :data:`LDL_TOL`) by SuperLU with partial pivoting.

:func:`follow_squeeze` follows a one-parameter family of body positions (the squeeze δ)
from first touch in steps, halving a step whose Newton iteration does not converge, and
reports the squeeze it could not reach instead of clipping.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Protocol, Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..elasticity.condense import nested_dissection_order, node_adjacency
from ..limits import blas_threads

try:                                    # optional: a faster factorisation of the KKT systems
    import qdldl as _qdldl
except ImportError:                     # pragma: no cover - depends on the installation
    _qdldl = None

__all__ = ["CapsuleObstacle", "ContactState", "FiniteStrainContact", "SqueezePath",
           "follow_squeeze", "RESIDUAL_TOL"]

#: Relative residual at which a Newton solve has converged (SPEC §8: ≤ 1e-10).
RESIDUAL_TOL = 1e-10
#: Newton iterations per solve before the step is halved.
MAX_NEWTON = 30
#: Iterations without halving the best residual after which a solve gives up (the step is
#: halved instead: an active set that cycles is cured by a smaller step).
STALL = 4
#: A full Newton step is taken while the residual grows by less than this factor.
NONMONOTONE = 10.0
#: Halvings of a squeeze step before the squeeze is reported as not reached.
MAX_HALVINGS = 5
#: Factorisation of the Newton systems: ``"qdldl"`` (when installed) or ``"superlu"``.
#: ``benchmarks/bench_kkt_solvers.py`` (notched bar, 5 088 nodes, 54 systems of one
#: curve): SuperLU 68 ms per system, qdldl's numeric refactorisation 21 ms, residuals
#: 1.5e-12 and 2.9e-13; 3–12x faster on 600–5 000 nodes.
LINEAR_SOLVER = "qdldl" if _qdldl is not None else "superlu"
#: The qdldl shift ``ε`` relative to the tangent's mean diagonal: ``+ε`` on the
#: displacements, ``−ε`` on the multipliers, so that the LDLᵀ without pivoting meets no
#: zero pivot (the gauge and active rows have zero diagonal; the tangent alone is
#: singular along the rigid modes the gauge removes).
LDL_SHIFT = 1e-12
#: Relative residual ``‖A x − b‖∞ / ‖b‖∞`` the refined qdldl solution must reach, else
#: the system goes to SuperLU (whose solutions reach ~2e-12 on these systems).
LDL_TOL = 1e-12
#: Refinement sweeps of a qdldl solution.
LDL_SWEEPS = 10


class Material(Protocol):  # pragma: no cover - a protocol
    """What the solver needs of a material law (SI: J, N, N/m)."""

    n_dofs: int

    def energy(self, u: np.ndarray) -> float: ...

    def gradient(self, u: np.ndarray) -> np.ndarray: ...

    def energy_gradient(self, u: np.ndarray) -> tuple[float, np.ndarray]: ...

    def energy_gradient_tangent(self, u: np.ndarray) -> tuple[float, np.ndarray, sp.csr_matrix]: ...


@dataclass(frozen=True)
class CapsuleObstacle:
    """A rigid capsule: the segment ``p → q`` (m) swept by a disc of ``radius`` (m) —
    with ``back``, the finger that carries it: the half-strip of the capsule's width
    behind the segment (away from the part).

    ``p == q`` is a disc. The signed distance of a point ``x`` in front of the segment's
    line (or of a capsule without ``back``) is ``|x − c(x)| − radius`` with ``c(x)`` the
    segment's point nearest ``x``; its gradient is the unit vector from ``c(x)`` to ``x``
    (the direction of the force the body exerts) and its Hessian ``(I − n nᵀ)/|x − c(x)|``
    where ``c(x)`` is an end of the segment, ``0`` along the straight face. Behind the line
    (``(x − p)·back > 0``) the finger's straight sides are the nearest surface: distance
    ``|t − L/2| − (L/2 + radius)`` along the segment's direction, no curvature. The two
    pieces meet tangentially, so the distance is continuously differentiable: a part that
    wraps around a round fingertip slides onto the finger's flanks, never behind it.
    """

    p: tuple[float, float]
    q: tuple[float, float]
    radius: float
    back: tuple[float, float] | None = None

    def distance(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Signed distances (m), unit gradients and Hessians (1/m) at points ``X`` (k, 2).

        Returns
        -------
        g : ndarray, shape (k,)
        n : ndarray, shape (k, 2)
        H : ndarray, shape (k, 2, 2)
        """
        X = np.asarray(X, float)
        p, q = np.asarray(self.p, float), np.asarray(self.q, float)
        e = q - p
        L2 = float(e @ e)
        if L2 > 0:
            t = np.clip(((X - p) @ e) / L2, 0.0, 1.0)
        else:
            t = np.zeros(len(X))
        c = p + t[:, None] * e
        r = X - c
        dist = np.hypot(r[:, 0], r[:, 1])
        safe = np.where(dist > 0, dist, 1.0)
        n = r / safe[:, None]
        g = dist - self.radius
        # Along the face (0 < t < 1) the distance is the distance to a line: no curvature.
        end = (t <= 0.0) | (t >= 1.0) if L2 > 0 else np.ones(len(X), bool)
        k = np.where(end, 1.0 / safe, 0.0)
        H = k[:, None, None] * (np.eye(2)[None] - n[:, :, None] * n[:, None, :])
        if self.back is not None:
            b = np.asarray(self.back, float)
            behind = (X - p) @ b > 0
            if behind.any():
                L = math.sqrt(L2)
                ehat = e / L if L > 0 else np.array([-b[1], b[0]])
                tl = (X[behind] - p) @ ehat - 0.5 * L
                side = np.where(tl >= 0, 1.0, -1.0)
                g[behind] = np.abs(tl) - (0.5 * L + self.radius)
                n[behind] = side[:, None] * ehat[None, :]
                H[behind] = 0.0
        return g, n, H


@dataclass
class ContactState:
    """A converged (or last) iterate of one contact solve.

    Attributes
    ----------
    u : ndarray, shape (2n,)
        Displacement (m).
    lam : ndarray, shape (r,)
        Normal force (N) of every candidate row; 0 off contact.
    mu : ndarray, shape (k,)
        Gauge multipliers (N, or N·m for a rotation functional): the load the gauge carries.
    energy : float
        Stored energy Ψ(u) (J).
    gaps : ndarray, shape (r,)
        Signed distances (m) of the rows at ``u``.
    normals : ndarray, shape (r, 2)
        Unit gradients of the gaps: the direction of each row's force on the part.
    residual : float
        Relative residual of the stationarity and complementarity conditions.
    iterations : int
    converged : bool
    """

    u: np.ndarray
    lam: np.ndarray
    mu: np.ndarray
    energy: float
    gaps: np.ndarray
    normals: np.ndarray
    residual: float
    iterations: int
    converged: bool

    def forces(self) -> np.ndarray:
        """Contact forces on the part (N), shape (r, 2)."""
        return self.lam[:, None] * self.normals


class FiniteStrainContact:
    """The contact problem of a part (material law ``material``) with rigid capsules.

    Parameters
    ----------
    material : Material
        Energy, gradient and tangent of the part (the protocol of this module).
    nodes : ndarray, shape (n, 2)
        Reference positions (m).
    rows : sequence of (ndarray of int, int)
        ``(node ids, body index)`` pairs: which nodes may touch which body.
    gauge : ndarray, shape (k, 2n)
        Linear functionals held at zero (SPEC §6/§8 gauge).
    length : float
        A length scale of the part (m, its diameter) for the gap tolerance.
    triangles : ndarray of int, shape (m, 3), optional
        The mesh's triangles: the Newton systems are then ordered by METIS nested
        dissection of the node graph (the multipliers last), which SuperLU factorises
        5–6 times faster than in its own column order on a 5k-node part
        (``benchmarks/bench_large_deformation.py``).
    """

    def __init__(self, material: Material, nodes: np.ndarray,
                 rows: Sequence[tuple[np.ndarray, int]], gauge: np.ndarray,
                 length: float, triangles: np.ndarray | None = None) -> None:
        self.material = material
        self.X = np.asarray(nodes, float)
        self.n_dofs = 2 * len(self.X)
        ids = [np.asarray(r[0], np.int64) for r in rows]
        self.node = np.concatenate(ids) if ids else np.zeros(0, np.int64)
        self.body = np.concatenate([np.full(len(i), r[1], np.int64) for i, r in zip(ids, rows)]) \
            if ids else np.zeros(0, np.int64)
        self.G = sp.csr_matrix(np.asarray(gauge, float))
        self.length = float(length)
        self.gap_tol = RESIDUAL_TOL * self.length
        self.area = float(np.ptp(self.X[:, 0]) * np.ptp(self.X[:, 1])) if len(self.X) else 0.0
        self._floor: float | None = None
        self._pattern: _KKTPattern | None = None
        dofs = np.column_stack([2 * self.node, 2 * self.node + 1]).ravel()
        self._dofs = dofs
        if triangles is not None and len(self.X) > 2:
            perm = nested_dissection_order(node_adjacency(np.asarray(triangles), len(self.X)))
            self._order = np.column_stack([2 * perm, 2 * perm + 1]).ravel()
        else:
            self._order = np.arange(self.n_dofs)

    # -------------------------------------------------------------------- geometry
    def gaps(self, u: np.ndarray, bodies: Sequence[CapsuleObstacle]
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Signed distances (m), unit normals and Hessians (1/m) of every row at ``u``."""
        x = self.X[self.node] + u.reshape(-1, 2)[self.node]
        r = len(self.node)
        g, n, H = np.empty(r), np.empty((r, 2)), np.empty((r, 2, 2))
        for b, body in enumerate(bodies):
            sel = self.body == b
            if sel.any():
                g[sel], n[sel], H[sel] = body.distance(x[sel])
        return g, n, H

    # -------------------------------------------------------------------- one solve
    def solve(self, bodies: Sequence[CapsuleObstacle], u0: np.ndarray | None = None,
              lam0: np.ndarray | None = None, mu0: np.ndarray | None = None,
              force_scale: float | None = None) -> ContactState:
        """:meth:`_solve` with the BLAS threads capped (``limits.BLAS_THREADS``: SuperLU's
        dense kernels are small and many)."""
        with blas_threads():
            return self._solve(bodies, u0, lam0, mu0, force_scale)

    def _solve(self, bodies: Sequence[CapsuleObstacle], u0: np.ndarray | None = None,
               lam0: np.ndarray | None = None, mu0: np.ndarray | None = None,
               force_scale: float | None = None) -> ContactState:
        """Equilibrium with the bodies at their given positions, from ``(u0, lam0, mu0)``.

        Parameters
        ----------
        bodies : sequence of CapsuleObstacle
        u0, lam0, mu0 : ndarray, optional
            Start (default zero); a converged state of a nearby body position is best.
        force_scale : float, optional
            Force (N) the residual is relative to; default the largest of the contact and
            internal forces of the iterate.

        Returns
        -------
        ContactState
            ``converged`` False when the iteration did not reach :data:`RESIDUAL_TOL`
            within :data:`MAX_NEWTON` steps.
        """
        nd, r, k = self.n_dofs, len(self.node), self.G.shape[0]
        u = np.zeros(nd) if u0 is None else np.array(u0, float)
        lam = np.zeros(r) if lam0 is None else np.array(lam0, float)
        mu = np.zeros(k) if mu0 is None else np.array(mu0, float)
        mat = self.material
        E, grad, Kt = mat.energy_gradient_tangent(u)
        g, n, H = self.gaps(u, bodies)
        if not math.isfinite(E):                 # an inverted element: no Newton step
            return ContactState(u, lam, mu, math.inf, g, n, math.inf, 0, False)
        c = float(Kt.diagonal().mean())          # N/m: the scale of min(λ, c g)
        if self._floor is None:
            # Round-off of the internal force: about eps × (stiffness × element size) per
            # DOF (the stress of a law like neo-Hookean is a difference of O(μ) terms), so
            # at strains below ~1e-6 a residual of 1e-10 relative to the forces is below
            # what the arithmetic resolves; the residual is relative to at least 1e10 ×
            # that floor.
            h = math.sqrt(self.area / max(self.n_dofs // 2, 1))
            self._floor = 100.0 * np.finfo(float).eps * c * h / RESIDUAL_TOL
        res = self._residual(u, lam, mu, grad, g, n, c, force_scale)
        it = 0
        prev_active = None
        seen: set[bytes] = set()
        best_res, best_it = res, 0
        while it < MAX_NEWTON and it - best_it <= STALL:
            active = (lam - c * g) > 0
            # An active set met before means the full steps cycle (a row grazing the body
            # flips in and out): from then on a step must lower the residual.
            key = np.packbits(active).tobytes()
            cycling = key in seen
            seen.add(key)
            if res <= RESIDUAL_TOL and prev_active is not None and np.array_equal(active, prev_active):
                break
            if res <= RESIDUAL_TOL and it > 0 and self._complementary(lam, g):
                break
            step = self._newton_step(u, lam, mu, grad, Kt, g, n, H, active)
            if step is None:
                break
            du, lam_new, mu_new = step
            # Full steps while the residual falls or stays within NONMONOTONE times the
            # last one (an active-set change may raise it for a step); otherwise, and for
            # a trial that inverts an element (infinite energy), backtracking. The
            # tangent is formed only at the accepted iterate.
            alpha, accepted = 1.0, False
            for _ in range(12):
                ut = u + alpha * du
                lt = lam + alpha * (lam_new - lam)
                mt = mu + alpha * (mu_new - mu)
                Et, gt_ = mat.energy_gradient(ut)
                if math.isfinite(Et):
                    gg, nn, HH = self.gaps(ut, bodies)
                    rt = self._residual(ut, lt, mt, gt_, gg, nn, c, force_scale)
                    limit = NONMONOTONE * res if alpha == 1.0 and not cycling else res
                    if rt < limit or alpha < 1e-3 or not np.isfinite(res):
                        accepted = True
                        break
                alpha *= 0.5
            it += 1
            if not accepted:
                break
            prev_active = active
            u, lam, mu, g, n, H, res = ut, lt, mt, gg, nn, HH, rt
            E, grad, Kt = mat.energy_gradient_tangent(u)
            if res < 0.5 * best_res:
                best_res, best_it = res, it
        lam = np.where((lam - c * g) > 0, np.maximum(lam, 0.0), 0.0)
        converged = bool(res <= RESIDUAL_TOL and self._complementary(lam, g))
        return ContactState(u, lam, mu, float(E), g, n, float(res), it, converged)

    def _complementary(self, lam: np.ndarray, g: np.ndarray) -> bool:
        """No row penetrates beyond the gap tolerance and no active row pulls."""
        tol = self.gap_tol
        on = lam > 0
        return bool(np.all(g >= -tol) and np.all(np.abs(g[on]) <= tol) and np.all(lam >= 0))

    def _residual(self, u, lam, mu, grad, g, n, c, force_scale) -> float:
        """Relative residual: stationarity over the force scale, complementarity
        ``min(λ, c g)`` over the same scale, the gauge over the length scale."""
        r_u = grad - self._contact_load(lam, n) - self.G.T @ mu
        scale = force_scale
        if scale is None:
            scale = max(float(np.abs(grad).max(initial=0.0)), float(np.abs(lam).max(initial=0.0)))
        scale = max(scale, self._floor or 0.0, 1e-300)
        ncp = np.minimum(lam, c * g)
        gauge = np.abs(self.G @ u).max(initial=0.0) / self.length
        return float(max(np.abs(r_u).max(initial=0.0) / scale,
                         np.abs(ncp).max(initial=0.0) / scale, gauge))

    def _contact_load(self, lam: np.ndarray, n: np.ndarray) -> np.ndarray:
        """``Σ_j λ_j ∇g_j`` (N), shape (2n,)."""
        f = np.zeros(self.n_dofs)
        np.add.at(f, self._dofs, (lam[:, None] * n).ravel())
        return f

    def _newton_step(self, u, lam, mu, grad, Kt, g, n, H, active):
        """One primal–dual active-set Newton step; returns ``(Δu, λ⁺, μ⁺)``, or ``None``
        when the Newton system is singular even regularised.

        The system is ``[[K_T − Σ_A λ_j ∇²g_j, −Jᵀ, −Gᵀ], [−J, D, 0], [−G, 0, 0]]`` over every
        candidate row: an active row ``j`` has its gradient in ``J`` and ``D_jj = 0`` (its
        gap linearised to zero), an inactive one a zero row of ``J`` and ``D_jj = 1`` (its
        force set to zero). So the pattern is the same at every step: it is built once
        (:class:`_KKTPattern`) and each step only fills its values.
        """
        nd, r = self.n_dofs, len(self.node)
        pat = self._pattern
        if pat is None or not pat.fits(Kt):
            pat = self._pattern = _KKTPattern(Kt, self.node, self.G, self._order)
        A = active
        lamA = np.where(A, lam, 0.0)
        r_u = grad - self._contact_load(lamA, n) - self.G.T @ mu
        # the pad's surface curvature under the active forces, on the nodes' diagonal blocks
        curv = -(lamA[:, None, None] * H)
        KKT = pat.matrix(Kt.data, curv, n, A)
        o = self._order
        rhs = np.concatenate([-r_u[o], np.where(A, g, -lam), self.G @ u])
        sol = pat.solve_ldl(KKT, rhs, nd) if LINEAR_SOLVER == "qdldl" else None
        try:
            if sol is None:
                KKT = pat.full(KKT)
                sol = spla.splu(KKT, permc_spec="NATURAL").solve(rhs)
        except RuntimeError:
            # A singular system (a body with no active row leaves the float along the
            # axis free): a proximal step regularised by a tiny multiple of the diagonal.
            eps = 1e-10 * float(abs(Kt.diagonal()).mean())
            reg = sp.diags(np.concatenate([np.full(nd, eps), np.full(KKT.shape[0] - nd, -eps)]))
            try:
                sol = spla.splu((KKT + reg).tocsc(), permc_spec="COLAMD").solve(rhs)
            except RuntimeError:
                return None
        if not np.all(np.isfinite(sol)):
            return None
        du = np.empty(nd)
        du[o] = sol[:nd]
        lam_new = np.where(A, lam + sol[nd:nd + r], 0.0)
        mu_new = mu + sol[nd + r:]
        return du, lam_new, mu_new


class _KKTPattern:
    """The fixed sparsity pattern of the Newton system of :class:`FiniteStrainContact`, in
    the solver's nested-dissection order (CSC), and where each value goes: the tangent's
    CSR values, the rows' gradients (twice, the matrix is symmetric), the gauge and the
    multipliers' diagonal. Built once per tangent pattern; :meth:`matrix` fills it."""

    def __init__(self, Kt: sp.csr_matrix, node: np.ndarray, G: sp.csr_matrix,
                 order: np.ndarray) -> None:
        Kt = Kt.tocsr()
        nd, r = Kt.shape[0], len(node)
        self.indptr_K, self.indices_K = Kt.indptr.copy(), Kt.indices.copy()
        nK = Kt.nnz
        # ids (1-based, so no value is dropped as a zero) of every source value
        K_ids = sp.csr_matrix((np.arange(1, nK + 1, dtype=float), Kt.indices, Kt.indptr),
                              shape=(nd, nd))
        jr = np.repeat(np.arange(r), 2)
        jc = np.stack([2 * node, 2 * node + 1], 1).ravel()
        base_jl = nK + 1
        Jl = sp.csr_matrix((np.arange(base_jl, base_jl + 2 * r, dtype=float), (jr, jc)),
                           shape=(r, nd))
        base_ju = base_jl + 2 * r
        Ju = sp.csr_matrix((np.arange(base_ju, base_ju + 2 * r, dtype=float), (jr, jc)),
                           shape=(r, nd))
        Gd = np.asarray(G.todense())
        base_g = base_ju + 2 * r
        gl = (np.arange(Gd.size, dtype=float) + base_g).reshape(Gd.shape)
        base_gu = base_g + Gd.size
        gu = (np.arange(Gd.size, dtype=float) + base_gu).reshape(Gd.shape)
        base_d = base_gu + Gd.size
        D = sp.diags(np.arange(base_d, base_d + r, dtype=float))
        o = order
        k = Gd.shape[0]
        # the gauge rows' zero diagonal, kept in the pattern (ids past every source value)
        # so that the qdldl shift has a place on every diagonal entry
        base_z = base_d + r
        Z = sp.diags(np.arange(base_z, base_z + k, dtype=float)) if k else None
        T = sp.bmat([[K_ids[o][:, o], Ju[:, o].T, sp.csr_matrix(gu[:, o].T)],
                     [Jl[:, o], D, None],
                     [sp.csr_matrix(gl[:, o]), None, Z]], format="csc")
        T.sort_indices()
        # the system is symmetric: only its upper triangle is kept and filled (qdldl reads
        # it as is, ``upper=True``; :meth:`full` and :meth:`times` give the whole)
        cols = np.repeat(np.arange(T.shape[1]), np.diff(T.indptr))
        keep = T.indices <= cols
        ids = T.data[keep].astype(np.int64)
        indices, cols = T.indices[keep], cols[keep]
        indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=T.shape[1]))])
        # where each diagonal entry sits in the CSC values (the last of its column)
        on_diag = np.flatnonzero(indices == cols)
        if len(on_diag) != T.shape[0]:
            raise ValueError("Newton system without a full diagonal")
        self.pos_diag = on_diag
        self._ldl = None
        self.indptr = indptr.astype(T.indptr.dtype)
        self.indices, self.shape = indices, T.shape
        self.nnz = len(ids)
        self.pos_K = np.flatnonzero(ids < base_jl)
        self.src_K = ids[self.pos_K] - 1
        self.pos_Jl = np.flatnonzero((ids >= base_jl) & (ids < base_ju))
        self.src_Jl = ids[self.pos_Jl] - base_jl                 # index into (r, 2) ravel
        self.pos_Ju = np.flatnonzero((ids >= base_ju) & (ids < base_g))
        self.src_Ju = ids[self.pos_Ju] - base_ju
        pos_g = np.flatnonzero((ids >= base_g) & (ids < base_d))
        src = ids[pos_g]
        val = np.where(src < base_gu, Gd.ravel()[np.clip(src - base_g, 0, Gd.size - 1)],
                       Gd.ravel()[np.clip(src - base_gu, 0, Gd.size - 1)])
        self.pos_G, self.val_G = pos_g, -val
        self.pos_D = np.flatnonzero((ids >= base_d) & (ids < base_z))
        self.src_D = ids[self.pos_D] - base_d
        self.pos_Z = np.flatnonzero(ids >= base_z)
        # where each row's node's 2×2 diagonal block sits in the tangent's CSR values
        blocks = np.empty((r, 4), np.int64)
        for q, (di, dj) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
            row, col = 2 * node + di, 2 * node + dj
            for j in range(r):
                lo, hi = Kt.indptr[row[j]], Kt.indptr[row[j] + 1]
                hit = np.flatnonzero(Kt.indices[lo:hi] == col[j])
                if len(hit) != 1:
                    raise ValueError("tangent without the nodes' diagonal blocks")
                blocks[j, q] = lo + hit[0]
        self.blocks = blocks

    def fits(self, Kt: sp.csr_matrix) -> bool:
        """Whether ``Kt`` has the pattern this was built for."""
        return (Kt.nnz == len(self.indices_K) and np.array_equal(Kt.indptr, self.indptr_K)
                and np.array_equal(Kt.indices, self.indices_K))

    def matrix(self, K_data: np.ndarray, curv: np.ndarray, n: np.ndarray,
               active: np.ndarray) -> sp.csc_matrix:
        """The upper triangle (CSC) of the Newton matrix: tangent values ``K_data`` plus the
        rows' curvature blocks ``curv`` (r, 2, 2), gradients ``n`` (r, 2) of the active
        rows."""
        Kd = np.array(K_data, float)
        np.add.at(Kd, self.blocks.ravel(), curv.reshape(-1))
        data = np.empty(self.nnz)
        data[self.pos_K] = Kd[self.src_K]
        nv = np.where(active[:, None], -n, 0.0).ravel()
        data[self.pos_Jl] = nv[self.src_Jl]
        data[self.pos_Ju] = nv[self.src_Ju]
        data[self.pos_G] = self.val_G
        data[self.pos_D] = np.where(active[self.src_D], 0.0, 1.0)
        data[self.pos_Z] = 0.0
        return sp.csc_matrix((data, self.indices, self.indptr), shape=self.shape)

    def full(self, U: sp.csc_matrix) -> sp.csc_matrix:
        """The whole symmetric matrix of its upper triangle ``U`` (for SuperLU)."""
        return (U + sp.triu(U, k=1).T).tocsc()

    def times(self, U: sp.csc_matrix, x: np.ndarray) -> np.ndarray:
        """``A x`` for the symmetric ``A`` whose upper triangle is ``U``."""
        return U @ x + U.T @ x - U.data[self.pos_diag] * x

    def solve_ldl(self, A: sp.csc_matrix, b: np.ndarray, n_u: int) -> np.ndarray | None:
        """``A⁻¹ b`` by qdldl: the LDLᵀ of ``A`` (its upper triangle, as :meth:`matrix`
        gives it) shifted by ``+ε`` on the first ``n_u`` (displacement) diagonal entries
        and ``−ε`` on the rest (:data:`LDL_SHIFT`), its symbolic factorisation made once
        for this pattern and refactorised numerically (``Solver.update``) for each system,
        then iterative refinement on ``A`` until the relative residual is ``≤ LDL_TOL``.
        ``None`` when it does not get there (a nearly singular system, a zero pivot): the
        caller uses SuperLU instead.

        (Refining with the previous system's factorisation instead of refactorising was
        measured on the notched bar's finite-strain optimize: half the systems needed 5–12
        sweeps at ~0.65 ms each against a 5.3 ms refactorisation, so it saved ~5 % and is
        not done.)
        """
        d = A.data[self.pos_diag]
        eps = LDL_SHIFT * float(np.abs(d[:n_u]).mean())
        shifted = A.data.copy()
        shifted[self.pos_diag[:n_u]] += eps
        shifted[self.pos_diag[n_u:]] -= eps
        As = sp.csc_matrix((shifted, A.indices, A.indptr), shape=A.shape)
        try:
            if self._ldl is None:
                self._ldl = _qdldl.Solver(As, upper=True)
            else:
                self._ldl.update(As, upper=True)
            x = self._ldl.solve(b)
        except (ValueError, RuntimeError):          # a zero pivot even shifted
            self._ldl = None
            return None
        scale = float(np.abs(b).max())
        if scale == 0.0:
            return np.zeros_like(b)
        for _ in range(LDL_SWEEPS + 1):
            if not np.all(np.isfinite(x)):
                return None
            res = b - self.times(A, x)
            if float(np.abs(res).max()) <= LDL_TOL * scale:
                return x
            x = x + self._ldl.solve(res)
        return None


@dataclass
class SqueezePath:
    """Converged states along a squeeze, from first touch.

    Attributes
    ----------
    delta : ndarray
        Squeezes (m) at which a state converged, increasing.
    states : list of ContactState
    reached : bool
        Whether the last requested squeeze was reached.
    delta_failed : float or None
        The smallest squeeze (m) at which the solver failed (a step halved
        :data:`MAX_HALVINGS` times without converging), ``None`` when all were reached.
    """

    delta: np.ndarray
    states: list
    reached: bool = True
    delta_failed: float | None = None
    n_solves: int = field(default=0)


def follow_squeeze(problem: FiniteStrainContact, bodies_at: Callable[[float], list],
                   targets: Sequence[float], start: ContactState | None = None,
                   start_delta: float = 0.0) -> SqueezePath:
    """Follow the contact equilibrium through the squeezes ``targets`` (m, increasing).

    Each target is reached from the previous converged state in one step, halved (and
    the halves chained) when Newton does not converge or converges to a state of lower
    energy than the last (the bodies only push, so the energy cannot fall as the squeeze
    grows: such a state is another equilibrium branch); after :data:`MAX_HALVINGS`
    halvings the rest is reported as not reached.

    Parameters
    ----------
    problem : FiniteStrainContact
    bodies_at : callable
        ``δ (m) → list of CapsuleObstacle``: the bodies' positions at squeeze δ.
    targets : sequence of float
        Squeezes (m) whose states are wanted, increasing, ``> start_delta``.
    start : ContactState, optional
        A converged state at ``start_delta`` (default: the unloaded part, ``u = 0``).
    start_delta : float
        Squeeze (m) of ``start``.

    Returns
    -------
    SqueezePath
        States at the targets reached (intermediate states of halved steps are not kept).
    """
    nd, r, k = problem.n_dofs, len(problem.node), problem.G.shape[0]
    if start is None:
        state = ContactState(np.zeros(nd), np.zeros(r), np.zeros(k), 0.0, np.zeros(r),
                             np.zeros((r, 2)), 0.0, 0, True)
    else:
        state = start
    d_now = float(start_delta)
    out_d, out_s = [], []
    prev: tuple[float, ContactState] | None = None
    solves = 0
    for target in targets:
        target = float(target)
        step = target - d_now
        halvings = 0
        while d_now < target:
            d_try = d_now + step
            if d_try >= target - 1e-9 * step:
                d_try = target
            u0 = state.u
            if prev is not None and d_now > prev[0]:
                # Linear predictor from the last two states (the path is smooth between
                # contact events).
                w = (d_try - d_now) / (d_now - prev[0])
                u0 = state.u + w * (state.u - prev[1].u)
            trial = problem.solve(bodies_at(d_try), u0, state.lam, state.mu)
            solves += 1
            if not trial.converged and u0 is not state.u:
                trial = problem.solve(bodies_at(d_try), state.u, state.lam, state.mu)
                solves += 1
            if trial.converged and trial.energy < state.energy * (1 - 1e-9):
                # the squeeze only adds energy (the bodies push: dU/dδ ≥ 0); a converged
                # state below the last one is another equilibrium branch: a smaller step
                trial.converged = False
            if trial.converged:
                prev = (d_now, state)
                state, d_now = trial, d_try
                if halvings and step < target - d_now:
                    step *= 2.0
                    halvings -= 1
                continue
            halvings += 1
            if halvings > MAX_HALVINGS:
                return SqueezePath(np.array(out_d), out_s, False, d_try, solves)
            step *= 0.5
        out_d.append(d_now)
        out_s.append(state)
    return SqueezePath(np.array(out_d), out_s, True, None, solves)
