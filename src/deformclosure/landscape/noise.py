"""The one noise-floor rule of every release landscape (SPEC §6 "Noise floor", §7).

On an unstructured mesh a vertex energy (a grasp axis, a placement) carries an error that
changes from vertex to vertex: it depends on where the nodes happen to sit under the
contacts. Energy differences below that discretisation noise are not resolved, so they are
ties — and a tie is not a hold. Each model *measures* the noise in its own coordinates (a
second mesh realisation, the twin, compared on the same vertices; the jitter of the energy
under sub-cell moves of a vertex); this module turns the measurements into one relative
floor ``τ`` and makes the two decisions that use it:

* :func:`twin_floor` — ``τ`` from two realisations: :data:`TWIN_FACTOR` × the
  :data:`TWIN_QUANTILE` quantile of ``|U₁ − U₂| / max(U₁, U₂)``;
* :func:`jitter_floor` — ``τ`` from the jitter: :data:`JITTER_FACTOR` × the largest residual
  of quadratic fits (:func:`quadratic_residual`) over the vertex' own energy;
* :func:`combined_floor` — several measurements: the largest counts;
* :func:`higher` — an energy exceeds another beyond the floor (the strict-minimum and
  equilibrium tests of the landscapes);
* :func:`resolved` — a barrier beyond the floor of its height (a barrier within it is
  none: ``U_A = 0``).

Every function takes and returns *relative* floors (dimensionless); energies are in J.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["TWIN_FACTOR", "TWIN_QUANTILE", "JITTER_FACTOR", "ROUND_OFF", "twin_floor",
           "jitter_floor", "combined_floor", "quadratic_residual", "higher", "resolved"]

#: The twin floor is this many times the quantile below (a coarser twin already errs on
#: the large side; the factor covers the vertices not compared).
TWIN_FACTOR = 2.0

#: Quantile of the relative twin differences taken as the noise.
TWIN_QUANTILE = 0.9

#: The jitter floor is this many times the largest quadratic-fit residual.
JITTER_FACTOR = 4.0

#: Relative energy differences below this are round-off, whatever the floor (a relative
#: threshold on energies computed by an iterative contact solver; not the SPEC §3 touching
#: tolerance of lengths).
ROUND_OFF = 1e-9


def twin_floor(U1, U2, factor: float = TWIN_FACTOR, quantile: float = TWIN_QUANTILE) -> float:
    """Relative noise floor from the energies of the same vertices on two realisations.

    Parameters
    ----------
    U1, U2 : array_like (n,)
        Energies (J) of ``n`` vertices on the mesh and on its twin.
    factor, quantile : float
        The floor is ``factor`` × the ``quantile`` of ``|U₁ − U₂| / max(U₁, U₂)`` over the
        vertices where ``max(U₁, U₂)`` is finite and positive.

    Returns
    -------
    float
        ``τ`` (relative); 0 when no vertex is comparable.

    Examples
    --------
    >>> twin_floor([1.0, 2.0, 0.0], [1.01, 2.0, 0.0])   # 2 × the 90th percentile of (1 %, 0)
    0.0178...
    """
    U1 = np.asarray(U1, float)
    U2 = np.asarray(U2, float)
    top = np.maximum(U1, U2)
    ok = (top > 0) & np.isfinite(top)
    if not ok.any():
        return 0.0
    return factor * float(np.quantile(np.abs(U1[ok] - U2[ok]) / top[ok], quantile))


def quadratic_residual(ts) -> np.ndarray:
    """The projector ``I − V V⁺`` onto the residual of the least-squares quadratic through
    samples at the abscissae ``ts`` (``V`` their Vandermonde matrix of degree 2)."""
    V = np.vander(np.asarray(ts, float), 3)
    return np.eye(V.shape[0]) - V @ np.linalg.pinv(V)


def jitter_floor(residual: float, U0: float, factor: float = JITTER_FACTOR) -> float:
    """Relative noise floor from the jitter of a vertex energy under sub-cell moves.

    A continuum energy is smooth on the scale of one grid cell, so the residual of a
    quadratic fit to it there is discretisation noise.

    Parameters
    ----------
    residual : float
        Largest absolute residual (J) of the quadratic fits (:func:`quadratic_residual`).
    U0 : float
        The vertex' own energy (J).
    factor : float

    Returns
    -------
    float
        ``factor × residual / U0``; 0 when ``U0`` is not positive (nothing to compare with).

    Examples
    --------
    >>> jitter_floor(1e-6, 1e-3)
    0.004
    """
    return factor * residual / U0 if U0 > 0 else 0.0


def combined_floor(*floors: float) -> float:
    """One floor from several measurements of it: the largest counts (0 for none)."""
    return max(floors, default=0.0)


def higher(e: float, e0: float, tau: float) -> bool:
    """Whether energy ``e`` exceeds ``e0`` beyond the relative floor ``tau``:
    ``e − e0 > tau · e``. An inadmissible vertex (``e`` not finite) always does.

    A model whose energies come from an iterative solver passes ``max(tau, ROUND_OFF)``.

    Examples
    --------
    >>> higher(1.02, 1.0, 0.01), higher(1.005, 1.0, 0.01), higher(math.inf, 1.0, 0.5)
    (True, False, True)
    """
    return (not math.isfinite(e)) or e - e0 > tau * e


def resolved(barrier: float, height: float, tau: float) -> bool:
    """Whether a barrier ``barrier`` (J, above its start) rising to the energy ``height``
    (J) is beyond the relative floor ``tau``: ``barrier > tau · height``. A barrier within
    the floor is none (``U_A = 0``): the mesh cannot tell it from a tie.

    Examples
    --------
    >>> resolved(0.02, 1.0, 0.01), resolved(0.01, 1.0, 0.01)
    (True, False)
    """
    return barrier > tau * height
