"""Parametric frictionless contact: the exact solution path of a linear complementarity
problem as the squeeze grows (SPEC §6).

With contact multipliers ``λ`` (N) and the Delassus matrix ``W = Gᵀ Y G`` (m/N) the
linearised gaps are ``g = g0 − δ b + W λ + e t`` (m): ``δ`` is the squeeze, ``b`` marks
the contacts of the moving pad, ``t`` the free translation of the part along the axis and
``e = ±1`` its effect on each pad's gaps. The contact problem is::

    g ≥ 0,  λ ≥ 0,  λᵀ g = 0,  eᵀ λ = 0   (the pads' axial forces balance)

and its solution is piecewise linear in ``δ``: on each piece the set of active contacts
is fixed. We follow it exactly (a homotopy / parametric active-set method): at each
breakpoint the direction ``(dλ/dδ, dt/dδ)`` solves the *derivative* problem — the same
complementarity on the contacts that are active or just touching — posed as the convex QP
``min ½ xᵀ W x − bᵀ x`` s.t. ``eᵀx = 0`` and ``x ≥ 0`` on the just-touching contacts
(Goldfarb–Idnani, ``quadprog``); the piece ends where a multiplier reaches 0 or a gap
closes. The energy ``½ λᵀ W λ`` is then exactly quadratic on every piece.

References
----------
K. G. Murty, *Linear Complementarity, Linear and Nonlinear Programming* (1988), ch. 5
(parametric LCP).
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass, field

import numpy as np

__all__ = ["ContactPath", "trace_contact_path"]


@dataclass(frozen=True)
class ContactPath:
    """Exact piecewise-linear solution path ``λ(δ)``.

    Attributes
    ----------
    delta : ndarray, shape (k,)
        Breakpoints of the squeeze (m), increasing; ``delta[0]`` is the first touch.
    lam : ndarray, shape (k, m)
        Multipliers (N) at the breakpoints; linear in between.
    t : ndarray, shape (k,)
        Axial translation of the part (m) at the breakpoints.
    energy_coef : ndarray, shape (k − 1, 3)
        On piece ``i``, ``U = c0 + c1 (δ − delta[i]) + c2 (δ − delta[i])²`` (J).
    """

    delta: np.ndarray
    lam: np.ndarray
    t: np.ndarray
    energy_coef: np.ndarray
    _lists: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # Plain lists for the scalar fast path (the landscape evaluates ~10⁵ energies).
        object.__setattr__(self, "_lists", (self.delta.tolist(), self.energy_coef.tolist()))

    def energy_at(self, delta: float) -> float:
        """Energy (J) at one squeeze ``delta`` (m); same as :meth:`energy`, faster."""
        D, C = self._lists
        if len(D) < 2 or delta <= D[0]:
            return 0.0
        i = min(bisect_right(D, delta) - 1, len(D) - 2)
        h = delta - D[i]
        c0, c1, c2 = C[i]
        return c0 + h * (c1 + h * c2)

    def piece(self, delta: np.ndarray) -> np.ndarray:
        """Index of the piece holding each squeeze value (clipped to the traced range)."""
        i = np.searchsorted(self.delta, delta, side="right") - 1
        return np.clip(i, 0, max(len(self.delta) - 2, 0))

    def energy(self, delta: np.ndarray) -> np.ndarray:
        """Energy (J) at squeezes ``delta`` (m); 0 before first touch."""
        delta = np.asarray(delta, float)
        if len(self.delta) < 2:
            return np.zeros_like(delta)
        i = self.piece(delta)
        h = delta - self.delta[i]
        c = self.energy_coef[i]
        U = c[..., 0] + h * (c[..., 1] + h * c[..., 2])
        return np.where(delta <= self.delta[0], 0.0, U)

    def multipliers(self, delta: float) -> np.ndarray:
        """Multipliers (N) at squeeze ``delta`` (m), linear between breakpoints."""
        if delta <= self.delta[0] or len(self.delta) < 2:
            return np.zeros(self.lam.shape[1])
        i = int(self.piece(np.array(delta)))
        w = (delta - self.delta[i]) / (self.delta[i + 1] - self.delta[i])
        return (1 - w) * self.lam[i] + w * self.lam[i + 1]


def _direction(W, b, e, J, Zmask):
    """Solve the derivative QP on contacts ``J``; ``Zmask`` marks the sign-constrained ones."""
    import quadprog

    m = len(J)
    Wj = W[np.ix_(J, J)]
    Wj = 0.5 * (Wj + Wj.T)
    reg = 1e-13 * max(float(np.trace(Wj)) / max(m, 1), 1e-300)
    Wj = Wj + reg * np.eye(m)
    cols = [e[J][:, None]]
    z = np.flatnonzero(Zmask)
    if len(z):
        I = np.zeros((m, len(z)))
        I[z, np.arange(len(z))] = 1.0
        cols.append(I)
    C = np.hstack(cols)
    x = quadprog.solve_qp(Wj, b[J].astype(float), C, np.zeros(C.shape[1]), 1)[0]
    x[Zmask] = np.maximum(x[Zmask], 0.0)
    return x


def trace_contact_path(W: np.ndarray, g0: np.ndarray, b: np.ndarray, e: np.ndarray,
                       delta_max: float, *, gap_tol: float, max_pieces: int = 10000
                       ) -> ContactPath:
    """Follow the frictionless contact solution from first touch to ``delta_max``.

    Parameters
    ----------
    W : ndarray, shape (m, m)
        Delassus matrix (m/N), symmetric positive definite.
    g0 : ndarray, shape (m,)
        Rest gaps (m) with pad A at its first-touch position and no squeeze.
    b : ndarray, shape (m,)
        Rate at which each gap shrinks with ``δ`` (> 0 for the contacts of pad B, 0 for
        pad A).
    e : ndarray, shape (m,)
        Rate at which each gap grows with the part's axial translation (> 0 for pad A's
        contacts, < 0 for pad B's).
    delta_max : float
        Largest squeeze to trace (m).
    gap_tol : float
        Gaps below this (m) count as closed.

    Returns
    -------
    ContactPath
    """
    m = len(g0)
    A, B = e > 0, e < 0
    if not A.any() or not B.any():
        empty = np.array([np.inf])
        return ContactPath(empty, np.zeros((1, m)), np.zeros(1), np.zeros((0, 3)))
    # First touch on the nodes: translate until pad A touches, squeeze until B does.
    t = -float(np.min(g0[A] / e[A]))
    delta = float(np.min((g0[B] + e[B] * t) / b[B]))
    lam = np.zeros(m)
    deltas, lams, ts = [delta], [lam.copy()], [t]
    for _ in range(max_pieces):
        if delta >= delta_max:
            break
        g = g0 - delta * b + W @ lam + e * t
        lam_scale = max(float(np.abs(lam).max()), 1e-300)
        strong = lam > 1e-12 * lam_scale
        touching = (~strong) & (g <= gap_tol)
        J = np.flatnonzero(strong | touching)
        x = _direction(W, b, e, J, touching[J])
        dlam = np.zeros(m)
        dlam[J] = x
        # dt from the contacts that stay closed: (W x)_i + e_i dt = b_i.
        on = J[(strong[J]) | (x > 1e-12 * max(np.abs(x).max(), 1e-300))]
        r = (b - W @ dlam)[on] / e[on]
        dt = float(np.mean(r)) if len(on) else 0.0
        dg = W @ dlam + e * dt - b
        steps = [delta_max - delta]
        dec = np.flatnonzero(dlam < 0)
        if len(dec):
            steps.append(float(np.min(lam[dec] / -dlam[dec])))
        stays = np.zeros(m, bool)
        stays[on] = True
        closing = np.flatnonzero((dlam == 0) & (dg < 0) & ~stays)
        if len(closing):
            steps.append(float(np.min(np.maximum(g[closing], 0.0) / -dg[closing])))
        h = max(min(steps), 0.0)
        lam = np.maximum(lam + h * dlam, 0.0)
        if len(dec):
            hit = dec[np.isclose(lam[dec], 0.0, atol=1e-12 * lam_scale)]
            lam[hit] = 0.0
        t += h * dt
        delta += h
        if h > 0 or delta >= delta_max:
            deltas.append(delta)
            lams.append(lam.copy())
            ts.append(t)
    D = np.array(deltas)
    L = np.array(lams)
    # U = ½ λᵀWλ with λ linear on each piece: exact quadratic coefficients.
    dL = np.diff(L, axis=0) / np.diff(D)[:, None]
    WL = L[:-1] @ W
    c0 = 0.5 * np.einsum("ij,ij->i", WL, L[:-1])
    c1 = np.einsum("ij,ij->i", WL, dL)
    c2 = 0.5 * np.einsum("ij,jk,ik->i", dL, W, dL)
    return ContactPath(D, L, np.array(ts), np.column_stack([c0, c1, c2]))
