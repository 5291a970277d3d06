"""The finite-strain measure compared with ``e_L`` (SPEC §8).

The right Cauchy–Green tensor ``C = FᵀF`` of each element, averaged (area-weighted) over
the critical-distance disc of SPEC §6 like the small strain, has principal stretches
``λᵢ = sqrt(eig C̄)``; the strain magnitude is ``max |λᵢ − 1|``. As ``C = I + 2ε + O(∇u²)``
it equals §6's largest absolute principal strain in the small-strain limit.

The maximum over the elements uses the bound of
:class:`~deformclosure.elasticity.critical_distance.DiscAverage`: the eigenvalues of a
convex combination of symmetric matrices lie between the extreme eigenvalues of the terms,
so a disc's averaged stretch magnitude cannot exceed the largest element magnitude in it.
"""

from __future__ import annotations

import numpy as np

from .critical_distance import disc_average

__all__ = ["stretch_magnitudes", "averaged_stretch_magnitudes", "averaged_stretch_maximum",
           "law_strain_maximum"]

#: Rows averaged first (those of the largest element magnitudes) before pruning by the bound.
SEED_ROWS = 16


def stretch_magnitudes(C: np.ndarray) -> np.ndarray:
    """``max |λᵢ − 1|`` of in-plane tensors ``C = [C11, C22, C12]`` (shape (..., 3))."""
    C = np.asarray(C, float)
    mean = 0.5 * (C[..., 0] + C[..., 1])
    rad = np.hypot(0.5 * (C[..., 0] - C[..., 1]), C[..., 2])
    lo = np.sqrt(np.clip(mean - rad, 0.0, None))
    hi = np.sqrt(np.clip(mean + rad, 0.0, None))
    return np.maximum(np.abs(hi - 1.0), np.abs(lo - 1.0))


def averaged_stretch_magnitudes(mesh, C: np.ndarray, ell: float) -> np.ndarray:
    """Per element, the stretch magnitude ``max |λᵢ − 1|`` (dimensionless, m/m) of the
    right Cauchy–Green tensor averaged over its critical-distance disc: the field whose
    maximum :func:`averaged_stretch_maximum` finds (by bounds, without averaging every
    element), for pictures. Parameters as :func:`averaged_stretch_maximum`; returns an
    array of shape ``(m,)``."""
    C = np.asarray(C, float)
    disc = disc_average(mesh, ell)
    return stretch_magnitudes(C if disc.ell == 0.0 else disc.averaged(C))


def averaged_stretch_maximum(mesh, C: np.ndarray, ell: float) -> tuple[float, int]:
    """Largest disc-averaged stretch magnitude over the elements, and where.

    Parameters
    ----------
    mesh : Mesh
    C : ndarray, shape (m, 3)
        Element right Cauchy–Green tensors ``[C11, C22, C12]`` (dimensionless).
    ell : float
        Critical distance (m), >= 0.

    Returns
    -------
    value : float
        ``max_i stretch_magnitudes((W @ C)[i])`` (dimensionless).
    element : int
        The element ``i`` where it is reached.
    """
    disc = disc_average(mesh, ell)
    C = np.asarray(C, float)
    mags = stretch_magnitudes(C)
    if disc.ell == 0.0:
        i = int(np.argmax(mags))
        return float(mags[i]), i
    seed = np.argsort(mags)[::-1][:SEED_ROWS]
    avg = stretch_magnitudes(disc.averaged(C, seed))
    best_k = int(np.argmax(avg))
    best, where = float(avg[best_k]), int(seed[best_k])
    rows = disc.candidates(mags, best)
    rows = rows[~np.isin(rows, seed)]
    if len(rows):
        avg = stretch_magnitudes(disc.averaged(C, rows))
        k = int(np.argmax(avg))
        if avg[k] > best:
            best, where = float(avg[k]), int(rows[k])
    return best, where


def law_strain_maximum(mesh, law, u: np.ndarray, ell: float) -> float:
    """The strain compared with ``e_L`` of displacement ``u`` (m) under the material law
    ``law`` of the finite-strain solver: SPEC §8's averaged stretch magnitude
    (:func:`averaged_stretch_maximum`), or SPEC §6's averaged strain magnitude for the
    small-strain law (:class:`~deformclosure.elasticity.linear_energy.LinearEnergy`).
    ``ell``: the critical distance (m)."""
    from .critical_distance import averaged_strain_maximum
    from .linear_energy import LinearEnergy

    if isinstance(law, LinearEnergy):
        return float(averaged_strain_maximum(mesh, law.small_strains(u), ell))
    return float(averaged_stretch_maximum(mesh, law.right_cauchy_green(u), ell)[0])
