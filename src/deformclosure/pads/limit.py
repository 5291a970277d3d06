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
from ..limits import PADS_LIMIT_CHUNK_BYTES, PADS_LIMIT_GROUP
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
        Averaged strain magnitude (max over elements) at the traced breakpoints from first
        touch up to the end of the piece where it reaches ``e_L`` (every breakpoint when
        it never does): those past the crossing are not solved.
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
    if operator is None:            # the one rule (landscape.limit), on the discs it needs
        # a group's strain stack (24 bytes per triangle and breakpoint) kept below the
        # allocator's 32 MB ceiling, so it reuses the heap instead of mapping fresh pages
        fits = max(2, int(SCAN_GROUP_BYTES // (24.0 * mesh.n_triangles)))
        return _limit_in_order(solver, curve, e_L, ell, min(per, SCAN_GROUP, fits))
    E = _breakpoint_strains(solver, curve, range(k))             # (k, m, 3)
    # a given operator: the rule on every averaged element of every breakpoint
    Ebar = averaged_strains(mesh, E, None, operator=operator)
    e_bp = strain_measure(Ebar).max(axis=1)
    hit = first_limit_crossing(Ebar, e_L)
    at = hit.interpolate(Ebar) if hit.reached else Ebar[-1]
    elem = int(np.argmax(strain_measure(at)))
    e_max = float(strain_measure(hit.interpolate(E) if hit.reached else E[-1]).max())
    if not hit.reached:
        return PadLimit(curve.sigma_end, ell, elem, e_bp, e_max)
    delta = float(hit.interpolate(path.delta))
    return PadLimit(max(float(curve.sigma_at(delta)), 0.0), ell, elem, e_bp[:hit.piece[1] + 1],
                    e_max)


#: Largest memory (bytes) of the breakpoints' loads, displacements and strains that
#: :func:`pad_elastic_limit` holds at once (issue 25: a path of hundreds of breakpoints on
#: a 50 000-node mesh held gigabytes).
BREAKPOINT_CHUNK_BYTES = PADS_LIMIT_CHUNK_BYTES
#: Breakpoints solved together as the path is scanned from first touch for the crossing:
#: the breakpoints past the crossing are never solved (issue 25: "only the breakpoints the
#: σ_L search needs"; the crossing lies at ½–⅔ of a path traced to σ = 0 on the notched
#: bar), and a group's fields stay small. Measured on the notched bar at 20 000 nodes,
#: three axes of 72–75 breakpoints, one BLAS thread (min of 3): all at once 6.5 s, groups
#: of 4 / 8 / 16 / 32 3.5 / 2.9 / 2.5 / 3.3 s — faster even where every breakpoint is
#: needed (the (k, m, 3) stacks of all at once thrash the caches).
SCAN_GROUP = PADS_LIMIT_GROUP
#: Largest strain stack (bytes) of one group: glibc maps every block above 32 MB afresh
#: and a fresh page costs a fault on first touch — at 80 000 nodes a group of 16 (61 MB)
#: spent 1.0 s of the scan's 7.5 s in its strain products, a group of 8 (31 MB) 0.27 s.
SCAN_GROUP_BYTES = 30e6


def _breakpoint_strains(solver: PadContact, curve: GraspCurve, idx) -> np.ndarray:
    """Element strains ``(len(idx), m, 3)`` at the path's breakpoints ``idx``."""
    F = np.column_stack([solver.load_vector(curve, curve.path.lam[i]) for i in idx])
    return solver.element_strains(solver.displacement(F))


def _limit_in_order(solver: PadContact, curve: GraspCurve, e_L: float, ell: float,
                    group: int) -> PadLimit:
    """:func:`pad_elastic_limit` by the one rule, the breakpoints solved in order in groups
    of ``group`` until the first whose measure reaches ``e_L`` — the measure is convex
    along a piece, so the crossing is on the piece ending there (or on the last piece) —
    then the rule on that piece alone. Memory: one group's fields."""
    path, k = curve.path, len(curve.path.lam)
    disc = disc_average(solver.mesh, ell)
    e_parts: list[np.ndarray] = []
    last = None                       # strains of the previous group's last breakpoint
    with disc.reusing_rows():         # the groups average the same hot discs
        for a in range(0, k, group):
            b = min(a + group, k)
            E = _breakpoint_strains(solver, curve, range(a, b))
            e, _ = disc.maxima(E)
            above = np.flatnonzero(e >= e_L)
            if not len(above) and b < k:
                e_parts.append(e)
                last = E[-1]
                continue
            j = a + int(above[0]) if len(above) else k - 1
            e_parts.append(e[:j - a + 1])
            lo = max(j - 1, 0)
            piece = E[lo - a:j - a + 1] if lo >= a else np.concatenate([last[None], E[:j - a + 1]])
            lim = path_elastic_limit(disc, piece, e_L)
            break
    e_bp = np.concatenate(e_parts)
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

