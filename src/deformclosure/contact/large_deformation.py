"""Frictionless contact of rigid bodies (capsules, half-planes) with a part at finite
strain (SPEC §8).

At one position of the rigid bodies the part's displacement ``u`` (m, DOFs
``[x0, y0, x1, y1, …]``) solves

    min Ψ(u)   subject to   g_j(u) = dist(X_j + u_j, body_j) ≥ 0   and   G u = 0,

with ``Ψ`` the stored energy of any material law that gives its energy, gradient and
tangent (:class:`deformclosure.elasticity.neohookean.NeoHookean`, or the linear law
:class:`deformclosure.elasticity.linear_energy.LinearEnergy`), ``g_j`` the *exact*
signed distance of boundary node ``j``'s current position to a rigid body (no
linearisation: sliding along a round pad and contact on its flanks are right at any
squeeze) — or, for an *edge row*, of a round end's centre to a boundary edge less its
radius (:class:`FiniteStrainContact`'s ``edges``) — and ``G`` the gauge's linear
functionals (SPEC §6/§8: mean cross-axis displacement and mean rotation ω on a grasp
axis; mean displacement and ω for a placement among fingers). The stationarity
conditions

    ∇Ψ(u) − Σ_j λ_j ∇g_j(u) − Gᵀ μ = 0,   G u = 0,   λ ≥ 0, g ≥ 0, λ_j g_j = 0

are solved by a primal–dual active-set Newton method (Hintermüller, Ito & Kunisch,
SIAM J. Optim. 13 (2003), the semismooth Newton method for ``min(λ, c g) = 0``) with a
backtracking line search on the residual (and, once an active set repeats with edge
rows, the linearised problem's own step, :meth:`FiniteStrainContact._qp_step`); ``λ_j`` is
the normal force (N) of row ``j``
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
from typing import Callable, NamedTuple, Protocol, Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..elasticity.condense import nested_dissection_order, node_adjacency
from ..limits import blas_threads

try:                                    # optional: a faster factorisation of the KKT systems
    import qdldl as _qdldl
except ImportError:                     # pragma: no cover - depends on the installation
    _qdldl = None

__all__ = ["CapsuleObstacle", "HalfPlaneObstacle", "ContactState", "FiniteStrainContact", "SqueezePath",
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
#: Of the edge rows of one disc, only those that are a local minimum of the distance along
#: the boundary are on (ties, a foot clamped to a shared vertex, go to the edge that ends
#: there): so at every vertex exactly one row measures the distance, and as a contact
#: point crosses a vertex the row that holds it changes with equal values *and* gradients
#: (the distance to a polyline is continuously differentiable across a vertex region) —
#: never two nearly parallel active rows on one point, which split their force with
#: opposite signs and stall Newton (measured: a disc pressing a node of a flat side, with
#: node rows beside edge rows and with both edges of the node on). A disc in a notch has
#: one local minimum per wall it touches.
#: The gap (m) of a row that is off (beyond any reach).
OFF_GAP = 1.0e3
#: Re-solves of a Newton step by the active-set loop of its linearised contact problem.
QP_SWEEPS = 8
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
    #: The round front is held by the solver's *edge rows* (:meth:`centres`), not by its
    #: node rows: points in front of the segment's line then get no node-row gap (a
    #: large one), those behind it the finger's flanks as before.
    front_by_edges: bool = False

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
        if self.front_by_edges:
            front = np.ones(len(X), bool) if self.back is None else \
                (X - p) @ np.asarray(self.back, float) <= 0
            g[front], n[front], H[front] = OFF_GAP, 0.0, 0.0
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

    def centres(self) -> np.ndarray:
        """The round ends' centres and radius, rows ``(x, y, radius)`` (m): the part's
        boundary *edges* are kept outside these discs (edge rows of
        :class:`FiniteStrainContact`), so a facet cannot sag into a round end between two
        nodes."""
        ends = [self.p] if self.p == self.q else [self.p, self.q]
        return np.array([(x, y, self.radius) for x, y in ends], float)

    def moved(self, A: np.ndarray, b: np.ndarray) -> "CapsuleObstacle":
        """The capsule carried by the rigid motion ``x → A x + b`` (``A`` a rotation)."""
        A, b = np.asarray(A, float), np.asarray(b, float)
        p, q = A @ np.asarray(self.p, float) + b, A @ np.asarray(self.q, float) + b
        back = None if self.back is None else tuple(float(v) for v in A @ np.asarray(self.back, float))
        return CapsuleObstacle((float(p[0]), float(p[1])), (float(q[0]), float(q[1])),
                               self.radius, back, self.front_by_edges)


@dataclass(frozen=True)
class HalfPlaneObstacle:
    """A rigid half-plane ``{x : (x − point)·normal ≤ 0}`` (m); ``normal`` is the unit
    vector out of the body, towards the part. Its signed distance is affine: gradient
    ``normal``, no curvature."""

    point: tuple[float, float]
    normal: tuple[float, float]

    def distance(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Signed distances (m), unit gradients and Hessians (1/m) at points ``X`` (k, 2)."""
        X = np.asarray(X, float)
        nv = np.asarray(self.normal, float)
        g = (X - np.asarray(self.point, float)) @ nv
        return g, np.broadcast_to(nv, X.shape).copy(), np.zeros((len(X), 2, 2))

    def centres(self) -> np.ndarray:
        """No round part: a flat face meets a part's edge at a node."""
        return np.zeros((0, 3))

    def moved(self, A: np.ndarray, b: np.ndarray) -> "HalfPlaneObstacle":
        """The half-plane carried by the rigid motion ``x → A x + b``."""
        A, b = np.asarray(A, float), np.asarray(b, float)
        p, nv = A @ np.asarray(self.point, float) + b, A @ np.asarray(self.normal, float)
        return HalfPlaneObstacle((float(p[0]), float(p[1])), (float(nv[0]), float(nv[1])))


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
    edge_weights : ndarray or None
        Edge rows: the force's share ``s`` of each edge's second node (``1 − s`` on the
        first); None without edge rows.
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
    edge_weights: np.ndarray | None = None

    def forces(self) -> np.ndarray:
        """Contact forces on the part (N), one per row, shape (r, 2)."""
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
    edges : sequence of (ndarray of int (m, 2), int, int), optional
        *Edge rows*: ``(boundary edges as node pairs, body index, centre index)`` — each
        edge kept outside the disc ``body.centres()[centre]`` (a round end of the body).
        Node rows alone let a straight facet between two nodes sag into a round body by
        up to ``L²/8ρ`` (edge length ``L``, radius ``ρ``): on a coarse mesh a disc then
        nests in the facets of a flat side and holds a convex part. The gap of an edge
        row is the distance of the centre from the segment less ``ρ`` (:func:`_edge_rows`);
        a row is on where the centre lies in front of the edge and that distance is a
        local minimum along the boundary loop (the note above :data:`OFF_GAP`). A body
        held by edge rows keeps its round parts out of its node rows
        (``CapsuleObstacle.front_by_edges``), so no point is held by two kinds of rows.

    Rows are ordered node rows first, then edge rows; :attr:`body` gives each row's body.
    """

    def __init__(self, material: Material, nodes: np.ndarray,
                 rows: Sequence[tuple[np.ndarray, int]], gauge: np.ndarray,
                 length: float, triangles: np.ndarray | None = None,
                 edges: Sequence[tuple[np.ndarray, int, int]] = ()) -> None:
        self.material = material
        self.X = np.asarray(nodes, float)
        self.n_dofs = 2 * len(self.X)
        ids = [np.asarray(r[0], np.int64) for r in rows]
        self.node = np.concatenate(ids) if ids else np.zeros(0, np.int64)
        node_body = np.concatenate([np.full(len(i), r[1], np.int64) for i, r in zip(ids, rows)]) \
            if ids else np.zeros(0, np.int64)
        pairs = [np.asarray(e[0], np.int64).reshape(-1, 2) for e in edges]
        self.edge = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
        self.edge_body = (np.concatenate([np.full(len(q), e[1], np.int64) for q, e in zip(pairs, edges)])
                          if pairs else np.zeros(0, np.int64))
        self.edge_centre = (np.concatenate([np.full(len(q), e[2], np.int64) for q, e in zip(pairs, edges)])
                            if pairs else np.zeros(0, np.int64))
        self.n_node_rows = len(self.node)
        self.body = np.concatenate([node_body, self.edge_body])
        # each edge row's neighbours along its boundary loop (same body and centre), -1 at
        # an open end: the rows that are a local minimum of the distance are the ones on
        self._edge_next = np.full(len(self.edge), -1, np.int64)
        self._edge_prev = np.full(len(self.edge), -1, np.int64)
        key = {(int(b), int(k), int(a)): i for i, (a, b, k) in
               enumerate(zip(self.edge[:, 0], self.edge_body, self.edge_centre))}
        for i, (b_end, b, k) in enumerate(zip(self.edge[:, 1], self.edge_body, self.edge_centre)):
            j = key.get((int(b), int(k), int(b_end)), -1)
            if j >= 0:
                self._edge_next[i], self._edge_prev[j] = j, i
        self.n_rows = len(self.body)
        self.G = sp.csr_matrix(np.asarray(gauge, float))
        self.length = float(length)
        self.gap_tol = RESIDUAL_TOL * self.length
        self.area = float(np.ptp(self.X[:, 0]) * np.ptp(self.X[:, 1])) if len(self.X) else 0.0
        self._floor: float | None = None
        self._pattern: _KKTPattern | None = None
        if triangles is not None and len(self.X) > 2:
            perm = nested_dissection_order(node_adjacency(np.asarray(triangles), len(self.X)))
            self._order = np.column_stack([2 * perm, 2 * perm + 1]).ravel()
        else:
            self._order = np.arange(self.n_dofs)

    # -------------------------------------------------------------------- geometry
    def gaps(self, u: np.ndarray, bodies: Sequence[CapsuleObstacle]
             ) -> tuple[np.ndarray, np.ndarray, "RowCurvature"]:
        """Signed distances (m) and unit normals (the direction of each row's force on the
        part) of every row at ``u``, and the rows' curvature (:class:`RowCurvature`)."""
        rn = self.n_node_rows
        x = self.X[self.node] + u.reshape(-1, 2)[self.node]
        g, n, H = np.empty(self.n_rows), np.empty((self.n_rows, 2)), np.empty((rn, 2, 2))
        nb = self.body[:rn]
        for b, body in enumerate(bodies):
            sel = nb == b
            if sel.any():
                g[:rn][sel], n[:rn][sel], H[sel] = body.distance(x[sel])
        s, He = np.zeros(len(self.edge)), np.zeros((len(self.edge), 4, 4))
        if len(self.edge):
            U = u.reshape(-1, 2)
            xa = self.X[self.edge[:, 0]] + U[self.edge[:, 0]]
            xb = self.X[self.edge[:, 1]] + U[self.edge[:, 1]]
            C = np.zeros((len(self.edge), 3))
            for b, body in enumerate(bodies):
                sel = self.edge_body == b
                if sel.any():
                    C[sel] = body.centres()[self.edge_centre[sel]]
            g[rn:], n[rn:], s, He = _edge_rows(xa, xb, C, OFF_GAP, self._edge_prev,
                                               self._edge_next)
        return g, n, RowCurvature(H, s, He)

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
        nd, r, k = self.n_dofs, self.n_rows, self.G.shape[0]
        u = np.zeros(nd) if u0 is None else np.array(u0, float)
        lam = np.zeros(r) if lam0 is None else np.array(lam0, float)
        mu = np.zeros(k) if mu0 is None else np.array(mu0, float)
        mat = self.material
        E, grad, Kt = mat.energy_gradient_tangent(u)
        g, n, H = self.gaps(u, bodies)
        if not math.isfinite(E):                 # an inverted element: no Newton step
            return ContactState(u, lam, mu, math.inf, g, n, math.inf, 0, False)  # noqa: E501
        c = float(Kt.diagonal().mean())          # N/m: the scale of min(λ, c g)
        if self._floor is None:
            # Round-off of the internal force: about eps × (stiffness × element size) per
            # DOF (the stress of a law like neo-Hookean is a difference of O(μ) terms), so
            # at strains below ~1e-6 a residual of 1e-10 relative to the forces is below
            # what the arithmetic resolves; the residual is relative to at least 1e10 ×
            # that floor.
            h = math.sqrt(self.area / max(self.n_dofs // 2, 1))
            self._floor = 100.0 * np.finfo(float).eps * c * h / RESIDUAL_TOL
        res = self._residual(u, lam, mu, grad, g, n, H, c, force_scale)
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
            # a repeated active set: the semismooth steps cycle; with edge rows the step is
            # then the linearised problem's own solution (:meth:`_qp_step`)
            qp = cycling and len(self.edge) > 0
            step = (self._qp_step if qp else self._newton_step)(u, lam, mu, grad, Kt, g, n, H,
                                                                active)
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
                    rt = self._residual(ut, lt, mt, gt_, gg, nn, HH, c, force_scale)
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
        return ContactState(u, lam, mu, float(E), g, n, float(res), it, converged,
                            H.s if len(self.edge) else None)

    def _complementary(self, lam: np.ndarray, g: np.ndarray) -> bool:
        """No row penetrates beyond the gap tolerance and no active row pulls."""
        tol = self.gap_tol
        on = lam > 0
        return bool(np.all(g >= -tol) and np.all(np.abs(g[on]) <= tol) and np.all(lam >= 0))

    def _residual(self, u, lam, mu, grad, g, n, H, c, force_scale) -> float:
        """Relative residual: stationarity over the force scale, complementarity
        ``min(λ, c g)`` over the same scale, the gauge over the length scale."""
        r_u = grad - self._contact_load(lam, n, H) - self.G.T @ mu
        scale = force_scale
        if scale is None:
            scale = max(float(np.abs(grad).max(initial=0.0)), float(np.abs(lam).max(initial=0.0)))
        scale = max(scale, self._floor or 0.0, 1e-300)
        ncp = np.minimum(lam, c * g)
        gauge = np.abs(self.G @ u).max(initial=0.0) / self.length
        return float(max(np.abs(r_u).max(initial=0.0) / scale,
                         np.abs(ncp).max(initial=0.0) / scale, gauge))

    def _contact_load(self, lam: np.ndarray, n: np.ndarray, H: "RowCurvature") -> np.ndarray:
        """``Σ_j λ_j ∇g_j`` (N), shape (2n,)."""
        return self.nodal_forces(lam, n, H.s).ravel()

    def nodal_forces(self, lam: np.ndarray, n: np.ndarray,
                     edge_weights: np.ndarray | None = None) -> np.ndarray:
        """The rows' forces ``λ_j n_j`` (N) summed on the nodes, shape (n_nodes, 2): a node
        row's on its node, an edge row's shared ``1 − s``, ``s`` by its two nodes."""
        rn = self.n_node_rows
        f = np.zeros((len(self.X), 2))
        np.add.at(f, self.node, lam[:rn, None] * n[:rn])
        if len(self.edge) and edge_weights is not None:
            fe = lam[rn:, None] * n[rn:]
            s = edge_weights[:, None]
            np.add.at(f, self.edge[:, 0], (1.0 - s) * fe)
            np.add.at(f, self.edge[:, 1], s * fe)
        return f

    def state_forces(self, state: "ContactState") -> np.ndarray:
        """:meth:`nodal_forces` of a converged state (N), shape (n_nodes, 2)."""
        return self.nodal_forces(state.lam, state.normals, state.edge_weights)

    def _qp_step(self, u, lam, mu, grad, Kt, g, n, H, active):
        """The Newton step of the active set ``active``, made the solution of the
        linearised (quadratic) contact problem by a primal–dual active-set loop: while a
        row of the set pulls (``λ < 0``, the most negative leaves) or a row outside it
        penetrates at first order (``g + ∇g·Δu < 0``, the deepest joins), the step is
        solved again. With two nearly parallel rows on almost one point (a disc on the
        two edges of a dented node) the plain semismooth step splits their force with
        opposite signs and the next step swaps them, without end; the subproblem's own
        solution does not (at most :data:`QP_SWEEPS` re-solves). Used once an active set
        repeats, and only with edge rows (where such pairs arise): the pads' node rows
        cycle often at grazing rows (1 650 times in one 723-node neo-Hookean optimize),
        where backtracking cures it and this loop gave the same Q* 33 % slower (13.5 s
        against 10.2 s); re-solving every step measured 58 → 97 s on the three-level test."""
        A = active.copy()
        step = None
        tol = self.gap_tol
        for _ in range(QP_SWEEPS + 1):
            step = self._newton_step(u, lam, mu, grad, Kt, g, n, H, A)
            if step is None:
                return None
            du, lam_new, _ = step
            pull = A & (lam_new < 0.0)
            if pull.any():
                A[np.flatnonzero(pull)[np.argmin(lam_new[pull])]] = False
                continue
            lin = g + self._row_dot(n, H.s, du)
            deep = ~A & (lin < -tol)
            if deep.any():
                A[np.flatnonzero(deep)[np.argmin(lin[deep])]] = True
                continue
            break
        return step

    def _row_dot(self, n: np.ndarray, s: np.ndarray, du: np.ndarray) -> np.ndarray:
        """``∇g_j · Δu`` (m) of every row."""
        rn = self.n_node_rows
        D = du.reshape(-1, 2)
        out = np.einsum("ij,ij->i", n[:rn], D[self.node])
        if len(self.edge):
            ne = n[rn:]
            de = (1.0 - s)[:, None] * D[self.edge[:, 0]] + s[:, None] * D[self.edge[:, 1]]
            out = np.concatenate([out, np.einsum("ij,ij->i", ne, de)])
        return out

    def _newton_step(self, u, lam, mu, grad, Kt, g, n, H, active):
        """One primal–dual active-set Newton step; returns ``(Δu, λ⁺, μ⁺)``, or ``None``
        when the Newton system is singular even regularised.

        The system is ``[[K_T − Σ_A λ_j ∇²g_j, −Jᵀ, −Gᵀ], [−J, D, 0], [−G, 0, 0]]`` over every
        candidate row: an active row ``j`` has its gradient in ``J`` and ``D_jj = 0`` (its
        gap linearised to zero), an inactive one a zero row of ``J`` and ``D_jj = 1`` (its
        force set to zero). So the pattern is the same at every step: it is built once
        (:class:`_KKTPattern`) and each step only fills its values.
        """
        nd, r, rn = self.n_dofs, self.n_rows, self.n_node_rows
        pat = self._pattern
        if pat is None or not pat.fits(Kt):
            pat = self._pattern = _KKTPattern(Kt, self.node, self.edge, self.G, self._order)
        A = active
        lamA = np.where(A, lam, 0.0)
        r_u = grad - self._contact_load(lamA, n, H) - self.G.T @ mu
        # the bodies' surface curvature under the active forces: on the nodes' diagonal
        # blocks (node rows), on the edges' two nodes (edge rows)
        curv = -(lamA[:rn, None, None] * H.node)
        ecurv = -(lamA[rn:, None, None] * H.edge)
        grads = _row_gradients(n, H.s, rn)
        KKT = pat.matrix(Kt.data, curv, ecurv, grads, A)
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


class RowCurvature(NamedTuple):
    """The rows' second derivatives (1/m): node rows' Hessians ``node`` (r_n, 2, 2) in
    their node's position; edge rows' foot parameters ``s`` (r_e,) — the force's share of
    the edge's second node — and Hessians ``edge`` (r_e, 4, 4) in their two nodes'
    positions."""

    node: np.ndarray
    s: np.ndarray
    edge: np.ndarray


def _edge_rows(xa: np.ndarray, xb: np.ndarray, C: np.ndarray, off: float,
               prev: np.ndarray | None = None, nxt: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Gaps (m), unit normals, foot parameters and Hessians (1/m, over ``(x_a, x_b)``) of
    edges ``x_a → x_b`` (part's interior on their left) against discs ``C = (x, y, ρ)``.

    The gap is the distance ``d`` from the centre ``c`` to the segment less ``ρ``, at the
    foot ``s = (c − x_a)·e / L²`` clamped to ``[0, 1]`` (``e = x_b − x_a``, ``L = |e|``);
    the normal ``m = (f − c)/d`` points from the centre to the foot ``f`` (the force on
    the part). ``∇d = [(1 − s) m, s m]`` (the envelope of the distance over the segment's
    points). Inside the segment ``d`` is the line distance, smooth in the edge's ends:
    ``∇²d = −(Jᵀe wᵀ + w eᵀJ)/L² − d w wᵀ/L²`` with ``J = [(1 − s)I, sI]`` and
    ``w = [−m, m]`` (from ``d = min_s |x_a + s e − c|``; checked against finite
    differences in the tests); at an end vertex ``(I − m mᵀ)/d`` on its node. A row is
    off (gap ``off``, no gradient) when the centre is not in front of the edge's line or,
    with ``prev``/``nxt`` (each row's neighbours along the boundary, -1 for none), when
    its distance is not a local minimum along the boundary (the module's note on edge
    rows).
    """
    e = xb - xa
    L2 = np.einsum("ij,ij->i", e, e)
    c = C[:, :2]
    s_raw = np.einsum("ij,ij->i", c - xa, e) / L2
    s = np.clip(s_raw, 0.0, 1.0)
    L = np.sqrt(L2)
    inward = np.stack([-e[:, 1], e[:, 0]], 1) / L[:, None]
    front = -np.einsum("ij,ij->i", c - xa, inward) > 0.0
    f = xa + s[:, None] * e
    r = f - c
    d = np.hypot(r[:, 0], r[:, 1])
    on = front & (d > 0)
    if prev is not None:
        # a local minimum of the distance along the boundary: a foot inside the edge, or
        # the end vertex when the next edge's foot clamps to it too (a convex corner);
        # a foot clamped to the start vertex belongs to the previous edge
        s_next = np.where(nxt >= 0, s_raw[np.maximum(nxt, 0)], 0.0)
        on &= ((s_raw > 0.0) & (s_raw < 1.0)) | ((s_raw >= 1.0) & (s_next <= 0.0))
    m = np.where(on[:, None], r / np.where(d > 0, d, 1.0)[:, None], 0.0)
    g = np.where(on, d - C[:, 2], off)
    k = len(e)
    J = np.zeros((k, 2, 4))
    J[:, 0, 0] = J[:, 1, 1] = 1.0 - s
    J[:, 0, 2] = J[:, 1, 3] = s
    Je = np.einsum("kij,ki->kj", J, e)                            # Jᵀe, (k, 4)
    w = np.concatenate([-m, m], axis=1)
    H = -(Je[:, :, None] * w[:, None, :] + w[:, :, None] * Je[:, None, :]) / L2[:, None, None] \
        - (d / L2)[:, None, None] * (w[:, :, None] * w[:, None, :])
    for end, blk in ((on & (s_raw >= 1.0), slice(2, 4)), (on & (s_raw <= 0.0), slice(0, 2))):
        if end.any():
            P = np.eye(2)[None] - m[end][:, :, None] * m[end][:, None, :]
            He = np.zeros((int(end.sum()), 4, 4))
            He[:, blk, blk] = P / d[end][:, None, None]
            H[end] = He
    H[~on] = 0.0
    return g, m, np.where(on, s, 0.0), H


def _row_gradients(n: np.ndarray, s: np.ndarray, rn: int) -> np.ndarray:
    """The rows' gradient entries in the order of :class:`_KKTPattern`: a node row's
    normal, an edge row's ``[(1 − s) m, s m]``."""
    ne = n[rn:]
    edge = np.concatenate([(1.0 - s)[:, None] * ne, s[:, None] * ne], axis=1)
    return np.concatenate([n[:rn].ravel(), edge.ravel()])


def _csr_positions(K: sp.csr_matrix, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Positions in ``K.data`` of the entries ``(rows, cols)`` (same shape); ValueError
    when one is not in the pattern."""
    out = np.empty(rows.shape, np.int64)
    for idx in np.ndindex(rows.shape):
        lo, hi = K.indptr[rows[idx]], K.indptr[rows[idx] + 1]
        hit = np.flatnonzero(K.indices[lo:hi] == cols[idx])
        if len(hit) != 1:
            raise ValueError("tangent without the rows' node blocks")
        out[idx] = lo + hit[0]
    return out


class _KKTPattern:
    """The fixed sparsity pattern of the Newton system of :class:`FiniteStrainContact`, in
    the solver's nested-dissection order (CSC), and where each value goes: the tangent's
    CSR values, the rows' gradients (twice, the matrix is symmetric), the gauge and the
    multipliers' diagonal. Built once per tangent pattern; :meth:`matrix` fills it."""

    def __init__(self, Kt: sp.csr_matrix, node: np.ndarray, edge: np.ndarray,
                 G: sp.csr_matrix, order: np.ndarray) -> None:
        Kt = Kt.tocsr()
        rn, re = len(node), len(edge)
        nd, r = Kt.shape[0], rn + re
        self.indptr_K, self.indices_K = Kt.indptr.copy(), Kt.indices.copy()
        nK = Kt.nnz
        # ids (1-based, so no value is dropped as a zero) of every source value
        K_ids = sp.csr_matrix((np.arange(1, nK + 1, dtype=float), Kt.indices, Kt.indptr),
                              shape=(nd, nd))
        # the rows' gradient entries: a node row's 2 DOFs, an edge row's 4 (its two nodes)
        edofs = np.stack([2 * edge[:, 0], 2 * edge[:, 0] + 1, 2 * edge[:, 1], 2 * edge[:, 1] + 1], 1)
        jr = np.concatenate([np.repeat(np.arange(rn), 2), np.repeat(np.arange(rn, r), 4)])
        jc = np.concatenate([np.stack([2 * node, 2 * node + 1], 1).ravel(), edofs.ravel()])
        self.entry_row = jr
        ne = len(jr)
        base_jl = nK + 1
        Jl = sp.csr_matrix((np.arange(base_jl, base_jl + ne, dtype=float), (jr, jc)),
                           shape=(r, nd))
        base_ju = base_jl + ne
        Ju = sp.csr_matrix((np.arange(base_ju, base_ju + ne, dtype=float), (jr, jc)),
                           shape=(r, nd))
        Gd = np.asarray(G.todense())
        base_g = base_ju + ne
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
        # where each node row's 2×2 diagonal block, and each edge row's 4×4 block over its
        # two nodes (an edge of the mesh: the tangent has its off-diagonal blocks), sit in
        # the tangent's CSR values
        rows_n = np.stack([2 * node, 2 * node, 2 * node + 1, 2 * node + 1], 1)
        cols_n = np.stack([2 * node, 2 * node + 1, 2 * node, 2 * node + 1], 1)
        self.blocks = _csr_positions(Kt, rows_n, cols_n)
        self.eblocks = _csr_positions(Kt, np.repeat(edofs, 4, axis=1), np.tile(edofs, (1, 4)))

    def fits(self, Kt: sp.csr_matrix) -> bool:
        """Whether ``Kt`` has the pattern this was built for."""
        return (Kt.nnz == len(self.indices_K) and np.array_equal(Kt.indptr, self.indptr_K)
                and np.array_equal(Kt.indices, self.indices_K))

    def matrix(self, K_data: np.ndarray, curv: np.ndarray, ecurv: np.ndarray,
               grads: np.ndarray, active: np.ndarray) -> sp.csc_matrix:
        """The upper triangle (CSC) of the Newton matrix: tangent values ``K_data`` plus the
        node rows' curvature blocks ``curv`` (r_n, 2, 2) and the edge rows' ``ecurv``
        (r_e, 4, 4), the gradient entries ``grads`` (:func:`_row_gradients`) of the active
        rows."""
        Kd = np.array(K_data, float)
        np.add.at(Kd, self.blocks.ravel(), curv.reshape(-1))
        if len(ecurv):
            np.add.at(Kd, self.eblocks.ravel(), ecurv.reshape(-1))
        data = np.empty(self.nnz)
        data[self.pos_K] = Kd[self.src_K]
        nv = np.where(active[self.entry_row], -grads, 0.0)
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
                   start_delta: float = 0.0, monotone: bool = True) -> SqueezePath:
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
    monotone : bool
        The bodies only push deeper as δ grows, so a converged state of lower energy than
        the last is another branch (default). False for a path that may also release
        (e.g. a part moved among fixed fingers, δ the fraction of the move).

    Returns
    -------
    SqueezePath
        States at the targets reached (intermediate states of halved steps are not kept).
    """
    nd, r, k = problem.n_dofs, problem.n_rows, problem.G.shape[0]
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
            if monotone and trial.converged and trial.energy < state.energy * (1 - 1e-9):
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
