"""Rank grasp axes of a part for a pad gripper (SPEC §6, ``plan --pad-radius``).

Every axis of a ``(θ, c)`` grid over the whole part is solved once, as an exact energy
curve in σ; on a shared lattice of separations the release energies of *all* axes follow
from one union–find sweep per σ (the landscape is the same for every start axis). Axes
that are never a strict minimum beyond the noise floor cannot hold at any σ; for the
others the elastic limit is computed (critical-distance strain) and ``Q = min(U_A, U_L)``
is maximised on the lattice. The best ``top`` axes are then solved exactly with
:func:`~deformclosure.pads.optimize.optimize_pads` on a grid anchored at each of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from .. import graph_kernels
from ..errors import GraspError
from .contact import GraspCurve, PadContact
from .geometry import GraspAxis, Pad
from .landscape import AxisGrid
from .limit import elastic_limit_strain_of, pad_elastic_limit
from .optimize import UNITS, PadGraspResult, _check_counts, optimize_pads

__all__ = ["PadPlan", "plan_pads"]


@dataclass(frozen=True, eq=False)
class PadPlan:
    """A ranked list of grasp axes.

    Attributes
    ----------
    rows : list of dict
        One per axis that meets the part, best first: ``angle`` (rad), ``offset`` (m,
        from the area centroid), ``point`` (m), ``contacts`` (rest contact points, m),
        ``sigma0``, ``sigma_star`` (m or None), ``quality`` (J), ``verdict``, ``method``
        (``"exact"`` for the refined ones, ``"lattice"`` otherwise).
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

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready report (SI)."""
        return {"model": "pads", "pad": self.pad.to_dict(),
                "grid": {"n_angles": self.grid.n_angles, "n_offsets": self.grid.n_offsets,
                         "d_angle": self.grid.d_angle, "d_offset": self.grid.d_offset,
                         "origin": list(self.grid.origin)},
                "n_sigma": self.n_sigma, "noise_floor_relative": self.noise_relative,
                "axes": self.rows, "units": UNITS}


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
              solver: PadContact | None = None, progress=None) -> PadPlan:
    """Rank every grasp axis of a part for pads ``pad`` (contracting grasps).

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
        Number of best axes solved exactly afterwards (0: none).
    twin : PadContact, optional
        A second mesh realisation (:func:`.noise.twin_mesh`): ``noise_samples`` axes
        spread over the grid are solved on it too, and twice the 90th percentile of the
        relative difference is the noise floor at each lattice σ (ties below it).
    noise_samples : int
        Axes solved on ``twin`` (0: no noise floor).
    solver : PadContact, optional
        Reuse a factorisation of ``mesh``.
    progress : callable, optional
        ``progress(done, total)`` while the axes are solved.

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
    >>> [round(v * 1e3, 3) for v in best["point"]], best["verdict"], best["method"]
    ([15.0, 6.0], 'held', 'exact')
    """
    e_L = elastic_limit_strain_of(mesh)
    _check_counts(n_angles=n_angles, n_offsets=n_offsets, n_sigma=n_sigma, top=(top, 0),
                  noise_samples=(noise_samples, 0))
    solver = PadContact(mesh) if solver is None else solver
    grid = AxisGrid.over_part(solver, GraspAxis(0.0, 0.0, tuple(solver.centroid)), pad,
                              n_angles, n_offsets)
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
    refined = _refine_best(rows[:top], mesh, pad, solver, twin, n_angles, n_offsets)
    rows.sort(key=lambda r: (-r["quality"], r["method"] != "exact"))
    for r in rows:
        r.pop("vertex")
    return PadPlan(rows, pad, grid, n_sigma, float(np.max(tau)), refined)


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
    and its twin."""
    touching = [v for v in range(len(curves)) if curves[v].path is not None]
    pick = [touching[int(i)] for i in np.linspace(0, len(touching) - 1,
                                                   min(samples, len(touching)))]
    rel = []
    for v in pick:
        c2 = twin.curve(grid.axis(v), pad, curves[v].sigma_end)
        U1, U2 = E[v], c2.energy(lattice)
        top_ = np.maximum(U1, U2)
        rel.append(np.where(top_ > 0, np.abs(U1 - U2) / np.where(top_ > 0, top_, 1.0), np.nan))
    rel = np.array(rel).reshape(len(pick), len(lattice))
    tau = np.zeros(len(lattice))
    for k in range(len(lattice)):
        col = rel[:, k][np.isfinite(rel[:, k])]
        tau[k] = 2.0 * float(np.quantile(col, 0.9)) if len(col) else 0.0
    return tau


def _release_energies(A: sp.csr_matrix, E: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Release energy ``U_A`` (J) of every axis at every lattice σ, shape of ``E`` (V, K):
    one union–find sweep per σ over the grid graph ``A``, with ties within ``tau``."""
    V = E.shape[0]
    UA = np.zeros_like(E)
    for k in range(E.shape[1]):
        U = E[:, k]
        nmin = graph_kernels.neighbour_min(A.indptr, A.indices, U)
        # Strict beyond the noise floor: every neighbour higher by more than tau × its energy.
        Umin_rel = np.full(V, np.inf)
        for v in range(V):
            nb = A.indices[A.indptr[v]:A.indptr[v + 1]]
            Umin_rel[v] = np.min(U[nb] - tau[k] * U[nb] - U[v])
        strict = (Umin_rel > 0) & (U > 0)      # zero energy: released, holds nothing
        ua = graph_kernels.release_sweep(A.indptr, A.indices, U, np.argsort(U), U <= nmin, strict)
        ua[(ua > 0) & np.isfinite(ua) & (ua <= tau[k] * (U + ua))] = 0.0   # ties
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
            "contacts": [c.touch.contact_a.tolist(), c.touch.contact_b.tolist()],
            "sigma0": c.sigma0, "sigma_star": s_star, "quality": q,
            "verdict": "held" if q > 0 else "not held", "method": "lattice"}


def _refine_best(rows: list[dict], mesh, pad: Pad, solver: PadContact, twin: PadContact | None,
                 n_angles: int, n_offsets: int) -> list[PadGraspResult]:
    """Solve the best lattice rows exactly (:func:`optimize_pads`, grid anchored at each),
    updating them in place; stops at the first row that holds nothing."""
    refined = []
    for r in rows:
        if r["quality"] <= 0:
            break
        ax = GraspAxis(r["angle"], r["offset"], tuple(solver.centroid))
        res = optimize_pads(mesh, ax, pad, solver=solver, twin=twin, n_angles=2 * n_angles,
                            n_offsets=n_offsets)
        r.update({"sigma_star": res.sigma_star, "quality": res.quality, "verdict": res.verdict,
                  "method": "exact", "lattice_quality": r["quality"]})
        refined.append(res)
    return refined
