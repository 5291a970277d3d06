"""An independent reference of the parametric frictionless contact path (issue 25).

Plain numpy, sharing no code with ``deformclosure.contact``: the path of

    g(δ) = g0 − δ b + W λ + e t ≥ 0,   λ ≥ 0,   λᵀ g = 0,   eᵀ λ = 0

(m, N; ``W`` the Delassus matrix in m/N) from first touch to ``delta_max``. At every
breakpoint the direction ``(dλ/dδ, dt/dδ)`` is found from scratch: the rows with
``λ > 0`` keep their gaps closed (``dg = 0``), the touching rows (``λ = 0``, ``g = 0``)
obey the derivative complementarity ``dλ ≥ 0, dg ≥ 0, dλ·dg = 0``, and ``eᵀ dλ = 0``.
Every subset ``S`` of the touching rows is tried, smallest first: solve the equality
system on ``strong ∪ S`` (a dense KKT solve) and keep the subset whose ``dλ_S ≥ 0`` and
whose other touching rows open (``dg ≥ 0``). For a symmetric positive definite ``W`` the
derivative problem is a strictly convex QP, so that subset's solution is the unique
direction. The piece then runs until a multiplier reaches 0 or an open gap closes.

Enumeration is exponential in the number of touching rows: it is meant for tests
(random problems of a few contacts, a pad problem whose breakpoints touch a few rows).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np


@dataclass
class ReferencePath:
    """Breakpoints ``delta`` (m), multipliers ``lam`` (N) and translation ``t`` (m) at
    them, and each piece's active set (rows with ``λ > 0`` inside the piece)."""

    delta: np.ndarray
    lam: np.ndarray
    t: np.ndarray
    active: list

    def energy(self, delta: float, W: np.ndarray) -> float:
        """``½ λᵀ W λ`` (J) at squeeze ``delta`` (m), ``λ`` linear on each piece."""
        D = self.delta
        if delta <= D[0] or len(D) < 2:
            return 0.0
        i = min(int(np.searchsorted(D, delta, side="right")) - 1, len(D) - 2)
        w = (delta - D[i]) / (D[i + 1] - D[i])
        lam = (1 - w) * self.lam[i] + w * self.lam[i + 1]
        return 0.5 * float(lam @ W @ lam)


def first_touch(g0: np.ndarray, e: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Translate the part until pad A (``e > 0``) touches (``t``, m), then squeeze until
    pad B (``e < 0``) does (``δ``, m): ``(δ0, t0)``."""
    A, B = e > 0, e < 0
    t0 = -float(np.min(g0[A] / e[A]))
    d0 = float(np.min((g0[B] + e[B] * t0) / b[B]))
    return d0, t0


def derivative_direction(W, b, e, strong, touching, max_subsets=1 << 16):
    """``(dλ, dt)`` (N/m, dimensionless) at a breakpoint, by enumerating which touching
    rows carry load (module docstring)."""
    m = len(b)
    T = np.flatnonzero(touching)
    base = list(np.flatnonzero(strong))
    tried = 0
    for k in range(len(T) + 1):
        for S in itertools.combinations(T, k):
            tried += 1
            if tried > max_subsets:
                raise ValueError(f"{len(T)} touching rows: too many subsets to enumerate")
            A = np.array(sorted(base + list(S)), int)
            n = len(A)
            K = np.zeros((n + 1, n + 1))
            K[:n, :n] = W[np.ix_(A, A)]
            K[:n, n] = e[A]
            K[n, :n] = e[A]
            rhs = np.r_[b[A], 0.0]
            try:
                sol = np.linalg.solve(K, rhs)
            except np.linalg.LinAlgError:
                continue
            if not np.all(np.isfinite(sol)):
                continue
            dlam = np.zeros(m)
            dlam[A] = sol[:n]
            dt = sol[n]
            dg = W @ dlam + e * dt - b
            scale = max(np.abs(b).max(), np.abs(W).max() * np.abs(dlam).max(), 1e-300)
            ok_lam = all(dlam[i] >= -1e-9 * max(np.abs(dlam).max(), 1e-300) for i in S)
            rest = [i for i in T if i not in S]
            ok_gap = all(dg[i] >= -1e-9 * scale for i in rest)
            if ok_lam and ok_gap:
                return dlam, dt
    raise AssertionError("no subset of the touching rows solves the derivative problem")


def reference_path(W, g0, b, e, delta_max, *, gap_rtol=1e-9, max_pieces=10000) -> ReferencePath:
    """The contact path (module docstring), traced breakpoint by breakpoint."""
    W = 0.5 * (np.asarray(W, float) + np.asarray(W, float).T)
    g0, b, e = (np.asarray(v, float) for v in (g0, b, e))
    m = len(g0)
    delta, t = first_touch(g0, e, b)
    lam = np.zeros(m)
    D, L, Tt, act = [delta], [lam.copy()], [t], []
    gscale = max(np.abs(g0).max(), abs(delta) * np.abs(b).max(), 1e-300)
    for _ in range(max_pieces):
        if delta >= delta_max * (1 - 1e-11):
            break
        g = g0 - delta * b + W @ lam + e * t
        lscale = max(np.abs(lam).max(), 1e-300)
        strong = lam > 1e-9 * lscale
        touching = ~strong & (g <= gap_rtol * gscale)
        dlam, dt = derivative_direction(W, b, e, strong, touching)
        dg = W @ dlam + e * dt - b
        dscale = max(np.abs(dlam).max(), 1e-300)
        carries = strong | (dlam > 1e-9 * dscale)
        h = delta_max - delta
        for i in range(m):
            if strong[i] and dlam[i] < 0:            # a multiplier reaches 0
                h = min(h, lam[i] / -dlam[i])
            elif not strong[i] and not touching[i] and dg[i] < 0:   # an open gap closes
                h = min(h, g[i] / -dg[i])
        lam = lam + h * dlam
        lam[lam < 1e-9 * lscale] = 0.0
        t += h * dt
        delta += h
        if h > 0:
            act.append(np.flatnonzero(carries))
            D.append(delta), L.append(lam.copy()), Tt.append(t)
    return ReferencePath(np.array(D), np.array(L), np.array(Tt), act)
