"""Two-jaw grasp analysis of a meshed part: the user-facing pipeline (SPEC §4).

``grasp_model`` does the work shared by every jaw pair of a part — one factorisation of
``K`` condensed onto the perimeter, all pair stiffnesses, the contact graph — and
``optimize_separation`` finds the optimal jaw separation for one jaw pair on it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..choices import METHODS, MODES, choose
from ..elasticity import stiffness_matrix
from ..elasticity.condense import CondensedCompliance
from ..errors import GraspError
from ..units import SI_UNITS
from .contact_graph import ContactGraph, contact_graph, pulling_pairs
from .elastic_limit import ElasticLimit, elastic_limit
from .pair_stiffness import PairStiffness, pair_stiffness
from .separation import SeparationResult, lipschitz_constant, optimize_separation_arrays, vertex_energies

__all__ = ["GraspModel", "GraspAnalysis", "grasp_model", "optimize_separation", "check_jaws"]


@dataclass(frozen=True)
class GraspModel:
    """Everything about a part's two-jaw grasps that does not depend on the jaw pair.

    Attributes
    ----------
    mesh : Mesh
    mode : {"contracting", "expanding"}
    jaw_width : float
        Jaw contact width (m), 0 for point jaws.
    graph : ContactGraph
        Contact graph over pairs of perimeter nodes (outer loop for contracting grasps,
        every loop for expanding ones).
    stiffness : PairStiffness
        ``σ0`` and ``k`` of every graph vertex (aligned with ``graph.pairs``).
    condensed : CondensedCompliance
        The factorisation (for strain fields at a jaw pair).
    pulls : ndarray of bool, shape (V,)
        Pairs whose jaw line leaves the part at a jaw (the jaw would have to pull).
    timings : dict
        Seconds spent in each step.
    """

    mesh: Any
    mode: str
    jaw_width: float
    graph: ContactGraph
    stiffness: PairStiffness
    condensed: CondensedCompliance
    pulls: np.ndarray
    timings: dict = field(default_factory=dict)

    def energies(self, sigma: float) -> np.ndarray:
        """Energy (J) of every graph vertex at jaw separation ``sigma`` (m)."""
        return vertex_energies(sigma, self.stiffness.sigma0, self.stiffness.k, self.mode)


def grasp_model(mesh, K: sp.spmatrix | None = None, *, mode: str = "contracting",
                jaw_width: float = 0.0) -> GraspModel:
    """Build the jaw-pair-independent part of the two-jaw analysis.

    Parameters
    ----------
    mesh : Mesh
        Meshed part with a material (or give ``K``).
    K : sparse matrix, optional
        Stiffness (N/m); assembled from ``mesh`` if omitted (a user-supplied ``K`` is
        used as is).
    mode : {"contracting", "expanding"}
        Contracting jaws squeeze the outer boundary; expanding jaws push outward,
        typically from inside a hole.
    jaw_width : float
        Jaw contact width (m); 0 = point jaws.

    Returns
    -------
    GraspModel

    Raises
    ------
    GraspError

    Examples
    --------
    The contact graph of a coarse 12 × 20 mm block: every pair of its outer-perimeter
    nodes is a vertex.

    >>> from deformclosure import demo_part, mesh_part
    >>> mesh = mesh_part(demo_part(max_area_mm2=20.0))
    >>> model = grasp_model(mesh)
    >>> p = len(mesh.outer_loop)
    >>> model.graph.n_vertices == p * (p - 1) // 2, bool(model.stiffness.k.min() > 0)
    (True, True)
    """
    choose(mode, MODES, "mode", GraspError)
    if not (np.isfinite(jaw_width) and jaw_width >= 0):
        raise GraspError(f"jaw width = {jaw_width!r}: must be a finite length >= 0 (0 = point jaws)")
    if mode == "expanding" and len(mesh.loops) < 2:
        raise GraspError("expanding grasps need a part with a hole (jaws push outward from inside it)")
    t = {}
    t0 = time.perf_counter()
    if K is None:
        K = stiffness_matrix(mesh)
    t["stiffness"] = time.perf_counter() - t0
    vertex_loops = (0,) if mode == "contracting" else tuple(range(len(mesh.loops)))
    t0 = time.perf_counter()
    graph = contact_graph(mesh.nodes, list(mesh.loops), vertex_loops=vertex_loops)
    t["contact_graph"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    cc = CondensedCompliance(K, mesh.nodes, mesh.triangles, np.concatenate(mesh.loops))
    t["factorisation"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ps = pair_stiffness(mesh, K, pairs=graph.pairs, jaw_width=jaw_width, condensed=cc)
    t["pair_stiffness"] = time.perf_counter() - t0
    pulls = pulling_pairs(mesh.nodes, list(mesh.loops), graph.pairs, expanding=(mode == "expanding"))
    return GraspModel(mesh, mode, float(jaw_width), graph, ps, cc, pulls, t)


def check_jaws(model: GraspModel, n0: int, n1: int) -> int:
    """Validate a jaw pair and return its graph vertex index.

    Raises
    ------
    GraspError
        Same node twice, not a node, or not a perimeter node of the grasp's loops.
    """
    mesh = model.mesh
    for name, v in (("first jaw", n0), ("second jaw", n1)):
        if not isinstance(v, (int, np.integer)) or not (0 <= int(v) < mesh.n_nodes):
            raise GraspError(f"{name} = {v!r}: not a node id of the mesh (0..{mesh.n_nodes - 1})")
    if int(n0) == int(n1):
        raise GraspError(f"jaws: both jaws are on node {n0}; give two different perimeter nodes")
    allowed = np.zeros(mesh.n_nodes, bool)
    allowed[model.graph.vertex_nodes] = True
    for name, v in (("first jaw", n0), ("second jaw", n1)):
        if not allowed[int(v)]:
            where = "the outer boundary" if model.mode == "contracting" else "a boundary loop"
            raise GraspError(f"{name}: node {int(v)} is an interior node, not on {where}; "
                             "jaws must sit on perimeter nodes")
    return int(model.graph.vertex_index(int(n0), int(n1)))


@dataclass(frozen=True)
class GraspAnalysis:
    """Result of :func:`optimize_separation` for one jaw pair.

    Attributes
    ----------
    jaws : tuple of int
        Jaw nodes ``(n0, n1)``.
    limit : ElasticLimit
    separation : SeparationResult
    model : GraspModel
    timings : dict
        Seconds spent in each step.

    Examples
    --------
    >>> from deformclosure import demo_part, mesh_part
    >>> mesh = mesh_part(demo_part(max_area_mm2=20.0))
    >>> r = optimize_separation(mesh, (mesh.find_node([0, 0.01]), mesh.find_node([0.012, 0.01])))
    >>> report = r.to_dict()
    >>> report["model"], report["method"], report["units"]["energy"], report["quality"] == r.quality
    ('paper', 'exact', 'J', True)
    """

    jaws: tuple[int, int]
    limit: ElasticLimit
    separation: SeparationResult
    model: GraspModel
    timings: dict

    @property
    def sigma_star(self) -> float | None:
        """Optimal jaw separation (m), ``None`` if the pair cannot hold the part."""
        return self.separation.sigma_star

    @property
    def quality(self) -> float:
        """``Q(σ*)`` (J)."""
        return self.separation.quality

    def to_dict(self) -> dict[str, Any]:
        """JSON report of SPEC §5 (all SI)."""
        sep = self.separation.to_dict()
        mesh = self.model.mesh
        n0, n1 = self.jaws
        v = self.model.graph.vertex_index(n0, n1)
        report = {
            "model": "paper",
            "sigma_star": sep["sigma_star"],
            "quality": sep["quality"],
            "U_A": sep["U_A"],
            "U_A_infinite": sep["U_A_infinite"],
            "U_L": sep["U_L"],
            "sigma_L": self.limit.sigma_L,
            "sigma0": self.limit.sigma0,
            "k01": self.limit.k01,
            "e_max": self.limit.e_max,
            "jaws": [int(n0), int(n1)],
            "jaw_positions": mesh.nodes[[n0, n1]].tolist(),
            "jaw_width": self.model.jaw_width,
            "pulls": bool(self.model.pulls[v]),
            "mode": self.model.mode,
            "method": sep["method"],
            "epsilon": sep["epsilon"],
            "energy_model": "linear",
            "units": dict(SI_UNITS),
            "curve": sep["curve"],
        }
        for key, value in sep.items():
            report.setdefault(key, value)
        report["mesh"] = {"nodes": mesh.n_nodes, "triangles": mesh.n_triangles,
                          "perimeter_nodes": int(len(self.model.graph.vertex_nodes)),
                          "graph_vertices": int(self.model.graph.n_vertices),
                          "graph_edges": int(self.model.graph.n_edges)}
        report["timings_s"] = dict(self.timings)
        return report


def default_epsilon(limit: ElasticLimit, sigma0: np.ndarray | None = None,
                    k: np.ndarray | None = None, mode: str = "contracting",
                    max_samples: int = 20_000) -> float:
    """Default ε (J) of the approximate method.

    ``1e-3 · ½ k01 (σ0 − σ_L)²``: the energy of the jaw pair squeezed to its elastic limit
    bounds ``U_L`` on the whole range, hence ``Q``; a thousandth of it is a tolerance on
    the scale of the answer. When the grid step ``ξ = ε/λ`` this gives would need more
    than ``max_samples`` samples over the range (a stiff pair far from its elastic
    limit next to a small ``e_L``), ε is raised to ``λ·|σ0 − σ_L| / max_samples``, so the
    default run always completes. Falls back to ``1e-12`` J for an empty range.

    Parameters
    ----------
    limit : ElasticLimit
    sigma0, k : ndarray, optional
        Rest distances (m) and stiffnesses (N/m) of all graph vertices, for ``λ``.
    mode : {"contracting", "expanding"}
    max_samples : int
    """
    span = abs(limit.sigma0 - limit.sigma_L)
    e = 1e-3 * 0.5 * limit.k01 * span ** 2
    if sigma0 is not None and k is not None and span > 0:
        e = max(e, lipschitz_constant(sigma0, k, limit.sigma_L, mode) * span / max_samples)
    return float(e) if np.isfinite(e) and e > 0 else 1e-12


def optimize_separation(mesh, jaws: tuple[int, int], *, K: sp.spmatrix | None = None,
                        method: str = "exact", eps: float | None = None,
                        mode: str = "contracting", jaw_width: float = 0.0,
                        model: GraspModel | None = None) -> GraspAnalysis:
    """Optimal separation ``σ*`` of two frictionless jaws at perimeter nodes ``jaws``.

    Maximises ``Q(σ) = min(U_A(σ), U_L(σ))`` over ``σ ∈ [σ_L, σ0]`` (contracting) or
    ``[σ0, σ_L]`` (expanding) — paper §4.5–4.7, SPEC §4.

    Parameters
    ----------
    mesh : Mesh
        Meshed part with material.
    jaws : (int, int)
        Jaw node ids ``(n0, n1)`` on the perimeter.
    K : sparse matrix, optional
        Stiffness (N/m); assembled if omitted.
    method : {"exact", "approx", "paper"}
        ``"exact"`` (default): visits only the breakpoints that can change ``U_A``;
        ``"paper"``: every pairwise crossing (reference, small parts only);
        ``"approx"``: the paper's ε-approximation on a grid, ``eps`` in J.
    eps : float, optional
        Tolerance (J) of ``"approx"``. Default (:func:`default_epsilon`):
        ``1e-3 · ½ k01 (σ0 − σ_L)²``, a thousandth of the energy the jaw pair stores
        when squeezed to the elastic limit (an upper bound of ``Q*``), raised if needed
        so that at most 20 000 grid steps cover the range; the value used is reported
        as ``epsilon``.
    mode : {"contracting", "expanding"}
    jaw_width : float
        Jaw contact width (m).
    model : GraspModel, optional
        Reuse a model built by :func:`grasp_model` (same mode and width).

    Returns
    -------
    GraspAnalysis

    Raises
    ------
    GraspError
        Bad jaws, method, eps or width.

    Examples
    --------
    Jaws at the middle of the long sides of a coarse 12 × 20 mm rubber block, 12 mm
    apart at rest:

    >>> from deformclosure import demo_part, mesh_part
    >>> mesh = mesh_part(demo_part(max_area_mm2=20.0))
    >>> jaws = mesh.find_node([0.0, 0.01]), mesh.find_node([0.012, 0.01])
    >>> r = optimize_separation(mesh, jaws)
    >>> round(r.limit.sigma0, 9), r.sigma_star is None or r.limit.sigma_L <= r.sigma_star <= 0.012
    (0.012, True)
    """
    choose(method, METHODS, "method", GraspError)
    if eps is not None and not (np.isfinite(eps) and eps > 0):
        raise GraspError(f"eps = {eps!r}: must be a finite energy > 0 in joules")
    if model is None:
        model = grasp_model(mesh, K, mode=mode, jaw_width=jaw_width)
    elif model.mode != mode or model.jaw_width != jaw_width:
        raise GraspError("model was built for another mode or jaw width")
    n0, n1 = (int(jaws[0]), int(jaws[1])) if len(jaws) == 2 else (None, None)
    start = check_jaws(model, n0, n1)
    t = dict(model.timings)
    t0 = time.perf_counter()
    limit = elastic_limit(mesh, model.condensed, n0, n1, mode=mode, jaw_width=jaw_width)
    t["elastic_limit"] = time.perf_counter() - t0
    if method == "approx" and eps is None:
        eps = default_epsilon(limit, model.stiffness.sigma0, model.stiffness.k, mode)
    t0 = time.perf_counter()
    sep = optimize_separation_arrays(model.stiffness.sigma0, model.stiffness.k, model.graph,
                                     start, limit.sigma_L, mode=mode, method=method, eps=eps,
                                     e_max=limit.e_max)
    t[f"separation_{method}"] = time.perf_counter() - t0
    return GraspAnalysis((n0, n1), limit, sep, model, t)
