"""Plane stress / plane strain stiffness of linear (CST) triangles, vectorised.

For a triangle with nodes 1, 2, 3 (counter-clockwise, area A) the strain
``[exx, eyy, gamma_xy] = B u_e`` with ``u_e = [x1, y1, x2, y2, x3, y3]`` and

    B = 1/(2A) [[b1, 0, b2, 0, b3, 0], [0, c1, 0, c2, 0, c3], [c1, b1, c2, b2, c3, b3]],
    b_i = y_j - y_k,  c_i = x_k - x_j  (i, j, k cyclic),

and the element stiffness is ``K_e = t A Bᵀ D B`` (constant strain, exact integration).

Assembly works on 2×2 node blocks: element blocks are summed per node and per mesh edge
with ``np.bincount`` into a CSR layout computed once per mesh (kept in the mesh's cache),
instead of converting ``36 m`` COO triplets (which needs a sort). About 0.2-0.3 s for
100k nodes (``benchmarks/bench_fem.py``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import StiffnessError
from ..part import Material

__all__ = ["constitutive_matrix", "element_b_matrices", "element_stiffness", "stiffness_matrix",
           "assemble"]


def constitutive_matrix(material: Material) -> np.ndarray:
    """Elasticity matrix ``D`` (Pa) mapping ``[exx, eyy, gamma_xy]`` to stresses.

    Plane stress: ``E/(1-nu²) [[1, nu, 0], [nu, 1, 0], [0, 0, (1-nu)/2]]``;
    plane strain: ``E/((1+nu)(1-2nu)) [[1-nu, nu, 0], [nu, 1-nu, 0], [0, 0, (1-2nu)/2]]``.
    """
    E, nu = material.youngs_modulus, material.poisson_ratio
    if material.plane == "stress":
        c = E / (1.0 - nu**2)
        return c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, (1.0 - nu) / 2.0]])
    c = E / ((1.0 + nu) * (1.0 - 2.0 * nu))
    return c * np.array([[1.0 - nu, nu, 0.0], [nu, 1.0 - nu, 0.0], [0.0, 0.0, (1.0 - 2.0 * nu) / 2.0]])


def element_b_matrices(nodes: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strain-displacement matrices of all triangles.

    Returns
    -------
    B : ndarray, shape (m, 3, 6)
        In 1/m.
    area : ndarray, shape (m,)
        Signed areas (m²).
    """
    p = nodes[triangles]                       # (m, 3, 2)
    x, y = p[..., 0], p[..., 1]
    b = np.roll(y, -1, axis=1) - np.roll(y, -2, axis=1)   # y_j - y_k
    c = np.roll(x, -2, axis=1) - np.roll(x, -1, axis=1)   # x_k - x_j
    area = 0.5 * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
    m = len(triangles)
    B = np.zeros((m, 3, 6))
    B[:, 0, 0::2] = b
    B[:, 1, 1::2] = c
    B[:, 2, 0::2] = c
    B[:, 2, 1::2] = b
    B /= (2.0 * area)[:, None, None]
    return B, area


def _gradients(nodes: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``b``, ``c`` of the module docstring, shape ``(m, 3)``, and twice the signed area."""
    x = nodes[triangles, 0]
    y = nodes[triangles, 1]
    b = y[:, [1, 2, 0]] - y[:, [2, 0, 1]]
    c = x[:, [2, 0, 1]] - x[:, [1, 2, 0]]
    return b, c, b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0]


def element_stiffness(nodes: np.ndarray, triangles: np.ndarray, material: Material) -> np.ndarray:
    """Element stiffness matrices ``t A Bᵀ D B`` (N/m), shape ``(m, 6, 6)``.

    Evaluated in closed form: the 2×2 block of nodes ``p, q`` is ``t/(4A)`` times
    ``[[D11 b_p b_q + D33 c_p c_q, D12 b_p c_q + D33 c_p b_q],
    [D12 c_p b_q + D33 b_p c_q, D22 c_p c_q + D33 b_p b_q]]`` (isotropic ``D``).
    """
    b, c, a2 = _gradients(nodes, triangles)
    D = constitutive_matrix(material)
    s = (material.thickness / (2.0 * np.abs(a2)))[:, None, None]    # t A / (2A)²
    bb = b[:, :, None] * b[:, None, :] * s
    cc = c[:, :, None] * c[:, None, :] * s
    bc = b[:, :, None] * c[:, None, :] * s
    cb = bc.transpose(0, 2, 1)
    Ke = np.empty((len(triangles), 3, 2, 3, 2))
    Ke[:, :, 0, :, 0] = D[0, 0] * bb + D[2, 2] * cc
    Ke[:, :, 0, :, 1] = D[0, 1] * bc + D[2, 2] * cb
    Ke[:, :, 1, :, 0] = D[1, 0] * cb + D[2, 2] * bc
    Ke[:, :, 1, :, 1] = D[1, 1] * cc + D[2, 2] * bb
    return Ke.reshape(-1, 6, 6)


# Local edges (p, q) of a triangle: (0, 1), (1, 2), (2, 0).
_P = np.array([0, 1, 2])
_Q = np.array([1, 2, 0])


def _exclusive_cumsum(a: np.ndarray) -> np.ndarray:
    out = np.zeros(len(a), np.int64)
    np.cumsum(a[:-1], out=out[1:])
    return out


class _Pattern:
    """Symbolic assembly of a 2-DOF-per-node operator on a triangle mesh.

    The node-level sparsity has a diagonal block per node and two blocks per mesh edge
    ``lo < hi``: *upper* ``(lo, hi)`` and *lower* ``(hi, lo)``. Element contributions are
    summed per node and per edge with ``np.bincount`` and scattered straight into the
    data array of the CSR matrix, whose column indices come out sorted. This replaces the
    COO → CSR conversion of the ``36 m`` triplets (a sort) by one sort of the ``3 m``
    edge keys.
    """

    def __init__(self, triangles: np.ndarray, n: int) -> None:
        t = np.asarray(triangles, dtype=np.int64)
        ta, tb = t[:, _P], t[:, _Q]
        self.flip = ta > tb                                   # local edge runs hi -> lo
        lo = np.where(self.flip, tb, ta).ravel()
        hi = np.where(self.flip, ta, tb).ravel()
        key = lo * n + hi
        order = np.argsort(key)
        ks = key[order]
        new = np.empty(len(ks), bool)
        new[:1] = True
        np.not_equal(ks[1:], ks[:-1], out=new[1:])
        self.edge = np.empty(len(ks), np.int64)               # edge id of each local edge
        self.edge[order] = np.cumsum(new) - 1
        first = order[new]
        er, ec = lo[first], hi[first]                          # unique edges, sorted (lo, hi)
        E = len(er)
        self.n, self.n_edges, self.nodes_of = n, E, t.ravel()
        # Block row a lists: lower blocks (a, er) with er < a, the diagonal, then upper
        # blocks (a, ec) with ec > a. The upper edges are sorted by (er, ec) already; a
        # stable sort by ec orders the lower ones by (ec, er).
        n_up = np.bincount(er, minlength=n)
        n_lo = np.bincount(ec, minlength=n)
        r = n_up + n_lo + 1                                    # blocks in block row a
        k_diag = n_lo                                          # positions within the row
        k_up = n_lo[er] + 1 + np.arange(E) - _exclusive_cumsum(n_up)[er]
        lo_order = np.argsort(ec, kind="stable")
        k_lo = np.empty(E, np.int64)
        k_lo[lo_order] = np.arange(E) - _exclusive_cumsum(n_lo)[ec[lo_order]]
        # DOF row 2a holds [uu, uv] of every block of block row a, row 2a+1 [vu, vv].
        base = 4 * _exclusive_cumsum(r)
        nnz = int(4 * r.sum())
        idx = np.int32 if nnz < 2**31 else np.int64
        self.indptr = np.empty(2 * n + 1, idx)
        self.indptr[0:-1:2] = base
        self.indptr[1::2] = base + 2 * r
        self.indptr[-1] = nnz
        self.indices = np.empty(nnz, idx)
        self.slots = []                                        # (uu, vu) positions per kind
        nodes = np.arange(n)
        for k, row, col in ((k_diag, nodes, nodes), (k_up, er, ec), (k_lo, ec, er)):
            p_uu = base[row] + 2 * k
            p_vu = p_uu + 2 * r[row]
            for p in (p_uu, p_vu):
                self.indices[p] = 2 * col
                self.indices[p + 1] = 2 * col + 1
            self.slots.append((p_uu, p_vu))

    def blocks(self, diag: np.ndarray, upper: np.ndarray,
               lower: np.ndarray | None = None) -> sp.csr_matrix:
        """CSR matrix from the local contributions, each of shape ``(4, k)``.

        ``diag[:, 3 e + p]`` is the 2×2 block ``(p, p)`` of element ``e``, row-major
        (``uu, uv, vu, vv``); ``upper[:, 3 e + l]`` the block of local edge ``l`` at
        ``(lo, hi)``, ``lower`` the one at ``(hi, lo)`` (default: the transpose of
        ``upper``, for symmetric element matrices).
        """
        n, E = self.n, self.n_edges
        data = np.empty(len(self.indices))
        (d_uu, d_vu), (u_uu, u_vu), (l_uu, l_vu) = self.slots
        ids = self.nodes_of
        data[d_uu] = np.bincount(ids, diag[0], minlength=n)
        data[d_uu + 1] = np.bincount(ids, diag[1], minlength=n)
        data[d_vu] = np.bincount(ids, diag[2], minlength=n)
        data[d_vu + 1] = np.bincount(ids, diag[3], minlength=n)
        ids = self.edge
        uu, uv, vu, vv = (np.bincount(ids, upper[k], minlength=E) for k in range(4))
        data[u_uu], data[u_uu + 1], data[u_vu], data[u_vu + 1] = uu, uv, vu, vv
        if lower is None:
            data[l_uu], data[l_uu + 1], data[l_vu], data[l_vu + 1] = uu, vu, uv, vv
        else:
            data[l_uu] = np.bincount(ids, lower[0], minlength=E)
            data[l_uu + 1] = np.bincount(ids, lower[1], minlength=E)
            data[l_vu] = np.bincount(ids, lower[2], minlength=E)
            data[l_vu + 1] = np.bincount(ids, lower[3], minlength=E)
        K = sp.csr_matrix((data, self.indices, self.indptr), shape=(2 * n, 2 * n))
        K.has_sorted_indices = True
        return K

    def element_blocks(self, Kb: np.ndarray, symmetric: bool = False) -> sp.csr_matrix:
        """CSR matrix from element 2×2 node blocks ``Kb[e, p, q]`` of shape ``(m, 3, 3, 2, 2)``.

        ``Kb[e, p, q, i, k]`` couples DOF ``i`` of local node ``p`` with DOF ``k`` of local
        node ``q`` (element matrix ``(m, 6, 6)`` reshaped and transposed). ``symmetric``:
        the element matrices are symmetric, so the lower blocks are the upper ones'
        transposes (exactly symmetric result, less work). The sparsity pattern is the
        same for any ``Kb`` (explicit zeros are kept).
        """
        Kb = np.asarray(Kb, float)
        f = self.flip[..., None, None]
        pq, qp = Kb[:, _P, _Q], Kb[:, _Q, _P]
        upper = np.ascontiguousarray(np.where(f, qp, pq).reshape(-1, 4).T)
        lower = None if symmetric else np.ascontiguousarray(np.where(f, pq, qp).reshape(-1, 4).T)
        diag = np.ascontiguousarray(Kb[:, _P, _P].reshape(-1, 4).T)
        return self.blocks(diag, upper, lower)

    @classmethod
    def of_mesh(cls, mesh) -> "_Pattern":
        """The pattern of ``mesh``, computed once and kept in the mesh's cache."""
        pat = mesh._cache.get("cst_pattern")
        if pat is None:
            pat = mesh._cache["cst_pattern"] = cls(mesh.triangles, mesh.n_nodes)
        return pat


def assemble(triangles: np.ndarray, Ke: np.ndarray, n_nodes: int) -> sp.csr_matrix:
    """Assemble element matrices ``(m, 6, 6)`` into a ``(2n, 2n)`` CSR matrix.

    ``Ke`` need not be symmetric. Triangles must have three distinct nodes.
    """
    t = np.asarray(triangles, dtype=np.int64)
    Kb = np.asarray(Ke, float).reshape(len(t), 3, 2, 3, 2).transpose(0, 1, 3, 2, 4)
    return _Pattern(t, n_nodes).element_blocks(Kb)


def stiffness_matrix(mesh, material: Material | None = None) -> sp.csr_matrix:
    """Global stiffness ``K`` (N/m), ``(2n, 2n)`` CSR, DOF order ``[x0, y0, x1, y1, ...]``.

    Parameters
    ----------
    mesh : Mesh
    material : Material, optional
        Defaults to ``mesh.material``.

    Raises
    ------
    StiffnessError
        If no material is known.

    Notes
    -----
    For a connected mesh the null space of ``K`` is exactly the three planar rigid
    modes (tested). The energy of a displacement ``u`` is ``½ uᵀ K u`` (J).

    Examples
    --------
    A unit square of two triangles: ``K`` is symmetric and a rigid translation costs no
    energy.

    >>> from deformclosure import Material, Mesh
    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2], [0, 2, 3]],
    ...                         Material(1e6, 0.3, 1e-3, 0.1))
    >>> K = stiffness_matrix(mesh)
    >>> K.shape, bool(abs(K - K.T).max() == 0)
    ((8, 8), True)
    >>> bool(abs(K @ np.tile([1.0, 0.0], 4)).max() < 1e-9 * abs(K).max())   # N/m · m
    True
    """
    material = material if material is not None else mesh.material
    if material is None:
        raise StiffnessError("no material: give the part's material (youngs_modulus, poisson_ratio, "
                             "thickness, elastic_limit_strain) with the mesh")
    # Closed-form 2×2 blocks (see element_stiffness) straight into the assembly slots,
    # without forming the (m, 6, 6) element matrices. Scaling b and c by sqrt(t/(4A))
    # puts the factor t/(4A) into every product.
    b, c, a2 = _gradients(mesh.nodes, mesh.triangles)
    D = constitutive_matrix(material)
    d11, d12, d22, d33 = D[0, 0], D[0, 1], D[1, 1], D[2, 2]
    w = np.sqrt(material.thickness / (2.0 * np.abs(a2)))[:, None]
    b *= w
    c *= w
    pat = _Pattern.of_mesh(mesh)
    m3 = 3 * mesh.n_triangles
    bq, cq = b[:, _Q], c[:, _Q]
    upper = np.empty((4, m3))
    # uu and vv are symmetric in (p, q); uv and vu swap when the edge runs hi -> lo.
    upper[0] = (d11 * b * bq + d33 * c * cq).ravel()
    upper[3] = (d22 * c * cq + d33 * b * bq).ravel()
    x = (d12 * b * cq + d33 * c * bq).ravel()
    y = (d12 * c * bq + d33 * b * cq).ravel()
    flip = pat.flip.ravel()
    upper[1] = np.where(flip, y, x)
    upper[2] = np.where(flip, x, y)
    bd, cd = b.ravel(), c.ravel()
    diag = np.empty((4, m3))
    diag[0] = d11 * bd * bd + d33 * cd * cd
    diag[1] = (d12 + d33) * bd * cd
    diag[2] = diag[1]
    diag[3] = d22 * cd * cd + d33 * bd * bd
    return pat.blocks(diag, upper)
