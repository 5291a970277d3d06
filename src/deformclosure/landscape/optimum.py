"""The one σ*-search over piecewise-quadratic energy curves (SPEC §4, §6):
``σ* = argmax Q(σ)``, ``Q = min(U_A, U_L)`` on ``[σ_L, σ0]``.

Every vertex energy of a landscape whose vertices are traced exactly in σ is a piecewise
quadratic, so between two separations where the escape runs over the same saddle vertex
``w`` (and the start stays a strict minimum), ``U_A = U_w − U_s`` is piecewise quadratic
with the kinks of ``U_w`` and ``U_s``, and so is ``U_L = U_s(σ_L) − U_s``; on each such
piece ``Q`` is maximised in closed form (ends, stationary points, crossings of ``U_A``
with ``U_L``) and every candidate is checked against ``U_A`` evaluated by its definition.
Where the saddle or the class of the release changes, the interval is bisected to
``1e-7 σ0``; ``U_A`` can jump there. This is §4's exact algorithm for curves with several
pieces; the paper model keeps its own sweep over §4's breakpoints
(:mod:`deformclosure.grasp.separation`), which the SPEC fixes, with closed-form vertex
energies ``½ k (σ0 − σ)²`` and the paper's method as a reference.

The search knows nothing of coordinates: a model gives it an evaluation of the release at
one σ and the energy curves of the start and of a saddle vertex.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

__all__ = ["maximise_quality"]


def _quadratic(f, lo: float, hi: float) -> np.ndarray:
    """Coefficients ``[a, b, c]`` of the quadratic through ``f`` at lo, mid, hi, in ``x − lo``."""
    h = hi - lo
    f0, f1, f2 = f(lo), f(lo + 0.5 * h), f(hi)
    return np.array([2.0 * (f2 - 2.0 * f1 + f0) / h**2, (4.0 * f1 - f2 - 3.0 * f0) / h, f0])


def _quadratic_max_min(fa, fb, lo: float, hi: float) -> list[float]:
    """Candidates for ``argmax min(fa, fb)`` on ``[lo, hi]``; fa, fb exact quadratics there."""
    out = [lo, hi]
    if hi - lo <= 0:
        return out
    coefs = [_quadratic(f, lo, hi) for f in (fa, fb)]
    for a, b, _ in coefs:
        if a < 0:
            x = lo - b / (2 * a)
            if lo < x < hi:
                out.append(float(x))
    diff = coefs[0] - coefs[1]
    if np.any(diff):
        for r in np.roots(diff):
            if abs(r.imag) <= 1e-12 * (hi - lo) and 0 < r.real < hi - lo:
                out.append(float(lo + r.real))
    return out


def maximise_quality(evaluate: Callable[[float], Any], start_energy: Callable[[float], float],
                     start_kinks, saddle_curve: Callable[[Any], tuple], U_sL: float,
                     sigma_L: float, sigma0: float, n_samples: int):
    """``argmax Q`` on ``[σ_L, σ0]`` (module docstring).

    Parameters
    ----------
    evaluate : callable
        ``evaluate(σ)`` → an object with ``Q`` (J) and ``key`` = ``(strict, saddle,
        infinite)``: whether the start is a strict minimum, the saddle vertex (``None``
        unless strict and finite) and whether ``U_A`` is infinite.
    start_energy : callable
        ``U_s(σ)`` (J), the start vertex's energy.
    start_kinks : array_like
        Separations (m) where ``U_s`` changes piece, and any others the caller knows the
        release class can change at (the start's crossings with its neighbours). They
        are evaluated with the samples, and the interval on each side of one is probed at
        its middle; elsewhere, between two evaluated separations with the same ``key``
        the class is taken not to change, so a window of strictness narrower than the
        sampling that does not start at one of these is not seen.
    saddle_curve : callable
        ``saddle_curve(w)`` → ``(U_w, kinks_w)``: vertex ``w``'s energy (callable, J) and
        its kinks (m).
    U_sL : float
        ``U_s(σ_L)`` (J).
    sigma_L, sigma0 : float
        The range (m); either order (expanding grasps have ``σ_L > σ0``).
    n_samples : int
        Separations sampled to start the search (at least 2).

    Returns
    -------
    best : tuple (Q*, σ*) or None
        ``None`` when ``Q ≡ 0``; on ties the least squeeze (nearest ``σ0``).
    ev : callable
        ``ev(σ)``: ``evaluate`` cached.

    Examples
    --------
    One vertex pair, ``U_s = (1 − σ)²`` and a saddle ``U_w = 3 (1 − σ)²`` on ``[0, 1]``,
    ``U_L = U_s(0) − U_s``: ``U_A = 2 (1 − σ)²`` meets ``U_L = 1 − (1 − σ)²`` where
    ``(1 − σ)² = 1/3``:

    >>> from types import SimpleNamespace
    >>> Us = lambda x: (1 - x) ** 2
    >>> Uw = lambda x: 3 * (1 - x) ** 2
    >>> def evaluate(x):
    ...     UA, UL = Uw(x) - Us(x), 1.0 - Us(x)
    ...     return SimpleNamespace(Q=min(UA, UL), key=(x < 1, "w" if x < 1 else None, False))
    >>> best, _ = maximise_quality(evaluate, Us, [], lambda w: (Uw, np.zeros(0)), 1.0,
    ...                            0.0, 1.0, 5)
    >>> round(best[0], 12), round(best[1], 12)
    (0.666666666667, 0.42264973081)
    """
    UL = lambda x: U_sL - float(start_energy(x))     # noqa: E731
    Us = start_energy
    tol = 1e-7 * sigma0
    evals: dict[float, Any] = {}

    def ev(sig: float):
        if sig not in evals:
            evals[sig] = evaluate(sig)
        return evals[sig]

    kinks = np.asarray(start_kinks, float)
    lo, hi = min(sigma_L, sigma0), max(sigma_L, sigma0)
    xs = sorted(set(np.linspace(lo, hi, n_samples).tolist())
                | set(k for k in kinks.tolist() if lo < k < hi))
    best: tuple[float, float] | None = None   # (Q, σ)
    closer = 1.0 if sigma0 >= sigma_L else -1.0  # on ties, the least squeeze (nearer σ0)

    def consider(sig: float, Q: float) -> None:
        nonlocal best
        if Q > 0 and (best is None or Q > best[0]
                      or (Q == best[0] and closer * sig > closer * best[1])):
            best = (Q, sig)

    for x in xs:
        consider(x, ev(x).Q)
    stack = list(zip(xs[:-1], xs[1:]))
    # a kink is where the class may change: the class on either side of it can differ
    # from its own (a tie at the crossing itself), so such an interval is probed once
    kink_set = set(k for k in kinks.tolist() if lo < k < hi)
    probed: set[tuple[float, float]] = set()
    guard = 0
    while stack and guard < 20000:
        guard += 1
        a, b = stack.pop()
        ea, eb = ev(a), ev(b)
        if ea.key != eb.key:                  # the saddle or the class changes inside
            if b - a > tol:
                m = 0.5 * (a + b)
                consider(m, ev(m).Q)
                stack += [(a, m), (m, b)]
            continue
        strict, w, infinite = ea.key
        if ((a in kink_set or b in kink_set) and (a, b) not in probed and b - a > tol):
            probed.add((a, b))
            m = 0.5 * (a + b)
            consider(m, ev(m).Q)
            if ev(m).key != ea.key:
                stack += [(a, m), (m, b)]
                continue
        if not strict or infinite:
            continue        # Q ≡ 0, or Q = U_L (increasing in σ): the ends suffice
        Uw, w_kinks = saddle_curve(w)

        def UA(x: float) -> float:
            return float(Uw(x)) - float(Us(x))

        cuts = np.concatenate([np.asarray(w_kinks, float), kinks])
        cuts = np.unique(np.concatenate([[a, b], cuts[(cuts > a) & (cuts < b)]]))
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            split = False
            for x in _quadratic_max_min(UA, UL, lo, hi):
                Qp = min(UA(x), UL(x))
                if best is not None and Qp <= best[0]:
                    continue
                e = ev(x)
                if e.key == ea.key and abs(e.Q - Qp) <= 1e-9 * max(abs(Qp), 1e-300):
                    consider(x, e.Q)
                elif x not in (a, b) and b - a > tol:
                    stack += [(a, x), (x, b)]     # the piece assumption failed: split
                    split = True
                    break
            if split:
                break
    return best, ev
