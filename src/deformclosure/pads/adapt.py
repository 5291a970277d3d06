"""Where the next mesh of a pad grasp is finer (SPEC §6 "Accuracy by default").

* **First level** — cheap but not blind: the part's own ``max_area`` everywhere, and
  ``h ≤ ℓ/2`` (ℓ the critical distance) where the answer is decided before anything is
  solved: around the pads' rest contacts (out to the pads' half span plus ℓ) and within ℓ
  of every re-entrant corner of the part (notch roots, the inside corner of an L), where
  the limiting strain sits.
* **Next levels** — driven by the solution: the recovered-strain indicator
  (:func:`deformclosure.elasticity.error.recovered_strain_indicator`) of the start axis
  and of the escape path's saddle axis at σ* (each relative to its own energy, since the
  barrier is their difference), Dörfler-marked (:func:`~deformclosure.elasticity.error.
  bulk_marking`); marked elements have ``h`` halved, and so has the critical-distance
  disc of the limiting strain (σ_L, hence U_L, is read there).
"""

from __future__ import annotations

import numpy as np

from ..elasticity.critical_distance import critical_distance_of
from ..elasticity.error import bulk_marking, recovered_strain_indicator
from ..mesh.sizing import Sizing, area_of_size
from .geometry import GraspAxis, Pad, first_touch

__all__ = ["first_sizing", "next_sizing", "MARKED_FRACTION"]

#: Dörfler's θ: the share of the estimated error whose elements are refined per level.
MARKED_FRACTION = 0.5


def _reentrant_corners(ring: np.ndarray, hole: bool) -> np.ndarray:
    """Vertices (m) of ``ring`` where the material's interior angle exceeds π."""
    P = np.asarray(ring, float)
    a, b = np.roll(P, 1, axis=0) - P, np.roll(P, -1, axis=0) - P
    u, w = P - np.roll(P, 1, axis=0), np.roll(P, -1, axis=0) - P
    turn = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
    area2 = float(np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1]))
    ccw = area2 > 0
    # A convex turn of the ring (left on a CCW ring) has the material inside the angle;
    # a right turn is re-entrant. A hole's ring bounds material on its outside.
    reentrant = (turn < 0) if ccw else (turn > 0)
    if hole:
        reentrant = ~reentrant
    reentrant &= np.linalg.norm(a, axis=1) > 0
    reentrant &= np.linalg.norm(b, axis=1) > 0
    # ignore turns of a polygonised arc (less than 10°), they are no corner
    ang = np.abs(np.arctan2(turn, np.einsum("ij,ij->i", u, w)))
    return P[reentrant & (ang > np.radians(10.0))]


def first_sizing(part, axis: GraspAxis, pad: Pad, max_area: float,
                 hole_ring: np.ndarray | None = None) -> Sizing:
    """The first level's sizing (module docstring): ``max_area`` (m²) and ``h ≤ ℓ/2`` at
    the rest contacts of ``axis`` and at re-entrant corners. ``hole_ring`` (m): the hole
    an expanding grasp opens in."""
    ell = critical_distance_of(part)
    fine = area_of_size(0.5 * ell)
    discs = []
    if fine < max_area:
        # an expanding grasp's contacts are found on the mesh; the indicator refines them
        touch = None if hole_ring is not None else first_touch(part.outer, axis, pad)
        if touch is not None:
            r = pad.half_span + ell
            discs += [(*touch.contact_a, r, fine), (*touch.contact_b, r, fine)]
        for k, ring in enumerate([part.outer, *part.holes]):
            for x, y in _reentrant_corners(ring, hole=k > 0):
                discs.append((x, y, ell, fine))
    return Sizing(max_area, tuple((float(x), float(y), float(r), float(a))
                                  for x, y, r, a in discs))


def next_sizing(result, sizing: Sizing, theta: float = MARKED_FRACTION) -> Sizing:
    """The sizing of the level after ``result`` (a
    :class:`~deformclosure.pads.optimize.PadGraspResult` on the mesh made with
    ``sizing``): marked elements and the limiting strain's disc with ``h`` halved."""
    solver = result.solver
    mesh = solver.mesh
    sigma = (result.sigma_star if result.sigma_star is not None
             else 0.5 * (result.sigma0 + result.sigma_L))
    eta2 = _relative_indicator(mesh, result.state_at(sigma, "start").displacement)
    if result.saddle is not None:
        curve = solver.curve(result.saddle, result.pad, result.sigma_L)
        if curve.path is not None:
            lam = curve.path.multipliers(curve.delta(sigma))
            u = solver.displacement(solver.load_vector(curve, lam))
            eta2 = eta2 + _relative_indicator(mesh, u)
    marked = bulk_marking(eta2, theta)
    ell = result.limit.critical_distance
    crit = mesh.nodes[mesh.triangles[result.limit.critical_element]].mean(axis=0)
    near = np.hypot(*(mesh.nodes[mesh.triangles].mean(axis=1) - crit).T) <= ell
    a_crit = 0.25 * float(mesh.areas[near].max()) if near.any() else sizing.default
    return Sizing.refining(mesh, marked, sizing.default,
                           discs=sizing.discs + ((crit[0], crit[1], ell, a_crit),))


def _relative_indicator(mesh, u: np.ndarray) -> np.ndarray:
    """Recovered-strain indicators of ``u`` relative to its energy (dimensionless)."""
    from ..elasticity.strain import element_strains
    from ..elasticity.stiffness import constitutive_matrix

    eta2 = recovered_strain_indicator(mesh, u)
    eps = element_strains(mesh, u)
    C = constitutive_matrix(mesh.material)
    energy = 0.5 * mesh.material.thickness * float(
        np.sum(mesh.areas * np.einsum("mi,ij,mj->m", eps, C, eps)))
    return eta2 / energy if energy > 0 else np.zeros_like(eta2)
