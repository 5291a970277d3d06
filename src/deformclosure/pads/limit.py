"""Elastic limit of a pad grasp: strain averaged over the critical distance (SPEC §6).

Along the exact contact path the displacement is linear in the squeeze on every piece,
so is the element strain and its average over each critical-distance disc. The largest
absolute principal value of a tensor is a norm, hence convex along a piece: its maximum
over the elements, ``e(δ)``, is convex on every piece and the first squeeze where it
reaches ``e_L`` is found by bisection inside the first piece that crosses it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..elasticity.critical_distance import averaged_strains
from ..elasticity.strain import principal_strains
from ..errors import GraspError
from .contact import GraspCurve, PadContact

__all__ = ["PadLimit", "pad_elastic_limit", "critical_distance_of", "elastic_limit_strain_of"]


def critical_distance_of(mesh) -> float:
    """The material's critical distance ``ℓ`` (m), default 2 % of the part's diameter."""
    cd = getattr(mesh.material, "critical_distance", None) if mesh.material is not None else None
    return 0.02 * mesh.diameter if cd is None else float(cd)


def elastic_limit_strain_of(mesh) -> float:
    """The material's elastic-limit strain ``e_L``; a pad grasp needs it.

    Raises
    ------
    GraspError
        When the mesh has no material.
    """
    if getattr(mesh, "material", None) is None:
        raise GraspError("material: the mesh has no material; give a part file or a mesh JSON "
                         "with a material")
    return mesh.material.elastic_limit_strain


@dataclass(frozen=True)
class PadLimit:
    """Elastic limit of one grasp axis.

    Attributes
    ----------
    sigma_L : float
        Separation (m) where the averaged strain reaches ``e_L`` (contracting: 0 if it
        never does; otherwise the end of the traced range).
    critical_distance : float
        ``ℓ`` (m).
    critical_element : int
        Element where the averaged strain first reaches ``e_L``.
    e_breakpoints : ndarray
        Averaged strain magnitude (max over elements) at each traced breakpoint.
    element_max_at_limit : float
        Largest *element* (not averaged) strain magnitude at ``σ_L`` (for comparison).
    """

    sigma_L: float
    critical_distance: float
    critical_element: int
    e_breakpoints: np.ndarray
    element_max_at_limit: float


def _magnitudes(T: np.ndarray) -> np.ndarray:
    p = principal_strains(T.reshape(-1, 3)).reshape(*T.shape[:-1], 2)
    return np.abs(p).max(-1)


def pad_elastic_limit(solver: PadContact, curve: GraspCurve, e_L: float,
                      ell: float | None = None, operator=None) -> PadLimit:
    """Separation ``σ_L`` at which the critical-distance strain reaches ``e_L``.

    Parameters
    ----------
    solver : PadContact
    curve : GraspCurve
        Traced far enough (``curve.sigma_end``); if ``e_L`` is not reached on the traced
        range, ``σ_L`` is the end of that range.
    e_L : float
        Elastic-limit strain.
    ell : float, optional
        Critical distance (m); default from the material (2 % of the diameter).
    operator : sparse matrix, optional
        Averaging operator for ``ell``; default the solver's own, built once per mesh and
        ``ell`` (:meth:`PadContact.averaging_operator`).
    """
    mesh = solver.mesh
    ell = critical_distance_of(mesh) if ell is None else ell
    A = solver.averaging_operator(ell) if operator is None else operator
    path = curve.path
    F = np.column_stack([solver.load_vector(curve, l) for l in path.lam])
    E = solver.element_strains(solver.displacement(F))           # (k, m, 3)
    Ebar = averaged_strains(mesh, E, None, operator=A)
    e_bp = _magnitudes(Ebar).max(axis=1)
    above = np.flatnonzero(e_bp >= e_L)
    if len(above) == 0:
        j = len(e_bp) - 1
        elem = int(np.argmax(_magnitudes(Ebar[j])))
        return PadLimit(curve.sigma_end, ell, elem, e_bp, float(_magnitudes(E[j]).max()))
    i0, i1, s = _crossing(Ebar, int(above[0]), e_L)
    delta = (1 - s) * path.delta[i0] + s * path.delta[i1]
    Tbar = (1 - s) * Ebar[i0] + s * Ebar[i1]
    T = (1 - s) * E[i0] + s * E[i1]
    return PadLimit(max(float(curve.sigma_at(delta)), 0.0), ell, int(np.argmax(_magnitudes(Tbar))),
                    e_bp, float(_magnitudes(T).max()))


def _crossing(Ebar: np.ndarray, j: int, e_L: float) -> tuple[int, int, float]:
    """Where the averaged strain magnitude first reaches ``e_L``, breakpoint ``j`` being the
    first at or above it: the piece ``(i0, i1)`` and the fraction ``s`` along it."""
    if j == 0:
        return 0, 0, 0.0
    i0, i1 = j - 1, j
    s_lo, s_hi = 0.0, 1.0
    for _ in range(60):   # convex in s on the piece, below e_L at 0, above at 1
        s = 0.5 * (s_lo + s_hi)
        if _magnitudes((1 - s) * Ebar[i0] + s * Ebar[i1]).max() >= e_L:
            s_hi = s
        else:
            s_lo = s
    return i0, i1, s_hi
