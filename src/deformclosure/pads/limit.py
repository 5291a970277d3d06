"""Elastic limit of a pad grasp: strain averaged over the critical distance (SPEC §6).

Along the exact contact path the displacement is linear in the squeeze on every piece,
so is the element strain and its average over each critical-distance disc; the first
squeeze where the strain measure reaches ``e_L`` is the one elastic-limit rule of
:mod:`deformclosure.landscape.limit`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..elasticity.critical_distance import (averaged_strain_maximum, averaged_strains,
                                            critical_distance_of, disc_average)
from ..errors import GraspError
from ..limits import PADS_LIMIT_CHUNK_BYTES
from ..landscape.limit import first_limit_crossing, path_elastic_limit, strain_measure
from .contact import GraspCurve, PadContact

__all__ = ["PadLimit", "pad_elastic_limit", "pad_strain_at", "critical_distance_of",
           "elastic_limit_strain_of", "LINEAR_STRAIN_RANGE"]

#: Strain up to which small-strain linear elasticity is trusted (SPEC §8): a linear run
#: whose strain at σ* exceeds it warns.
LINEAR_STRAIN_RANGE = 0.05


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
        Averaging operator for ``ell`` (:func:`~deformclosure.elasticity.averaging_operator`),
        applied to every element; by default only the discs that can hold the limit are
        averaged (:func:`~deformclosure.landscape.limit.path_elastic_limit`, the same
        numbers without the operator's ``m`` × disc-size memory).
    """
    mesh = solver.mesh
    ell = critical_distance_of(mesh) if ell is None else ell
    path = curve.path
    k = len(path.lam)
    # loads, displacements and strains of a breakpoint: (2n + 2n + 3m) doubles and the
    # solve's and the strains' temporaries, about twice that
    per = max(2, int(BREAKPOINT_CHUNK_BYTES // (16.0 * (4 * mesh.n_nodes + 3 * mesh.n_triangles))))
    if operator is None and k > per:
        return _limit_in_chunks(solver, curve, e_L, ell, per)
    E = _breakpoint_strains(solver, curve, range(k))             # (k, m, 3)
    if operator is None:            # the one rule (landscape.limit), on the discs it needs
        lim = path_elastic_limit(disc_average(mesh, ell), E, e_L)
        hit, e_bp, elem, e_max = lim.crossing, lim.e_breakpoints, lim.critical_element, \
            lim.element_max
    else:                           # a given operator: the rule on every averaged element
        Ebar = averaged_strains(mesh, E, None, operator=operator)
        e_bp = strain_measure(Ebar).max(axis=1)
        hit = first_limit_crossing(Ebar, e_L)
        at = hit.interpolate(Ebar) if hit.reached else Ebar[-1]
        elem = int(np.argmax(strain_measure(at)))
        e_max = float(strain_measure(hit.interpolate(E) if hit.reached else E[-1]).max())
    if not hit.reached:
        return PadLimit(curve.sigma_end, ell, elem, e_bp, e_max)
    delta = float(hit.interpolate(path.delta))
    return PadLimit(max(float(curve.sigma_at(delta)), 0.0), ell, elem, e_bp, e_max)


#: Largest memory (bytes) of the breakpoints' loads, displacements and strains that
#: :func:`pad_elastic_limit` holds at once: a longer path is taken in groups of
#: breakpoints (the maxima of each), then the crossing piece alone (issue 25: a path of
#: hundreds of breakpoints on a 50 000-node mesh held gigabytes).
BREAKPOINT_CHUNK_BYTES = PADS_LIMIT_CHUNK_BYTES


def _breakpoint_strains(solver: PadContact, curve: GraspCurve, idx) -> np.ndarray:
    """Element strains ``(len(idx), m, 3)`` at the path's breakpoints ``idx``."""
    F = np.column_stack([solver.load_vector(curve, curve.path.lam[i]) for i in idx])
    return solver.element_strains(solver.displacement(F))


def _limit_in_chunks(solver: PadContact, curve: GraspCurve, e_L: float, ell: float,
                     per: int) -> PadLimit:
    """:func:`pad_elastic_limit` by the one rule with bounded memory, the same numbers:
    the breakpoints' maxima in groups of ``per`` (each field's maximum is its own), then
    the rule on the crossing piece alone — the first piece whose end reaches ``e_L`` (the
    measure is convex along a piece), or the last breakpoint."""
    path, k = curve.path, len(curve.path.lam)
    disc = disc_average(solver.mesh, ell)
    parts = [disc.maxima(_breakpoint_strains(solver, curve, range(a, min(a + per, k))))
             for a in range(0, k, per)]
    e_bp = np.concatenate([v for v, _ in parts])
    above = np.flatnonzero(e_bp >= e_L)
    j = int(above[0]) if len(above) else k - 1
    lo = max(j - 1, 0) if len(above) else max(k - 2, 0)
    lim = path_elastic_limit(disc, _breakpoint_strains(solver, curve, range(lo, j + 1)), e_L)
    i0, i1 = lim.crossing.piece
    hit = replace(lim.crossing, piece=(i0 + lo, i1 + lo))
    if not hit.reached:
        return PadLimit(curve.sigma_end, ell, lim.critical_element, e_bp, lim.element_max)
    delta = float(hit.interpolate(path.delta))
    return PadLimit(max(float(curve.sigma_at(delta)), 0.0), ell, lim.critical_element, e_bp,
                    lim.element_max)


def pad_strain_at(solver: PadContact, curve: GraspCurve, sigma: float,
                  ell: float | None = None) -> float:
    """The strain measure of SPEC §6 (critical-distance average, largest absolute
    principal value, maximised over the elements) at separation ``sigma`` (m)."""
    if curve.path is None:
        return 0.0
    mesh = solver.mesh
    ell = critical_distance_of(mesh) if ell is None else ell
    lam = curve.path.multipliers(curve.delta(sigma))
    u = solver.displacement(solver.load_vector(curve, lam))
    E = solver.element_strains(u[:, None])[0]
    return float(averaged_strain_maximum(mesh, E, ell))

