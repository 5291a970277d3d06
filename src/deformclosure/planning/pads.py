"""Rank grasp axes of a part for a pad gripper (SPEC §6, ``plan --pad-radius``).

Every axis of a ``(θ, c)`` grid over the whole part is solved once, as an exact energy
curve in σ; on a shared lattice of separations the release energies of *all* axes follow
from one union–find sweep per σ (the landscape is the same for every start axis). Axes
that are never a strict minimum beyond the noise floor cannot hold at any σ; for the
others the elastic limit is computed (critical-distance strain) and ``Q = min(U_A, U_L)``
is maximised on the lattice. A screened row is a *candidate*, never "held" (SPEC §6
"Plan"): the lattice reads the barrier off one coarse mesh and grid. The best ``verify``
candidates are then verified with the code path of ``optimize``
(:func:`~deformclosure.pads.refine.pad_grasp`: a landscape anchored at the axis, exact σ*,
the noise floor, and — given the part — a coarser mesh with ``h`` doubled below the plan's
own, whose Richardson error estimate decides the verdict); verified rows rank first, and ``top`` lists the
verified rows that are held.
"""

from __future__ import annotations

import time

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import GraspError
from ..limits import blas_threads
from ..landscape import kernels
from ..landscape.noise import resolved, twin_floor
from ..pads.contact import GraspCurve, PadContact
from ..pads.geometry import GraspAxis, Pad
from ..pads.landscape import AxisGrid
from ..pads.limit import elastic_limit_strain_of, pad_elastic_limit
from ..pads.optimize import UNITS, check_counts, optimize_pads

__all__ = ["PadPlan", "plan_pads"]


@dataclass(frozen=True, eq=False)
class PadPlan:
    """A ranked list of grasp axes.

    Attributes
    ----------
    rows : list of dict
        One per axis that meets the part, best first: ``angle`` (rad), ``offset`` (m,
        from the area centroid), ``point`` (m), ``contacts`` (rest contact points, m),
        ``sigma0``, ``sigma_star`` (m or None), ``quality`` (J), ``verdict``
        (``"candidate"`` or ``"not held"`` for a screened row; ``"held"``, ``"not held"``
        or ``"undecided"`` for a verified one), ``verified`` (bool), ``axis``
        (``{"point", "angle"}``, m and rad, as ``optimize --axis`` takes it), ``method``
        (``"exact"`` for the verified ones, ``"lattice"`` otherwise) and, when verified,
        ``error_estimate`` (``{"quality", "sigma_star"}``, J and m; ``None`` on one mesh).
    pad : Pad
    grid : AxisGrid
    n_sigma : int
    noise_relative : float
    """

    rows: list[dict]
    pad: Pad
    grid: AxisGrid
    n_sigma: int
    noise_relative: float
    top: list = field(default_factory=list)
    friction: float = 0.0

    @property
    def held(self) -> list[dict]:
        """The verified rows whose verdict is ``"held"``, best first (the plan's ``top``)."""
        return [r for r in self.rows if r["verified"] and r["verdict"] == "held"]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready report (SI): ``axes`` (every row, verified first) and ``top`` (the
        verified rows that are held; empty when none is); ``friction`` (μ) when ``μ > 0``."""
        extra = {"friction": self.friction} if self.friction > 0 else {}
        return {"model": "pads", "pad": self.pad.to_dict(), **extra,
                "grid": {"n_angles": self.grid.n_angles, "n_offsets": self.grid.n_offsets,
                         "d_angle": self.grid.d_angle, "d_offset": self.grid.d_offset,
                         "origin": list(self.grid.origin)},
                "n_sigma": self.n_sigma, "noise_floor_relative": self.noise_relative,
                "n_verified": sum(r["verified"] for r in self.rows),
                "axes": self.rows, "top": self.held, "units": UNITS}


def _grid_graph(grid: AxisGrid) -> sp.csr_matrix:
    V = grid.size
    rows, cols = [], []
    for v in range(V):
        for w in grid.neighbours(v):
            rows.append(v)
            cols.append(w)
    A = sp.csr_matrix((np.ones(len(rows), bool), (rows, cols)), shape=(V, V))
    A = (A + A.T).tocsr()
    A.sort_indices()
    return A


def plan_pads(mesh, pad: Pad, *, n_angles: int = 36, n_offsets: int = 40, n_sigma: int = 64,
              top: int = 5, twin: PadContact | None = None, noise_samples: int = 48,
              solver: PadContact | None = None, progress=None, part=None,
              rtol: float | None = None, max_seconds: float | None = None,
              elasticity: str = "linear", friction: float = 0.0) -> PadPlan:
    """Rank every grasp axis of a part for pads ``pad`` (contracting grasps).

    With ``elasticity="neo-hookean"`` the verified rows are re-solved at finite strain
    (SPEC §8, :func:`~deformclosure.pads.finite_strain_grasp.finite_strain_levels`, the
    code path of ``optimize --elasticity neo-hookean``); screening stays linear.

    Parameters
    ----------
    mesh : Mesh
        Nodes in m, with a material (``e_L``, optional ``critical_distance``).
    pad : Pad
        Width and end radius in m.
    n_angles, n_offsets : int
        Grid: ``Δθ = π / n_angles`` (rad), ``Δc = D / n_offsets`` (m, D = diameter).
    n_sigma : int
        Separations in the shared lattice (at least 1).
    top : int
        Number of best candidates verified afterwards (0: none), ``--verify``.
    twin : PadContact, optional
        A second mesh realisation (:func:`deformclosure.mesh.generate.twin_mesh`): ``noise_samples`` axes
        spread over the grid are solved on it too, and twice the 90th percentile of the
        relative difference is the noise floor at each lattice σ (ties below it).
    noise_samples : int
        Axes solved on ``twin`` (0: no noise floor).
    solver : PadContact, optional
        Reuse a factorisation of ``mesh``.
    progress : callable, optional
        ``progress(done, total)`` while the axes are solved.
    part : Part, optional
        The part ``mesh`` was made from (with its own ``max_area``): verification then
        refines each candidate to ``rtol`` with the code path of ``optimize``
        (:func:`~deformclosure.pads.refine.pad_grasp`: mesh and landscape, adaptively,
        with the error estimate and the verdict of
        :class:`~deformclosure.pads.refine.RefinedPadGrasp`); without it, on ``mesh``
        alone (no error estimate: the verdict is "held" only for a barrier above the
        noise floor on a mesh that resolves the answer,
        :attr:`~deformclosure.pads.optimize.PadGraspResult.resolves`).
    rtol : float, optional
        Relative accuracy of each verified candidate (default 0.05).
    max_seconds : float, optional
        Time budget (s) of all verifications together (default 120), shared equally.
    friction : float
        Coulomb coefficient μ (SPEC §9). With ``μ > 0`` the screening stays frictionless
        (it ranks the lattice's ``Q``; rows of equal ``Q`` by ``|offset|``, the axes
        through the centroid first), the best ``top`` screened rows are verified even
        without a frictionless barrier, and each verified row carries ``Q = min(U_A^μ,
        U_L)`` from optimize's code path
        (:func:`~deformclosure.pads.friction_grasp.frictional_refined`).

    Returns
    -------
    PadPlan
        Rows best first; qualities in J, lengths in m, angles in rad.

    Raises
    ------
    GraspError
        When the mesh has no material or a count is not a whole number in range.

    Examples
    --------
    The notched bar on a coarse grid (about 1 s; the default grid takes minutes): the best
    axis joins the two notches. The offset step (2 mm here) must resolve the notches (6 mm
    wide): with 8 offsets (4 mm) the neighbours of the notch axis lie outside the notches
    and its barrier is a grid artefact.

    >>> from deformclosure import mesh_part, notched_part
    >>> from deformclosure.pads import Pad
    >>> mesh = mesh_part(notched_part(), max_area=1e-6)            # m²
    >>> plan = plan_pads(mesh, Pad(0.0, 2e-3), n_angles=6, n_offsets=16, n_sigma=16, top=1)
    >>> best = plan.rows[0]
    >>> [round(v * 1e3, 3) for v in best["point"]], best["verdict"], best["verified"]
    ([15.0, 6.0], 'undecided', True)

    (verified on ``mesh`` alone, which does not resolve the contacts: ``"undecided"``;
    with ``part=`` each candidate is refined to ``rtol`` and decided.)
    """
    e_L = elastic_limit_strain_of(mesh)
    check_counts(n_angles=n_angles, n_offsets=n_offsets, n_sigma=n_sigma, top=(top, 0),
                  noise_samples=(noise_samples, 0))
    solver = PadContact(mesh) if solver is None else solver
    grid = AxisGrid.over_part(solver, GraspAxis(0.0, 0.0, tuple(solver.centroid)), pad,
                              n_angles, n_offsets)
    with blas_threads():          # the screening: small solves of every axis (limits.BLAS_THREADS)
        return _plan(mesh, pad, solver, grid, e_L, n_sigma, top, twin, noise_samples,
                     n_angles, n_offsets, progress, part, rtol, max_seconds, elasticity,
                     friction)


def _plan(mesh, pad: Pad, solver: PadContact, grid: AxisGrid, e_L: float, n_sigma: int,
          top: int, twin: PadContact | None, noise_samples: int, n_angles: int,
          n_offsets: int, progress, part, rtol: float | None,
          max_seconds: float | None, elasticity: str = "linear",
          friction: float = 0.0) -> PadPlan:
    """:func:`plan_pads` on a solver and grid: screen, rank and verify."""
    curves = _solve_axes(solver, grid, pad, e_L, progress)
    touching = [c for c in curves if c.touch is not None]
    if not touching:
        raise GraspError("pad: the pads miss the part on every grasp axis; check the part's "
                         "size and the pad's units")
    sig0 = np.array([c.sigma0 if c.touch is not None else np.nan for c in curves])
    lattice = np.linspace(float(np.nanmin([c.sigma_end for c in touching])),
                          float(np.nanmax(sig0)), n_sigma)
    E = np.array([c.energy(lattice) for c in curves])            # (V, K)
    tau = np.zeros(n_sigma) if twin is None else \
        _noise_floor(twin, grid, pad, curves, E, lattice, noise_samples)
    UA = _release_energies(_grid_graph(grid), E, tau)
    rows = [_lattice_row(v, grid.axis(v), c, solver, lattice, E[v], UA[v], e_L)
            for v, c in enumerate(curves) if c.touch is not None]
    rows.sort(key=lambda r: -r["quality"])
    if friction > 0:
        # no friction screening yet: among equal screened Q the axes nearest the area
        # centroid first (the longest way out for the release work, a heuristic)
        rows.sort(key=lambda r: (-r["quality"], abs(r["offset"])))
    refined = _verify_best(rows[:top], mesh, pad, solver, twin, n_angles, n_offsets, part,
                           rtol, max_seconds, elasticity, friction)
    # verified rows first (held, then undecided, then not held), then the candidates
    order = {"held": 0, "undecided": 1, "not held": 2, "candidate": 3}
    rows.sort(key=lambda r: (not r["verified"], order[r["verdict"]] if r["verified"] else 0,
                             -r["quality"]))
    for r in rows:
        r.pop("vertex")
    return PadPlan(rows, pad, grid, n_sigma, float(np.max(tau)), refined, friction)


def _solve_axes(solver: PadContact, grid: AxisGrid, pad: Pad, e_L: float,
                progress) -> list[GraspCurve]:
    """The energy curve of every grid axis, traced from first touch to a squeeze of
    ``min(e_L, 0.95)`` × its rest width."""
    curves = []
    for v in range(grid.size):
        ax = grid.axis(v)
        c = solver.curve(ax, pad, np.inf)          # first touch only, to know σ0
        if c.touch is not None:
            c = solver.curve(ax, pad, max(c.sigma0 * (1.0 - min(e_L, 0.95)), 0.0))
        curves.append(c)
        if progress is not None:
            progress(v + 1, grid.size)
    return curves


def _noise_floor(twin: PadContact, grid: AxisGrid, pad: Pad, curves: list[GraspCurve],
                 E: np.ndarray, lattice: np.ndarray, samples: int) -> np.ndarray:
    """Relative noise floor at each lattice σ: twice the 90th percentile, over ``samples``
    touching axes spread over the grid, of ``|U₁ − U₂| / max(U₁, U₂)`` between the mesh
    and its twin (:func:`~deformclosure.landscape.noise.twin_floor`)."""
    touching = [v for v in range(len(curves)) if curves[v].path is not None]
    pick = [touching[int(i)] for i in np.linspace(0, len(touching) - 1,
                                                   min(samples, len(touching)))]
    U1 = E[pick].reshape(len(pick), len(lattice))
    U2 = np.array([twin.curve(grid.axis(v), pad, curves[v].sigma_end).energy(lattice)
                   for v in pick]).reshape(len(pick), len(lattice))
    return np.array([twin_floor(U1[:, k], U2[:, k]) for k in range(len(lattice))])


def _release_energies(A: sp.csr_matrix, E: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Release energy ``U_A`` (J) of every axis at every lattice σ, shape of ``E`` (V, K):
    one union–find sweep per σ over the grid graph ``A``, with ties within ``tau``."""
    V = E.shape[0]
    UA = np.zeros_like(E)
    for k in range(E.shape[1]):
        U = E[:, k]
        nmin = kernels.neighbour_min(A.indptr, A.indices, U)
        # Strict beyond the noise floor: every neighbour higher by more than tau × its energy.
        Umin_rel = np.full(V, np.inf)
        for v in range(V):
            nb = A.indices[A.indptr[v]:A.indptr[v + 1]]
            Umin_rel[v] = np.min(U[nb] - tau[k] * U[nb] - U[v])
        strict = (Umin_rel > 0) & (U > 0)      # zero energy: released, holds nothing
        ua = kernels.release_sweep(A.indptr, A.indices, U, np.argsort(U), U <= nmin, strict)
        ua[(ua > 0) & np.isfinite(ua) & ~resolved(ua, U + ua, tau[k])] = 0.0   # ties
        UA[:, k] = ua
    return UA


def _lattice_row(v: int, ax: GraspAxis, c: GraspCurve, solver: PadContact, lattice: np.ndarray,
                 E: np.ndarray, UA: np.ndarray, e_L: float) -> dict:
    """The report row of axis ``v``: ``Q = min(U_A, U_L)`` maximised on the lattice (the
    elastic limit is computed only for an axis that holds somewhere)."""
    q, s_star = 0.0, None
    inrange = lattice <= c.sigma0
    if np.any(UA[inrange] > 0):
        lim = pad_elastic_limit(solver, c, e_L)
        UL = c.energy_at(lim.sigma_L) - E
        ok = inrange & (lattice >= lim.sigma_L)
        Q = np.where(ok, np.minimum(UA, UL), 0.0)
        k = int(np.argmax(Q))
        if Q[k] > 0:
            q, s_star = float(Q[k]), float(lattice[k])
    return {"vertex": v, "angle": ax.angle, "offset": ax.offset, "point": ax.point.tolist(),
            "axis": ax.to_dict(),
            "contacts": [c.touch.contact_a.tolist(), c.touch.contact_b.tolist()],
            "sigma0": c.sigma0, "sigma_star": s_star, "quality": q,
            "verdict": screened_verdict(q), "verified": False, "method": "lattice"}


def screened_verdict(quality: float) -> str:
    """The verdict of a row screened on the lattice (SPEC §6 "Plan"): ``"candidate"`` when
    it shows a barrier, ``"not held"`` when it shows none — never ``"held"``: only
    verification (:func:`_verify_best`) can say that."""
    return "candidate" if quality > 0 else "not held"


def _verify_best(rows: list[dict], mesh, pad: Pad, solver: PadContact, twin: PadContact | None,
                 n_angles: int, n_offsets: int, part, rtol: float | None,
                 max_seconds: float | None, elasticity: str = "linear",
                 friction: float = 0.0) -> list:
    """Verify the best candidates with the code path of ``optimize`` (:func:`pad_grasp`
    to ``rtol``, grid anchored at each axis, twice the plan's angular resolution), updating
    them in place; stops at the first row that shows no barrier."""
    from ..pads.refine import DEFAULT_MAX_SECONDS, DEFAULT_RTOL, pad_grasp
    from ..pads.finite_strain_grasp import finite_strain_levels, optimize_finite_strain
    from ..mesh.generate import default_max_area

    from ..pads.friction_grasp import frictional_level, frictional_refined

    first_gap = next((k for k, r in enumerate(rows) if r["quality"] <= 0), len(rows))
    # with friction a row without a frictionless barrier may hold: verify it too
    candidates = rows if friction > 0 else rows[:first_gap]
    total = DEFAULT_MAX_SECONDS if max_seconds is None else max_seconds
    t_start = time.perf_counter()
    opts = dict(n_angles=2 * n_angles, n_offsets=n_offsets)
    verified = []
    for n, r in enumerate(candidates):
        ax = GraspAxis(r["angle"], r["offset"], tuple(solver.centroid))
        if part is not None:
            # the time left, shared by the rows left (a quick row leaves more to the next)
            left = max(total - (time.perf_counter() - t_start), 1e-3)
            res = pad_grasp(part, ax, pad, rtol=DEFAULT_RTOL if rtol is None else rtol,
                            max_seconds=left / (len(candidates) - n),
                            max_area=default_max_area(part), **opts)
            if elasticity == "neo-hookean":
                res = finite_strain_levels(res, elasticity, rtol)
            if friction > 0:
                left = max(total - (time.perf_counter() - t_start), 1e-3)
                res = frictional_refined(res, friction, hold=False,
                                         max_seconds=left / (len(candidates) - n)).refined
            fine, err, verdict = res.finest, res.error_estimate(), res.verdict
            extra = {"converged": res.converged, "n_levels": len(res.levels),
                     "convergence": res.convergence()}
        else:
            fine = optimize_pads(mesh, ax, pad, solver=solver, twin=twin, **opts)
            if elasticity == "neo-hookean":
                fine = optimize_finite_strain(mesh, fine, rtol=DEFAULT_RTOL if rtol is None
                                              else rtol)
            if friction > 0:
                fine = frictional_level(fine, friction, rtol=rtol).result
            err = {"quality": None, "U_A": None, "sigma_star": None}
            verdict, extra = fine.verdict, {"converged": False, "n_levels": 1}
        if friction > 0:
            extra["U_A"] = None if np.isinf(fine.U_A) else fine.U_A
        r.update({"sigma_star": fine.sigma_star, "quality": fine.quality, "verdict": verdict,
                  "verified": True, "method": "exact", "lattice_quality": r["quality"],
                  "error_estimate": err, "force": fine.force, **extra})
        if elasticity != "linear":
            r["elasticity"] = elasticity
        verified.append(fine)
    return verified
