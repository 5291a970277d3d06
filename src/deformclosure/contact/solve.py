"""One entry point for the frictionless contact problem of every model (SPEC §6, §7).

Every model solves the same problem on the gauged boundary compliance
(:mod:`.compliance`): contact rows with unit normals, Delassus matrix ``W = N Y Nᵀ``
(m/N), gaps ``q`` (m) at zero force, optionally balance rows ``B`` whose multipliers
``y`` are rigid motions left free (the pads' float along the axis; a free part's
translation and rotation)::

    g = q + W λ + Bᵀ y ≥ 0,   λ ≥ 0,   λᵀ g = 0,   B λ = 0.

:class:`ContactProblem` states it; :func:`solve_contact` solves it at one configuration,
:func:`trace_contact` follows its exact solution path as the gaps shrink at the rates
``b`` with the squeeze ``δ`` (``q → q − δ b``). Behind them:

* no balance rows — block principal pivoting (:mod:`.lcp`), the placement energy's
  kernel; the QP below if pivoting fails;
* balance rows — the polished dual QP (:mod:`.qp`), the equilibrium of ``check``;
* a squeeze path — the parametric active-set method (:mod:`.path`), the pads.

Rows carry their unit normals; Coulomb friction (SPEC §9, :mod:`.friction`) adds the
tangents ``t = (−n_y, n_x)`` of the same rows (:meth:`ContactProblem.tangents`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..limits import blas_threads
from .lcp import solve_lcp
from .path import ContactPath, trace_contact_path
from .qp import solve_balanced_dual

__all__ = ["ContactProblem", "ContactSolution", "solve_contact", "trace_contact"]


@dataclass(frozen=True, eq=False)
class ContactProblem:
    """A frictionless contact problem (module docstring).

    Attributes
    ----------
    W : ndarray, shape (r, r)
        Delassus matrix (m/N), symmetric positive (semi-)definite.
    gap : ndarray, shape (r,)
        Gaps at zero force (m).
    balance : ndarray, shape (k, r), optional
        Balance rows ``B`` (``B λ = 0``); their multipliers are free rigid motions.
    rate : ndarray, shape (r,), optional
        How fast each gap shrinks with the squeeze (for :func:`trace_contact`).
    normals : ndarray, shape (r, 2), optional
        Unit normals of the rows (the direction of each contact force on the part).
    """

    W: np.ndarray
    gap: np.ndarray
    balance: np.ndarray | None = None
    rate: np.ndarray | None = None
    normals: np.ndarray | None = None

    def tangents(self) -> np.ndarray:
        """Unit tangents ``(−n_y, n_x)`` of the rows, shape (r, 2) (for friction)."""
        if self.normals is None:
            raise ValueError("this contact problem has no row normals")
        n = np.asarray(self.normals, float)
        return np.column_stack([-n[:, 1], n[:, 0]])


@dataclass(frozen=True, eq=False)
class ContactSolution:
    """The solution of a :class:`ContactProblem`.

    Attributes
    ----------
    lam : ndarray, shape (r,)
        Contact multipliers (N, or the problem's scaling).
    y : ndarray, shape (k,)
        Balance multipliers (free rigid motions).
    active : ndarray of bool, shape (r,)
        Rows carrying force.
    free_balance : ndarray, shape (k, j)
        Basis of the balance multipliers that leave every active gap unchanged.
    ok : bool
        Whether the solver converged.
    """

    lam: np.ndarray
    y: np.ndarray
    active: np.ndarray
    free_balance: np.ndarray
    ok: bool

    def energy(self, W: np.ndarray) -> float:
        """``½ λᵀ W λ`` (J with SI ``W`` and ``λ``)."""
        return 0.5 * float(self.lam @ (W @ self.lam))


def solve_contact(problem: ContactProblem, *, warm: np.ndarray | None = None) -> ContactSolution:
    """Solve ``problem`` at its gaps (module docstring).

    Parameters
    ----------
    problem : ContactProblem
    warm : ndarray of bool, optional
        Rows guessed active (used by the pivoting method).

    Returns
    -------
    ContactSolution

    Examples
    --------
    A node pressed 1 mm into a rigid wall through a 1 mm/N compliance:

    >>> sol = solve_contact(ContactProblem(np.array([[1e-3]]), np.array([-1e-3])))
    >>> float(sol.lam[0]), bool(sol.active[0])
    (1.0, True)
    """
    W = np.asarray(problem.W, float)
    q = np.asarray(problem.gap, float)
    B = problem.balance
    with blas_threads():          # a small dense problem, one of many (limits.BLAS_THREADS)
        if B is None or len(B) == 0:
            lam, ok = solve_lcp(W, q, warm)
            if ok:
                return ContactSolution(lam, np.zeros(0), lam > 0, np.zeros((0, 0)), True)
            B = np.zeros((0, len(q)))
        lam, y, N, active = solve_balanced_dual(W, q, np.asarray(B, float))
    return ContactSolution(lam, y, active, N, True)


def trace_contact(problem: ContactProblem, delta_max: float, *, gap_tol: float,
                  max_pieces: int = 10000) -> ContactPath:
    """The exact solution path of ``problem`` as the squeeze grows from first touch to
    ``delta_max`` (m): piecewise linear multipliers, piecewise quadratic energy.

    The problem needs ``rate`` and a single balance row ``e`` (the pads' float along the
    axis: ``> 0`` on pad A's rows, ``< 0`` on pad B's); see
    :func:`deformclosure.contact.path.trace_contact_path`.
    """
    if problem.rate is None or problem.balance is None or len(problem.balance) != 1:
        raise ValueError("trace_contact needs the squeeze rates and one balance row")
    with blas_threads():          # a small dense problem, one of many (limits.BLAS_THREADS)
        return trace_contact_path(problem.W, problem.gap, problem.rate, problem.balance[0],
                                  delta_max, gap_tol=gap_tol, max_pieces=max_pieces)
