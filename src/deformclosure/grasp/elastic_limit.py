"""Elastic limit of a jaw pair: ``e_max``, ``σ_L`` and ``U_L`` (SPEC §4, paper §4.1).

``e_max`` is the largest element strain magnitude (largest absolute in-plane principal
strain) produced by a unit change of the jaw distance at ``(n0, n1)`` (1/m; linear, so
strains scale with the distance change). The part reaches its elastic-limit strain
``e_L`` when the distance has changed by ``e_L / e_max``:

- contracting: ``σ_L = max(0, σ0 − e_L/e_max)``;
- expanding:   ``σ_L = σ0 + e_L/e_max``.

``U_L(σ) = U(n0, n1, σ_L) − U(n0, n1, σ)``, the energy still to be stored before the
elastic limit. (The paper prints ``½ k01 (σ_L² − σ²)``, equal to this only if σ measures
the compression; we use the energy difference.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..choices import MODES, choose
from ..elasticity.condense import CondensedCompliance
from ..elasticity.strain import strain_magnitude
from ..errors import GraspError
from .pair_stiffness import jaw_pair_forces

__all__ = ["ElasticLimit", "elastic_limit", "elastic_limit_separation"]


def elastic_limit_separation(sigma0: float | np.ndarray, e_max: float | np.ndarray,
                             elastic_limit_strain: float, mode: str = "contracting"
                             ) -> float | np.ndarray:
    """``σ_L`` (m): the jaw separation at which the largest strain reaches ``e_L`` (SPEC §4).

    The closed form of the one elastic-limit rule (:mod:`deformclosure.landscape.limit`)
    on the paper's loading path — one linear piece from rest, element strains (ℓ = 0) —
    for one jaw pair (floats) or many (arrays):
    the distance changes by ``e_L / e_max`` before the elastic limit, so
    ``σ_L = max(0, σ0 − e_L/e_max)`` (contracting) or ``σ0 + e_L/e_max`` (expanding).

    Parameters
    ----------
    sigma0 : float or ndarray
        Rest distance of the jaw nodes (m).
    e_max : float or ndarray
        Largest strain magnitude per metre of jaw-distance change (1/m).
    elastic_limit_strain : float
        ``e_L`` (dimensionless).
    mode : {"contracting", "expanding"}

    Returns
    -------
    float or ndarray
        Like ``sigma0``.

    Examples
    --------
    >>> elastic_limit_separation(0.012, 100.0, 0.8)
    0.004
    >>> elastic_limit_separation(np.array([0.012, 0.006]), np.array([100.0, 100.0]), 0.8)
    array([0.004, 0.   ])
    >>> elastic_limit_separation(0.012, 100.0, 0.8, "expanding")
    0.02
    """
    choose(mode, MODES, "mode", GraspError)
    travel = elastic_limit_strain / e_max
    if mode == "contracting":
        sigma_L = np.maximum(0.0, sigma0 - travel)
    else:
        sigma_L = sigma0 + travel
    return float(sigma_L) if np.ndim(sigma_L) == 0 else sigma_L


@dataclass(frozen=True)
class ElasticLimit:
    """Elastic limit of a jaw pair.

    Attributes
    ----------
    k01 : float
        Pair stiffness at the jaws (N/m).
    sigma0 : float
        Rest distance of the jaw nodes (m).
    e_max : float
        Largest element strain magnitude per metre of jaw-distance change (1/m).
    sigma_L : float
        Jaw separation (m) at which the elastic limit is reached.
    critical_element : int
        Element where ``e_max`` occurs.
    strain_per_length : ndarray, shape (m,)
        Strain magnitude of every element per metre of distance change (1/m).
    displacement_per_length : ndarray, shape (2n,)
        Displacement field per metre of approach (dimensionless, m/m), rigid part removed.
    """

    k01: float
    sigma0: float
    e_max: float
    sigma_L: float
    critical_element: int
    strain_per_length: np.ndarray
    displacement_per_length: np.ndarray


def elastic_limit(mesh, condensed: CondensedCompliance, n0: int, n1: int, *,
                  mode: str = "contracting", jaw_width: float = 0.0,
                  elastic_limit_strain: float | None = None) -> ElasticLimit:
    """``e_max`` and ``σ_L`` of the jaw pair ``(n0, n1)``.

    Parameters
    ----------
    mesh : Mesh
    condensed : CondensedCompliance
        Factorisation of the part's stiffness including both jaw nodes.
    n0, n1 : int
        Jaw nodes.
    mode : {"contracting", "expanding"}
    jaw_width : float
        Jaw contact width (m).
    elastic_limit_strain : float, optional
        ``e_L``; defaults to the mesh material's.

    Returns
    -------
    ElasticLimit

    Raises
    ------
    GraspError
    """
    choose(mode, MODES, "mode", GraspError)
    eL = elastic_limit_strain
    if eL is None:
        if mesh.material is None:
            raise GraspError("no material: the elastic-limit strain e_L is unknown")
        eL = mesh.material.elastic_limit_strain
    a, b = (n0, n1) if n0 < n1 else (n1, n0)
    k, f = jaw_pair_forces(mesh, condensed, a, b, jaw_width)
    u = condensed.project_out_rigid(condensed.solve(f))
    strain = strain_magnitude(mesh, u)
    i = int(np.argmax(strain))
    e_max = float(strain[i])
    sigma0 = float(np.linalg.norm(mesh.nodes[b] - mesh.nodes[a]))
    if not e_max > 0:
        raise GraspError("the jaw pair produces no strain; check the mesh and stiffness")
    sigma_L = elastic_limit_separation(sigma0, e_max, eL, mode)
    return ElasticLimit(k, sigma0, e_max, sigma_L, i, strain, u)
