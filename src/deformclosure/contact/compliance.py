"""The boundary compliance of a free part in the gauge of SPEC §6/§7 — one home for every
contact model (pads on an axis, fingers around a placement).

A free part's stiffness ``K`` is singular (the three planar rigid modes). A contact model
fixes the rigid motion by a *gauge*: three linear functionals ``G u = 0`` of the
displacement. SPEC §6 names them exactly:

* the area-weighted mean displacement, ``(1/A) ∫ u dA`` — exact for linear triangles as
  ``Σ_i w_i u_i / A`` with the lumped nodal areas ``w_i`` (a third of each adjacent
  triangle: P1 integration is exact);
* the area-weighted mean of the infinitesimal rotation field
  ``ω = ½(∂u_y/∂x − ∂u_x/∂y)``, constant on each triangle, so
  ``(1/A) Σ_e A_e ω_e`` is exact (built from the element gradients).

A uniform strain field has ``ω ≡ 0``, so it has no rotation in this gauge whatever the
mesh; a least-squares rotation fit with lumped nodal areas (``Σ w_i (p_i − c) × u_i = 0``)
does not have that property and puts a spurious moment on a grasp axis.

The energy of a load ``f`` on the part so constrained is ``½ fᵀ Y f`` with the gauged
compliance ``Y = Pᵀ Z P``: ``Z`` is the compliance with three DOFs pinned (one
factorisation of ``K``, :class:`~deformclosure.elasticity.condense.CondensedCompliance`),
``P = I − Gᵀ H Rᵀ`` with ``H = (Rᵀ Gᵀ)⁻¹`` moves the load's resultant onto the gauge's
reaction (``R``: rigid modes about the area centroid ``c``; ``G R = I`` up to rounding),
and ``Pᵀ = I − R Hᵀ G`` removes the rigid part so that ``G u = 0``. Only boundary DOFs
are loaded by contacts, so ``Y`` is needed on the boundary only: it follows from the
boundary block of ``Z`` and three extra solves.

The two uses, the same functionals:

* :meth:`BoundaryCompliance.axis_gauge` (SPEC §6): at a grasp axis the part's mean
  rotation and mean cross-axis displacement are those of the axis. The mean *axial*
  displacement is constrained too, which is harmless: the contact problem carries the
  part's float along the axis as its own unknown.
* :meth:`BoundaryCompliance.placement_gauge` (SPEC §7): the placement ``g = (x, y, φ)``
  of a part among fixed fingers *is* its mean displacement and mean rotation about ``c``;
  the deformation has none.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..elasticity.condense import CondensedCompliance
from ..elasticity.critical_distance import averaging_operator
from ..elasticity.solve import rigid_modes
from ..elasticity.stiffness import stiffness_matrix
from ..elasticity.strain import element_strain_columns
from ..limits import blas_threads

__all__ = ["BoundaryCompliance", "gauge_functionals", "nodal_areas", "mean_rotation_row"]


def nodal_areas(mesh) -> np.ndarray:
    """Lumped nodal areas (m²): one third of each adjacent triangle's area, shape (n,).

    ``Σ_i w_i f_i`` is the exact integral of a piecewise-linear ``f``.
    """
    w = np.zeros(mesh.n_nodes)
    np.add.at(w, mesh.triangles.ravel(), np.repeat(mesh.areas / 3.0, 3))
    return w


def mean_rotation_row(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The row ``r`` (1/m), shape ``(2n,)``, with ``r·u`` the area-weighted mean of the
    infinitesimal rotation ``ω = ½(∂u_y/∂x − ∂u_x/∂y)`` of the P1 field ``u``
    (DOFs ``[x0, y0, x1, y1, …]``).

    On a triangle with vertices ``a, b, c`` the gradient of the hat function of ``a`` is
    ``(y_b − y_c, x_c − x_b) / (2 A_e)``, so ``A_e ω_e = ¼ Σ_a ((y_b − y_c) u_ya
    − (x_c − x_b) u_xa)`` — the element area cancels.

    Examples
    --------
    A rigid rotation by ``θ`` has mean rotation ``θ``:

    >>> nodes = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]])
    >>> r = mean_rotation_row(nodes, np.array([[0, 1, 2]]))
    >>> u = 1e-3 * np.c_[-nodes[:, 1], nodes[:, 0]].ravel()
    >>> float(np.round(r @ u, 12))
    0.001
    """
    nodes = np.asarray(nodes, float)
    tri = np.asarray(triangles)
    p = nodes[tri]                                        # (m, 3, 2)
    pb, pc = np.roll(p, -1, axis=1), np.roll(p, -2, axis=1)
    b = pb[..., 1] - pc[..., 1]                           # 2 A_e ∂N_a/∂x
    c = pc[..., 0] - pb[..., 0]                           # 2 A_e ∂N_a/∂y
    d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum()
    r = np.zeros(2 * len(nodes))
    np.add.at(r, 2 * tri + 1, 0.25 * b)
    np.add.at(r, 2 * tri, -0.25 * c)
    return r / area


def gauge_functionals(mesh) -> np.ndarray:
    """The gauge ``G`` of SPEC §6/§7, shape ``(3, 2n)``: rows the mean x and y
    displacement (dimensionless weights ``w_i / A``) and the mean rotation (1/m).

    Examples
    --------
    ``G R = I`` for the rigid modes ``R`` about the area centroid:

    >>> from deformclosure import Material, Mesh
    >>> from deformclosure.elasticity.solve import rigid_modes
    >>> mesh = Mesh.from_arrays([[0, 0], [3, 0], [3, 1], [0, 2]], [[0, 1, 2], [0, 2, 3]],
    ...                         Material(1e6, 0.3, 1.0, 0.1))
    >>> G = gauge_functionals(mesh)
    >>> w = nodal_areas(mesh); c = (w[:, None] * mesh.nodes).sum(0) / w.sum()
    >>> bool(np.allclose(G @ rigid_modes(mesh.nodes - c), np.eye(3)))
    True
    """
    w = nodal_areas(mesh)
    G = np.zeros((3, 2 * mesh.n_nodes))
    G[0, 0::2] = w / w.sum()
    G[1, 1::2] = w / w.sum()
    G[2] = mean_rotation_row(mesh.nodes, mesh.triangles)
    return G


class BoundaryCompliance:
    """One factorisation of a part's stiffness; its boundary compliance in the gauge of
    SPEC §6/§7, displacements, strains and critical-distance averages.

    Build it with :meth:`axis_gauge` (pads on a grasp axis) or :meth:`placement_gauge`
    (a part placed among fixed fingers); both fix the same functionals (module
    docstring).

    Parameters
    ----------
    mesh : Mesh
    K : sparse matrix, optional
        Stiffness (N/m); default the mesh's CST stiffness.

    Attributes
    ----------
    boundary : ndarray of int, shape (q,)
        The perimeter nodes onto which the compliance is condensed.
    centroid : ndarray, shape (2,)
        Area centroid (m), the reference point of rotations.
    Y : ndarray, shape (2q, 2q)
        Gauged compliance (m/N) of the boundary DOFs ``[x, y]`` in ``boundary`` order.
    G : ndarray, shape (3, 2n)
        The gauge functionals (:func:`gauge_functionals`).
    """

    def __init__(self, mesh, K: sp.spmatrix | None = None) -> None:
        self.mesh = mesh
        K = stiffness_matrix(mesh) if K is None else K
        nodes = mesh.nodes
        self.boundary = mesh.perimeter_nodes
        self.cc = CondensedCompliance(K, nodes, mesh.triangles, self.boundary)
        w = nodal_areas(mesh)
        self.centroid = (w[:, None] * nodes).sum(0) / w.sum()
        R = rigid_modes(nodes - self.centroid)
        G = gauge_functionals(mesh)
        with blas_threads():      # dense steps of a few thousand rows (limits.BLAS_THREADS)
            H = np.linalg.inv(R.T @ G.T)              # = I up to rounding (G R = I)
            ZG = self.cc.solve(G.T)
            bd = np.column_stack([2 * self.boundary, 2 * self.boundary + 1]).ravel()
            A = R[bd] @ H.T
            # Y_bb = [(I − R Hᵀ G) Z (I − Gᵀ H Rᵀ)]_bb = Z_bb − T − Tᵀ + A (G Z Gᵀ) Aᵀ
            T = ZG[bd] @ A.T
            Y = self.cc.C - T - T.T + A @ (G @ ZG) @ A.T
        self.Y = 0.5 * (Y + Y.T)
        self.G = G
        self._R, self._H = R, H
        self.diameter = mesh.diameter
        self._averaging: dict[float, sp.csr_matrix] = {}

    @classmethod
    def axis_gauge(cls, mesh, K: sp.spmatrix | None = None) -> "BoundaryCompliance":
        """The SPEC §6 gauge of a grasp axis: mean rotation ω and mean cross-axis
        displacement zero (the mean axial displacement too; the part's float along the
        axis is an unknown of the contact problem)."""
        return cls(mesh, K)

    @classmethod
    def placement_gauge(cls, mesh, K: sp.spmatrix | None = None) -> "BoundaryCompliance":
        """The SPEC §7 gauge of a placement ``g = (x, y, φ)``: the deformation has zero
        mean displacement and zero mean rotation about :attr:`centroid` — the placement
        carries the rigid motion."""
        return cls(mesh, K)

    # ---------------------------------------------------------------- loads and fields
    def position(self, node_ids: np.ndarray) -> np.ndarray:
        """Row index (node position in :attr:`boundary`) of node ids; -1 if not there."""
        return self.cc.position(node_ids)

    def load_vector(self, nodes: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """Global load vector (N), shape (2n,), of ``forces (k, 2)`` (N) at ``nodes``."""
        f = np.zeros(2 * self.mesh.n_nodes)
        forces = np.asarray(forces, float).reshape(-1, 2)
        np.add.at(f, 2 * np.asarray(nodes), forces[:, 0])
        np.add.at(f, 2 * np.asarray(nodes) + 1, forces[:, 1])
        return f

    def displacement(self, f: np.ndarray) -> np.ndarray:
        """Displacement ``Pᵀ Z P f`` (m) of the gauged part under loads ``f`` (N),
        shape ``(2n,)`` or ``(2n, r)``; ``G u = 0``."""
        R, G, H = self._R, self.G, self._H
        with blas_threads():
            fp = f - G.T @ (H @ (R.T @ f))
            v = self.cc.solve(fp)
            return v - R @ (H.T @ (G @ v))

    def delassus(self, nodes: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """Contact compliance ``W = N Y Nᵀ`` (m/N), shape (k, k), of unit normals
        ``normals (k, 2)`` at boundary ``nodes (k,)``."""
        pos = self.cc.position(nodes)
        dx, dy = 2 * pos, 2 * pos + 1
        Y = self.Y
        gx, gy = normals[:, 0], normals[:, 1]
        W = (np.outer(gx, gx) * Y[np.ix_(dx, dx)] + np.outer(gx, gy) * Y[np.ix_(dx, dy)]
             + np.outer(gy, gx) * Y[np.ix_(dy, dx)] + np.outer(gy, gy) * Y[np.ix_(dy, dy)])
        return 0.5 * (W + W.T)

    def element_strains(self, U: np.ndarray) -> np.ndarray:
        """Engineering element strains ``[exx, eyy, gamma_xy]`` of the displacement
        columns ``U`` (m), shape ``(2n, k)``, as an array ``(k, m, 3)``.

        The same numbers as :func:`deformclosure.elasticity.strain.element_strains` on each
        column (:func:`~deformclosure.elasticity.strain.element_strain_columns`: one sparse
        product with the mesh's strain operator, built once per mesh).
        """
        return element_strain_columns(self.mesh, U)

    def averaging_operator(self, ell: float) -> sp.csr_matrix:
        """The critical-distance averaging operator of this mesh for ``ell`` (m)
        (:func:`deformclosure.elasticity.critical_distance.averaging_operator`), built
        once per ``ell``. It holds ``m`` times the elements per disc; the elastic limits
        use :func:`~deformclosure.elasticity.critical_distance.disc_average` instead."""
        W = self._averaging.get(ell)
        if W is None:
            W = self._averaging[ell] = averaging_operator(self.mesh, ell)
        return W
