"""Solving ``K u = f`` for a free (unsupported) part: rigid modes removed once.

``K`` of a free part is singular with the three planar rigid modes as null space. For a
self-equilibrated load ``f`` (orthogonal to the rigid modes: zero net force and moment)
the solution is unique up to a rigid motion, and ``fᵀu`` and the strains do not depend
on that motion. We pin three DOFs — both DOFs of node ``i0`` and, of a far node ``i1``,
the DOF across the line ``i0 → i1`` — which removes exactly the rigid modes, and factorise
the remaining SPD matrix once with a sparse LU.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import StiffnessError
from ..limits import blas_threads

__all__ = ["rigid_modes", "pinned_dofs", "PinnedFactorisation", "FreeBodySolver"]


def rigid_modes(nodes: np.ndarray) -> np.ndarray:
    """The three planar rigid modes as columns, shape ``(2n, 3)``: x, y translation and
    the infinitesimal rotation about the origin (``[-y, x]`` per node, m/rad).

    Examples
    --------
    >>> rigid_modes(np.array([[0.0, 0.0], [2.0, 1.0]]))
    array([[ 1.,  0., -0.],
           [ 0.,  1.,  0.],
           [ 1.,  0., -1.],
           [ 0.,  1.,  2.]])
    """
    n = len(nodes)
    R = np.zeros((2 * n, 3))
    R[0::2, 0] = 1.0
    R[1::2, 1] = 1.0
    R[0::2, 2] = -nodes[:, 1]
    R[1::2, 2] = nodes[:, 0]
    return R


def pinned_dofs(nodes: np.ndarray) -> np.ndarray:
    """Three DOFs whose fixing removes the rigid modes (see module docstring)."""
    i0 = int(np.argmin(nodes[:, 0] + nodes[:, 1]))
    d = np.linalg.norm(nodes - nodes[i0], axis=1)
    i1 = int(np.argmax(d))
    dx, dy = np.abs(nodes[i1] - nodes[i0])
    # Rotation about i0 moves i1 across the line i0→i1; pin the DOF it moves most.
    dof1 = 2 * i1 + 1 if dx >= dy else 2 * i1
    return np.array([2 * i0, 2 * i0 + 1, dof1])


class PinnedFactorisation:
    """A sparse LU of ``K`` on the DOFs left free by three pins: the rigid modes removed.

    The one home of what every factorisation of a free part's stiffness shares — the
    pinned solve and the removal of the rigid part of a displacement. Subclasses
    (:class:`FreeBodySolver`, :class:`~deformclosure.elasticity.condense.CondensedCompliance`)
    choose the pins and the order of the free DOFs and set :attr:`nodes`,
    :attr:`free_dofs` and the factor ``_lu``.

    Attributes
    ----------
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).
    free_dofs : ndarray of int, shape (2n - 3,)
        The unpinned DOFs, in the order of the factorisation.
    """

    nodes: np.ndarray
    free_dofs: np.ndarray

    @staticmethod
    def _factorise(Kf: sp.spmatrix, **options) -> spla.SuperLU:
        """``splu(Kf, **options)``; a singular ``Kf`` is a mesh with more than the three
        rigid zero-energy modes."""
        try:
            with blas_threads():      # SuperLU's supernode BLAS (limits.BLAS_THREADS)
                return spla.splu(sp.csc_matrix(Kf), **options)
        except RuntimeError as err:
            raise StiffnessError(f"stiffness is singular beyond the 3 rigid modes ({err}); "
                                 "the mesh is disconnected or a mechanism") from None

    def solve(self, f: np.ndarray) -> np.ndarray:
        """Displacements (m) for loads ``f`` (N), shape ``(2n,)`` or ``(2n, r)``.

        The pinned DOFs are zero; valid for self-equilibrated ``f`` (others get a
        reaction at the pins).
        """
        f = np.asarray(f, float)
        u = np.zeros(f.shape)
        with blas_threads():
            u[self.free_dofs] = self._lu.solve(np.ascontiguousarray(f[self.free_dofs]))
        return u

    def project_out_rigid(self, u: np.ndarray) -> np.ndarray:
        """``u`` minus its least-squares rigid part (columns of a 2-D ``u`` separately)."""
        R = rigid_modes(self.nodes)
        coef, *_ = np.linalg.lstsq(R, u, rcond=None)
        return u - R @ coef


class FreeBodySolver(PinnedFactorisation):
    """One factorisation of ``K`` with rigid modes removed; solves for self-equilibrated loads.

    Parameters
    ----------
    K : sparse matrix, shape (2n, 2n)
        Stiffness (N/m) of a free part whose null space is the rigid modes.
    nodes : ndarray, shape (n, 2)
        Node coordinates (m).

    Raises
    ------
    StiffnessError
        If ``K`` is singular after pinning (more than three zero-energy modes: the mesh
        is a mechanism or disconnected).

    Examples
    --------
    A unit square of two triangles pulled apart at opposite corners:

    >>> from deformclosure import Material, Mesh, stiffness_matrix
    >>> mesh = Mesh.from_arrays([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2], [0, 2, 3]],
    ...                         Material(1e6, 0.3, 1.0, 0.1))
    >>> solver = FreeBodySolver(stiffness_matrix(mesh), mesh.nodes)
    >>> f = np.array([-1.0, -1.0, 0, 0, 1.0, 1.0, 0, 0])     # N, self-equilibrated
    >>> u = solver.project_out_rigid(solver.solve(f))
    >>> bool(f @ u > 0), np.allclose(u[4:6], -u[0:2])
    (True, True)
    """

    def __init__(self, K: sp.spmatrix, nodes: np.ndarray) -> None:
        n2 = K.shape[0]
        self.n_dofs = n2
        self.nodes = np.asarray(nodes, float)
        self.pinned = pinned_dofs(self.nodes)
        free = np.ones(n2, bool)
        free[self.pinned] = False
        self.free = self.free_dofs = np.flatnonzero(free)
        Kf = sp.csc_matrix(K)[self.free][:, self.free]
        # K is symmetric positive definite once pinned: pivot on the diagonal
        # (threshold 0). SuperLU's default partial pivoting swaps rows, which makes
        # U's diagonal negative for valid meshes and breaks the definiteness test.
        self._lu = self._factorise(Kf, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                   options={"SymmetricMode": True})
        diag = self._lu.U.diagonal()
        if np.any(diag <= 0) or np.min(np.abs(diag)) < 1e-13 * np.max(np.abs(diag)):
            raise StiffnessError("stiffness is singular or indefinite beyond the 3 rigid modes; "
                                 "check the mesh and material")
