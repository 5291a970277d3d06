"""Pair stiffness ``k_ab`` of every pair of perimeter nodes (SPEC §4, paper §4.2).

``k_ab`` is the force along the line a–b per unit change of the distance |ab|, everything
else free. The two jaw forces are equal, opposite and collinear, hence orthogonal to the
rigid modes, so with ``C`` the compliance of the perimeter DOFs (any generalised inverse
of ``K`` restricted to them) and ``d`` the unit dipole along ``e = (b − a)/|b − a|``::

    1 / k_ab = dᵀ C_{ab} d = eᵀ (C_aa + C_bb − C_ab − C_ba) e.

One factorisation of ``K`` and the condensed compliance give all ``k_ab`` at once
(:class:`~deformclosure.elasticity.condense.CondensedCompliance`). The paper computes
each ``k_ab`` by its own Dirichlet solve — pin a at (0, 0) and b at (σ0 − 1, 0) and read
the energy ``U = ½ k_ab`` — kept here as ``method="paper"`` for reference and tests.

Jaws of finite width (see :mod:`deformclosure.grasp.jaws`) tie the normal displacement
of their contact patch; their ``k_ab`` comes from a small constrained problem on the
same condensed compliance, solved for all pairs in vectorised batches.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..choices import choose
from ..elasticity.condense import CondensedCompliance
from ..errors import GraspError
from ..geometry import touch_tolerance
from .jaws import jaw_patches

__all__ = ["PairStiffness", "pair_stiffness", "all_pairs", "pair_stiffness_paper",
           "jaw_pair_forces", "wide_jaw_forces", "PAIR_METHODS"]

#: How :func:`pair_stiffness` computes ``k_ab``: condensed compliance, or the paper's
#: one Dirichlet solve per pair.
PAIR_METHODS = ("schur", "paper")


@dataclass(frozen=True)
class PairStiffness:
    """Rest distances and stiffnesses of node pairs.

    Attributes
    ----------
    pairs : ndarray, shape (V, 2)
        Node ids ``(a, b)``, ``a < b``.
    sigma0 : ndarray, shape (V,)
        Rest distance |ab| (m).
    k : ndarray, shape (V,)
        Pair stiffness (N/m).
    jaw_width : float
        Jaw contact width used (m); 0 for point jaws.
    method : str
    """

    pairs: np.ndarray
    sigma0: np.ndarray
    k: np.ndarray
    jaw_width: float = 0.0
    method: str = "schur"


def all_pairs(node_ids: np.ndarray) -> np.ndarray:
    """All unordered pairs ``(a, b)``, ``a < b``, of distinct node ids, lexicographic."""
    ids = np.unique(np.asarray(node_ids, dtype=np.int64))
    i, j = np.triu_indices(len(ids), k=1)
    return np.column_stack([ids[i], ids[j]])


def _unit(nodes: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d = nodes[pairs[:, 1]] - nodes[pairs[:, 0]]
    s = np.linalg.norm(d, axis=1)
    if np.any(s <= 0):
        raise GraspError("two jaw nodes coincide; a pair needs two distinct positions")
    return d / s[:, None], s


def pair_stiffness(mesh, K: sp.spmatrix | None = None, pairs: np.ndarray | None = None, *,
                   loops: tuple[int, ...] = (0,), jaw_width: float = 0.0,
                   method: str = "schur", condensed: CondensedCompliance | None = None
                   ) -> PairStiffness:
    """``σ0(a,b)`` and ``k_ab`` for node pairs of the perimeter.

    Parameters
    ----------
    mesh : Mesh
    K : sparse matrix, optional
        Stiffness (N/m); assembled from ``mesh`` if omitted.
    pairs : ndarray, shape (V, 2), optional
        Node pairs; default every pair of nodes on ``loops``.
    loops : tuple of int
        Boundary loops whose nodes form pairs (0 = outer; all loops for expanding grasps).
    jaw_width : float
        Jaw contact width (m); 0 = point jaws.
    method : {"schur", "paper"}
        ``"schur"``: one factorisation, condensed compliance (default).
        ``"paper"``: one Dirichlet solve per pair (paper §4.2; point jaws only; slow).
    condensed : CondensedCompliance, optional
        Reuse an existing condensation (must include all nodes of ``pairs``).

    Returns
    -------
    PairStiffness

    Raises
    ------
    GraspError
        Unknown method, negative width, pair nodes not on the boundary.

    Examples
    --------
    A coarse 12 × 20 mm rubber block: ``σ0`` and ``k_ab`` of every pair of its
    outer-perimeter nodes, and the paper's Dirichlet solve agreeing on one pair:

    >>> from deformclosure import demo_part, mesh_part
    >>> mesh = mesh_part(demo_part(max_area_mm2=20.0))
    >>> ps = pair_stiffness(mesh)
    >>> p = len(mesh.outer_loop)
    >>> len(ps.k) == p * (p - 1) // 2, bool(np.all(ps.k > 0))
    (True, True)
    >>> ref = pair_stiffness(mesh, pairs=ps.pairs[:1], method="paper").k[0]
    >>> bool(np.isclose(ref, ps.k[0], rtol=1e-9))
    True
    """
    from ..elasticity import stiffness_matrix

    choose(method, PAIR_METHODS, "method", GraspError)
    if K is None:
        K = stiffness_matrix(mesh)
    loop_nodes = np.concatenate([mesh.loops[i] for i in loops])
    pairs = all_pairs(loop_nodes) if pairs is None else np.asarray(pairs, dtype=np.int64)
    e, sigma0 = _unit(mesh.nodes, pairs)
    if method == "paper":
        if jaw_width:
            raise GraspError("method 'paper' supports point jaws only; use jaw_width = 0")
        return PairStiffness(pairs, sigma0, pair_stiffness_paper(mesh, K, pairs), 0.0, "paper")
    cc = condensed if condensed is not None else CondensedCompliance(
        K, mesh.nodes, mesh.triangles, np.concatenate(mesh.loops))
    if jaw_width == 0:
        k = 1.0 / _point_compliance(cc, pairs, e)
    else:
        k = _wide_jaw_stiffness(mesh, cc, pairs, e, jaw_width)[0]
    if np.any(~np.isfinite(k)) or np.any(k <= 0):
        raise GraspError("a pair stiffness is not positive; the stiffness matrix is not valid")
    return PairStiffness(pairs, sigma0, k, float(jaw_width), "schur")


def _point_compliance(cc: CondensedCompliance, pairs: np.ndarray, e: np.ndarray) -> np.ndarray:
    """``eᵀ (C_aa + C_bb − C_ab − C_ba) e`` for all pairs (m/N)."""
    pa = cc.position(pairs[:, 0])
    pb = cc.position(pairs[:, 1])
    if np.any(pa < 0) or np.any(pb < 0):
        raise GraspError("a jaw node is not a perimeter node; jaws sit on the part's boundary")
    C = cc.C.reshape(len(cc.boundary), 2, len(cc.boundary), 2)
    Caa = C[pa, :, pa, :]
    Cbb = C[pb, :, pb, :]
    Cab = C[pa, :, pb, :]
    M = Caa + Cbb - Cab - np.transpose(Cab, (0, 2, 1))
    return np.einsum("vi,vij,vj->v", e, M, e)


def _disjoint_patches(mesh, pairs: np.ndarray, width: float
                      ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Contact patches ``J_a``, ``J_b`` of the two jaws of every pair; a node in both goes
    to the nearer jaw."""
    uniq = np.unique(pairs)
    patches = dict(zip(uniq.tolist(), jaw_patches(mesh.nodes, mesh.loops, uniq, width)))
    sets_a, sets_b = [], []
    for (a, b) in pairs.tolist():
        Ja, Jb = patches[a], patches[b]
        shared = np.intersect1d(Ja, Jb)
        if len(shared):
            da = np.linalg.norm(mesh.nodes[shared] - mesh.nodes[a], axis=1)
            db = np.linalg.norm(mesh.nodes[shared] - mesh.nodes[b], axis=1)
            to_b = shared[db < da]
            to_a = shared[db >= da]
            Ja = Ja[~np.isin(Ja, to_b)]
            Jb = Jb[~np.isin(Jb, to_a)]
        sets_a.append(Ja)
        sets_b.append(Jb)
    return sets_a, sets_b


def _patch_system(G: np.ndarray, rho: np.ndarray, ma: int, mb: int, flat_tol: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The stacked systems ``A x = rhs`` of :func:`_wide_jaw_stiffness` for ``B`` pairs
    with patches of ``ma`` and ``mb`` nodes (``G``: ``(B, m, m)``, ``rho``: ``(B, m)``)."""
    m = ma + mb
    B = len(G)
    A = np.zeros((B, m + 3, m + 3))
    rhs = np.zeros((B, m + 3))
    A[:, :m, :m] = G
    A[:, :m, m] = rho
    A[:, :m, m + 1] = -np.concatenate([np.ones(ma), np.zeros(mb)])
    A[:, :m, m + 2] = -np.concatenate([np.zeros(ma), np.ones(mb)])
    A[:, m, :m] = 1.0
    A[:, m + 1, :m] = rho
    A[:, m + 2, m + 1] = -1.0
    A[:, m + 2, m + 2] = 1.0
    rhs[:, m + 2] = -1.0
    # Patches with no lever-arm spread (all nodes on the jaw line, within the touching
    # tolerance) cannot transmit a moment: drop the moment equation and fix ω = 0 there.
    flat = np.ptp(rho, axis=1) <= flat_tol
    A[flat, m + 1, :] = 0.0
    A[flat, :, m] = 0.0
    A[flat, m + 1, m] = 1.0
    return A, rhs


def _wide_jaw_stiffness(mesh, cc: CondensedCompliance, pairs: np.ndarray, e: np.ndarray,
                        width: float) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """Stiffness of flat frictionless jaws of ``width`` for all pairs.

    For each pair, unknowns ``x = [λ (m normal forces on the patch nodes), ω, δa, δb]``:
    compatibility ``G λ + ω ρ − δa s_a − δb s_b = 0`` (normal displacement of each
    patch node equals its jaw's, up to the part's rigid motion), equilibrium
    ``Σλ = 0``, ``ρᵀλ = 0`` and the unit approach ``δb − δa = −1``; ``G_ij = eᵀ C_ij e``
    and ``ρ_i = (r_i × e)`` is the lever arm. ``k = −Σ_{J_b} λ``.

    Returns
    -------
    k : ndarray (V,)
    node_sets : list of ndarray
        Patch node ids ``[J_a, J_b]`` per pair (concatenated).
    forces : list of ndarray
        Normal forces λ (N per m of approach) on those nodes.
    """
    V = len(pairs)
    sets_a, sets_b = _disjoint_patches(mesh, pairs, width)
    sizes = np.array([[len(x), len(y)] for x, y in zip(sets_a, sets_b)])
    k = np.empty(V)
    node_sets: list[np.ndarray] = [None] * V  # type: ignore[list-item]
    forces: list[np.ndarray] = [None] * V  # type: ignore[list-item]
    Cn = cc.C.reshape(len(cc.boundary), 2, len(cc.boundary), 2)
    flat_tol = touch_tolerance(mesh.diameter)
    # Batch the pairs by patch sizes: one stacked linear solve per group.
    keys, inv = np.unique(sizes, axis=0, return_inverse=True)
    for g, (ma, mb) in enumerate(keys):
        idx = np.flatnonzero(inv.ravel() == g)
        J = np.array([np.concatenate([sets_a[i], sets_b[i]]) for i in idx])   # (B, m)
        P = cc.position(J)
        if np.any(P < 0):
            raise GraspError("a jaw patch reaches a node that is not on the boundary")
        eg = e[idx]                                                            # (B, 2)
        Cblk = Cn[P[:, :, None], :, P[:, None, :], :]                          # (B, m, m, 2, 2)
        G = np.einsum("bi,bpqij,bj->bpq", eg, Cblk, eg)
        xy = mesh.nodes[J] - mesh.nodes[J].mean(axis=1, keepdims=True)
        rho = xy[..., 0] * eg[:, None, 1] - xy[..., 1] * eg[:, None, 0]       # (B, m)
        A, rhs = _patch_system(G, rho, ma, mb, flat_tol)
        lam = np.linalg.solve(A, rhs[..., None])[..., 0][:, :ma + mb]
        k[idx] = -lam[:, ma:].sum(axis=1)
        for r, i in enumerate(idx):
            node_sets[i] = J[r]
            forces[i] = lam[r]
    return k, node_sets, forces


def wide_jaw_forces(mesh, cc: CondensedCompliance, pairs: np.ndarray, width: float
                    ) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """Stiffness, patch nodes and normal forces of flat jaws of ``width`` (m) at each of
    ``pairs`` (node ids, (V, 2)): ``(k (N/m), node_sets, forces (N per m of approach))``,
    as :func:`pair_stiffness` computes them for ``jaw_width > 0``.
    """
    e, _ = _unit(mesh.nodes, pairs)
    return _wide_jaw_stiffness(mesh, cc, pairs, e, width)


def jaw_pair_forces(mesh, cc: CondensedCompliance, a: int, b: int, width: float = 0.0
                    ) -> tuple[float, np.ndarray]:
    """Stiffness and nodal force vector (N per m of approach) of the jaw pair (a, b).

    Returns
    -------
    k : float
        N/m.
    f : ndarray, shape (2n,)
        Forces on the part for a unit decrease of the jaw distance (self-equilibrated).
    """
    pairs = np.array([[a, b]], dtype=np.int64)
    e, _ = _unit(mesh.nodes, pairs)
    f = np.zeros(2 * mesh.n_nodes)
    if width == 0:
        k = float(1.0 / _point_compliance(cc, pairs, e)[0])
        # Unit approach: the part is pushed by k at b along −e and at a along +e.
        f[2 * a:2 * a + 2] = k * e[0]
        f[2 * b:2 * b + 2] = -k * e[0]
        return k, f
    kk, sets, lam = _wide_jaw_stiffness(mesh, cc, pairs, e, width)
    J, l = sets[0], lam[0]
    np.add.at(f, 2 * J, l * e[0, 0])
    np.add.at(f, 2 * J + 1, l * e[0, 1])
    return float(kk[0]), f


def pair_stiffness_paper(mesh, K: sp.spmatrix, pairs: np.ndarray) -> np.ndarray:
    """Paper §4.2 reference: one Dirichlet solve per pair (slow, for tests/benchmarks).

    For each pair: u_a = 0, u_b = −e (b moved one metre toward a, perpendicular
    displacement 0), all other nodes free; ``k_ab = 2 U`` with ``U = ½ uᵀ K u``.
    """
    K = sp.csr_matrix(K)
    n2 = K.shape[0]
    e, _ = _unit(mesh.nodes, pairs)
    out = np.empty(len(pairs))
    for i, ((a, b), ei) in enumerate(zip(pairs, e)):
        fixed = np.array([2 * a, 2 * a + 1, 2 * b, 2 * b + 1])
        uc = np.array([0.0, 0.0, -ei[0], -ei[1]])
        free = np.setdiff1d(np.arange(n2), fixed)
        Kff = K[free][:, free].tocsc()
        rhs = -(K[free][:, fixed] @ uc)
        u = np.zeros(n2)
        u[fixed] = uc
        u[free] = spla.spsolve(Kff, rhs)
        out[i] = float(u @ (K @ u))  # 2U
    return out
