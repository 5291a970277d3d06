"""The one σ*-search over piecewise-quadratic or sampled energy curves (SPEC §4, §6):
``σ* = argmax Q(σ)``, ``Q = min(U_A, U_L)`` on ``[σ_L, σ0]``.

Two pieces of it are the same for every model and live here once, free of coordinates:

* :func:`max_min_candidates` — where ``min(f, g)`` of two quadratics can be largest on
  an interval: the ends, the stationary point of a concave one, and the crossings
  ``f = g`` (SPEC §4, paper §4.6). A model turns its curves into coefficients
  (:class:`Quadratic`) and evaluates ``Q`` at the candidates its own way.
* :func:`better` — the ranking of candidates ``(Q, σ)``: the larger ``Q``; on exact ties
  an attained value before a one-sided limit, then the least squeeze (the separation
  nearest ``σ0``). A sampled search (the paper's §4.7 grid, the lazy samples below)
  ranks its samples with it too.

What stays with each caller is *where the pieces are*:

* the paper model (:mod:`deformclosure.grasp.separation`) sweeps the events of SPEC §4
  — crossings of adjacent vertex curves, tie-creating kinks and crossings of the
  saddle's curve — over closed-form vertex energies ``½ k (σ0 − σ)²``; its pieces are
  known exactly before any maximisation, ``U_A`` is evaluated there by its closed form
  (the one-sided limits at jumps are candidates with ``attained=False``), and its §4.7
  ε-grid is a sampling rule with a guarantee of its own;
* :func:`maximise_quality` (pads, §6) knows only a lazy ``evaluate(σ)`` and vertex
  energy curves as callables with their kinks: it samples, probes the intervals next to
  kinks, bisects where the saddle or class of the release changes, fits the quadratics
  through three points of each piece (:meth:`Quadratic.through`), and checks every
  candidate against ``U_A`` evaluated by its definition (a failed check splits the
  interval).

:func:`maximise_quality` in detail: every vertex energy of a landscape whose vertices
are traced exactly in σ is a piecewise quadratic, so between two separations where the
escape runs over the same saddle vertex ``w`` (and the start stays a strict minimum),
``U_A = U_w − U_s`` is piecewise quadratic with the kinks of ``U_w`` and ``U_s``, and so
is ``U_L = U_s(σ_L) − U_s``; on each such piece ``Q`` is maximised in closed form and
every candidate is checked against ``U_A`` evaluated by its definition. Where the saddle
or the class of the release changes, the interval is bisected to ``1e-7 σ0``; ``U_A``
can jump there.

The search knows nothing of coordinates: a model gives it an evaluation of the release at
one σ and the energy curves of the start and of a saddle vertex.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import numpy as np

__all__ = ["Quadratic", "Candidate", "max_min_candidates", "better", "maximise_quality"]


class Quadratic(NamedTuple):
    """``q(x) = a (x − x_ref)² + b (x − x_ref) + c`` (units of the curve, x in m).

    The reference ``x_ref`` is the caller's choice: one where the coefficients are
    formed without cancellation (e.g. a kink of a vertex curve) keeps the candidates of
    :func:`max_min_candidates` accurate.
    """

    a: float
    b: float
    c: float
    x_ref: float = 0.0

    @classmethod
    def through(cls, f: Callable[[float], float], lo: float, hi: float) -> Quadratic:
        """The quadratic through ``f`` at ``lo``, the middle and ``hi`` (``x_ref = lo``)."""
        h = hi - lo
        f0, f1, f2 = f(lo), f(lo + 0.5 * h), f(hi)
        return cls(2.0 * (f2 - 2.0 * f1 + f0) / h**2, (4.0 * f1 - f2 - 3.0 * f0) / h, f0, lo)

    def shifted(self, x_ref: float) -> Quadratic:
        """The same polynomial about another reference."""
        d = x_ref - self.x_ref
        if d == 0.0:
            return self
        return Quadratic(self.a, 2.0 * self.a * d + self.b, (self.a * d + self.b) * d + self.c,
                         x_ref)

    def __call__(self, x):
        t = np.asarray(x, dtype=float) - self.x_ref
        return (self.a * t + self.b) * t + self.c


def _real_roots(a: float, b: float, c: float, im_tol: float) -> list[float]:
    """Real roots of ``a t² + b t + c`` (stable formula); a complex pair whose imaginary
    part is at most ``im_tol`` (a tangency blurred by rounding) counts as its real part."""
    if a == 0.0:
        return [] if b == 0.0 else [-c / b]
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return [-b / (2.0 * a)] if math.sqrt(-disc) / (2.0 * abs(a)) <= im_tol else []
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    return [q / a] if q == 0.0 else [q / a, c / q]


def max_min_candidates(f: Quadratic, g: Quadratic, lo: float, hi: float,
                       difference: Quadratic | None = None) -> list[float]:
    """Points of ``[lo, hi]`` where ``min(f, g)`` of two quadratics can be largest.

    At an interior maximum ``x*`` either ``f(x*) ≠ g(x*)`` — then the smaller one is
    locally the minimum, so ``x*`` is its stationary point and it is concave there — or
    ``f(x*) = g(x*)``. The candidates are therefore the ends, the stationary points of
    the concave ones strictly inside, and the crossings strictly inside (a double root
    blurred into a complex pair by less than ``1e-12 (hi − lo)`` included).

    Parameters
    ----------
    f, g : Quadratic
        The two curves, exact quadratics on ``[lo, hi]``.
    lo, hi : float
        The interval (m), ``lo ≤ hi``.
    difference : Quadratic, optional
        ``f − g`` when the caller can form it without cancellation (the paper model's
        ``U_A − U_L = E_w − C``); by default the difference of the coefficients, about
        ``f.x_ref``.

    Returns
    -------
    list of float
        ``[lo, hi]``, then the stationary points of ``f`` and ``g``, then the crossings
        in increasing order (not deduplicated beyond that).

    Examples
    --------
    ``f = 1 − x²`` and ``g = x`` on ``[−2, 2]``: the top of ``f`` at 0 and the crossings
    ``x = (−1 ± √5)/2``:

    >>> [round(x, 12) for x in max_min_candidates(Quadratic(-1, 0, 1), Quadratic(0, 1, 0),
    ...                                           -2.0, 2.0)]
    [-2.0, 2.0, 0.0, -1.61803398875, 0.61803398875]
    """
    out = [lo, hi]
    h = hi - lo
    if h <= 0:
        return out
    for q in (f, g):
        if q.a < 0:
            x = q.x_ref - q.b / (2.0 * q.a)
            if lo < x < hi:
                out.append(float(x))
    if difference is None:
        gf = g.shifted(f.x_ref)
        difference = Quadratic(f.a - gf.a, f.b - gf.b, f.c - gf.c, f.x_ref)
    d = difference
    if d.a or d.b or d.c:
        for t in sorted(_real_roots(d.a, d.b, d.c, 1e-12 * h)):
            x = d.x_ref + t
            if lo < x < hi:
                out.append(float(x))
    return out


@dataclass
class Candidate:
    """A candidate for σ*: the quality ``Q`` (J) at ``x`` (m), and whether it is attained
    there (False: a one-sided limit at a jump of ``U_A``)."""

    Q: float
    x: float
    attained: bool


def better(c: Candidate, best: Candidate | None, toward: float = 1.0) -> bool:
    """Whether ``c`` ranks above ``best`` (``None``: nothing yet).

    The larger ``Q``; on exact ties an attained value, then the least squeeze: the
    larger ``toward · x`` (``toward = +1`` when ``σ0`` is the upper end of the range).
    """
    if best is None or c.Q > best.Q:
        return True
    if c.Q < best.Q:
        return False
    if c.attained != best.attained:
        return c.attained
    return toward * c.x > toward * best.x


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
    best: Candidate | None = None
    closer = 1.0 if sigma0 >= sigma_L else -1.0  # on ties, the least squeeze (nearer σ0)

    def consider(sig: float, Q: float) -> None:
        nonlocal best
        c = Candidate(Q, sig, True)
        if Q > 0 and better(c, best, closer):
            best = c

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
            if hi - lo <= 0:
                xc = [lo, hi]
            else:
                xc = max_min_candidates(Quadratic.through(UA, lo, hi),
                                        Quadratic.through(UL, lo, hi), lo, hi)
            for x in xc:
                Qp = min(UA(x), UL(x))
                if best is not None and Qp <= best.Q:
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
    return (None if best is None else (best.Q, best.x)), ev


def maximise_sampled(quality: Callable[[float], float], lo: float, hi: float, n_samples: int,
                     rtol: float, x_tol: float,
                     bound: Callable[[float], float] | None = None) -> tuple[float, float] | None:
    """``argmax Q`` on ``[lo, hi]`` for a ``Q`` known only by evaluation (SPEC §8: the
    finite-strain energies are smooth between contact events, not piecewise quadratic).

    ``n_samples`` evenly spaced values of ``x`` (the ends included) locate the best
    sample; the bracket of its two neighbours is then narrowed around the best point (both
    half-way points evaluated, the best kept, the bracket shrunk to its neighbours) until
    the bracket is narrower than ``x_tol`` or the steeper slope from the best point to the
    bracket's ends, times the bracket, is within ``rtol / 4`` of ``Q*`` — a bound on how
    much higher a peak inside the bracket could be. Samples
    rank by :func:`better` (larger ``Q``, then ``toward`` the upper end, the least
    squeeze).

    Parameters
    ----------
    quality : callable
        ``x → Q`` (J); ``x`` in m.
    lo, hi : float
        The range (m), ``lo < hi``.
    n_samples : int
        At least 3.
    rtol : float
        Relative accuracy of ``Q*`` to locate.
    x_tol : float
        Bracket width (m) at which the search stops regardless.
    bound : callable, optional
        A cheap upper bound ``x → B(x) ≥ Q(x)`` (J; e.g. ``U_L`` for ``Q = min(U_A, U_L)``):
        samples are evaluated in order of decreasing bound, and a sample whose bound cannot
        beat the best value found is not evaluated (it cannot win).

    Returns
    -------
    (Q*, x*) or None
        ``None`` when ``Q ≤ 0`` at every sample (no barrier on the range).
    """
    xs = np.linspace(lo, hi, max(int(n_samples), 3))
    best: Candidate | None = None
    k_best = 0
    order = range(len(xs))
    bounds = None
    if bound is not None:
        bounds = [float(bound(float(x))) for x in xs]
        order = sorted(order, key=lambda k: -bounds[k])
    for k in order:
        x = float(xs[k])
        if bounds is not None and best is not None and bounds[k] < best.Q:
            continue
        c = Candidate(float(quality(x)), x, True)
        if better(c, best):
            best, k_best = c, k
    if best is None or not best.Q > 0:
        return None
    a = float(xs[max(k_best - 1, 0)])
    b = float(xs[min(k_best + 1, len(xs) - 1)])
    Qa = float(quality(a)) if a != best.x else best.Q
    Qb = float(quality(b)) if b != best.x else best.Q
    while b - a > x_tol:
        # Inside [a, b] Q can exceed the best sample by at most the steeper of the two
        # slopes from it to the bracket's ends times the bracket (a peak, even a kink of
        # a max-min, is where those slopes change sign): stop when that is within rtol/4.
        slope = max(abs(best.Q - Qa) / max(best.x - a, 1e-300),
                    abs(best.Q - Qb) / max(b - best.x, 1e-300))
        if slope * (b - a) <= 0.25 * rtol * abs(best.Q):
            break
        for x in (0.5 * (a + best.x), 0.5 * (best.x + b)):
            if a < x < b and x != best.x:
                c = Candidate(float(quality(x)), x, True)
                if better(c, best):
                    if x < best.x:
                        b, Qb = best.x, best.Q
                    else:
                        a, Qa = best.x, best.Q
                    best = c
                elif x < best.x:
                    a, Qa = x, c.Q
                else:
                    b, Qb = x, c.Q
    return best.Q, best.x
