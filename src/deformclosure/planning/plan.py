"""Grasp planning: the ε-optimal separation and quality of every jaw pair at once.

For every pair ``s`` of perimeter nodes the quality is ``Q_s(σ) = min(U_A(s, σ),
U_L(s, σ))`` on ``[σ_L(s), σ0(s)]`` (contracting; SPEC §4). Evaluating each pair with
its own ε-approximation repeats the same work: at a given σ the vertex energies do not
depend on the start, and one union–find sweep over the vertices in energy order gives
the release energy of *every* vertex (:func:`~deformclosure.grasp.release.release_energies`).
So the planner samples one σ lattice shared by all pairs — the paper's ε-grid (§4.7)
``σ_j = j·ξ``, ``ξ = ε/λ``, ``λ = max_v k_v σ0_v`` — does one sweep per lattice value,
and keeps, per pair, the best lattice value inside its own range. This equals the
paper's ε-approximation of each pair on the same lattice
(``optimize_separation_arrays(method="approx", grid="lattice", lipschitz=λ)``); the
``top`` pairs are then refined with the exact method.

``e_max`` and ``σ_L`` of every pair come from the strain response to unit forces at
the perimeter DOFs (one block solve with the factorisation already built).
"""

from __future__ import annotations

import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np
import scipy.sparse as sp

from ..elasticity.stiffness import element_b_matrices
from ..errors import GraspError
from ..grasp.analysis import GraspAnalysis, GraspModel, grasp_model, optimize_separation
from ..grasp.release import release_energies
from ..grasp.separation import lipschitz_constant, vertex_energies
from ..units import SI_UNITS

__all__ = ["PlanResult", "plan_grasps", "pair_elastic_limits", "lattice"]



def _workers() -> int:
    """Threads for the GIL-free kernels: the CPUs this process may use (at most 8)."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        n = os.cpu_count() or 1
    return max(1, min(n, 8))


@dataclass(frozen=True)
class PlanResult:
    """Quality of every jaw pair, ranked (SI units).

    Attributes
    ----------
    pairs : ndarray, shape (P, 2)
        Jaw node pairs considered (after the filters), in ranking order (best first).
    sigma0, k, e_max, sigma_L : ndarray, shape (P,)
        Rest distance (m), stiffness (N/m), strain per unit distance change (1/m) and
        elastic-limit separation (m) of each pair.
    sigma_star : ndarray, shape (P,)
        ε-optimal separation (m), NaN where the pair cannot hold (Q ≡ 0 on the lattice);
        the exact ``σ*`` for the refined pairs.
    quality, U_A, U_L : ndarray, shape (P,)
        Q, release energy (``inf`` possible) and elastic margin at ``sigma_star`` (J):
        the lattice values, replaced by the exact ones for the ``top`` refined pairs
        (whose exact optimum is never below their lattice value, so the order holds).
    lattice_quality : ndarray, shape (P,)
        Q on the shared lattice for every pair (J), refined or not.
    exact : ndarray of bool, shape (P,)
        The pair's values come from the exact method.
    pulls : ndarray of bool, shape (P,)
        The jaw line leaves the part at a jaw.
    epsilon, lipschitz, step : float
        ε (J), λ (N) and ξ = ε/λ (m) of the shared lattice.
    n_sigma : int
        Number of lattice values (one all-vertices sweep each).
    refined : list of GraspAnalysis
        The ``top`` pairs re-optimised with the exact method.
    mode : str
    jaw_width : float
    timings : dict
    """

    pairs: np.ndarray
    sigma0: np.ndarray
    k: np.ndarray
    e_max: np.ndarray
    sigma_L: np.ndarray
    sigma_star: np.ndarray
    quality: np.ndarray
    U_A: np.ndarray
    U_L: np.ndarray
    pulls: np.ndarray
    lattice_quality: np.ndarray
    exact: np.ndarray
    epsilon: float
    lipschitz: float
    step: float
    n_sigma: int
    refined: list = field(default_factory=list)
    mode: str = "contracting"
    jaw_width: float = 0.0
    timings: dict = field(default_factory=dict)
    model: GraspModel | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON report (SPEC §5 "Plan report"); SI units, infinities as ``None``."""
        def f(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        rows = []
        for i in range(len(self.pairs)):
            rows.append({
                "a": int(self.pairs[i, 0]), "b": int(self.pairs[i, 1]),
                "sigma_star": f(self.sigma_star[i]),
                "quality": float(self.quality[i]),
                "U_A": f(self.U_A[i]), "U_A_infinite": bool(np.isinf(self.U_A[i])),
                "U_L": f(self.U_L[i]),
                "sigma0": float(self.sigma0[i]), "k": float(self.k[i]),
                "sigma_L": float(self.sigma_L[i]), "e_max": float(self.e_max[i]),
                "pulls": bool(self.pulls[i]),
                "method": "exact" if self.exact[i] else "approx-lattice",
                "lattice_quality": float(self.lattice_quality[i]),
            })
        top = []
        for r in self.refined:
            d = r.to_dict()
            top.append({"a": int(r.jaws[0]), "b": int(r.jaws[1]),
                        **{k: d[k] for k in ("sigma_star", "quality", "U_A", "U_A_infinite",
                                             "U_L", "sigma_L", "sigma0", "k01", "e_max",
                                             "method", "attained")}})
        return {
            "model": "paper",
            "pairs": rows,
            "top": top,
            "epsilon": float(self.epsilon),
            "lipschitz": float(self.lipschitz),
            "step": float(self.step),
            "n_sigma": int(self.n_sigma),
            "mode": self.mode,
            "jaw_width": float(self.jaw_width),
            "method": "approx-lattice",
            "energy_model": "linear",
            "units": dict(SI_UNITS),
            "timings_s": dict(self.timings),
        }


def pair_elastic_limits(model: GraspModel, pairs_idx: np.ndarray,
                        elastic_limit_strain: float, max_bytes: float = 4e9
                        ) -> tuple[np.ndarray, np.ndarray]:
    """``e_max`` (1/m) and ``σ_L`` (m) of many graph vertices at once.

    The strain of every element under a unit force at every loaded perimeter DOF is
    ``T = B K⁺ E_b`` (one block solve with the model's factorisation); a jaw pair's
    strain per unit distance change is ``Σ_j λ_j T_j e`` over its contact nodes
    (``λ = ±k`` for point jaws), maximised over the elements by a compiled kernel.

    Parameters
    ----------
    model : GraspModel
    pairs_idx : ndarray of int
        Graph vertices (jaw pairs).
    elastic_limit_strain : float
        ``e_L`` (-).
    max_bytes : float
        Memory allowed for ``T`` (bytes); a larger request raises ``GraspError``.
    """
    from ._kernels import max_strain_magnitude, max_strain_point_jaws

    mesh = model.mesh
    cc = model.condensed
    pairs = model.graph.pairs[pairs_idx]
    e = mesh.nodes[pairs[:, 1]] - mesh.nodes[pairs[:, 0]]
    sig0 = np.linalg.norm(e, axis=1)
    e /= sig0[:, None]
    if model.jaw_width:
        node_sets, forces = _wide_forces(model, pairs)
        counts = np.array([len(J) for J in node_sets], dtype=np.int64)
        loaded = np.concatenate([np.asarray(J, dtype=np.int64) for J in node_sets])
        weight = np.concatenate([np.asarray(f, dtype=float) for f in forces])
    else:
        counts = np.full(len(pairs), 2, dtype=np.int64)
        loaded = pairs.ravel().astype(np.int64)
        k = model.stiffness.k[pairs_idx]
        weight = np.column_stack([k, -k]).ravel()           # +k e at a, −k e at b
    ptr = np.concatenate([[0], np.cumsum(counts)])
    nodes_used, pos = np.unique(loaded, return_inverse=True)
    q = len(nodes_used)
    need = 8.0 * mesh.n_triangles * 3 * q * 2 + 8.0 * 2 * mesh.n_nodes * 2 * q
    if need > max_bytes:
        raise GraspError(f"planning all pairs of this part needs {need / 1e9:.1f} GB for the strain "
                         f"responses of {q} perimeter nodes; restrict the pairs (regions, separation "
                         f"range) or coarsen the perimeter")
    n2 = 2 * mesh.n_nodes
    E = np.zeros((n2, 2 * q))
    E[2 * nodes_used, 2 * np.arange(q)] = 1.0
    E[2 * nodes_used + 1, 2 * np.arange(q) + 1] = 1.0
    # Unit forces at single DOFs are not self-equilibrated; the pinned solve adds
    # reactions at the pins, but every jaw-pair combination below is self-equilibrated,
    # so the reactions cancel and the strains are exact.
    X = cc.solve(E)                                            # (2n, 2q)
    del E
    B, _ = element_b_matrices(mesh.nodes, mesh.triangles)      # (m, 3, 6)
    tri_dofs = np.empty((mesh.n_triangles, 6), dtype=np.int64)
    tri_dofs[:, 0::2] = 2 * mesh.triangles
    tri_dofs[:, 1::2] = 2 * mesh.triangles + 1
    # T[P, 3c + j, i] = strain component j of element i under a unit force at node P,
    # direction c (component-major: the kernels' inner loops run over elements)
    T = np.einsum("mij,mjr->rim", B, X[tri_dofs]).reshape(q, 6, mesh.n_triangles)
    del X
    T = np.ascontiguousarray(T)
    ex, ey = np.ascontiguousarray(e[:, 0]), np.ascontiguousarray(e[:, 1])
    e_max = np.empty(len(pairs))
    bounds = np.linspace(0, len(pairs), 8 * _workers() + 1).astype(np.int64)
    if model.jaw_width:
        def chunk(i: int) -> None:
            max_strain_magnitude(T, ptr, pos, weight, ex, ey, bounds[i], bounds[i + 1], e_max)
    else:
        pa, pb = np.ascontiguousarray(pos[0::2]), np.ascontiguousarray(pos[1::2])
        kk = np.ascontiguousarray(weight[0::2])

        def chunk(i: int) -> None:
            max_strain_point_jaws(T, pa, pb, kk, ex, ey, bounds[i], bounds[i + 1], e_max)
    with ThreadPoolExecutor(_workers()) as pool:  # the kernels release the GIL
        list(pool.map(chunk, range(len(bounds) - 1)))
    travel = elastic_limit_strain / e_max
    if model.mode == "contracting":
        sigma_L = np.maximum(0.0, sig0 - travel)
    else:
        sigma_L = sig0 + travel
    return e_max, sigma_L


def _wide_forces(model: GraspModel, pairs: np.ndarray):
    from ..grasp.pair_stiffness import _unit, _wide_jaw_stiffness

    e, _ = _unit(model.mesh.nodes, pairs)
    _, sets, lam = _wide_jaw_stiffness(model.mesh, model.condensed, pairs, e, model.jaw_width)
    return np.array(sets, dtype=object), np.array(lam, dtype=object)


def lattice(lo: float, hi: float, step: float, max_size: int | None = None) -> np.ndarray:
    """The ε-grid ``σ_j = j·step`` (m) inside ``[lo, hi]`` (paper §4.7).

    Raises ``GraspError`` when it would hold more than ``max_size`` values.
    """
    j0 = math.ceil(lo / step - 1e-9)
    j1 = math.floor(hi / step + 1e-9)
    if max_size is not None and j1 - j0 + 1 > max_size:
        raise GraspError(f"the step {step:.3g} m needs {j1 - j0 + 1} lattice values of σ, more than "
                         f"{max_size}; use a larger eps")
    return np.arange(j0, j1 + 1) * step


def _region_mask(nodes: np.ndarray, regions: Sequence[Any] | None) -> np.ndarray | None:
    if not regions:
        return None
    import shapely
    from shapely.geometry import box

    geoms = []
    for r in regions:
        if isinstance(r, (tuple, list)) and len(r) == 4:
            x0, y0, x1, y1 = map(float, r)
            if not (x0 < x1 and y0 < y1):
                raise GraspError(f"region {r!r}: expected (xmin, ymin, xmax, ymax) with min < max")
            geoms.append(box(x0, y0, x1, y1))
        elif hasattr(r, "geom_type"):
            geoms.append(r)
        else:
            raise GraspError(f"region {r!r}: give (xmin, ymin, xmax, ymax) in m or a shapely geometry")
    union = shapely.union_all(geoms)
    tol = 1e-9 * float(np.ptp(nodes, axis=0).max())
    return shapely.dwithin(shapely.points(nodes), union, tol)


def plan_grasps(mesh, K: sp.spmatrix | None = None, *, eps: float | None = None,
                mode: str = "contracting", jaw_width: float = 0.0,
                separation_range: tuple[float, float] | None = None,
                regions: Sequence[Any] | None = None, top: int = 10,
                n_sigma: int = 400, max_sigma: int = 200_000, progress: Callable[[int, int], None] | None = None,
                model: GraspModel | None = None) -> PlanResult:
    """Rank every jaw pair of a part by its ε-optimal quality.

    Parameters
    ----------
    mesh : Mesh
        Meshed part with material.
    K : sparse matrix, optional
        Stiffness (N/m); assembled if omitted.
    eps : float, optional
        ε (J) of the shared lattice; default: the value giving about ``n_sigma``
        lattice points over the range of all selected pairs (reported).
    mode : {"contracting", "expanding"}
    jaw_width : float
        Jaw contact width (m).
    separation_range : (float, float), optional
        Keep pairs whose rest distance σ0 (m) lies in this range.
    regions : sequence, optional
        Keep pairs whose both jaw nodes lie in the union of these regions: boxes
        ``(xmin, ymin, xmax, ymax)`` in m or shapely geometries.
    top : int
        Number of best pairs refined with the exact method.
    n_sigma : int
        Lattice size used to choose the default ε.
    max_sigma : int
        Largest lattice accepted (a tiny ``eps`` raises ``GraspError`` instead of
        running for hours).
    progress : callable, optional
        Called as ``progress(done, total)`` after each lattice value.
    model : GraspModel, optional
        Reuse a model from :func:`grasp_model`.

    Returns
    -------
    PlanResult

    Raises
    ------
    GraspError
        Bad ε, range, regions, or no pair left after filtering.
    """
    t = {}
    if eps is not None and not (math.isfinite(eps) and eps > 0):
        raise GraspError(f"eps = {eps!r}: must be a finite energy > 0 in joules")
    if not (isinstance(top, (int, np.integer)) and top >= 0):
        raise GraspError(f"top = {top!r}: must be a whole number >= 0")
    if model is None:
        model = grasp_model(mesh, K, mode=mode, jaw_width=jaw_width)
    t.update(model.timings)
    graph = model.graph
    V = graph.n_vertices
    sigma0 = model.stiffness.sigma0
    k = model.stiffness.k
    sel = np.ones(V, bool)
    if separation_range is not None:
        lo_r, hi_r = map(float, separation_range)
        if not (math.isfinite(lo_r) and math.isfinite(hi_r) and 0 <= lo_r <= hi_r):
            raise GraspError(f"separation range {separation_range!r}: need 0 <= min <= max (m)")
        sel &= (sigma0 >= lo_r) & (sigma0 <= hi_r)
    rm = _region_mask(mesh.nodes, regions)
    if rm is not None:
        sel &= rm[graph.pairs[:, 0]] & rm[graph.pairs[:, 1]]
    idx = np.flatnonzero(sel)
    if not len(idx):
        raise GraspError("no jaw pair is left after the separation-range and region filters; widen them")
    if mesh.material is None:
        raise GraspError("no material: the elastic-limit strain e_L is unknown")
    t0 = time.perf_counter()
    e_max, sigma_L = pair_elastic_limits(model, idx, mesh.material.elastic_limit_strain)
    t["elastic_limits"] = time.perf_counter() - t0

    # Shared lattice (paper §4.7). λ bounds the slope of every vertex energy, so of
    # U_A = U_w − U_s and of U_L, over the whole range.
    if mode == "contracting":
        lo, hi = float(sigma_L.min()), float(sigma0[idx].max())
    else:
        lo, hi = float(sigma0[idx].min()), float(sigma_L.max())
    lam = lipschitz_constant(sigma0, k, hi, mode)
    if eps is None:
        eps = lam * max(hi - lo, 1e-300) / max(int(n_sigma), 1)
    step = eps / lam
    grid = lattice(lo, hi, step, max_size=max_sigma)
    best_Q = np.zeros(len(idx))
    best_s = np.full(len(idx), np.nan)
    best_UA = np.zeros(len(idx))
    best_UL = np.zeros(len(idx))
    s0 = sigma0[idx]
    kk = k[idx]
    UsL = 0.5 * kk * (s0 - sigma_L) ** 2                # U_s(σ_L) per pair (J)
    t0 = time.perf_counter()

    range_lo, range_hi = (sigma_L, s0) if mode == "contracting" else (s0, sigma_L)

    def sweep(sig: float) -> tuple[np.ndarray, np.ndarray]:
        U = vertex_energies(sig, sigma0, k, mode)
        return release_energies(U, graph)[idx], UsL - U[idx]

    # The sweeps of different σ are independent and their kernels release the GIL: run
    # them on threads, fold the results in lattice order (deterministic ties).
    workers = _workers()
    with ThreadPoolExecutor(workers) as pool:
        for lo_j in range(0, len(grid), 4 * workers):
            block = grid[lo_j: lo_j + 4 * workers]
            for j, (sig, (R, UL)) in enumerate(zip(block, pool.map(sweep, block)), start=lo_j):
                Q = np.where((sig >= range_lo) & (sig <= range_hi), np.minimum(R, UL), -np.inf)
                better = Q > best_Q
                best_Q = np.where(better, Q, best_Q)
                best_s = np.where(better, sig, best_s)
                best_UA = np.where(better, R, best_UA)
                best_UL = np.where(better, UL, best_UL)
                if progress is not None:
                    progress(j + 1, len(grid))
    t["lattice_sweeps"] = time.perf_counter() - t0
    # Rank: quality descending, ties by pair order (stable).
    order = np.argsort(-best_Q, kind="stable")
    gi = idx[order]
    refined: list[GraspAnalysis] = []
    t0 = time.perf_counter()
    for v in gi[: int(top)]:
        if best_Q[np.searchsorted(idx, v)] <= 0:
            break
        a, b = graph.pairs[v]
        refined.append(optimize_separation(mesh, (int(a), int(b)), method="exact", mode=mode,
                                           jaw_width=jaw_width, model=model))
    t["refine_exact"] = time.perf_counter() - t0
    # Report the refined pairs' exact values (never below their lattice values), then
    # re-rank: the refined pairs stay ahead of every unrefined one.
    lattice_Q = best_Q[order]
    Q, s_star = lattice_Q.copy(), best_s[order].copy()
    UA, UL = best_UA[order].copy(), best_UL[order].copy()
    exact = np.zeros(len(order), bool)
    for i, r in enumerate(refined):
        exact[i] = True
        Q[i] = r.quality
        s_star[i] = np.nan if r.sigma_star is None else r.sigma_star
        sep = r.separation
        UA[i] = math.inf if sep.U_A_infinite else (0.0 if sep.U_A is None else sep.U_A)
        UL[i] = sep.U_L
    rank = np.argsort(-Q, kind="stable")
    sel = order[rank]
    return PlanResult(
        pairs=graph.pairs[idx[sel]], sigma0=sigma0[idx[sel]], k=k[idx[sel]], e_max=e_max[sel],
        sigma_L=sigma_L[sel], sigma_star=s_star[rank], quality=Q[rank],
        U_A=UA[rank], U_L=UL[rank], pulls=model.pulls[idx[sel]],
        lattice_quality=lattice_Q[rank], exact=exact[rank], epsilon=float(eps),
        lipschitz=lam, step=step, n_sigma=len(grid), refined=refined, mode=mode,
        jaw_width=float(jaw_width), timings=t, model=model)
