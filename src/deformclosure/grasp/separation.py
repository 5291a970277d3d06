"""Optimal jaw separation σ* of a two-jaw grasp (paper §4.5–4.7, SPEC §4).

The problem is given as arrays on a precomputed contact graph: for every graph vertex
``v`` (an unordered pair of perimeter nodes) its rest distance ``sigma0[v]`` (m) and pair
stiffness ``k[v]`` (N/m).  With the jaws at separation ``σ`` the vertex energies are

* contracting: ``U_v(σ) = ½ k_v (σ0_v − σ)²`` for ``σ < σ0_v``, else 0;
* expanding:   ``U_v(σ) = ½ k_v (σ − σ0_v)²`` for ``σ > σ0_v``, else 0.

For the start vertex ``s = {n0, n1}`` the release energy ``U_A(σ)`` is
:func:`~deformclosure.grasp.release.release_energy` of the energy vector ``U(σ)``, the
elastic-limit margin is ``U_L(σ) = U_s(σ_L) − U_s(σ)`` and the quality is
``Q(σ) = min(U_A(σ), U_L(σ))`` on ``[σ_L, σ0_s]`` (contracting) or ``[σ0_s, σ_L]``
(expanding).  :func:`optimize_separation_arrays` returns ``σ* = argmax Q``.

Conventions fixed here (SPEC §4 is silent on them)
-------------------------------------------------
* **Jumps.**  ``U_A`` is piecewise quadratic but *not* continuous (the paper says it
  is): it jumps where two adjacent vertex curves cross (the set of equilibrium vertices
  changes, or the start stops being a strict minimum) and at kinks ``σ0_v`` where a
  curve reaches 0 next to a neighbour already at 0 (a tie at level 0).  At such a
  tie the equilibrium set is the union of the limits from both sides and strictness can
  only be lost, so ``U_A`` there is at most the smaller one-sided limit (lower
  semicontinuous).  The reported ``quality`` is ``sup Q``; ``sigma_star`` is where it is
  attained, or the breakpoint it is approached at, with ``attained=False``.  ``U_A`` and
  ``U_L`` are then the one-sided limits that define the supremum.
* **Ties** of the maximum value (exactly equal ``Q``) prefer an attained value, then
  the least squeeze (the separation closest to ``σ0_s``)
  (:func:`deformclosure.landscape.optimum.better`).
* **Evaluation at breakpoints** is by definition, at the exact tie: the two (or more)
  curves known to cross there are set equal, and a kink's energy to 0, before calling
  ``release_energy``; they differ from that only by rounding (see
  :func:`~deformclosure.grasp.pieces.snapped_energies`).
* **Tolerances.** Breakpoints closer than ``1e-12 × max(|σ_L|, σ0_s, range)`` are
  merged; a one-sided limit is considered attained at its breakpoint when the value
  there is within ``1e-12 × U_s(σ_L)`` (the largest ``U_L``, hence the scale of ``Q``)
  of it; the same relative tolerance decides which breakpoints are reported as jumps.
* **Q ≡ 0** (including a degenerate range ``σ_L = σ0_s``): ``sigma_star=None``,
  ``quality=0`` and ``U_A = U_L = 0``.
* Expanding grasps are solved as contracting ones after the exact substitution
  ``σ → −σ`` (see :mod:`deformclosure.grasp.pieces`).

Methods
-------
``"paper"`` (§4.5–4.6, reference): every pairwise crossing of two vertex curves and
every kink is a breakpoint (O(V²)); one ``release_energy`` call per piece finds its
saddle ``w``, so ``U_A = U_w − U_s`` there, and one per breakpoint evaluates ``U_A`` by
definition.  ``"exact"`` (default): the same closed-form maximisation, but only at
breakpoints that can change ``U_A`` (see :func:`_sweep_exact`): typically 10–100×
fewer evaluations for p ≈ 30 perimeter nodes.  ``"approx"`` (§4.7): samples, with the
guarantee ``Q* − Q(σ_ε) ≤ ε`` kept valid across the jumps (see :func:`_approx`).
Per piece, ``Q = min(U_w, C) − U_s`` with ``C = U_s(σ_L)``; its maximum lies at a
piece end (a one-sided limit), at the stationary point of ``U_w − U_s``, or where
``U_w = C`` (:func:`~deformclosure.grasp.pieces.piece_candidates`).

What is shared and what is this module's own
--------------------------------------------
The maximisation of the minimum of two quadratics on a piece and the ranking of
candidates (the tie rules above) are the one σ*-search mechanics of
:mod:`deformclosure.landscape.optimum` (``max_min_candidates``, ``Candidate``,
``better``), which the pads' lazy search uses too. What stays here is specific to the
paper's closed-form curves and cannot move without changing results: the §4 event table
(adjacent crossings, tie-creating kinks, the saddle's crossings; :func:`_sweep_exact`,
:func:`_sweep_paper`) that fixes every piece before any maximisation, ``U_A`` at a
candidate by its closed form (:func:`~deformclosure.grasp.pieces.piece_quality`), the
one-sided limits at jumps as candidates with ``attained=False`` and the jump report,
and the §4.7 ε-grid (:func:`_approx`), whose samples are ranked by the same rule.

References
----------
K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure Grasps of Deformable
Parts", IJRR 24(11), 2005, §4.5 (piecewise-quadratic ``U_A``), §4.6 (exact
algorithm), §4.7 (ε-approximation).
"""

from __future__ import annotations

import math
import threading
import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..choices import METHODS, MODES, choose
from ..errors import GraspError
from ..landscape.optimum import Candidate, better
from . import pieces as pc
from .release import release_energy

if TYPE_CHECKING:  # pragma: no cover
    from .contact_graph import ContactGraph

__all__ = [
    "SeparationResult",
    "optimize_separation_arrays",
    "lipschitz_constant",
    "quality_at",
    "vertex_energies",
]

#: Sample grids of ``method="approx"`` (:func:`_approx`).
GRIDS = ("pieces", "lattice")

_UNITS = {"length": "m", "energy": "J", "stiffness": "N/m", "strain_per_length": "1/m"}


def _jsonf(v: float | None) -> float | None:
    """A float for JSON: ``None`` for ``None``, ``inf`` and ``nan``."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


@dataclass(frozen=True, eq=False)
class SeparationResult:
    """Optimal separation of one jaw pair (SPEC §5, optimize report). SI units.

    Attributes
    ----------
    sigma_star : float or None
        Optimal separation σ* (m); ``None`` when ``Q ≡ 0`` (the pair cannot hold).
    quality : float
        ``sup Q = Q(σ*)`` (J), or the one-sided limit at σ* when not ``attained``.
    U_A : float or None
        Release energy at σ* (J); ``None`` when it is infinite.
    U_A_infinite : bool
        True when no other equilibrium vertex is reachable at σ* (``Q = U_L`` there).
    U_L : float
        Elastic-limit margin ``U_s(σ_L) − U_s(σ*)`` (J).
    sigma_L : float
        Elastic-limit separation (m).
    sigma0 : float
        Rest distance of the jaw nodes (m).
    k01 : float
        Pair stiffness of the jaw nodes (N/m).
    method : str
        ``"exact"``, ``"paper"`` or ``"approx"``.
    epsilon : float or None
        ε of the approximation (J); ``None`` for the exact methods.
    mode : str
        ``"contracting"`` or ``"expanding"``.
    n_evaluations : int
        Number of evaluations of ``U_A`` by its definition (``release_energy`` calls).
    n_breakpoints : int
        Exact methods: number of breakpoints where ``U_A`` was evaluated, ends of the
        range included.  ``"approx"``: number of breakpoints that split its grid.
    jumps : list of (float, float, float, float)
        ``(σ, left limit, value at σ, right limit)`` of ``U_A`` (m, J, J, J) at each
        visited interior breakpoint where ``U_A`` is discontinuous; ``inf`` for infinite
        values.
        Left means smaller σ.  Empty for ``"approx"``, which does not resolve them.
    saddle : int or None
        Graph vertex whose energy bounds the escape at σ* (``None`` if ``U_A`` is 0 or
        infinite there); when not ``attained``, the saddle on the side σ* is approached
        from.
    escape_path : ndarray of int or None
        Graph vertices of a minimax escape path at σ* (likewise), start first, ending
        at another equilibrium vertex.
    curve : dict
        ``{"sigma", "U_A", "U_L", "Q"}``: lists of floats for plotting (≈400 samples
        plus the jumps and σ*), ``None`` for infinite values.
    attained : bool
        Whether ``Q(σ*) = quality`` (False: the supremum is a one-sided limit at a jump).
    n_pieces : int
        Number of quadratic pieces (exact methods) or of interior samples (approx).
    e_max : float or None
        Largest element strain per unit jaw displacement (1/m), if given (report only).
    lipschitz : float or None
        λ of the ε-approximation (N), ``None`` for the exact methods.
    step : float or None
        Sample step ξ = ε/λ (m), ``None`` for the exact methods.
    saddle_pair : tuple of int or None
        Perimeter nodes of ``saddle``.
    """

    sigma_star: float | None
    quality: float
    U_A: float | None
    U_A_infinite: bool
    U_L: float
    sigma_L: float
    sigma0: float
    k01: float
    method: str
    epsilon: float | None
    mode: str
    n_evaluations: int
    n_breakpoints: int
    jumps: list[tuple[float, float, float, float]]
    saddle: int | None
    escape_path: np.ndarray | None
    curve: dict
    attained: bool = True
    n_pieces: int = 0
    e_max: float | None = None
    lipschitz: float | None = None
    step: float | None = None
    saddle_pair: tuple[int, int] | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict in SI units; an infinite ``U_A`` is ``None`` + ``U_A_infinite``."""
        return {
            "sigma_star": _jsonf(self.sigma_star),
            "quality": float(self.quality),
            "attained": bool(self.attained),
            "U_A": _jsonf(self.U_A),
            "U_A_infinite": bool(self.U_A_infinite),
            "U_L": float(self.U_L),
            "sigma_L": float(self.sigma_L),
            "sigma0": float(self.sigma0),
            "k01": float(self.k01),
            "e_max": _jsonf(self.e_max),
            "method": self.method,
            "epsilon": _jsonf(self.epsilon),
            "lipschitz": _jsonf(self.lipschitz),
            "step": _jsonf(self.step),
            "mode": self.mode,
            "n_evaluations": int(self.n_evaluations),
            "n_breakpoints": int(self.n_breakpoints),
            "n_pieces": int(self.n_pieces),
            "jumps": [[_jsonf(v) for v in j] for j in self.jumps],
            "saddle": None if self.saddle is None else int(self.saddle),
            "saddle_pair": None if self.saddle_pair is None else [int(v) for v in self.saddle_pair],
            "escape_path": None if self.escape_path is None else [int(v) for v in self.escape_path],
            "curve": {key: [_jsonf(v) for v in vals] for key, vals in self.curve.items()},
            "units": dict(_UNITS),
        }


# --------------------------------------------------------------------------- helpers


def vertex_energies(sigma: float | np.ndarray, sigma0: np.ndarray, k: np.ndarray,
                    mode: Literal["contracting", "expanding"] = "contracting") -> np.ndarray:
    """Energy of every graph vertex at jaw separation(s) ``sigma`` (J), SPEC §4.

    Parameters
    ----------
    sigma : float or ndarray, shape (n,)
        Jaw separation(s) (m).
    sigma0 : ndarray, shape (V,)
        Rest distances of the vertices (m).
    k : ndarray, shape (V,)
        Pair stiffnesses (N/m).
    mode : {"contracting", "expanding"}

    Returns
    -------
    ndarray, shape (V,) or (n, V)
        ``½ k (σ0 − σ)²`` where the jaws squeeze that pair, else 0.

    Examples
    --------
    >>> vertex_energies(0.5, np.array([1.0, 0.2]), np.array([2.0, 2.0]))
    array([0.25, 0.  ])
    >>> vertex_energies(0.5, np.array([1.0, 0.2]), np.array([2.0, 2.0]), "expanding")
    array([0.  , 0.09])
    """
    choose(mode, MODES, "mode", GraspError)
    sign = 1.0 if mode == "contracting" else -1.0
    return pc.energies(sign * np.asarray(sigma, dtype=float), sign * np.asarray(sigma0, float),
                       np.asarray(k, float))


@dataclass
class _Eval:
    """``U_A``, ``U_L``, ``Q`` (J) at one separation, with the Release behind them."""

    x: float
    UA: float
    UL: float
    Q: float
    release: Any
    kind: str
    w: int | None


@dataclass
class _Piece:
    """An open interval ``(a, b)`` on which ``U_A`` is one closed-form function."""

    a: float
    b: float
    kind: str
    w: int | None
    release: Any


@dataclass
class _Problem:
    """A validated problem in the contracting frame ``x = sign·σ``."""

    x0: np.ndarray
    k: np.ndarray
    graph: Any
    s: int
    lo: float
    hi: float
    sign: float
    C: float  # U_s(σ_L), the largest U_L (J)
    tol_x: float
    tol_E: float
    n_eval: int = 0

    def release(self, U: np.ndarray):
        self.n_eval += 1
        return release_energy(U, self.graph, self.s)

    def classify(self, rel) -> tuple[str, int | None, float]:
        if not bool(rel.strict_minimum):
            return "zero", None, 0.0
        val = float(rel.value)
        if math.isinf(val):
            return "inf", None, math.inf
        return "finite", int(rel.saddle), val

    def UL(self, x: float) -> float:
        d = self.x0[self.s] - x
        return self.C - (0.5 * self.k[self.s] * d * d if d > 0.0 else 0.0)

    def evaluate(self, U: np.ndarray, x: float) -> _Eval:
        rel = self.release(U)
        kind, w, UA = self.classify(rel)
        UL = self.UL(x)
        return _Eval(x, UA, UL, min(UA, UL), rel, kind, w)

    def eval_bp(self, bp: pc.Breakpoint) -> _Eval:
        return self.evaluate(pc.snapped_energies(bp, self.x0, self.k), bp.x)

    def eval_x(self, x: float) -> _Eval:
        return self.evaluate(pc.energies(x, self.x0, self.k), x)


def _as_vector(name: str, a, V: int | None = None) -> np.ndarray:
    try:
        arr = np.asarray(a, dtype=float)
    except (TypeError, ValueError) as err:
        raise GraspError(f"{name} must be an array of numbers") from err
    if arr.ndim != 1:
        raise GraspError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if V is not None and arr.size != V:
        raise GraspError(f"{name} has {arr.size} entries but the contact graph has {V} vertices")
    if not np.all(np.isfinite(arr)):
        raise GraspError(f"{name} must be finite")
    return arr


def _validate(sigma0, k, graph, start, sigma_L, mode) -> _Problem:
    choose(mode, MODES, "mode", GraspError)
    pairs = getattr(graph, "pairs", None)
    if pairs is None or getattr(graph, "edges", None) is None:
        raise GraspError("graph must be a ContactGraph (with .pairs and .edges)")
    V = len(pairs)
    sigma0 = _as_vector("sigma0", sigma0, V)
    k = _as_vector("k", k, V)
    if np.any(sigma0 < 0):
        raise GraspError("sigma0 (rest distances, m) must be non-negative")
    if np.any(k <= 0):
        raise GraspError("k (pair stiffnesses, N/m) must be positive")
    if isinstance(start, (tuple, list, np.ndarray)) and np.size(start) == 2 \
            and hasattr(graph, "vertex_index"):
        a, b = np.asarray(start).ravel()
        start = graph.vertex_index(int(a), int(b))  # raises GraspError if not a vertex
    if isinstance(start, (bool, np.bool_)) or not isinstance(start, (int, np.integer)):
        raise GraspError(f"start must be a vertex index (int) or a node pair (a, b), "
                         f"got {start!r}")
    start = int(start)
    if not 0 <= start < V:
        raise GraspError(f"start={start} is out of range: the contact graph has {V} vertices")
    try:
        sigma_L = float(sigma_L)
    except (TypeError, ValueError) as err:
        raise GraspError(f"sigma_L must be a number (m), got {sigma_L!r}") from err
    if not math.isfinite(sigma_L):
        raise GraspError("sigma_L must be finite (m)")
    s0 = float(sigma0[start])
    if mode == "contracting":
        if not 0.0 <= sigma_L <= s0:
            raise GraspError(
                f"contracting grasp needs 0 <= sigma_L <= sigma0 = {s0:g} m, got sigma_L = "
                f"{sigma_L:g} m (clamp sigma_L at 0; for sigma_L > sigma0 use mode='expanding')")
        sign = 1.0
    else:
        if sigma_L < s0:
            raise GraspError(
                f"expanding grasp needs sigma_L >= sigma0 = {s0:g} m, got sigma_L = {sigma_L:g} m "
                f"(for sigma_L < sigma0 use mode='contracting')")
        sign = -1.0
    x0 = sign * sigma0
    lo, hi = sorted((sign * sigma_L, sign * s0))
    d = x0[start] - lo
    C = 0.5 * k[start] * d * d
    tol_x = pc.RTOL * max(abs(lo), abs(hi), hi - lo, 1e-300)
    tol_E = pc.RTOL * C
    return _Problem(x0, k, graph, start, lo, hi, sign, C, tol_x, tol_E)


# --------------------------------------------------------------------------- methods


def _tie_kinks(P: _Problem) -> np.ndarray:
    """Vertices whose kink can change an equilibrium: some neighbour is already 0 there.

    A curve is continuous at its kink, so the kink changes no strict order; it matters
    only where the vertex joins a neighbour that is already at 0 (contracting frame:
    ``x0_u ≤ x0_v``), creating a tie — an adjacent crossing at level 0.
    """
    e = np.asarray(P.graph.edges, dtype=np.int64).reshape(-1, 2)
    flag = np.zeros(P.x0.size, dtype=bool)
    u, v = e[:, 0], e[:, 1]
    flag[v[P.x0[u] <= P.x0[v]]] = True
    flag[u[P.x0[v] <= P.x0[u]]] = True
    return flag


#: Per contact graph, the crossings of all adjacent curves on the whole line and the
#: tie-kink flags of its last two curve sets (see :func:`_graph_events`).
_GRAPH_EVENTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_GRAPH_EVENTS_LOCK = threading.Lock()


def _graph_events(P: _Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Crossings of every pair of adjacent curves (all of them, any separation) and the
    tie-kink flags of :func:`_tie_kinks`.

    They depend on the graph and the curves ``(x0, k)`` only, not on the start or the
    range, so one computation serves every jaw pair of a part (a plan, or a loop over
    pairs); each call filters them to its range, which gives the very arrays
    ``adjacent_crossings(x0, k, edges, lo, hi)`` returns (same elementwise arithmetic,
    same order). Kept per graph object (weakly) for its last two curve sets.
    """
    with _GRAPH_EVENTS_LOCK:
        entries = _GRAPH_EVENTS.get(P.graph, [])
        for x0, k, xs, pairs, tie in entries:
            if np.array_equal(x0, P.x0) and np.array_equal(k, P.k):
                return xs, pairs, tie
    xs, pairs = pc.adjacent_crossings(P.x0, P.k, P.graph.edges, -np.inf, np.inf)
    tie = _tie_kinks(P)
    with _GRAPH_EVENTS_LOCK:
        _GRAPH_EVENTS[P.graph] = [(P.x0.copy(), P.k.copy(), xs, pairs, tie),
                                  *_GRAPH_EVENTS.get(P.graph, [])][:2]
    return xs, pairs, tie


def _static_breakpoints(P: _Problem) -> pc.EventTable:
    """Where ``U_A`` can jump: adjacent-vertex crossings and tie-creating kinks, merged.

    These are the only separations where the set of equilibrium vertices, or whether
    the start is a strict minimum, can change.  The ends of the range are included.
    """
    xs_all, pairs_all, tie = _graph_events(P)
    with np.errstate(invalid="ignore"):
        inside = (xs_all >= P.lo) & (xs_all <= P.hi)
    xs, pairs = xs_all[inside], pairs_all[inside]
    kx, kv = pc.kinks_in(P.x0, P.lo, P.hi)
    keep = tie[kv]
    return pc.merge_breakpoints(xs, pairs, kx[keep], kv[keep], P.lo, P.hi, P.tol_x)


def _sweep_exact(P: _Problem) -> tuple[list[pc.Breakpoint], list[_Eval], list[_Piece]]:
    """Our exact method: visit only breakpoints that can change ``U_A`` (SPEC §4).

    Candidate events are the crossings of *adjacent* vertices' curves and the kinks
    that create a tie with a neighbour at 0 (only there can the set of equilibria or
    the strictness of the start change; O(E), precomputed), and the crossings of the
    current saddle's curve ``U_w`` with any other curve (found on the fly, vectorised
    over all vertices, O(V)).  The range is swept: at a probe point ``m`` inside an
    unexplored interval, ``release_energy`` gives the saddle ``w``; the piece around
    ``m`` extends to the nearest *relevant* events on either side, those ends are
    evaluated by definition, and the rest of the interval is swept likewise.

    Why ``w`` stays the bottleneck on the piece: let ``A = {v : U_v ≤ U_w}`` and
    ``B = {v : U_v < U_w}``.  With no curve crossing ``U_w`` both sets are fixed.  The
    equilibrium status of a vertex of ``A`` depends only on its neighbours in ``A``
    (the others lie above ``U_w``), so it changes only at a crossing of two adjacent
    vertices of ``A`` or a tie-creating kink in ``A``; the same holds for the
    strictness of the start (``s ∈ B``).  With none of those either, the component of
    the start in ``A`` still holds another equilibrium while its component in ``B``
    (and at every lower level) holds none: ``U_A = U_w − U_s`` is one quadratic.
    Adjacent crossings *above* ``U_w`` cannot change ``U_A`` and are skipped (a
    refinement of SPEC §4's list).  Where the start is not a strict minimum
    (``U_A = 0``) only crossings of the start with its neighbours matter; where no
    other equilibrium is reachable (``U_A = ∞``) every adjacent crossing does.
    Crossings of the start's curve ``U_s`` with non-adjacent curves, listed by SPEC
    §4, cannot change ``U_A`` either (``s`` is in ``B`` on both sides and ``U_s`` is
    one quadratic on the whole range), so they are not visited; the test suite checks
    the result against the paper's all-crossings method.
    """
    return _ExactSweep(P).run()


class _ExactSweep:
    """State of :func:`_sweep_exact`: the static events, the breakpoints visited with
    their evaluations, and the pieces found."""

    def __init__(self, P: _Problem) -> None:
        self.P = P
        self.static = static = _static_breakpoints(P)
        self.sx = static.x
        self.memb_bp, self.memb_v = static.members()  # for the relevance filter
        self.involves_s = np.zeros(len(static), dtype=bool)
        gp = np.repeat(np.arange(len(static)), np.diff(static.pair_ptr))
        self.involves_s[gp[np.any(static.pairs == P.s, axis=1)]] = True
        self.tol = P.tol_x
        self._w_cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        first, last = static.breakpoint(0), static.breakpoint(len(static) - 1)
        self.bps: list[pc.Breakpoint] = [first, last]
        self.evals: list[_Eval] = [P.eval_bp(first), P.eval_bp(last)]
        self.pieces: list[_Piece] = []

    def w_crossings(self, w: int, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
        """Crossings of U_w with every curve in (a, b); all of them computed once per w."""
        if w not in self._w_cache:
            self._w_cache[w] = pc.curve_crossings(w, self.P.x0, self.P.k, self.P.lo, self.P.hi)
        xs, vs = self._w_cache[w]
        i, j = np.searchsorted(xs, [a, b], side="right")
        return xs[i:j], vs[i:j]

    def events(self, a: float, b: float, U: np.ndarray, kind: str, w: int | None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Events in ``(a, b)`` that can end the piece of the saddle ``w``: indices of
        relevant static breakpoints, and crossings of ``U_w`` (positions, vertex pairs)."""
        tol, sx = self.tol, self.sx
        i0 = int(np.searchsorted(sx, a + tol, side="right"))
        i1 = int(np.searchsorted(sx, b - tol, side="left"))
        st_idx = np.arange(i0, i1)
        dx = np.empty(0)
        dpairs = np.empty((0, 2), dtype=np.int64)
        if kind == "zero":               # only the start's crossings with its neighbours
            st_idx = st_idx[self.involves_s[i0:i1]]
        elif kind == "finite":           # adjacent crossings at or below U_w, and U_w's own
            j0, j1 = np.searchsorted(self.memb_bp, [i0, i1])
            A = U <= U[w]
            st_idx = np.unique(self.memb_bp[j0:j1][A[self.memb_v[j0:j1]]])
            dx, dv = self.w_crossings(w, a + tol, b - tol)
            dpairs = np.stack([np.full(dv.size, w), dv], axis=1).astype(np.int64)
        return st_idx, dx, dpairs

    def add_breakpoint(self, x: float, st_idx: np.ndarray, dx: np.ndarray,
                       dpairs: np.ndarray) -> float:
        """Visit the breakpoint at ``x`` (static and dynamic events within ``tol``
        merged), evaluate ``U_A`` there by definition; returns its position."""
        static, sx, tol = self.static, self.sx, self.tol
        near_s = st_idx[np.abs(sx[st_idx] - x) <= tol]
        near_d = np.abs(dx - x) <= tol
        pairs = [dpairs[near_d]] + [static.breakpoint(i).pairs for i in near_s]
        kinks = [np.empty(0, np.int64)] + [static.breakpoint(i).kinks for i in near_s]
        pos = float(sx[near_s[0]]) if near_s.size else float(x)
        bp = pc.Breakpoint(pos, np.concatenate(pairs).reshape(-1, 2), np.concatenate(kinks),
                           static=bool(near_s.size))
        self.bps.append(bp)
        self.evals.append(self.P.eval_bp(bp))
        return bp.x

    def step(self, a: float, b: float) -> list[tuple[float, float]]:
        """Probe the middle of ``(a, b)``; record the piece around it and its ending
        breakpoints; return the intervals left to sweep."""
        P, tol = self.P, self.tol
        m = 0.5 * (a + b)
        U = pc.energies(m, P.x0, P.k)
        rel = P.release(U)
        kind, w, _ = P.classify(rel)
        if b - a <= 4 * tol:
            self.pieces.append(_Piece(a, b, kind, w, rel))
            return []
        st_idx, dx, dpairs = self.events(a, b, U, kind, w)
        ev = np.concatenate([self.sx[st_idx], dx])
        if ev.size == 0:
            self.pieces.append(_Piece(a, b, kind, w, rel))
            return []
        if np.any(np.abs(ev - m) <= tol):
            # The probe sits on an event: the saddle may be valid on one side only.
            x = self.add_breakpoint(float(ev[np.argmin(np.abs(ev - m))]), st_idx, dx, dpairs)
            return [(x, b), (a, x)]
        left_e, right_e = ev[ev < m], ev[ev > m]
        left, right = a, b
        todo = []
        if right_e.size:
            right = self.add_breakpoint(float(right_e.min()), st_idx, dx, dpairs)
            todo.append((right, b))
        if left_e.size:
            left = self.add_breakpoint(float(left_e.max()), st_idx, dx, dpairs)
            todo.append((a, left))
        self.pieces.append(_Piece(left, right, kind, w, rel))
        return todo

    def run(self) -> tuple[list[pc.Breakpoint], list[_Eval], list[_Piece]]:
        stack = [(self.P.lo, self.P.hi)]
        while stack:
            stack += self.step(*stack.pop())
        return self.bps, self.evals, self.pieces


def _sweep_paper(P: _Problem, max_breakpoints: int):
    """The paper's exact method (§4.5–4.6): every pairwise crossing and every kink.

    Between consecutive breakpoints the order of all vertex energies is fixed, so one
    probe per piece gives the saddle; O(V²) crossings, a reference for small parts.
    """
    xs, pairs = pc.all_crossings(P.x0, P.k, P.lo, P.hi, max_breakpoints)
    kx, kv = pc.kinks_in(P.x0, P.lo, P.hi)
    if xs.size + kx.size > max_breakpoints:
        raise GraspError(f"method='paper' needs more than max_breakpoints={max_breakpoints} "
                         f"breakpoints; use method='exact' or raise max_breakpoints")
    table = pc.merge_breakpoints(xs, pairs, kx, kv, P.lo, P.hi, P.tol_x)
    bps = [table.breakpoint(i) for i in range(len(table))]
    evals = [P.eval_bp(bp) for bp in bps]
    pieces = []
    for b0, b1 in zip(bps[:-1], bps[1:]):
        m = 0.5 * (b0.x + b1.x)
        rel = P.release(pc.energies(m, P.x0, P.k))
        kind, w, _ = P.classify(rel)
        pieces.append(_Piece(b0.x, b1.x, kind, w, rel))
    return bps, evals, pieces


@dataclass
class _Cand(Candidate):
    """A :class:`~deformclosure.landscape.optimum.Candidate` with what the report needs."""

    UA: float
    UL: float
    release: Any
    w: int | None


def _maximise(P: _Problem, bps, evals, pieces) -> tuple[_Cand | None, list]:
    """Closed-form maximisation of Q over all pieces plus the breakpoint values."""
    order = np.argsort([bp.x for bp in bps], kind="stable")
    bps = [bps[i] for i in order]
    evals = [evals[i] for i in order]
    pieces = sorted(pieces, key=lambda p: p.a)
    if len(pieces) != len(bps) - 1 or any(
            p.a != b0.x or p.b != b1.x for p, b0, b1 in zip(pieces, bps[:-1], bps[1:])):
        raise RuntimeError("internal error: pieces and breakpoints do not tile the range")
    best: _Cand | None = None
    for e in evals:
        c = _Cand(e.Q, e.x, True, e.UA, e.UL, e.release, e.w)
        if better(c, best):  # contracting frame: σ0 is the upper end
            best = c
    limits = []  # per piece: (U_A at a+, U_A at b-)
    for i, p in enumerate(pieces):
        xc = pc.piece_candidates(p.a, p.b, p.w, p.kind, P.s, P.x0, P.k, P.C)
        UA, Q, UL = pc.piece_quality(xc, p.w, p.kind, P.s, P.x0, P.k, P.C)
        limits.append((float(UA[0]), float(UA[-1])))
        for j, x in enumerate(xc):
            end = 0 if x == p.a else (1 if x == p.b else -1)
            if end >= 0:
                # A one-sided limit: attained if the value at the breakpoint reaches it.
                e = evals[i + end]
                if e.Q >= Q[j] - P.tol_E:
                    continue
                c = _Cand(float(Q[j]), float(x), False, float(UA[j]), float(UL[j]), p.release, p.w)
            else:
                c = _Cand(float(Q[j]), float(x), True, float(UA[j]), float(UL[j]), p.release, p.w)
            if better(c, best):  # contracting frame: σ0 is the upper end
                best = c
    # Jumps of U_A at interior breakpoints (x order; converted to σ order by the caller).
    jumps = []
    for i in range(1, len(bps) - 1):
        left, right, val = limits[i - 1][1], limits[i][0], evals[i].UA
        if not (_close(left, val, P.tol_E) and _close(right, val, P.tol_E)):
            jumps.append((bps[i].x, left, val, right))
    return best, jumps, (bps, evals, pieces)


def _close(a: float, b: float, tol: float) -> bool:
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= tol + pc.RTOL * max(abs(a), abs(b))


def _approx(P: _Problem, eps: float, lam: float, max_samples: int, grid: str):
    """ε-approximation (paper §4.7) made valid in spite of the jumps of ``U_A``.

    ``Q`` is λ-Lipschitz on every interval between static breakpoints (adjacent-vertex
    crossings and tie-creating kinks), where it is continuous: ``|d(U_w − U_s)/dσ| ≤
    max(k_w|σ0_w−σ|, k_s|σ0_s−σ|) ≤ λ`` and ``|dU_L/dσ| ≤ λ``.  The paper samples the
    plain lattice ``σ_j = j·ξ``, ``ξ = ε/λ`` (``grid="lattice"``): a supremum in (or
    approached at the end of) a continuity piece that holds a lattice point is within
    ``λξ = ε`` of it, but a piece shorter than ξ between two jumps may hold none, and
    its supremum can then be missed by more than ε — the paper assumed ``U_A``
    continuous.  ``grid="pieces"`` (default) cuts every interval between static
    breakpoints into cells of length ≤ ξ and samples the cell *centres*, so each point
    — and each one-sided limit at a jump — is within ξ/2 of a sample on its own side:
    ``Q* − Q(σ_ε) ≤ λξ/2 = ε/2 ≤ ε`` always.  The interior breakpoints themselves need
    no evaluation: at a tie the equilibrium set contains the limits of both sides and
    strictness can only be lost, so ``Q`` there is at most either one-sided limit.  The
    two ends of the range are evaluated too (e.g. ``Q = U_L`` peaks at ``σ0`` when
    ``U_A`` is infinite).

    Returns the evaluated breakpoints, all evaluations, ξ and the number of static
    breakpoints.
    """
    xi = eps / lam
    if not (math.isfinite(xi) and xi > 0):
        raise GraspError(f"method='approx' with eps={eps:g} J: the step ε/λ = {xi:g} m is not a "
                         "usable length; use a larger eps or method='exact'")
    if grid == "lattice":
        s_lo, s_hi = sorted((P.sign * P.lo, P.sign * P.hi))  # the range in σ (m)
        j0, j1 = math.ceil(s_lo / xi), math.floor(s_hi / xi)
        if j1 - j0 + 1 > max_samples:
            raise GraspError(
                f"method='approx' with eps={eps:g} J needs {j1 - j0 + 1} evaluations of U_A "
                f"(step {xi:.3g} m), more than max_samples={max_samples}; use a larger eps, "
                f"method='exact', or raise max_samples")
        sig = np.arange(j0, j1 + 1) * xi
        sig = sig[(sig >= s_lo) & (sig <= s_hi)]
        return [], [P.eval_x(float(P.sign * s)) for s in sig], xi, 0
    static = _static_breakpoints(P)
    widths = np.diff(static.x)
    cells = np.maximum(1.0, np.ceil(widths / xi))      # float: no integer overflow
    total = float(cells.sum()) + 2
    if not total <= max_samples:
        raise GraspError(
            f"method='approx' with eps={eps:g} J needs {total:.3g} evaluations of U_A "
            f"(step {xi:.3g} m), more than max_samples={max_samples}; use a larger eps, "
            f"method='exact', or raise max_samples")
    counts = cells.astype(np.int64)
    ends = [static.breakpoint(0), static.breakpoint(len(static) - 1)]
    evals = [P.eval_bp(bp) for bp in ends]
    h = widths / counts
    xs = np.repeat(static.x[:-1], counts) + (np.arange(int(counts.sum())) - np.repeat(
        np.cumsum(counts) - counts, counts) + 0.5) * np.repeat(h, counts)
    for x in xs:
        evals.append(P.eval_x(float(x)))
    return ends, evals, xi, len(static)


# --------------------------------------------------------------------------- public


def lipschitz_constant(sigma0: np.ndarray, k: np.ndarray, sigma_L: float,
                       mode: str = "contracting") -> float:
    """``λ`` (N) of paper §4.7: a bound on ``|dU_v/dσ| = k_v |σ0_v − σ|`` of every vertex
    over the range — ``max k σ0`` (contracting, σ ≥ 0) or ``max k (σ_L − σ0)⁺``
    (expanding, σ ≤ σ_L)."""
    if mode == "contracting":
        return float(np.max(k * np.abs(sigma0)))
    return float(np.max(k * np.maximum(sigma_L - sigma0, 0.0)))


def optimize_separation_arrays(
    sigma0: np.ndarray,
    k: np.ndarray,
    graph: ContactGraph,
    start: int | tuple[int, int],
    sigma_L: float,
    *,
    mode: Literal["contracting", "expanding"] = "contracting",
    method: Literal["exact", "approx", "paper"] = "exact",
    eps: float | None = None,
    e_max: float | None = None,
    grid: Literal["pieces", "lattice"] = "pieces",
    lipschitz: float | None = None,
    max_breakpoints: int = 20_000, max_samples: int = 200_000, n_curve: int = 400,
) -> SeparationResult:
    """Optimal jaw separation ``σ* = argmax min(U_A, U_L)`` (paper §4.5–4.7, SPEC §4).

    Parameters
    ----------
    sigma0, k : ndarray, shape (V,)
        Rest distance (m) and pair stiffness (N/m, positive) of every contact-graph vertex.
    graph : ContactGraph
        Contact graph whose vertex ``i`` is the pair with ``sigma0[i]``, ``k[i]``.
    start : int or (int, int)
        Vertex index of the jaw pair ``{n0, n1}``, or the node pair itself.
    sigma_L : float
        Elastic-limit separation (m): ``0 ≤ σ_L ≤ σ0_s`` contracting, ``≥ σ0_s`` expanding.
    mode : {"contracting", "expanding"}
    method : {"exact", "approx", "paper"}
        ``"exact"``: the sweep of :func:`_sweep_exact`; ``"paper"``: every pairwise
        crossing (reference, small parts; ``max_breakpoints``); ``"approx"``: the
        ε-approximation of §4.7, ``Q* − Q(σ_ε) ≤ ε`` (see the module docstring).
    eps, e_max : float, optional
        ε (J), required by ``"approx"``; strain per unit jaw displacement (1/m), recorded.
    grid : {"pieces", "lattice"}
        Samples of ``"approx"``: cells ≤ ξ between the jumps of ``U_A``, or the paper's
        lattice ``σ_j = j·ξ`` (no guarantee on pieces shorter than ξ; :func:`_approx`).
    lipschitz : float, optional
        λ (N) instead of :func:`lipschitz_constant` (e.g. one λ for all pairs of a part).
    max_breakpoints, max_samples : int
        Largest number of breakpoints (``"paper"``) / ``U_A`` evaluations (``"approx"``).
    n_curve : int
        Number of uniform samples in ``result.curve``.

    Returns
    -------
    SeparationResult
        ``quality = sup Q`` (conventions: module docstring).

    Raises
    ------
    GraspError
        Bad options or arrays, ``sigma_L`` on the wrong side of ``sigma0[start]``, too
        many breakpoints/samples.

    Examples
    --------
    Path graph ``0 – 1 – 2``, vertex 1 the saddle, so ``U_A = U_1 − U_0``; ``k = 1``,
    ``σ_L = 0``, ``σ0 = (a, c, ·)``: ``σ* = c − a``, ``Q* = ½ (c − a)(3a − c)``:

    >>> from deformclosure.grasp.contact_graph import ContactGraph
    >>> g = ContactGraph.from_edges([[0, 1], [0, 2], [1, 2]], [[0, 1], [1, 2]])
    >>> r = optimize_separation_arrays([1.0, 1.2, 0.1], [1.0, 1.0, 1.0], g, 0, 0.0)
    >>> round(r.sigma_star, 12), round(r.quality, 12), r.escape_path.tolist()
    (0.2, 0.18, [0, 1, 2])
    """
    eps = _checked_options(method, eps, e_max, grid, lipschitz, max_breakpoints, max_samples)
    P = _validate(sigma0, k, graph, start, sigma_L, mode)
    common = dict(sigma_L=float(sigma_L), sigma0=float(np.asarray(sigma0, dtype=float)[P.s]),
                  k01=float(P.k[P.s]), method=method, epsilon=eps if method == "approx" else None,
                  mode=mode, e_max=None if e_max is None else float(e_max))
    if P.hi - P.lo <= 4 * P.tol_x:  # degenerate range: Q ≡ 0
        return SeparationResult(None, 0.0, 0.0, False, 0.0, n_evaluations=0, n_breakpoints=0,
                                jumps=[], saddle=None, escape_path=None,
                                curve={"sigma": [], "U_A": [], "U_L": [], "Q": []},
                                attained=False, n_pieces=0, **common)
    sol = _solve(P, method, eps, lipschitz, np.asarray(sigma0, dtype=float), float(sigma_L),
                 mode, int(max_breakpoints), int(max_samples), grid, n_curve)
    return _result(P, sol, common)


def _checked_options(method, eps, e_max, grid, lipschitz, max_breakpoints, max_samples
                     ) -> float | None:
    """Refuse bad options of :func:`optimize_separation_arrays`; ``eps`` as a float."""
    choose(method, METHODS, "method", GraspError)
    if eps is not None:
        try:
            eps = float(eps)
        except (TypeError, ValueError) as err:
            raise GraspError(f"eps must be a number of joules, got {eps!r}") from err
        if not math.isfinite(eps) or eps <= 0:
            raise GraspError(f"eps must be finite and positive (J), got {eps!r}")
    if method == "approx" and eps is None:
        raise GraspError("method='approx' needs eps (J), the allowed loss of quality")
    if e_max is not None and not (math.isfinite(float(e_max)) and float(e_max) >= 0):
        raise GraspError(f"e_max must be finite and non-negative (1/m), got {e_max!r}")
    choose(grid, GRIDS, "grid", GraspError)
    if lipschitz is not None and not (isinstance(lipschitz, (int, float, np.floating))
                                      and math.isfinite(lipschitz) and lipschitz > 0):
        raise GraspError(f"lipschitz must be a finite positive slope (N), got {lipschitz!r}")
    if int(max_breakpoints) < 1 or int(max_samples) < 1:
        raise GraspError("max_breakpoints and max_samples must be positive")
    return eps


@dataclass
class _Solution:
    """What a method found: the best candidate (``None``: Q ≡ 0 on the samples), the jumps
    of ``U_A`` (contracting frame), counts, the curve, and λ and ξ of ``"approx"``."""

    best: _Cand | None
    jumps_x: list
    n_breakpoints: int
    n_pieces: int
    curve: dict
    lam: float | None = None
    xi: float | None = None


def _solve(P: _Problem, method: str, eps: float | None, lipschitz: float | None,
           sigma0: np.ndarray, sigma_L: float, mode: str, max_breakpoints: int,
           max_samples: int, grid: str, n_curve: int) -> _Solution:
    """Run ``method`` on the problem ``P`` (non-degenerate range)."""
    if method == "approx":
        lam = float(lipschitz) if lipschitz is not None else \
            lipschitz_constant(sigma0, P.k, sigma_L, mode)
        ends, evals, xi, n_static = _approx(P, eps, lam, max_samples, grid)
        best = None
        for e in evals:
            c = _Cand(e.Q, e.x, True, e.UA, e.UL, e.release, e.w)
            if better(c, best):  # contracting frame: σ0 is the upper end
                best = c
        # n_breakpoints: those that split the grid; n_pieces: interior samples
        return _Solution(best, [], n_static, len(evals) - len(ends),
                         _curve_from_samples(P, evals, n_curve), lam, xi)
    if method == "exact":
        bps, evals, pieces = _sweep_exact(P)
    else:
        bps, evals, pieces = _sweep_paper(P, max_breakpoints)
    best, jumps_x, (bps, evals, pieces) = _maximise(P, bps, evals, pieces)
    curve = _curve_from_pieces(P, bps, evals, pieces, jumps_x, best, n_curve)
    return _Solution(best, jumps_x, len(bps), len(pieces), curve)


def _result(P: _Problem, sol: _Solution, common: dict) -> SeparationResult:
    """The :class:`SeparationResult` of a solution, back in σ (m)."""
    sign = P.sign
    # Jumps in σ order: for expanding grasps x = −σ reverses left and right.
    if sign > 0:
        jumps = [(float(x), l, v, r) for x, l, v, r in sol.jumps_x]
    else:
        jumps = [(float(-x), r, v, l) for x, l, v, r in reversed(sol.jumps_x)]
    counts = dict(n_evaluations=P.n_eval, n_breakpoints=sol.n_breakpoints, jumps=jumps,
                  curve=sol.curve, n_pieces=sol.n_pieces, lipschitz=sol.lam, step=sol.xi)
    best = sol.best
    if best is None or not best.Q > 0.0:
        return SeparationResult(None, 0.0, 0.0, False, 0.0, saddle=None, escape_path=None,
                                attained=False, **counts, **common)
    rel = best.release
    saddle = best.w
    path = None
    if saddle is not None and getattr(rel, "path", None) is not None:
        path = np.asarray(rel.path, dtype=np.int64)
    saddle_pair = None
    if saddle is not None:
        saddle_pair = tuple(int(v) for v in np.asarray(P.graph.pairs)[saddle])
    UA_inf = math.isinf(best.UA)
    return SeparationResult(
        sigma_star=float(sign * best.x), quality=float(best.Q),
        U_A=None if UA_inf else float(best.UA), U_A_infinite=UA_inf, U_L=float(best.UL),
        saddle=saddle, escape_path=path, attained=best.attained, saddle_pair=saddle_pair,
        **counts, **common)


def _curve_lists(P: _Problem, x, UA, UL, Q) -> dict:
    x, UA, UL, Q = (np.asarray(v, dtype=float) for v in (x, UA, UL, Q))
    order = np.argsort(P.sign * x, kind="stable")

    def lst(a):
        return [float(v) if math.isfinite(v) else None for v in a[order]]

    return {"sigma": lst(P.sign * x), "U_A": lst(UA), "U_L": lst(UL), "Q": lst(Q)}


def _curve_from_pieces(P: _Problem, bps, evals, pieces, jumps_x, best, n) -> dict:
    """Uniform samples from the closed-form pieces, plus jump points and σ* (no evaluations)."""
    xs = np.linspace(P.lo, P.hi, max(int(n), 2))
    starts = np.array([p.a for p in pieces])
    bx = np.array([bp.x for bp in bps])
    out_x, out_UA, out_UL, out_Q = [], [], [], []
    on_bp = {float(bp.x): e for bp, e in zip(bps, evals)}
    for x in xs:
        e = on_bp.get(float(x))
        if e is None:
            p = pieces[max(0, int(np.searchsorted(starts, x, side="right")) - 1)]
            UA, Q, UL = pc.piece_quality(x, p.w, p.kind, P.s, P.x0, P.k, P.C)
            out_x.append(x), out_UA.append(float(UA)), out_UL.append(float(UL)), out_Q.append(float(Q))
        else:
            out_x.append(x), out_UA.append(e.UA), out_UL.append(e.UL), out_Q.append(e.Q)
    extra = [j[0] for j in jumps_x] + ([best.x] if best is not None else [])
    for x in extra:
        i = int(np.searchsorted(bx, x))
        if i < len(bps) and bps[i].x == x:
            e = evals[i]
            vals = (e.UA, e.UL, e.Q)
        else:
            p = pieces[max(0, int(np.searchsorted(starts, x, side="right")) - 1)]
            UA, Q, UL = pc.piece_quality(x, p.w, p.kind, P.s, P.x0, P.k, P.C)
            vals = (float(UA), float(UL), float(Q))
        out_x.append(x), out_UA.append(vals[0]), out_UL.append(vals[1]), out_Q.append(vals[2])
    return _curve_lists(P, out_x, out_UA, out_UL, out_Q)


def _curve_from_samples(P: _Problem, evals, n) -> dict:
    """The approximation's own samples (thinned to about ``n``), no extra evaluations."""
    ev = sorted(evals, key=lambda e: e.x)
    if len(ev) > n:
        idx = np.unique(np.linspace(0, len(ev) - 1, n).round().astype(int))
        ev = [ev[i] for i in idx]
    return _curve_lists(P, [e.x for e in ev], [e.UA for e in ev], [e.UL for e in ev],
                        [e.Q for e in ev])


def quality_at(sigma: float | np.ndarray, sigma0: np.ndarray, k: np.ndarray,
               graph: ContactGraph, start: int | tuple[int, int], sigma_L: float,
               mode: Literal["contracting", "expanding"] = "contracting",
               ) -> tuple[float | np.ndarray, float | np.ndarray, float | np.ndarray]:
    """``Q``, ``U_A`` and ``U_L`` at given separations, by definition (J).

    One ``release_energy`` call per separation: meant for tests and plots.

    Parameters
    ----------
    sigma : float or ndarray, shape (n,)
        Separations (m) inside the range ``[σ_L, σ0_s]`` (contracting) or
        ``[σ0_s, σ_L]`` (expanding).
    sigma0, k, graph, start, sigma_L, mode
        As in :func:`optimize_separation_arrays`.

    Returns
    -------
    Q, U_A, U_L : float or ndarray, shape (n,)
        ``U_A`` is ``inf`` where no other equilibrium is reachable.

    Raises
    ------
    GraspError
        Bad inputs, or a separation outside the range.
    """
    P = _validate(sigma0, k, graph, start, sigma_L, mode)
    sig = np.asarray(sigma, dtype=float)
    x = P.sign * np.atleast_1d(sig).ravel()
    if x.size and (not np.all(np.isfinite(x)) or x.min() < P.lo - P.tol_x or x.max() > P.hi + P.tol_x):
        raise GraspError("quality_at: every sigma must lie in the separation range "
                         f"[{min(P.sign * P.lo, P.sign * P.hi):g}, "
                         f"{max(P.sign * P.lo, P.sign * P.hi):g}] m")
    out = np.empty((3, x.size))
    for i, xi in enumerate(x):
        e = P.eval_x(float(xi))
        out[:, i] = (e.Q, e.UA, e.UL)
    if sig.ndim == 0:
        return float(out[0, 0]), float(out[1, 0]), float(out[2, 0])
    return out[0].reshape(sig.shape), out[1].reshape(sig.shape), out[2].reshape(sig.shape)
