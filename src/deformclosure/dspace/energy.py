"""Elastic energy of configurations of a meshed part (paper §3.1, SPEC §2).

A *configuration* ``q`` gives every node's position: ``(n, 2)`` or flat ``(2n,)`` with
DOF order ``[x0, y0, x1, y1, ...]`` (metres); a *batch* of configurations is
``(b, n, 2)`` or ``(b, 2n)``. ``X = q - q0`` is the nodal displacement from the rest
configuration ``q0 = mesh.nodes``.

Two energies are provided, both in joules and both vectorised over elements and over
configurations:

* **linear** -- ``U(q) = 1/2 X^T K X`` (paper §3.1). Per element this is
  ``1/2 t A eps^T D eps`` with the small (engineering) strain
  ``eps = [F_xx - 1, F_yy - 1, F_xy + F_yx]`` of the element's deformation gradient
  ``F``. It is invariant to *infinitesimal* rigid motions only: a finite rotation by
  ``phi`` of a stress-free part costs ``O((1 - cos phi)^2)`` and is not zero.
* **corotational** -- per element, the polar decomposition ``F = R S`` removes the
  element's rotation and the strain ``eps = [S_xx - 1, S_yy - 1, 2 S_xy]`` (Biot strain)
  enters the same quadratic form. It equals the linear energy to second order in the
  displacement (the difference is ``O(|X|^3)``) and is exactly invariant to finite
  rigid motions of the whole part (any rotation angle, any translation).

For a CST element the 2x2 polar decomposition is closed form: the rotation angle is
``atan2(F_yx - F_xy, F_xx + F_yy)``.

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.1 (energy ``U = 1/2 X^T K X``).
C. A. Felippa and B. Haugen, "A unified formulation of small-strain corotational finite
elements", CMAME 194, 2005 (element-independent corotational energy).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from ..errors import DeformClosureError

__all__ = [
    "EnergyKind",
    "as_configurations",
    "deformation_gradients",
    "polar_rotation",
    "configuration_strains",
    "element_energies",
    "linear_energy",
    "corotational_energy",
    "strain_energy",
]

EnergyKind = Literal["linear", "corotational"]
_KINDS = ("linear", "corotational")


def as_configurations(q: Any, n_nodes: int) -> tuple[np.ndarray, bool]:
    """Normalise one or many configurations to a ``(b, n, 2)`` array.

    Parameters
    ----------
    q : array_like
        ``(n, 2)``, ``(2n,)``, ``(b, n, 2)`` or ``(b, 2n)`` node positions (m).
    n_nodes : int
        Number of mesh nodes ``n``.

    Returns
    -------
    qb : ndarray, shape (b, n, 2)
    batched : bool
        Whether ``q`` was a batch (results are then returned per configuration).
    """
    try:
        a = np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise DeformClosureError(f"configuration: not an array of numbers ({type(q).__name__}); give "
                                 f"node positions in m, shape ({n_nodes}, 2) or ({2 * n_nodes},)") from None
    n = n_nodes
    if a.shape == (n, 2):
        return a[None], False
    if a.shape == (2 * n,):
        return a.reshape(1, n, 2), False
    if a.ndim == 3 and a.shape[1:] == (n, 2):
        return a, True
    if a.ndim == 2 and a.shape[1] == 2 * n:
        return a.reshape(len(a), n, 2), True
    raise DeformClosureError(
        f"configuration has shape {a.shape}; expected ({n}, 2), ({2 * n},), (b, {n}, 2) or (b, {2 * n})"
    )


def _material(mesh: Any, material: Any = None) -> Any:
    mat = material if material is not None else getattr(mesh, "material", None)
    if mat is None:
        raise DeformClosureError("the mesh has no material; pass material=... or read a mesh/part that has one")
    return mat


def _rest_edges_inverse(nodes0: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``Dm^-1`` (m, 2, 2) and rest areas (m,) for the edge matrices ``[X1-X0, X2-X0]``."""
    p = nodes0[triangles]
    dm = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]], axis=-1)  # columns are edges
    det = dm[:, 0, 0] * dm[:, 1, 1] - dm[:, 0, 1] * dm[:, 1, 0]
    inv = np.empty_like(dm)
    inv[:, 0, 0] = dm[:, 1, 1]
    inv[:, 1, 1] = dm[:, 0, 0]
    inv[:, 0, 1] = -dm[:, 0, 1]
    inv[:, 1, 0] = -dm[:, 1, 0]
    return inv / det[:, None, None], 0.5 * det


def deformation_gradients(nodes0: np.ndarray, triangles: np.ndarray, q: Any) -> np.ndarray:
    """Deformation gradient ``F = dx/dX`` of every CST element.

    Parameters
    ----------
    nodes0 : ndarray, shape (n, 2)
        Rest positions (m).
    triangles : ndarray, shape (m, 3)
        Counter-clockwise triangles.
    q : array_like
        Configuration(s), see :func:`as_configurations`.

    Returns
    -------
    F : ndarray, shape (m, 2, 2) or (b, m, 2, 2)
        Dimensionless.
    """
    qb, batched = as_configurations(q, len(nodes0))
    inv, _ = _rest_edges_inverse(np.asarray(nodes0, float), np.asarray(triangles))
    F = _gradients(qb, np.asarray(triangles), inv)
    return F if batched else F[0]


def _gradients(qb: np.ndarray, triangles: np.ndarray, dm_inv: np.ndarray) -> np.ndarray:
    p = qb[:, triangles]  # (b, m, 3, 2)
    ds = np.stack([p[..., 1, :] - p[..., 0, :], p[..., 2, :] - p[..., 0, :]], axis=-1)
    return ds @ dm_inv


def polar_rotation(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form 2x2 polar decomposition ``F = R S`` with ``R`` a proper rotation.

    Parameters
    ----------
    F : ndarray, shape (..., 2, 2)

    Returns
    -------
    angle : ndarray, shape (...)
        Rotation angle of ``R`` (rad), ``atan2(F_yx - F_xy, F_xx + F_yy)``.
    S : ndarray, shape (..., 2, 2)
        The symmetric stretch ``R^T F`` (positive definite when ``det F > 0``).
    """
    angle = np.arctan2(F[..., 1, 0] - F[..., 0, 1], F[..., 0, 0] + F[..., 1, 1])
    c, s = np.cos(angle), np.sin(angle)
    S = np.empty_like(F)
    S[..., 0, 0] = c * F[..., 0, 0] + s * F[..., 1, 0]
    S[..., 0, 1] = c * F[..., 0, 1] + s * F[..., 1, 1]
    S[..., 1, 0] = -s * F[..., 0, 0] + c * F[..., 1, 0]
    S[..., 1, 1] = -s * F[..., 0, 1] + c * F[..., 1, 1]
    return angle, S


def _strains_from_F(F: np.ndarray, kind: str) -> np.ndarray:
    if kind == "linear":
        return np.stack([F[..., 0, 0] - 1.0, F[..., 1, 1] - 1.0, F[..., 0, 1] + F[..., 1, 0]], axis=-1)
    if kind == "corotational":
        _, S = polar_rotation(F)
        # S is symmetric up to rounding; average the off-diagonal terms
        return np.stack([S[..., 0, 0] - 1.0, S[..., 1, 1] - 1.0, S[..., 0, 1] + S[..., 1, 0]], axis=-1)
    raise DeformClosureError(f"energy kind {kind!r} is not valid; use one of {', '.join(_KINDS)}")


def configuration_strains(mesh: Any, q: Any, kind: EnergyKind = "linear") -> np.ndarray:
    """Engineering strain ``[e_xx, e_yy, gamma_xy]`` of every element in configuration ``q``.

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        Configuration(s) (m).
    kind : {"linear", "corotational"}
        Small strain of ``F`` or Biot strain of the stretch ``S`` (rotation removed).

    Returns
    -------
    ndarray, shape (m, 3) or (b, m, 3)
        Dimensionless.
    """
    F = deformation_gradients(mesh.nodes, mesh.triangles, q)
    return _strains_from_F(F, kind)


class _ElementModel:
    """Per-element data for fast repeated energy evaluation (rest edges, ``t A D``)."""

    def __init__(self, mesh: Any, material: Any = None):
        from ..elasticity.stiffness import constitutive_matrix

        mat = _material(mesh, material)
        self.nodes0 = np.asarray(mesh.nodes, dtype=float)
        self.triangles = np.asarray(mesh.triangles, dtype=np.int64)
        self.dm_inv, self.areas = _rest_edges_inverse(self.nodes0, self.triangles)
        self.D = np.asarray(constitutive_matrix(mat), dtype=float)
        self.t = float(mat.thickness)

    def energies(self, qb: np.ndarray, kind: str, elements: np.ndarray | None = None) -> np.ndarray:
        """Element energies (J), ``(b, m)`` or ``(b, len(elements))``."""
        tri = self.triangles if elements is None else self.triangles[elements]
        inv = self.dm_inv if elements is None else self.dm_inv[elements]
        area = self.areas if elements is None else self.areas[elements]
        eps = _strains_from_F(_gradients(qb, tri, inv), kind)
        return 0.5 * self.t * area * np.einsum("...i,ij,...j->...", eps, self.D, eps)


def element_energies(mesh: Any, q: Any, kind: EnergyKind = "linear", material: Any = None) -> np.ndarray:
    """Strain energy of every element (J).

    Parameters
    ----------
    mesh : Mesh
        With a material (or pass ``material``).
    q : array_like
        Configuration(s) (m), see :func:`as_configurations`.
    kind : {"linear", "corotational"}
        Which energy, see the module docstring.
    material : Material, optional
        Overrides ``mesh.material``.

    Returns
    -------
    ndarray, shape (m,) or (b, m)
    """
    if kind not in _KINDS:
        raise DeformClosureError(f"energy kind {kind!r} is not valid; use one of {', '.join(_KINDS)}")
    qb, batched = as_configurations(q, len(mesh.nodes))
    e = _ElementModel(mesh, material).energies(qb, kind)
    return e if batched else e[0]


def linear_energy(mesh: Any, q: Any, stiffness: Any = None, material: Any = None) -> float | np.ndarray:
    """Linear elastic energy ``U = 1/2 X^T K X`` (J) of configuration(s) ``q`` (paper §3.1).

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        Configuration(s) (m).
    stiffness : sparse matrix (2n, 2n), optional
        Use this ``K`` (N/m), e.g. one read from a FEM code; otherwise the energy is
        summed element by element from the mesh's material (identical to the assembled
        ``K``).
    material : Material, optional
        Overrides ``mesh.material``.

    Returns
    -------
    float or ndarray, shape (b,)

    Notes
    -----
    Not invariant to finite rotations; see :func:`corotational_energy`.
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    if stiffness is not None:
        X = (qb - np.asarray(mesh.nodes)[None]).reshape(len(qb), -1)
        U = 0.5 * np.einsum("bi,ib->b", X, stiffness @ X.T)
    else:
        U = _ElementModel(mesh, material).energies(qb, "linear").sum(axis=-1)
    return U if batched else float(U[0])


def corotational_energy(mesh: Any, q: Any, material: Any = None) -> float | np.ndarray:
    """Corotational elastic energy (J): per element ``1/2 t A eps^T D eps`` with the Biot
    strain of the polar stretch, exactly invariant to finite rigid motions.

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        Configuration(s) (m).
    material : Material, optional
        Overrides ``mesh.material``.

    Returns
    -------
    float or ndarray, shape (b,)
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    U = _ElementModel(mesh, material).energies(qb, "corotational").sum(axis=-1)
    return U if batched else float(U[0])


def strain_energy(
    mesh: Any, q: Any, kind: EnergyKind = "linear", stiffness: Any = None, material: Any = None
) -> float | np.ndarray:
    """Energy of configuration(s) ``q`` (J) of the given ``kind`` ("linear" or "corotational")."""
    if kind == "linear":
        return linear_energy(mesh, q, stiffness=stiffness, material=material)
    if kind == "corotational":
        return corotational_energy(mesh, q, material=material)
    raise DeformClosureError(f"energy kind {kind!r} is not valid; use one of {', '.join(_KINDS)}")
