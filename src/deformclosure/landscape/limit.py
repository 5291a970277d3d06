"""The one elastic-limit rule of every model (SPEC §4, §6, §7).

The strain measure is the largest absolute in-plane principal value of the strain tensor
averaged over the critical-distance disc of each element (SPEC §6; ``ℓ = 0``: the element
strains themselves, the paper's §4), maximised over the elements. A grasp loads the part
along a path on which the displacement — and so every element strain and its average — is
*piecewise linear* in the squeeze: the exact contact path of the pads, one linear piece
from zero for the paper's jaws (strain ``e_max · δ``) and for a placement of fixed
fingers scaled from rest (``check``). The elastic limit is where the measure first
reaches ``e_L`` along that path, and ``U_L`` the energy still to be stored until then.

The largest absolute principal value is a norm of the tensor, so the measure is convex
along each piece: the first crossing is found by bisection inside the first piece whose
end reaches ``e_L`` — and in closed form on a piece that starts from zero strain, where
the measure is homogeneous (``e(sδ) = s e(δ)``), which is the paper's
``σ_L = σ0 − e_L / e_max`` (:func:`deformclosure.grasp.elastic_limit.elastic_limit_separation`,
kept as the vectorised form of this closed form for all jaw pairs at once).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..elasticity.strain import principal_strains

__all__ = ["LimitCrossing", "PathLimit", "strain_measure", "first_limit_crossing",
           "limit_crossing", "path_elastic_limit", "energy_to_limit_from_rest"]


@dataclass(frozen=True)
class LimitCrossing:
    """Where a piecewise-linear loading path first reaches the elastic limit.

    Attributes
    ----------
    piece : tuple of int
        Breakpoints ``(i0, i1)`` of the piece holding the crossing (``(0, 0)``: the path
        starts at or above the limit).
    fraction : float
        Position ``s`` in ``[0, 1]`` along the piece (the crossing is
        ``(1 − s) · x[i0] + s · x[i1]`` for any quantity ``x`` linear on the piece).
    reached : bool
        ``False`` when the limit is not reached on the path (then ``piece`` is the last
        breakpoint twice and ``fraction`` 0).
    """

    piece: tuple[int, int]
    fraction: float
    reached: bool

    def interpolate(self, values: np.ndarray) -> np.ndarray:
        """A quantity linear on each piece (breakpoint values along axis 0) at the
        crossing."""
        i0, i1 = self.piece
        s = self.fraction
        return (1 - s) * np.asarray(values)[i0] + s * np.asarray(values)[i1]


def strain_measure(T: np.ndarray) -> np.ndarray:
    """Largest absolute in-plane principal strain of engineering strain tensors
    ``T (..., 3)`` = ``[exx, eyy, gamma_xy]``; shape ``T.shape[:-1]`` (dimensionless).

    Examples
    --------
    >>> float(strain_measure(np.array([0.01, -0.03, 0.0])))
    0.03
    """
    T = np.asarray(T, float)
    p = principal_strains(T.reshape(-1, 3)).reshape(*T.shape[:-1], 2)
    return np.abs(p).max(-1)


def first_limit_crossing(strains: np.ndarray, e_L: float) -> LimitCrossing:
    """The first point of a piecewise-linear loading path where the strain measure of
    the (averaged) element strains reaches ``e_L``.

    Parameters
    ----------
    strains : ndarray, shape (k, m, 3)
        Averaged element strain tensors at the ``k`` breakpoints of the path (linear in
        between).
    e_L : float
        Elastic-limit strain (> 0).

    Returns
    -------
    LimitCrossing

    Examples
    --------
    One piece from rest to twice the limit (a uniaxial strain 0 → 0.2, e_L = 0.1): the
    crossing is halfway, exactly.

    >>> T = np.array([[[0.0, 0.0, 0.0]], [[0.2, 0.0, 0.0]]])
    >>> c = first_limit_crossing(T, 0.1)
    >>> c.piece, c.fraction, c.reached
    ((0, 1), 0.5, True)
    """
    T = np.asarray(strains, float)
    return limit_crossing(strain_measure(T).max(axis=1), e_L, lambda i0, i1: (T[i0], T[i1]),
                          lambda i0: not np.any(T[i0]))


def limit_crossing(e_bp: np.ndarray, e_L: float,
                   piece: Callable[[int, int], tuple[np.ndarray, np.ndarray]],
                   at_rest: Callable[[int], bool]) -> LimitCrossing:
    """The rule of :func:`first_limit_crossing` from the breakpoints' maxima.

    Parameters
    ----------
    e_bp : ndarray, shape (k,)
        Strain measure maximised over the elements at each breakpoint.
    e_L : float
        Elastic-limit strain (> 0).
    piece : callable
        ``piece(i0, i1) -> (T0, T1)``: the averaged strain tensors ``(r, 3)`` at both ends
        of the piece of every element that can reach ``e_L`` on it (all elements, or those
        a bound cannot exclude: the crossing is the same).
    at_rest : callable
        ``at_rest(i0)``: whether the strain at breakpoint ``i0`` is zero (the measure is
        then homogeneous on the piece, and the crossing has a closed form).

    Returns
    -------
    LimitCrossing
    """
    above = np.flatnonzero(np.asarray(e_bp) >= e_L)
    if len(above) == 0:
        j = len(e_bp) - 1
        return LimitCrossing((j, j), 0.0, False)
    j = int(above[0])
    if j == 0:
        return LimitCrossing((0, 0), 0.0, True)
    i0, i1 = j - 1, j
    if at_rest(i0):
        # from zero strain the measure is homogeneous along the piece: closed form
        return LimitCrossing((i0, i1), float(e_L / e_bp[i1]), True)
    T0, T1 = piece(i0, i1)
    s_lo, s_hi = 0.0, 1.0
    for _ in range(60):   # convex in s on the piece, below e_L at 0, at or above at 1
        s = 0.5 * (s_lo + s_hi)
        if strain_measure((1 - s) * T0 + s * T1).max() >= e_L:
            s_hi = s
        else:
            s_lo = s
    return LimitCrossing((i0, i1), s_hi, True)


@dataclass(frozen=True)
class PathLimit:
    """The elastic limit of a piecewise-linear loading path, with the strain measure over
    the critical distance (:func:`path_elastic_limit`).

    Attributes
    ----------
    crossing : LimitCrossing
        Where the measure first reaches ``e_L``.
    e_breakpoints : ndarray, shape (k,)
        The measure (maximised over the elements) at each breakpoint (dimensionless).
    critical_element : int
        Element of the largest averaged strain at the crossing (at the last breakpoint when
        the limit is not reached).
    element_max : float
        Largest *element* (not averaged) strain magnitude there (dimensionless).
    """

    crossing: LimitCrossing
    e_breakpoints: np.ndarray
    critical_element: int
    element_max: float


def path_elastic_limit(disc, strains: np.ndarray, e_L: float) -> PathLimit:
    """The one elastic-limit rule on a path given by its *element* strains.

    The same crossing as :func:`first_limit_crossing` of the averaged strains
    ``W @ strains`` (SPEC §6), from the few discs that can reach the limit: the maxima at
    the breakpoints by :meth:`~deformclosure.elasticity.critical_distance.DiscAverage.maxima`,
    and the bisection on the crossing piece over the elements whose bound reaches ``e_L``
    at one of its ends (the measure is convex along the piece, so an average below ``e_L``
    at both ends stays below it).

    Parameters
    ----------
    disc : DiscAverage
        The mesh's averages for its critical distance
        (:func:`~deformclosure.elasticity.critical_distance.disc_average`).
    strains : ndarray, shape (k, m, 3)
        Element strain tensors ``[exx, eyy, gamma_xy]`` at the ``k`` breakpoints (linear in
        between).
    e_L : float
        Elastic-limit strain (> 0).

    Returns
    -------
    PathLimit
    """
    E = np.asarray(strains, float)
    e_bp, elements = disc.maxima(E)
    held: dict[str, np.ndarray] = {}

    def piece(i0: int, i1: int) -> tuple[np.ndarray, np.ndarray]:
        reach = np.maximum(strain_measure(E[i0]), strain_measure(E[i1]))
        held["rows"] = rows = disc.candidates(reach, e_L)
        held["T"] = T = disc.averaged(E[[i0, i1]], rows)
        return T[0], T[1]

    hit = limit_crossing(e_bp, e_L, piece, lambda i0: not np.any(E[i0]))
    if not hit.reached:
        j = len(e_bp) - 1
        return PathLimit(hit, e_bp, int(elements[j]), float(strain_measure(E[j]).max()))
    i0, i1 = hit.piece
    if "rows" in held:                    # bisected: the largest average at the crossing
        Tbar = (1 - hit.fraction) * held["T"][0] + hit.fraction * held["T"][1]
        critical = int(held["rows"][np.argmax(strain_measure(Tbar))])
    else:                                 # at a breakpoint, or a multiple of one from rest
        critical = int(elements[i1])
    return PathLimit(hit, e_bp, critical, float(strain_measure(hit.interpolate(E)).max()))


def energy_to_limit_from_rest(energy: float, strain: float, e_L: float) -> float:
    """``U_L`` (J) of a contact state loaded proportionally from rest: the energy still to
    be stored until the strain measure reaches ``e_L``.

    On a path ``s · (state)`` from rest (one linear piece from zero, the rule above) the
    strain is ``s · strain`` and the energy ``s² · energy``, so the limit is at
    ``s_L = e_L / strain`` and ``U_L = energy · (s_L² − 1)`` (0 past the limit; infinite
    for an unstrained state).

    Examples
    --------
    >>> energy_to_limit_from_rest(1e-3, 0.05, 0.1)       # J: four times the energy, minus it
    0.003
    """
    if strain <= 0.0 or energy <= 0.0:
        return float("inf")
    return max(energy * ((e_L / strain) ** 2 - 1.0), 0.0)
