"""Compliance of a free part condensed onto a set of boundary nodes (static condensation).

For the two-jaw problem we need, for every pair of perimeter nodes, the compliance of
the part under a self-equilibrated pair of forces (SPEC §4). All of them follow from
one matrix: the compliance ``C`` of the chosen boundary DOFs, i.e. the inverse of the
Schur complement ``S = K_bb - K_bi K_ii⁻¹ K_ib`` (with the 3 rigid modes removed by
pinning 3 boundary DOFs).

We get ``S`` from a single sparse LU factorisation in which the interior nodes are
ordered first, by METIS nested dissection, and the boundary DOFs last: with no pivoting,
``A = L U`` gives ``S = L₂₂ U₂₂`` (the trailing blocks), so no solve with many
right-hand sides is needed. The same factorisation then solves for whole displacement
fields (strains at the jaw pair).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import StiffnessError
from ..limits import blas_threads
from ..log import done
from .solve import PinnedFactorisation, pinned_dofs

__all__ = ["CondensedCompliance", "node_adjacency", "nested_dissection_order"]


def node_adjacency(triangles: np.ndarray, n_nodes: int) -> sp.csr_matrix:
    """Symmetric node adjacency (no diagonal) of a triangle mesh, CSR bool."""
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(len(e), bool), (e[:, 0], e[:, 1])), shape=(n_nodes, n_nodes))
    A = (A + A.T).tocsr()
    A.setdiag(False)
    A.eliminate_zeros()
    A.sort_indices()
    return A


def nested_dissection_order(adjacency: sp.csr_matrix) -> np.ndarray:
    """Fill-reducing elimination order (METIS nested dissection) of a graph's vertices."""
    n = adjacency.shape[0]
    if n <= 2:
        return np.arange(n)
    import pymetis

    adj = pymetis.CSRAdjacency(adjacency.indptr.astype(np.int64), adjacency.indices.astype(np.int64)) \
        if hasattr(pymetis, "CSRAdjacency") else None
    if adj is not None:
        perm, _ = pymetis.nested_dissection(adj)
    else:  # pragma: no cover - older pymetis
        perm, _ = pymetis.nested_dissection(xadj=adjacency.indptr, adjncy=adjacency.indices)
    return np.asarray(perm, dtype=np.int64)


class CondensedCompliance(PinnedFactorisation):
    """One factorisation of a free part's ``K``; compliance of chosen boundary nodes.

    Parameters
    ----------
    K : sparse matrix, shape (2n, 2n)
        Stiffness (N/m) of the free part (null space = rigid modes).
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).
    triangles : ndarray, shape (m, 3)
        Triangles (for the elimination order).
    boundary : ndarray of int, shape (q,)
        Node ids onto which to condense (e.g. perimeter nodes), distinct.

    Attributes
    ----------
    boundary : ndarray, shape (q,)
    C : ndarray, shape (2q, 2q)
        Compliance (m/N) of the boundary DOFs ``[x, y]`` per node in ``boundary`` order:
        for a self-equilibrated load ``f`` on them, ``u_b = C f`` up to a rigid motion, so
        ``fᵀ C f`` (twice the energy per unit load squared) is exact.

    Raises
    ------
    StiffnessError
        If ``K`` has more zero-energy modes than the 3 rigid ones.
    """

    def __init__(self, K: sp.spmatrix, nodes: np.ndarray, triangles: np.ndarray,
                 boundary: np.ndarray) -> None:
        t0 = time.perf_counter()
        n = len(nodes)
        boundary = np.asarray(boundary, dtype=np.int64)
        self.boundary = boundary
        self.n_nodes = n
        self.nodes = np.asarray(nodes, float)
        # Rigid modes: pin 3 DOFs, chosen among the boundary nodes so that the interior
        # stays untouched (both DOFs of one node, one of a far node).
        pins = pinned_dofs_among(nodes, boundary)
        dof_order = _interior_first_order(triangles, n, boundary, pins)
        self.dof_order = self.free_dofs = dof_order
        self.pins = pins
        Kp = sp.csc_matrix(K)[dof_order][:, dof_order].tocsc()
        lu = self._factorise(Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True, "Equil": False})
        N = len(dof_order)
        if not (np.array_equal(lu.perm_r, np.arange(N)) and np.array_equal(lu.perm_c, np.arange(N))):
            raise StiffnessError("sparse LU reordered the condensation; K is not positive definite "
                                 "after removing the rigid modes")
        self._lu = lu
        nb = 2 * len(boundary) - int(np.isin(pins, _dofs(boundary)).sum())
        Cb = _schur_inverse(lu, N - nb)
        # Place into the full (2q x 2q) boundary compliance; pinned DOFs get zeros.
        idx = np.flatnonzero(~np.isin(_dofs(boundary), pins))
        C = np.zeros((2 * len(boundary), 2 * len(boundary)))
        C[np.ix_(idx, idx)] = Cb
        self.C = C
        self._pos = np.full(n, -1, dtype=np.int64)
        self._pos[boundary] = np.arange(len(boundary))
        done("factorised K (%d DOFs) and condensed it onto %d boundary nodes", t0, N,
             len(boundary))

    def position(self, node_ids: np.ndarray) -> np.ndarray:
        """Row index (node position in ``boundary``) of node ids; -1 if not condensed."""
        return self._pos[np.asarray(node_ids)]


def _interior_first_order(triangles: np.ndarray, n: int, boundary: np.ndarray,
                          pins: np.ndarray) -> np.ndarray:
    """The unpinned DOFs in elimination order: interior nodes first, by METIS nested
    dissection, then the boundary nodes (so the trailing block of the factor is the
    Schur complement on the boundary)."""
    is_b = np.zeros(n, bool)
    is_b[boundary] = True
    interior = np.flatnonzero(~is_b)
    adj = node_adjacency(triangles, n)
    order_int = interior[nested_dissection_order(adj[interior][:, interior])] \
        if len(interior) else interior
    node_order = np.concatenate([order_int, boundary])
    dof_order = np.column_stack([2 * node_order, 2 * node_order + 1]).ravel()
    return dof_order[~np.isin(dof_order, pins)]


def _schur_inverse(lu: spla.SuperLU, start: int) -> np.ndarray:
    """Inverse of the Schur complement on the trailing DOFs ``start:`` of an unpivoted LU.

    K is symmetric and factorised without pivoting, so U = D Lᵀ and the Schur
    complement is S = L₂₂ D₂₂ L₂₂ᵀ: its Cholesky factor is L₂₂ D₂₂^½, and LAPACK's
    potri inverts S from it directly (no dense product, no second factorisation).
    """
    import scipy.linalg as sla

    L22 = _trailing_block(lu.L, start)
    d = _trailing_diagonal(lu.U, start)
    if np.any(d <= 0) or np.min(d) < 1e-13 * np.max(d):
        raise StiffnessError("stiffness is singular or indefinite beyond the 3 rigid modes; "
                             "the mesh is disconnected or a mechanism")
    R = L22
    R *= np.sqrt(d)[None, :]
    with blas_threads():      # dpotri loses 30x to a second thread under load (limits.BLAS_THREADS)
        Cl, info = sla.lapack.dpotri(R, lower=1, overwrite_c=1)
    if info != 0:
        raise StiffnessError("condensed stiffness is not positive definite; K has more than "
                             "3 zero-energy modes")
    # the lower triangle (Fortran order) mirrored, on its C-ordered transpose: the upper
    # triangle of a row-major view (20x faster than mirroring the Fortran array itself)
    Ut = Cl.T
    C = np.triu(Ut)
    C += np.triu(Ut, 1).T
    return C


def _dofs(nodes_: np.ndarray) -> np.ndarray:
    return np.column_stack([2 * nodes_, 2 * nodes_ + 1]).ravel()


def pinned_dofs_among(nodes: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Like :func:`pinned_dofs` but choosing the pinned nodes among ``candidates``."""
    sub = pinned_dofs(nodes[candidates])
    node = candidates[sub // 2]
    return 2 * node + sub % 2


def _trailing_diagonal(M: sp.spmatrix, start: int) -> np.ndarray:
    """``diag(M)[start:]`` of a CSC matrix."""
    M = sp.csc_matrix(M)
    N = M.shape[0]
    lo = M.indptr[start]
    rows = M.indices[lo:]
    cols = np.repeat(np.arange(start, N), np.diff(M.indptr[start:]))
    d = np.zeros(N - start)
    on = rows == cols
    d[rows[on] - start] = M.data[lo:][on]
    return d


def _trailing_block(M: sp.spmatrix, start: int) -> np.ndarray:
    """Dense ``M[start:, start:]`` (Fortran order) of a CSC matrix, sliced without copying
    the rest."""
    M = sp.csc_matrix(M)
    N = M.shape[0]
    lo = M.indptr[start]
    data = M.data[lo:]
    rows = M.indices[lo:]
    counts = np.diff(M.indptr[start:])
    cols = np.repeat(np.arange(N - start), counts)
    keep = rows >= start
    # Fortran order: the columns are filled in storage order (and LAPACK takes it as is)
    out = np.zeros((N - start, N - start), order="F")
    out[rows[keep] - start, cols[keep]] = data[keep]
    return out
