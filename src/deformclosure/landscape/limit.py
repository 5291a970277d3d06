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

import numpy as np

from ..elasticity.strain import principal_strains

__all__ = ["LimitCrossing", "strain_measure", "first_limit_crossing",
           "energy_to_limit_from_rest"]


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
    e_bp = strain_measure(T).max(axis=1)
    above = np.flatnonzero(e_bp >= e_L)
    if len(above) == 0:
        j = len(e_bp) - 1
        return LimitCrossing((j, j), 0.0, False)
    j = int(above[0])
    if j == 0:
        return LimitCrossing((0, 0), 0.0, True)
    i0, i1 = j - 1, j
    if not np.any(T[i0]):
        # from zero strain the measure is homogeneous along the piece: closed form
        return LimitCrossing((i0, i1), float(e_L / e_bp[i1]), True)
    s_lo, s_hi = 0.0, 1.0
    for _ in range(60):   # convex in s on the piece, below e_L at 0, at or above at 1
        s = 0.5 * (s_lo + s_hi)
        if strain_measure((1 - s) * T[i0] + s * T[i1]).max() >= e_L:
            s_hi = s
        else:
            s_lo = s
    return LimitCrossing((i0, i1), s_hi, True)


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
