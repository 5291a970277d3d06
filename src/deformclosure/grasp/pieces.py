"""Quadratic-piece algebra of the two-jaw energy curves (paper §4.5–4.6, SPEC §4).

Every function here works in the *contracting frame*: a vertex ``v`` of the contact
graph has the energy curve

.. math:: E_v(x) = \\tfrac12 k_v (x_{0,v} - x)^2 \\quad (x < x_{0,v}), \\qquad 0 \\text{ else},

with ``x`` the jaw separation ``σ`` (m) and ``x0 = σ0``.  An *expanding* grasp,
``U_v(σ) = ½ k_v (σ − σ0_v)²`` for ``σ > σ0_v``, is the same problem after the exact
change of variables ``x = −σ``, ``x0 = −σ0`` (negation is exact in floating point), so
:mod:`deformclosure.grasp.separation` maps expanding grasps here and back.

Crossings of two curves
-----------------------
On the set where both curves are active, ``sqrt(2 E_v)`` is the *line*
``sqrt(k_v) (x0_v − x)``, so two active curves cross at most once and never elsewhere
(an active curve is strictly positive away from its kink; two inactive curves are both
identically 0, a tie, not a crossing).  Writing ``y = x0_a − x`` and ``d = x0_b − x0_a``
the difference ``E_a − E_b`` is the quadratic

.. math:: \\tfrac12 (k_a - k_b) y^2 - k_b d\\, y - \\tfrac12 k_b d^2

whose discriminant is exactly ``k_a k_b d²``.  Forming every coefficient from the input
data (no cancellation in ``x0_a² − x0_b²``) and taking the root with the sign that keeps
both curves active gives

.. math:: y = \\frac{\\sqrt{k_b}\\,(\\sqrt{k_a} + \\sqrt{k_b})\\, d}{k_a - k_b},

valid when ``y > 0``.  :func:`pair_crossings` uses this closed form;
:func:`pair_crossings_quadratic` (used by the paper's reference method) solves the same
quadratic with the numerically stable (Citardauq) formula ``q = −½(B + sign(B)√Δ)``,
roots ``q/A`` and ``C/q``, and keeps the root where both curves are active.  The two
agree to a few ulps, which the tests check.

Breakpoints closer than ``rtol · scale`` (``rtol = 1e-12``, ``scale`` = the largest of
``|x|`` at the ends of the range and the range width) are merged into one.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import GraspError
from ..landscape.optimum import Quadratic, max_min_candidates

__all__ = [
    "RTOL",
    "energies",
    "pair_crossings",
    "pair_crossings_quadratic",
    "curve_crossings",
    "adjacent_crossings",
    "all_crossings",
    "kinks_in",
    "Breakpoint",
    "EventTable",
    "merge_breakpoints",
    "snapped_energies",
    "piece_quality",
    "piece_candidates",
]

#: Relative tolerance used to merge breakpoints and to compare energies (dimensionless).
RTOL = 1e-12


def energies(x: float | np.ndarray, x0: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Vertex energy curves in the contracting frame (J).

    Parameters
    ----------
    x : float or ndarray, shape (n,)
        Jaw separation(s) in the contracting frame (m).
    x0 : ndarray, shape (V,)
        Rest separations (kinks) of the vertices (m).
    k : ndarray, shape (V,)
        Pair stiffnesses (N/m).

    Returns
    -------
    ndarray, shape (V,) or (n, V)
        ``½ k (x0 − x)²`` where ``x < x0``, else 0.
    """
    x = np.asarray(x, dtype=float)
    d = x0 - x[..., None] if x.ndim else x0 - x
    return np.where(d > 0.0, 0.5 * k * d * d, 0.0)


def pair_crossings(x0a, ka, x0b, kb) -> np.ndarray:
    """Separation where two active energy curves cross (closed form), else NaN.

    Parameters
    ----------
    x0a, ka, x0b, kb : array_like
        Kinks (m) and stiffnesses (N/m) of the two curves, broadcast together.

    Returns
    -------
    ndarray
        ``x`` with ``E_a(x) = E_b(x)`` and both curves active (``x < min(x0a, x0b)``);
        NaN where the curves never cross while active (equal stiffness, identical
        curves, or crossing only at/after a kink).
    """
    x0a, ka, x0b, kb = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x0a, ka, x0b, kb)))
    dk = ka - kb
    d = x0b - x0a
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.sqrt(kb) * (np.sqrt(ka) + np.sqrt(kb)) * d / dk
    ok = (dk != 0.0) & np.isfinite(y) & (y > 0.0)
    return np.where(ok, x0a - np.where(ok, y, 0.0), np.nan)


def _stable_roots(A: np.ndarray, B: np.ndarray, C: np.ndarray, disc: np.ndarray):
    """Both roots of ``A y² + B y + C`` given the discriminant (stable formula)."""
    sq = np.sqrt(np.maximum(disc, 0.0))
    q = -0.5 * (B + np.where(B >= 0.0, sq, -sq))
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = np.where(A != 0.0, q / A, np.where(B != 0.0, -C / B, np.nan))
        r2 = np.where((A != 0.0) & (q != 0.0), C / q, np.nan)
    return r1, r2


def pair_crossings_quadratic(x0a, ka, x0b, kb) -> np.ndarray:
    """Same as :func:`pair_crossings`, by the stable quadratic formula (paper's way).

    Solves ``E_a − E_b = 0`` as a quadratic in ``y = x0a − x`` and keeps the root where
    both curves are active.  Used by the reference ("paper") method so that it does not
    share the closed form of the fast method.
    """
    x0a, ka, x0b, kb = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x0a, ka, x0b, kb)))
    d = x0b - x0a
    A = 0.5 * (ka - kb)
    B = -kb * d
    C = -0.5 * kb * d * d
    disc = ka * kb * d * d  # exact: B² − 4AC simplifies to k_a k_b d²
    r1, r2 = _stable_roots(A, B, C, disc)
    out = np.full(x0a.shape, np.nan)
    for y in (r1, r2):
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(y) & (y > 0.0) & (d + y > 0.0) & np.isnan(out)
        out = np.where(ok, x0a - np.where(ok, y, 0.0), out)
    return out


def curve_crossings(v: int, x0: np.ndarray, k: np.ndarray, lo: float, hi: float):
    """Crossings of curve ``v`` with every other curve strictly inside ``(lo, hi)``.

    Vectorised over all vertices, O(V).

    Returns
    -------
    xs : ndarray, shape (m,)
        Crossing separations (m), sorted.
    partners : ndarray of int, shape (m,)
        The other vertex of each crossing.
    """
    xs = pair_crossings(x0[v], k[v], x0, k)
    xs[v] = np.nan
    with np.errstate(invalid="ignore"):
        inside = (xs > lo) & (xs < hi)
    idx = np.flatnonzero(inside)
    order = np.argsort(xs[idx], kind="stable")
    return xs[idx][order], idx[order]


def adjacent_crossings(x0: np.ndarray, k: np.ndarray, edges: np.ndarray, lo: float, hi: float):
    """Crossings of the curves of adjacent vertices in the closed range ``[lo, hi]``.

    These are the only places besides kinks where the set of equilibrium vertices (and
    whether the start is a strict minimum) can change.  O(E).

    Returns
    -------
    xs : ndarray, shape (m,)
    pairs : ndarray of int, shape (m, 2)
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    xs = pair_crossings(x0[edges[:, 0]], k[edges[:, 0]], x0[edges[:, 1]], k[edges[:, 1]])
    with np.errstate(invalid="ignore"):
        inside = (xs >= lo) & (xs <= hi)
    return xs[inside], edges[inside]


def all_crossings(x0: np.ndarray, k: np.ndarray, lo: float, hi: float, max_count: int):
    """Every pairwise crossing in ``[lo, hi]`` (paper §4.5; O(V²) work), stable formula.

    Raises
    ------
    GraspError
        If more than ``max_count`` crossings lie in the range.
    """
    V = x0.size
    xs_out, pairs_out, count = [], [], 0
    # Rows in blocks keep memory at O(block · V) for large graphs.
    block = max(1, min(V, 2_000_000 // max(V, 1)))
    for start in range(0, V, block):
        a = np.arange(start, min(V, start + block))
        aa, bb = np.nonzero(a[:, None] < np.arange(V)[None, :])
        aa = a[aa]
        xs = pair_crossings_quadratic(x0[aa], k[aa], x0[bb], k[bb])
        with np.errstate(invalid="ignore"):
            inside = (xs >= lo) & (xs <= hi)
        count += int(inside.sum())
        if count > max_count:
            raise GraspError(
                f"method='paper' needs more than max_breakpoints={max_count} pairwise "
                f"crossings of vertex energy curves in the separation range; it is a "
                f"reference for small parts only: use method='exact' or raise max_breakpoints"
            )
        xs_out.append(xs[inside])
        pairs_out.append(np.stack([aa[inside], bb[inside]], axis=1))
    if not xs_out:
        return np.empty(0), np.empty((0, 2), dtype=np.int64)
    return np.concatenate(xs_out), np.concatenate(pairs_out).astype(np.int64)


def kinks_in(x0: np.ndarray, lo: float, hi: float):
    """Vertices whose kink ``x0_v`` lies in ``[lo, hi]`` and the kink positions."""
    idx = np.flatnonzero((x0 >= lo) & (x0 <= hi))
    return x0[idx], idx


@dataclass
class Breakpoint:
    """A separation where ``U_A`` is evaluated by its definition.

    ``pairs`` lists the curves that cross there and ``kinks`` the vertices whose curve
    reaches 0 there; :func:`snapped_energies` uses them to evaluate the exact tie
    instead of a rounding-perturbed neighbour of it.
    """

    x: float
    pairs: np.ndarray = field(default_factory=lambda: np.empty((0, 2), dtype=np.int64))
    kinks: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    static: bool = True


@dataclass
class EventTable:
    """Merged breakpoints as arrays (sorted by position, ends of the range included).

    Attributes
    ----------
    x : ndarray, shape (G,)
        Positions (m, contracting frame), increasing; ``x[0] = lo``, ``x[-1] = hi``.
    pair_ptr, pairs : ndarray
        Crossing pairs of breakpoint ``i``: ``pairs[pair_ptr[i]:pair_ptr[i + 1]]``.
    kink_ptr, kinks : ndarray
        Kink vertices of breakpoint ``i``: ``kinks[kink_ptr[i]:kink_ptr[i + 1]]``.
    """

    x: np.ndarray
    pair_ptr: np.ndarray
    pairs: np.ndarray
    kink_ptr: np.ndarray
    kinks: np.ndarray

    def __len__(self) -> int:
        return int(self.x.size)

    def breakpoint(self, i: int) -> Breakpoint:
        """Breakpoint ``i`` as a :class:`Breakpoint`."""
        return Breakpoint(float(self.x[i]), self.pairs[self.pair_ptr[i]:self.pair_ptr[i + 1]],
                          self.kinks[self.kink_ptr[i]:self.kink_ptr[i + 1]], static=True)

    def members(self) -> tuple[np.ndarray, np.ndarray]:
        """``(breakpoint index, vertex)`` of every vertex involved, sorted by index."""
        G = len(self)
        gp = np.repeat(np.arange(G), np.diff(self.pair_ptr))
        gk = np.repeat(np.arange(G), np.diff(self.kink_ptr))
        bp = np.concatenate([gp, gp, gk])
        v = np.concatenate([self.pairs[:, 0], self.pairs[:, 1], self.kinks])
        order = np.argsort(bp, kind="stable")
        return bp[order], v[order]


def merge_breakpoints(xs: np.ndarray, pairs: np.ndarray, kink_x: np.ndarray, kink_v: np.ndarray,
                      lo: float, hi: float, tol: float) -> EventTable:
    """Sort and merge crossings and kinks into breakpoints, always including ``lo``, ``hi``.

    Points closer than ``tol`` (m) to their sorted neighbour are merged (transitively);
    points within ``tol`` of an end merge into it.  A merged point sits at ``lo``/``hi``
    when it is within ``tol`` of an end, else
    at its first kink when it has one (so that kink's energy is exactly 0), else at its
    median member.  Vectorised; O(m log m).
    """
    xs = np.asarray(xs, dtype=float).ravel()
    kink_x = np.asarray(kink_x, dtype=float).ravel()
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    kink_v = np.asarray(kink_v, dtype=np.int64).ravel()
    n_c, n_k = xs.size, kink_x.size
    pos = np.concatenate([[lo, hi], xs, kink_x])
    tag = np.concatenate([[-1, -1], np.arange(n_c), n_c + np.arange(n_k)])  # -1: range end
    order = np.lexsort((tag, pos))
    pos, tag = pos[order], tag[order]
    # Chains break at gaps > tol and on entering/leaving the zones within tol of the
    # ends, so that lo and hi always head distinct groups (the range is > 4 tol wide).
    zone = np.where(pos <= lo + tol, 0, np.where(pos >= hi - tol, 2, 1))
    new = np.r_[True, (np.diff(pos) > tol) | (np.diff(zone) != 0)]
    gid = np.cumsum(new) - 1
    G = int(gid[-1]) + 1
    starts = np.flatnonzero(new)
    ends = np.r_[starts[1:], pos.size]
    x = pos[(starts + ends - 1) // 2].copy()  # median (lower middle)
    is_k = tag >= n_c
    kfirst = np.full(G, -1)
    ki = np.flatnonzero(is_k)[::-1]  # reversed so that the first kink of a group wins
    kfirst[gid[ki]] = ki
    x = np.where(kfirst >= 0, pos[np.maximum(kfirst, 0)], x)
    x[zone[starts] == 0] = lo
    x[zone[starts] == 2] = hi
    is_c = (tag >= 0) & ~is_k
    pair_ptr = np.r_[0, np.cumsum(np.bincount(gid[is_c], minlength=G))]
    kink_ptr = np.r_[0, np.cumsum(np.bincount(gid[is_k], minlength=G))]
    return EventTable(x, pair_ptr, pairs[tag[is_c]], kink_ptr, kink_v[tag[is_k] - n_c])


def snapped_energies(bp: Breakpoint, x0: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Vertex energies at a breakpoint with its exact ties restored (J).

    The computed crossing is within a few ulps of the true one, so the two crossing
    energies differ only by rounding; they are set equal (to their mean, or to 0 when a
    kink of the same group is involved), transitively over chains of crossings, so that
    ``U_A`` is evaluated at the tie itself — where, e.g., the start stops being a strict
    minimum.
    """
    U = energies(bp.x, x0, k)
    if bp.kinks.size:
        U[bp.kinks] = 0.0
    if bp.pairs.size:
        parent: dict[int, int] = {}

        def find(i: int) -> int:
            while parent.setdefault(i, i) != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for a, b in bp.pairs.tolist():
            ra, rb = find(a), find(b)
            if ra != rb:
                parent[ra] = rb
        comps: dict[int, list[int]] = {}
        for i in list(parent):
            comps.setdefault(find(i), []).append(i)
        zero = set(bp.kinks.tolist())
        for members in comps.values():
            m = np.asarray(members)
            U[m] = 0.0 if zero.intersection(members) else float(np.mean(U[m]))
    return U


def piece_quality(x, w: int | None, kind: str, s: int, x0: np.ndarray, k: np.ndarray, C: float):
    """``U_A`` and ``Q`` of one piece as closed-form functions of ``x`` (J).

    On a piece the release energy is ``E_w − E_s`` (``kind="finite"``), ``+∞``
    (``"inf"``) or 0 (``"zero"``, start not a strict minimum); ``U_L = C − E_s`` with
    ``C = E_s(lo)``.  Evaluated at a piece end this is the one-sided limit there.
    """
    x = np.asarray(x, dtype=float)
    d_s = x0[s] - x
    Es = np.where(d_s > 0.0, 0.5 * k[s] * d_s * d_s, 0.0)
    UL = C - Es
    if kind == "zero":
        UA = np.zeros_like(x)
    elif kind == "inf":
        UA = np.full_like(x, np.inf)
    else:
        d_w = x0[w] - x
        UA = np.where(d_w > 0.0, 0.5 * k[w] * d_w * d_w, 0.0) - Es
    return UA, np.minimum(UA, UL), UL


def piece_candidates(a: float, b: float, w: int | None, kind: str, s: int,
                     x0: np.ndarray, k: np.ndarray, C: float) -> np.ndarray:
    """Points of ``[a, b]`` where ``Q = min(U_A, U_L)`` of a piece can be largest.

    Only a ``"finite"`` piece has interior candidates (``Q ≡ 0`` on a ``"zero"`` piece;
    ``Q = U_L`` increases on an ``"inf"`` one). There ``U_A = E_w − E_s`` and
    ``U_L = C − E_s`` are both active quadratics (``E_w > E_s > 0`` on the piece), and
    the one maximiser of the minimum of two quadratics,
    :func:`deformclosure.landscape.optimum.max_min_candidates` (paper §4.6), is given
    them in the forms this model knows exactly: ``U_A`` about ``x0_w``, ``U_L`` about
    ``x0_s`` (its top, the end of the range, so never an interior candidate) and the
    crossing ``U_A − U_L = E_w − C = ½ k_w (x − x0_w)² − C`` without cancellation (roots
    ``x0_w ∓ sqrt(2C/k_w)``). The candidates are the ends, the stationary point of
    ``E_w − E_s`` where it is concave (``k_w < k_s``), and the point ``E_w = C``.
    Returned sorted, ends included.
    """
    if kind != "finite" or not b > a:
        return np.unique(np.asarray([a, b], dtype=float))
    kw, ks, xw, xs = float(k[w]), float(k[s]), float(x0[w]), float(x0[s])
    d = xs - xw
    UA = Quadratic(0.5 * (kw - ks), ks * d, -0.5 * ks * d * d, xw)
    UL = Quadratic(-0.5 * ks, 0.0, C, xs)
    cand = max_min_candidates(UA, UL, a, b, difference=Quadratic(0.5 * kw, 0.0, -C, xw))
    return np.asarray(sorted(set(cand)), dtype=float)
