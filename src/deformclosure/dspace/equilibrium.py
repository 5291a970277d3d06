"""Frictionless contact equilibrium of a free deformable part between fixed fingers
(paper §3.3, SPEC §3).

The part is free to translate and rotate; the fingers are fixed. The equilibrium is a
local minimum of the linear elastic energy ``U = 1/2 X^T K X`` in ``D_free``:

    minimise 1/2 X^T K X  subject to  gap_r(q(X)) >= 0  for every contact condition r.

Model (small-displacement theory, like the paper's ``K``)
---------------------------------------------------------
* ``X`` is the nodal displacement including the rigid motion (``K`` ignores it). The
  configuration ``q(X)`` applies the *rigid part* of ``X`` (mean displacement and mean
  rotation ω = ½ curl u, the gauge of SPEC §6/§7) as an exact
  finite rotation + translation and the rest as deformation, so a turning part does
  not swell (a linearised rotation would stretch it).
* Contact conditions are node-to-surface (:func:`deformclosure.contact.rows.contact_rows`,
  its §3 rule): part nodes against finger bodies, finger corners against part edges,
  discs against edges. Their
  force directions (finger normals at the rigidly placed nodes, part-edge normals at
  rest), the material points carrying them on edges (foot points at rest) and the
  moment arms are taken on the rest geometry placed by the part's rigid motion, so the
  contact forces balance exactly, in sum and in moment.

Method
------
Sequential linearisation: at the current configuration the gaps are linearised and the
convex QP is solved *in its dual*, whose size is the number of contact conditions:

    minimise 1/2 lam^T W lam + g~^T lam   s.t.  lam >= 0,  B lam = 0,

with ``W = C Y C^T`` the contact compliance (``Y``: the gauged compliance of the
perimeter DOFs, :class:`deformclosure.contact.compliance.BoundaryCompliance`, one
factorisation — the same as the pads' and ``check``'s placements), ``g~`` the gaps at ``X = 0`` and ``B lam = 0`` the force and moment
balance. The QP is solved with Clarabel (through qpsolvers), *polished* on its active
set (exact complementarity), and the rigid motion is the smallest one keeping every gap
non-negative (a trust region of 5 % of the diameter per step lets a squeezed-out part
leave gradually). While the contact rows and the active set stay the same, the
re-linearisations are accelerated with Anderson mixing (depth 5): the plain iteration
converges only linearly, at a rate near 1 for parts that must turn to balance. Gaps are re-linearised until the step is below ``1e-9`` x the
diameter (or ``1e-6`` x the largest elastic displacement); the rigid placement used for
the force directions is iterated to a fixed point with Aitken relaxation. ``lam`` are
the contact forces (N).

Limits: equilibria that need a large rigid rotation to balance, where the active set
keeps changing as the part turns, may stop at the iteration budget
(``converged=False``); the forces still balance. Like any node-to-surface scheme, part edges between two contact nodes may cut
a curved finger by up to ``l^2 / (8 r)`` (edge length ``l``, radius ``r``).

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.3 (equilibrium, deform closure).
P. Wriggers, *Computational Contact Mechanics*, 2nd ed., Springer 2006 (frictionless
node-to-surface contact, dual formulation).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..contact.solve import ContactProblem, solve_contact
from ..errors import DeformClosureError
from ..elasticity.strain import strain_magnitude
from .fingers import Finger, as_fingers
from .placement import check_finger_placement
from ..contact.rows import BoundaryModel, ContactRows, contact_rows, merge_rows, refresh_rows
from .obstacles import nonnegative, resolve_tolerance

__all__ = ["EquilibriumResult", "equilibrium", "area_centroid"]

_J = np.array([[0.0, -1.0], [1.0, 0.0]])
UNITS = {"length": "m", "energy": "J", "force": "N", "moment": "N*m", "angle": "rad"}


def area_centroid(triangles: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Area centroid (m) of the triangulated region in configuration ``x (n, 2)``."""
    p = x[np.asarray(triangles)]
    d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    A = 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    return (A[:, None] * p.mean(axis=1)).sum(axis=0) / A.sum()


def _rot(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class EquilibriumResult:
    """Frictionless contact equilibrium of a free part (paper §3.3).

    Attributes
    ----------
    q : ndarray (n, 2)
        Equilibrium configuration (m).
    displacement : ndarray (n, 2)
        ``X`` (m): its elastic part gives the energy; its rigid part (mean displacement
        and mean rotation) is applied exactly in ``q``.
    rotation : float
        Mean rigid rotation of the part (rad).
    translation : ndarray (2,)
        Displacement of the area centroid (m).
    forces : ndarray (n_fingers, 2)
        Force each finger exerts on the part (N).
    moments : ndarray (n_fingers,)
        Moment of each finger's force about the rest area centroid, with the rest-geometry
        arms of the small-displacement model (N m); they sum to zero.
    points : ndarray (n_fingers, 2)
        Point of application of each finger's resultant in ``q`` (centre of its contact
        forces; the nearest contact point when the force is zero) (m).
    nodal_forces : ndarray (n, 2)
        Contact forces on the nodes (N).
    gaps : ndarray (n_fingers,)
        Smallest gap of each finger at the equilibrium, node-to-surface (m; ``inf`` if
        out of reach).
    active : ndarray (n_fingers,) of bool
        Finger touches the part (gap within ``tol``) or pushes on it.
    energy : float
        Linear elastic energy ``1/2 X^T K X`` (J).
    centroid : ndarray (2,)
        Area centroid of the equilibrium configuration (m).
    iterations : int
        Number of linearised QPs solved.
    converged : bool
        Steps and rigid placement settled (see module notes) and no penetration.
    tol : float
        Touching tolerance used (m).
    max_strain : float
        Largest element strain magnitude of the elastic deformation (-), to compare
        with the material's elastic-limit strain ``e_L``.
    accuracy : float
        Convergence threshold (m): ``max(1e-9 L, 1e-6 x`` the largest elastic
        displacement``)``. A converged equilibrium moved less than this in its last
        linearisation and penetrates no finger by more than ``max(tol, accuracy)``.
    rows : ContactRows
        The final linearised contact conditions, ``multipliers`` their forces (N).
    """

    q: np.ndarray
    displacement: np.ndarray
    rotation: float
    translation: np.ndarray
    forces: np.ndarray
    moments: np.ndarray
    points: np.ndarray
    nodal_forces: np.ndarray
    gaps: np.ndarray
    active: np.ndarray
    energy: float
    centroid: np.ndarray
    iterations: int
    converged: bool
    tol: float
    accuracy: float
    max_strain: float
    rows: ContactRows = field(repr=False)
    multipliers: np.ndarray = field(repr=False)

    def to_dict(self) -> dict:
        """JSON-ready summary (SI units)."""
        return {
            "energy": float(self.energy),
            "energy_kind": "linear",
            "iterations": int(self.iterations),
            "converged": bool(self.converged),
            "accuracy": float(self.accuracy),
            "max_strain": float(self.max_strain),
            "rotation": float(self.rotation),
            "translation": [float(v) for v in self.translation],
            "forces": self.forces.tolist(),
            "moments": self.moments.tolist(),
            "points": self.points.tolist(),
            "gaps": [None if not np.isfinite(g) else float(g) for g in self.gaps],
            "active": [bool(a) for a in self.active],
            "units": dict(UNITS),
        }


def _min_norm_rigid(y0: np.ndarray, N: np.ndarray, Mi: np.ndarray, zi: np.ndarray,
                    slack: float = 1e-10) -> np.ndarray:
    """``min |y0 + N eta|`` subject to ``zi + Mi (y0 + N eta) >= 0`` (a tiny QP).

    Gaps down to ``-slack`` (scaled by the part's diameter) count as satisfied, so
    round-off in touching contacts does not move the part.
    """
    if N.shape[1] == 0:
        return y0
    y = y0 - N @ np.linalg.lstsq(N, y0, rcond=None)[0]  # unconstrained minimum
    if len(zi) == 0 or np.all(zi + Mi @ y >= -slack):
        return y
    import scipy.sparse as sp
    from qpsolvers import Problem, solve_problem

    k = N.shape[1]
    MN = Mi @ N
    h = zi + Mi @ y0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = solve_problem(Problem(sp.csc_matrix(N.T @ N + 1e-12 * np.eye(k)), N.T @ y0, sp.csc_matrix(-MN), h),
                            solver="clarabel", tol_gap_abs=1e-12, tol_gap_rel=1e-12, tol_feas=1e-12)
    if sol.x is None:
        return y0
    eta = np.asarray(sol.x)
    # exact on the binding constraints (least-norm solution of the equalities)
    z = np.asarray(sol.z) if sol.z is not None else np.zeros(len(h))
    act = np.flatnonzero(z > 1e-9 * max(float(z.max(initial=0.0)), 1e-300))
    if len(act):
        KKT = np.block([[N.T @ N, MN[act].T], [MN[act], np.zeros((len(act), len(act)))]])
        rhs = np.r_[-N.T @ y0, -h[act]]
        sol2 = np.linalg.lstsq(KKT, rhs, rcond=1e-13)[0]
        eta2 = sol2[:k]
        if np.all(h + MN @ eta2 >= -slack):
            eta = eta2
    return y0 + N @ eta


class _RigidFit:
    """The rigid part of a displacement field in the gauge of SPEC §6/§7
    (:func:`deformclosure.contact.compliance.gauge_functionals`).

    ``coords(X)`` returns ``(tx, ty, L theta)``: the mean displacement (the displacement
    of the area centroid) and the area-weighted mean rotation ``ω = ½ curl u`` — exact
    for piecewise-linear fields, so a uniform strain has zero rotation on any mesh, and
    the same convention as the contact energies of ``check`` and the pads.
    """

    def __init__(self, mesh: Any, C0: np.ndarray, L: float):
        from ..contact.compliance import gauge_functionals

        x0 = np.asarray(mesh.nodes, float)
        n = len(x0)
        self.x0, self.C0, self.L = x0, C0, L
        self.R0 = np.zeros((2 * n, 3))
        self.R0[0::2, 0] = 1.0
        self.R0[1::2, 1] = 1.0
        self.R0[0::2, 2] = -(x0[:, 1] - C0[1]) / L
        self.R0[1::2, 2] = (x0[:, 0] - C0[0]) / L
        self.Gf = gauge_functionals(mesh)
        self.G = self.Gf @ self.R0               # diag(1, 1, 1/L) up to rounding

    def coords(self, X: np.ndarray) -> np.ndarray:
        v = np.asarray(X, float).reshape(-1)
        return np.linalg.solve(self.G, self.Gf @ v)

    def placed(self, X: np.ndarray, rigid: np.ndarray | None = None) -> np.ndarray:
        """Configuration of displacement ``X``: its rigid part applied as an exact
        (finite) rotation and translation, the rest as deformation.

        Linear elasticity sees only ``X`` (rigid modes cost nothing either way); the
        geometry uses the exact rotation, so a rotating part does not swell. With
        ``rigid = (tx, ty, L theta)`` given, the rest geometry placed by that rigid
        motion only.
        """
        if rigid is not None:
            c = np.asarray(rigid, float)
            return (self.x0 - self.C0) @ _rot(c[2] / self.L).T + self.C0 + c[:2]
        c = self.coords(X)
        Xd = X - (self.R0 @ c).reshape(X.shape)
        return (self.x0 - self.C0 + Xd) @ _rot(c[2] / self.L).T + self.C0 + c[:2]


def equilibrium(mesh: Any, fingers: Sequence[Finger], *, stiffness: Any = None, tol: float | None = None,
                max_iter: int = 50, search_radius: float | None = None,
                check_placement: bool = True) -> EquilibriumResult:
    """Frictionless contact equilibrium of the free part between fixed fingers.

    Parameters
    ----------
    mesh : Mesh
        The part's mesh (rest configuration, m) with its material.
    fingers : sequence of Finger
        Fixed fingers (m), placed against the part at rest (touching, or overlapping it
        to pre-squeeze it).
    stiffness : sparse matrix (2n, 2n), optional
        Stiffness ``K`` (N/m); assembled from the mesh when omitted.
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter`` (SPEC §3).
    max_iter : int
        Maximum number of updates of the rigid reference placement (each runs up to 8
        re-linearisations; at most ``4 max_iter`` in all).
    search_radius : float, optional
        Contact conditions are linearised for gaps below this (m); default
        ``max(0.02 L, 3 x deepest penetration)`` with ``L`` the diameter.
    check_placement : bool
        Refuse fingers that start deep inside the part
        (:func:`~deformclosure.dspace.placement.check_finger_placement`).

    Returns
    -------
    EquilibriumResult
        Configuration (m), contact force per finger (N) and its moment (N m), energy
        (J, linear), iterations, convergence.

    Raises
    ------
    FingerError, FingerPlacementError
        ``fingers`` is not a sequence of fingers, or one starts deep inside the part.
    DeformClosureError
        A bad ``tol``, ``max_iter`` or ``search_radius``, or the contact problem cannot
        be solved.

    Notes
    -----
    Small-displacement theory, like the paper's ``U = 1/2 X^T K X`` (see the module
    docstring): the rigid part of ``X`` is applied exactly, force directions and arms
    are those of the rest geometry placed by the rigid motion, and the contact forces
    balance exactly (sum and moment). When the fingers cannot hold the part against its
    own pre-squeeze, the part is pushed out by the smallest rigid motion and the
    equilibrium has zero energy. Check ``converged``.

    Examples
    --------
    A 30 mm square of soft rubber squeezed 0.1 mm at each side between two flat jaws:

    >>> import numpy as np
    >>> from deformclosure import Part, mesh_part
    >>> from deformclosure.dspace import HalfPlaneFinger, equilibrium
    >>> rubber = {"youngs_modulus": 1e6, "poisson_ratio": 0.45, "elastic_limit_strain": 0.3}
    >>> square = {"units": "mm", "outer": [[0, 0], [30, 0], [30, 30], [0, 30]], "material": rubber}
    >>> jaws = [HalfPlaneFinger((0.0001, 0.0), (1.0, 0.0)), HalfPlaneFinger((0.0299, 0.0), (-1.0, 0.0))]
    >>> res = equilibrium(mesh_part(Part.from_dict(square)), jaws)
    >>> res.converged, bool(res.energy > 0), bool(np.allclose(res.forces.sum(axis=0), 0.0, atol=1e-9))
    (True, True, True)

    References
    ----------
    Gopalakrishnan & Goldberg (2005), §3.3.
    """
    fingers = list(as_fingers(fingers))
    _check_iteration(max_iter, search_radius)
    if check_placement:
        check_finger_placement(mesh, fingers)
    tol = resolve_tolerance(mesh, tol)
    if stiffness is None:
        from ..elasticity.stiffness import stiffness_matrix

        stiffness = stiffness_matrix(mesh)
    solve = _ContactSolve(mesh, fingers, stiffness, search_radius)
    X, lam, converged = solve.run(max_iter)
    return solve.result(X, lam, converged, tol)


def _check_iteration(max_iter: Any, search_radius: Any) -> None:
    """Refuse an iteration budget or a search radius out of range."""
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise DeformClosureError(f"max_iter = {max_iter!r}: give an integer >= 1")
    if search_radius is not None:
        nonnegative(search_radius, "search_radius", "the contact search radius in m", "or None for the default")


class _Anderson:
    """Anderson acceleration (type II, depth 5) of the fixed-point map ``X -> X_new``
    while the contact rows and the active set (the ``signature``) stay the same: the plain
    iteration converges only linearly (the exact rigid rotation makes the gaps slightly
    nonlinear), with a rate near 1 for parts that must turn to balance."""

    def __init__(self) -> None:
        self.X: list[np.ndarray] = []
        self.F: list[np.ndarray] = []
        self.signature: Any = None

    def step(self, X: np.ndarray, X_new: np.ndarray, signature: Any) -> np.ndarray:
        """The next iterate after ``X`` whose image is ``X_new``."""
        if signature != self.signature:
            self.X, self.F, self.signature = [], [], signature
        self.X.append(X.ravel().copy())
        self.F.append((X_new - X).ravel())
        del self.X[:-6], self.F[:-6]
        if len(self.F) < 2:
            return X_new
        dX = np.diff(np.array(self.X), axis=0).T
        dF = np.diff(np.array(self.F), axis=0).T
        gamma = np.linalg.lstsq(dF, self.F[-1], rcond=1e-10)[0]
        return X_new - ((dX + dF) @ gamma).reshape(X_new.shape)


class _ContactSolve:
    """The sequential linearisation of the contact problem (module docstring, Method):
    the part, the fingers, the rigid-motion fit and the contact rows linearised so far."""

    def __init__(self, mesh: Any, fingers: list[Finger], K: Any, search_radius: float | None):
        self.mesh, self.fingers, self.K = mesh, fingers, K
        self.x0 = x0 = np.asarray(mesh.nodes, dtype=float)
        self.n = len(x0)
        self.L = L = float(mesh.diameter)
        self.search_radius = search_radius
        mat = getattr(mesh, "material", None)
        if mat is not None:
            self.F0 = float(mat.youngs_modulus * mat.thickness * L)   # force scale of the QP
        else:
            self.F0 = float(np.abs(K.diagonal()).mean() * L)
        self.bd = BoundaryModel(mesh)
        self.C0 = area_centroid(mesh.triangles, x0)
        self.fit = _RigidFit(mesh, self.C0, L)
        self.R0 = self.fit.R0  # rigid modes: translations (per m) and rotation (per L rad)
        self.comp: Any = None
        self.rows = contact_rows(self.bd, x0, fingers, radius=0.0)
        self.its = 0

    def accuracy(self, X: np.ndarray) -> float:
        """Convergence threshold (m): 1e-9 x diameter, or 1e-6 x the largest displacement
        (elastic part) when that is larger."""
        Xd = X - (self.R0 @ self.fit.coords(X)).reshape(X.shape)
        return max(1e-9 * self.L, 1e-6 * float(np.abs(Xd).max(initial=0.0)))

    def run(self, max_iter: int) -> tuple[np.ndarray, np.ndarray, bool]:
        """Outer iteration. The finger normals at the nodes follow the part's rigid
        placement r (the finger surface under a node moves when the part turns): r is a
        fixed point, r = rigid part of the solution computed with reference r, found by
        relaxed iteration with Aitken's adaptive relaxation factor (Irons-Tuck),
        interleaved with the inner iterations. Returns ``(X, λ, converged)``."""
        X = np.zeros((self.n, 2))
        r = np.zeros(3)
        omega = 0.5
        F_prev = None
        for _ in range(max_iter):
            X, lam, ok = self.inner(X, r, 8)
            F = self.fit.coords(X) - r
            if ok and np.abs(F).max() <= self.accuracy(X):
                return X, lam, True
            if self.its >= 4 * max_iter:
                break
            if F_prev is not None:
                dF = F - F_prev
                den = float(dF @ dF)
                if den > 0:
                    omega = float(np.clip(-omega * float(F_prev @ dF) / den, 0.05, 1.5))
            r = r + omega * F
            F_prev = F
        return X, lam, False

    def inner(self, X: np.ndarray, ref_rigid: np.ndarray, budget: int) -> tuple[np.ndarray, np.ndarray, bool]:
        """Sequential linearised QPs with the reference placement fixed: material points
        and finger normals are taken on the rest geometry placed by ``ref_rigid``; part
        edge normals, moment arms and rigid modes are those of the rest geometry."""
        xr = self.fit.placed(X, rigid=ref_rigid)
        lam = np.zeros(0)
        anderson = _Anderson()
        for _ in range(budget):
            self.its += 1
            x = self.fit.placed(X)
            rows = self.linearise(x, xr)
            if len(rows) == 0:
                return X, np.zeros(0), True
            X_new, lam, act = self.solve_qp(rows, X)
            X_new = self.limit_rigid_step(X_new, X)
            step = float(np.abs(self.fit.placed(X_new) - x).max())
            if step <= self.accuracy(X_new):
                return X_new, lam, True
            X = anderson.step(X, X_new, (len(rows), act.tobytes()))
        return X, lam, False

    def linearise(self, x: np.ndarray, xr: np.ndarray) -> ContactRows:
        """The contact rows in configuration ``x`` (directions on the reference ``xr``).
        Rows once linearised stay (re-measured), also across updates of the reference
        placement: the set does not flip-flop, and a turning part does not lose its
        contacts for a step (and jump) when the reference moves."""
        bd, fingers, x0, L = self.bd, self.fingers, self.x0, self.L
        if self.search_radius is None:
            probe = contact_rows(bd, x, fingers, radius=0.02 * L, x_ref=xr, normals_ref=x0, feet_ref=x0)
            pen = max(0.0, -float(probe.gap.min(initial=0.0)))
            radius = max(0.02 * L, 3.0 * pen)
            new = probe if radius == 0.02 * L else contact_rows(bd, x, fingers, radius=radius, x_ref=xr,
                                                                normals_ref=x0, feet_ref=x0)
        else:
            new = contact_rows(bd, x, fingers, radius=float(self.search_radius), x_ref=xr, normals_ref=x0,
                               feet_ref=x0)
        self.rows = merge_rows(new, refresh_rows(self.rows, bd, x, fingers))
        return self.rows

    def solve_qp(self, rows: ContactRows, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The linearised QP in its dual (scaled by ``F0`` and ``L``), polished: the new
        displacement, the contact forces (N) and the active rows."""
        if self.comp is None:
            from ..contact.compliance import BoundaryCompliance

            self.comp = BoundaryCompliance.placement_gauge(self.mesh, self.K)
        L, F0 = self.L, self.F0
        S, C = _gap_gradients(rows)
        pos = self.comp.position(S)
        d = np.ravel(np.c_[2 * pos, 2 * pos + 1])
        W = C @ self.comp.Y[np.ix_(d, d)] @ C.T  # contact compliance (m/N)
        gt = rows.gap - C @ X[S].ravel()  # linearised gaps at X = 0
        Ur, B = _balance_rows(rows, self.x0, self.C0, L)
        Ws, gs = W * F0 / L, gt / L
        sol = solve_contact(ContactProblem(Ws, gs, balance=B))
        lam_s, y, N, act = sol.lam, sol.y, sol.free_balance, sol.active
        lam = lam_s * F0
        f = np.zeros(2 * self.n)
        np.add.at(f, np.ravel(np.c_[2 * S, 2 * S + 1]), C.T @ lam)
        X_el = self.comp.displacement(f).reshape(self.n, 2)
        # rigid motion: y fixes it on the span of the active rows; on the free
        # directions take the smallest total rigid motion that keeps every gap >= 0
        c_rig = self.fit.coords(X_el) / L  # (tx, ty, L theta) / L
        cs = Ur.T @ c_rig
        ina = np.flatnonzero(~act)
        Mi = B[:, ina].T
        zi = (Ws @ lam_s + gs)[ina]
        if len(B):
            y = _min_norm_rigid(y + cs, N, Mi, zi - Mi @ cs) - cs
        alpha = (Ur @ y - (c_rig - Ur @ cs)) * L  # (tx, ty, L theta) in m
        return X_el + (self.R0 @ alpha).reshape(self.n, 2), lam, act

    def limit_rigid_step(self, X_new: np.ndarray, X: np.ndarray) -> np.ndarray:
        """Trust region on the rigid motion: at most 5 % of the diameter (or 0.05 rad) per
        linearisation, so a part squeezed out moves out gradually."""
        dc = self.fit.coords(X_new) - self.fit.coords(X)
        big = float(np.abs(dc).max())
        if big > 0.05 * self.L:
            X_new = X_new - (self.R0 @ (dc * (1.0 - 0.05 * self.L / big))).reshape(self.n, 2)
        return X_new

    def result(self, X: np.ndarray, lam: np.ndarray, converged: bool, tol: float) -> EquilibriumResult:
        """Forces, moments, points, gaps and energy of the solution ``X``."""
        fit, rows, L, x0 = self.fit, self.rows, self.L, self.x0
        x = fit.placed(X)
        nf = len(self.fingers)
        # gaps in the contact model of the solve (node-to-surface: part nodes against the
        # finger bodies, finger corners against part edges, material points fixed at rest)
        final_rows = merge_rows(contact_rows(self.bd, x, self.fingers, radius=max(0.02 * L, 10 * tol),
                                             x_ref=fit.placed(X, rigid=fit.coords(X)), normals_ref=x0,
                                             feet_ref=x0),
                                refresh_rows(rows, self.bd, x, self.fingers))
        gaps = np.full(nf, np.inf)
        np.minimum.at(gaps, final_rows.finger, final_rows.gap)
        forces, moments, nodal, points = _finger_forces(rows, lam, x, x0, self.C0, nf)
        for i in range(nf):
            if np.isnan(points[i, 0]):
                sel = np.flatnonzero(final_rows.finger == i)
                if len(sel):
                    points[i] = final_rows.point[sel[np.argmin(final_rows.gap[sel])]]
        active = (gaps <= tol) | (np.linalg.norm(forces, axis=1) > 0)
        Xf = X.ravel()
        energy = max(0.0, 0.5 * float(Xf @ (self.K @ Xf)))
        if np.isfinite(gaps).any() and gaps[np.isfinite(gaps)].min() < -max(tol, self.accuracy(X)):
            converged = False
        rig = fit.coords(X)  # (tx, ty, L theta): mean rigid motion
        return EquilibriumResult(
            q=x, displacement=X, rotation=float(rig[2] / L), translation=rig[:2].copy(), forces=forces,
            moments=moments, points=points, nodal_forces=nodal, gaps=gaps, active=active, energy=energy,
            centroid=area_centroid(self.mesh.triangles, x), iterations=self.its, converged=converged, tol=tol,
            accuracy=self.accuracy(X), max_strain=float(strain_magnitude(self.mesh, Xf).max(initial=0.0)),
            rows=rows, multipliers=lam,
        )


def _gap_gradients(rows: ContactRows) -> tuple[np.ndarray, np.ndarray]:
    """The perimeter nodes ``S`` the rows involve and the gradient ``C (r, 2|S|)`` of
    every gap with respect to their DOFs."""
    r = len(rows)
    S = np.unique(rows.nodes)
    col = {int(v): i for i, v in enumerate(S)}
    loc = np.vectorize(col.__getitem__, otypes=[np.int64])(rows.nodes)  # (r, 2)
    C = np.zeros((r, 2 * len(S)))
    ridx = np.arange(r)
    for jj in range(2):
        np.add.at(C, (ridx, 2 * loc[:, jj]), rows.weights[:, jj] * rows.direction[:, 0])
        np.add.at(C, (ridx, 2 * loc[:, jj] + 1), rows.weights[:, jj] * rows.direction[:, 1])
    return S, C


def _balance_rows(rows: ContactRows, x0: np.ndarray, C0: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """Force and moment balance of the row forces on the rest geometry (moment scaled by
    ``L``), reduced to independent rows: ``(Ur, B = Ur^T B_full)``."""
    p0 = (rows.weights[:, :, None] * x0[rows.nodes]).sum(axis=1)
    arm = p0 - C0
    d = rows.direction
    Bfull = np.vstack([d[:, 0], d[:, 1], (arm[:, 0] * d[:, 1] - arm[:, 1] * d[:, 0]) / L])
    U_, s_, _ = np.linalg.svd(Bfull, full_matrices=False)
    keep = s_ > 1e-10 * max(s_.max(initial=0.0), 1e-300)
    Ur = U_[:, keep]
    return Ur, Ur.T @ Bfull


def _finger_forces(rows: ContactRows, lam: np.ndarray, x: np.ndarray, x0: np.ndarray, C0: np.ndarray,
                   nf: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Force (N) and moment about ``C0`` (N m, rest arms) of every finger, the nodal
    forces, and the centre of each finger's contact forces in ``x`` (NaN without force)."""
    forces = np.zeros((nf, 2))
    moments = np.zeros(nf)
    nodal = np.zeros((len(x), 2))
    points = np.full((nf, 2), np.nan)
    if not len(lam):
        return forces, moments, nodal, points
    fr = lam[:, None] * rows.direction
    np.add.at(forces, rows.finger, fr)
    for j in range(2):
        np.add.at(nodal, rows.nodes[:, j], rows.weights[:, j, None] * fr)
    p0 = (rows.weights[:, :, None] * x0[rows.nodes]).sum(axis=1)
    arm = p0 - C0
    np.add.at(moments, rows.finger, arm[:, 0] * fr[:, 1] - arm[:, 1] * fr[:, 0])
    pts = (rows.weights[:, :, None] * x[rows.nodes]).sum(axis=1)
    wsum = np.zeros(nf)
    np.add.at(wsum, rows.finger, lam)
    psum = np.zeros((nf, 2))
    np.add.at(psum, rows.finger, lam[:, None] * pts)
    has = wsum > 0
    points[has] = psum[has] / wsum[has, None]
    return forces, moments, nodal, points
