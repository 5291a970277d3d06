"""Grasp planning: every jaw pair's optimal separation and quality, each within ε.

For every pair ``s`` of perimeter nodes the quality is ``Q_s(σ) = min(U_A(s, σ),
U_L(s, σ))`` on ``[σ_L(s), σ0(s)]`` (contracting; SPEC §4). The planner reports, for
*every* pair, a quality ``Q`` that was attained (a lower bound of the pair's optimum
``Q*``) and a proven upper bound ``Q⁺`` with ``Q ≤ Q* ≤ Q⁺ ≤ Q + ε``; the ranking by
``Q`` is therefore correct up to ε. It does so in three steps.

1. **Where Q can be positive — exactly, for all pairs.** ``U_A(s, σ) > 0`` only where
   ``s`` is a strict local minimum (``U_s < U_w`` for all its neighbours ``w``). That
   order changes only where ``U_s`` crosses a neighbour's curve, so the *strict spans*
   of every pair follow from its O(degree) adjacent crossings and one comparison per
   span. A pair with no strict span has ``Q ≡ 0`` (settled ``"zero"``): typically
   98–99 % of all pairs, certified without sampling.
2. **A coarse shared lattice.** The paper's lattice ``σ_j = j·ξ`` (§4.7) is swept for
   all pairs at once (one union–find sweep per σ gives every pair's ``U_A``,
   :func:`~deformclosure.grasp.release.release_energies`), ``ξ = ε/λ`` with the global
   ``λ = max k_v σ0_v``, but never more than about ``n_sigma`` values: a fine ε is
   reached in step 3, not by a finer shared lattice. ``lattice_quality`` is its value.
3. **Per-pair bounds, refined where they can still change the answer.** On a strict
   span ``Q = G − U_s`` with ``G = min(B, C)``, ``B`` the minimax escape level and
   ``C = U_s(σ_L)``. No vertex energy rises with σ (contracting frame), so if an
   equilibrium ``e`` stays reachable on a cell ``[x, y]`` — its energy is 0, or it has no
   adjacent crossing in the cell, or descending from it can never reach ``s`` — the
   minimax path ``P`` from ``s`` to ``e`` at ``x`` bounds the escape on the whole cell,
   jumps of ``U_A`` included: ``B(σ) ≤ max_{v∈P} U_v(σ)``. ``B`` and ``P`` come from one
   run of the package's one compiled minimax search
   (:func:`~deformclosure.landscape.kernels.minimax_search`) over the cell's energy
   bounds ``[U_v(y), U_v(x)]`` (:class:`_Cell`). The supremum over the cell
   of ``max_{v∈P} min(U_v, C) − U_s`` (piecewise quadratic, closed form) is the cell's
   bound — exact where ``P`` is the escape path of the whole cell, with a slack of the
   order of the pair's own energy change ``U_s(x) − U_s(y) ≤ k_s σ0_s (y − x)``
   otherwise, not of the global λ. The jumps that matter are only those of the
   equilibria the pair's escape uses, not every adjacent crossing (the jump-safe pieces
   of ``optimize --method approx``). Per pair, a branch and bound splits the cells whose
   bound exceeds ``best + ε`` where the bound peaks (:func:`_settle_pair`); a pair that
   does not settle within its budget of searches is solved by the exact method
   (``"exact"``), like the ``top`` pairs and the pairs whose curve agrees with a
   neighbour's to rounding (mirror images on a symmetric mesh).

Tolerances are the exact method's, per pair (breakpoints closer than ``1e-12 ×`` the
pair's separation scale are one), so the guarantee holds to rounding.

``e_max`` and ``σ_L`` of every pair come from the strain response to unit forces at
the perimeter DOFs (one block solve with the factorisation already built).

References
----------
K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure Grasps of Deformable
Parts", IJRR 24(11), 2005, §4.5–4.7.
"""

from __future__ import annotations

import heapq
import math
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple, Sequence

import numpy as np
import scipy.sparse as sp
from numba import njit

from ..elasticity.stiffness import element_b_matrices
from ..errors import GraspError
from ..grasp import pieces as pc
from ..landscape.kernels import (SearchWorkspace, is_strict_minimum, minimax_search, path_to,
                                 search_workspace, vertex_oracle)
from ..grasp.analysis import GraspAnalysis, GraspModel, grasp_model, optimize_separation
from ..grasp.elastic_limit import elastic_limit_separation
from ..grasp.release import release_energies
from ..grasp.separation import lipschitz_constant, optimize_separation_arrays, vertex_energies
from ..geometry import touch_tolerance
from ..limits import usable_cpus
from ..units import SI_UNITS

__all__ = ["PlanResult", "plan_grasps", "pair_elastic_limits", "lattice", "SETTLED"]

#: How a row of a plan was settled: ``"zero"`` (never a strict minimum: Q ≡ 0, exact),
#: ``"bounds"`` (sampled quality with a proven upper bound within ε), ``"exact"``
#: (the exact method of ``optimize --method exact``).
SETTLED = ("zero", "bounds", "exact")


def _workers() -> int:
    """Threads for the GIL-free kernels: the CPUs this process may use (at most 8)."""
    return min(usable_cpus(), 8)


# --------------------------------------------------------------------------- kernels
# Contracting frame throughout (x = σ, or x = −σ for expanding grasps, as in
# deformclosure.grasp.pieces): vertex v has the energy ½ k_v (x0_v − x)² for x < x0_v.


@njit(cache=True, nogil=True, inline="always")
def _e(x0v, kv, x):  # pragma: no cover - compiled
    d = x0v - x
    return 0.5 * kv * d * d if d > 0.0 else 0.0


@vertex_oracle
class _At(NamedTuple):
    """The vertex energies at one separation ``x`` (m, contracting frame), a point cell
    of the paper's landscape (:func:`deformclosure.landscape.kernels.vertex_oracle`)."""

    x0: np.ndarray
    k: np.ndarray
    x: float

    def energy(self, v):
        return _e(self.x0[v], self.k[v], self.x)

    def floor(self, v):
        return _e(self.x0[v], self.k[v], self.x)

    def kept(self, v):
        return True


@vertex_oracle
class _Cell(NamedTuple):
    """A cell ``[x, y]`` of separations (m, contracting frame), searched at ``x``.

    No vertex energy rises with σ, so ``U_v(x)`` is the largest energy of ``v`` over the
    cell and ``U_v(y)`` the smallest (its floor). An equilibrium at ``x`` stays one on
    the whole cell when its energy is 0 (energy 0 is never left) or none of its adjacent
    crossings (``cr_x[cr_ptr[v]:cr_ptr[v + 1]]``, sorted) lies in ``[wlo, whi]``, the cell
    shifted by the breakpoint tolerance.
    """

    x0: np.ndarray
    k: np.ndarray
    x: float
    y: float
    cr_ptr: np.ndarray
    cr_x: np.ndarray
    wlo: float
    whi: float

    def energy(self, v):
        return _e(self.x0[v], self.k[v], self.x)

    def floor(self, v):
        return _e(self.x0[v], self.k[v], self.y)

    def kept(self, v):
        if _e(self.x0[v], self.k[v], self.x) == 0.0:
            return True
        cr = self.cr_x[self.cr_ptr[v]:self.cr_ptr[v + 1]]
        return np.searchsorted(cr, self.wlo) == np.searchsorted(cr, self.whi, side="right")


@njit(cache=True, nogil=True, inline="always")
def _strict_at(indptr, indices, x0, k, s, x):  # pragma: no cover - compiled
    """Whether vertex ``s`` is below all its graph neighbours at σ = ``x`` (a strict local
    minimum of the vertex energies, SPEC §4)."""
    return is_strict_minimum(indptr, indices, _At(x0, k, x), s)


@njit(cache=True, nogil=True)
def _k_strict_spans(indptr, indices, x0, k, verts, lo, hi, cr_ptr, cr_x, tols,
                    out_i, out_a, out_b, out_ao, out_bo):  # pragma: no cover - compiled
    """Open spans of ``[lo_i, hi_i]`` where vertex ``verts[i]`` is a strict minimum.

    Strictness (``U_s < U_w`` for every neighbour ``w``) changes only at crossings of
    ``U_s`` with a neighbour's curve, listed in ``cr_x[cr_ptr[s]:cr_ptr[s + 1]]``;
    one comparison at the middle of each piece between them decides it. Pieces not
    longer than the pair's tolerance ``tols[i]`` (the exact method's: crossings closer
    than it are one breakpoint) are skipped. A span end is
    *open* (``out_ao``/``out_bo``) when it is such a crossing, closed when it is an end
    of the range. Returns the number of spans written.
    """
    n = 0
    for i in range(verts.shape[0]):
        s = verts[i]
        a0 = lo[i]
        b0 = hi[i]
        tol = tols[i]
        if b0 - a0 <= 4.0 * tol:
            continue
        c0 = cr_ptr[s]
        c1 = cr_ptr[s + 1]
        j0 = c0 + np.searchsorted(cr_x[c0:c1], a0 - tol)
        j1 = c0 + np.searchsorted(cr_x[c0:c1], b0 + tol, side="right")
        prev = a0
        prev_open = False
        for j in range(j0, j1 + 1):
            if j < j1:
                cur = min(max(cr_x[j], a0), b0)
                cur_open = True
            else:
                cur = b0
                cur_open = False
            if cur - prev > tol:
                m = 0.5 * (prev + cur)
                if _strict_at(indptr, indices, x0, k, s, m):
                    out_i[n] = i
                    out_a[n] = prev
                    out_b[n] = cur
                    out_ao[n] = prev_open
                    out_bo[n] = cur_open
                    n += 1
            prev = cur
            prev_open = cur_open
    return n


@njit(cache=True, nogil=True)
def _k_escape(indptr, indices, x0, k, s, x, y, cr_ptr, cr_x, wlo, whi, seen, done, best, pred,
              hk, hv, bseen, stack, ticket, epoch):  # pragma: no cover - compiled
    """Escape levels of start ``s`` at separation ``x``: ``(strict, B, B_stable, path)``.

    The one compiled minimax search,
    :func:`deformclosure.landscape.kernels.minimax_search`, on the cell ``[x, y]``
    (:class:`_Cell`: energies computed at ``x`` only where the search reaches, so that its
    work is the explored basin, not the graph). ``B`` is the level of the first
    equilibrium ``e ≠ s`` it settles — the release level, ``U_A = B − U_s`` when ``s`` is a
    strict minimum (``strict``). The search goes on to the first equilibrium ``e`` that
    keeps an equilibrium other than ``s`` within reach for every separation in ``[x, y]``:
    ``U_e(x) = 0``, or no adjacent crossing of ``e`` in ``[wlo, whi]`` (``e`` stays an
    equilibrium), or ``s`` outside the component of ``e`` in ``{v : U_v(y) ≤ U_e(x)}``
    (descending from ``e`` at any σ of the cell never reaches ``s``). Its level is
    ``B_stable ≥ B`` (J), and along the minimax path ``path`` (vertices, ``s`` first) to it
    ``B(σ) ≤ max_{v ∈ path} U_v(σ)`` for every σ of the cell, since no energy rises with
    σ. ``inf`` and an empty path where none is reachable. ``seen`` … ``ticket`` are the
    fields of the plan's :class:`~deformclosure.landscape.kernels.SearchWorkspace`
    (passed apart: unboxing a tuple costs more than the search), ``epoch`` this search's
    number.
    """
    cell = _Cell(x0, k, x, y, cr_ptr, cr_x, wlo, whi)
    ws = SearchWorkspace(seen, done, best, pred, hk, hv, bseen, stack, ticket)
    strict = is_strict_minimum(indptr, indices, cell, s)
    first, level, target = minimax_search(indptr, indices, cell, s, ws, epoch)
    return strict, first, level, path_to(ws.pred, target)


@njit(cache=True, nogil=True)
def _k_path_bound(path, x0, k, s, C, x, y):  # pragma: no cover - compiled
    """``sup`` over ``[x, y]`` of ``max_{v ∈ path} min(U_v, C) − U_s`` and where (J, m).

    Each term is piecewise quadratic in σ: its supremum lies at an end, at the
    stationary point of ``U_v − U_s``, where ``U_v = C`` or at the kink ``x0_v``. An
    empty path (no equilibrium reachable) gives ``U_L(y) = C − U_s(y)``.
    """
    if path.shape[0] == 0:
        return C - _e(x0[s], k[s], y), y
    top = -np.inf
    arg = x
    cand = np.empty(5)
    for i in range(path.shape[0]):
        v = path[i]
        if v == s:
            continue
        cand[0] = x
        cand[1] = y
        dk = k[v] - k[s]
        cand[2] = (k[v] * x0[v] - k[s] * x0[s]) / dk if dk != 0.0 else x
        cand[3] = x0[v] - np.sqrt(2.0 * C / k[v]) if C > 0.0 else x
        cand[4] = x0[v]
        for j in range(5):
            c = cand[j]
            if not (c >= x and c <= y):
                continue
            val = min(_e(x0[v], k[v], c), C) - _e(x0[s], k[s], c)
            if val > top:
                top = val
                arg = c
    return top, arg


class _Workspace:
    """Graph arrays, per-vertex crossing lists and reusable search buffers of one plan."""

    def __init__(self, graph, x0: np.ndarray, k: np.ndarray, cr_ptr: np.ndarray,
                 cr_x: np.ndarray, tol: float):
        self.all_x = np.sort(cr_x)
        self.indptr = np.ascontiguousarray(graph.indptr, dtype=np.int64)
        self.indices = np.ascontiguousarray(graph.indices, dtype=np.int64)
        self.x0 = np.ascontiguousarray(x0, dtype=float)
        self.k = np.ascontiguousarray(k, dtype=float)
        self.cr_ptr, self.cr_x, self.tol = cr_ptr, cr_x, float(tol)
        self.buf = search_workspace(len(self.x0), self.indices.shape[0])
        self.epoch = 0
        self.n_eval = 0

    def crossings_near(self, x: float, tol: float) -> tuple[bool, float]:
        """Whether some adjacent crossing lies within ``tol`` of ``x``, and the first one
        after ``x + tol`` (``inf`` if none)."""
        i0, i1 = np.searchsorted(self.all_x, [x - tol, x + tol], side="right")
        return bool(i1 > i0), (float(self.all_x[i1]) if i1 < len(self.all_x) else math.inf)

    def escape(self, s: int, x: float, y: float,
               tol: float) -> tuple[bool, float, float, np.ndarray]:
        """``(strict, B, B_stable, path)`` at ``x``, stability over ``[x, y]`` (see
        :func:`_k_escape`)."""
        self.epoch += 1
        self.n_eval += 1
        return _k_escape(self.indptr, self.indices, self.x0, self.k, s, x, y, self.cr_ptr,
                         self.cr_x, x - tol, y - tol, *self.buf, self.epoch)


def _crossing_lists(x0: np.ndarray, k: np.ndarray, edges: np.ndarray, lo: float, hi: float,
                    V: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Every adjacent crossing in ``[lo, hi]``, listed under both of its vertices (CSR,
    positions sorted per vertex)."""
    xs, prs = pc.adjacent_crossings(x0, k, edges, lo, hi)
    owner = np.concatenate([prs[:, 0], prs[:, 1]]).astype(np.int64)
    pos = np.concatenate([xs, xs])
    order = np.lexsort((pos, owner))
    cr_x = np.ascontiguousarray(pos[order])
    cr_ptr = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=V))]).astype(np.int64)
    return cr_ptr, cr_x, len(xs)


@dataclass
class _PairOutcome:
    Q: float              # best sampled quality (J), a lower bound of Q*
    x: float              # where (contracting frame), NaN if Q = 0
    B: float              # release level there (J), inf if unreachable
    upper: float          # proven upper bound of Q* (J)
    ok: bool              # settled within ε by bounds


class _PairSearch:
    """The branch and bound of :func:`_settle_pair` for one pair: its best sample, the
    heap of cells whose bound still exceeds ``best + ε``, and the bound of the cells
    settled so far (all in J, contracting frame)."""

    def __init__(self, ws: _Workspace, s: int, C: float, eps: float, lam: float,
                 tol: float) -> None:
        self.ws, self.s, self.C, self.eps, self.lam, self.tol = ws, s, C, eps, lam, tol
        self.x0s, self.ks = float(ws.x0[s]), float(ws.k[s])
        self.best = [0.0, math.nan, math.nan]            # Q, x, B
        self.start_evals = ws.n_eval
        self.delicate = False
        self.heap: list = []
        self.done_ub = 0.0
        self.counter = 0

    def evaluate(self, x: float, y: float, sample: bool = True) -> tuple[np.ndarray, float]:
        """Record Q(x) (if ``sample``); return the path that bounds G on [x, y], Q(x).

        A sample inside a strict span that is not a strict minimum means that ``U_s`` and
        a neighbour's curve agree to rounding (mirror-image pairs on a symmetric mesh):
        sampled energies cannot settle such a pair; the exact method does.
        """
        strict, B, _Bst, path = self.ws.escape(self.s, x, y, self.tol)
        Q = 0.0
        if strict:
            d = self.x0s - x
            Q = (B if B < self.C else self.C) - (0.5 * self.ks * d * d if d > 0.0 else 0.0)
            if sample and Q > self.best[0]:
                self.best[:] = Q, x, B
        elif sample:
            self.delicate = True
        return path, Q

    def push(self, x: float, y: float, path: np.ndarray, cap: float = math.inf) -> None:
        """Bound the cell ``[x, y]`` by ``path`` (at most ``cap``); keep it if it may still
        hold a quality above ``best + ε``."""
        ws = self.ws
        b, arg = _k_path_bound(path, ws.x0, ws.k, self.s, self.C, x, y)
        b = min(b, cap)
        if b <= self.best[0] + self.eps:
            self.done_ub = max(self.done_ub, b)
        else:
            self.counter += 1
            heapq.heappush(self.heap, (-b, self.counter, x, y, path, arg, cap))

    def seed(self, spans: list[tuple[float, float, bool, bool]], lat_x: np.ndarray) -> None:
        """The first cells: each strict span cut at the shared lattice values in it."""
        tol = self.tol
        for a, b, ao, bo in spans:
            j0, j1 = np.searchsorted(lat_x, [a + 2 * tol, b - 2 * tol])
            pts = [a, *(float(v) for v in lat_x[j0:j1]), b]
            for i in range(len(pts) - 1):
                push_path = self.evaluate(pts[i], pts[i + 1], sample=(i > 0 or not ao))[0]
                self.push(pts[i], pts[i + 1], push_path)
            if not bo:                                        # the closed end σ0 of the range,
                strict, B, _Bst, _p = self.ws.escape(self.s, b, b, tol)  # a tie at 0 is no surprise
                if strict and min(B, self.C) > self.best[0]:
                    self.best[:] = min(B, self.C), b, B

    def open(self, max_evals: int) -> bool:
        """Whether a cell may still beat ``best + ε`` and the budget allows a split."""
        return bool(self.heap and -self.heap[0][0] > self.best[0] + self.eps
                    and self.ws.n_eval - self.start_evals < max_evals and not self.delicate)

    def _split_point(self, x: float, y: float, arg: float, cap: float
                     ) -> tuple[float | None, str]:
        """Where to split ``[x, y]`` and how (:func:`_settle_pair`); ``None``: a sliver."""
        if math.isfinite(cap):                       # a sliver: nothing left to split
            return None, ""
        w = y - x
        if arg > x:                                  # where the bound peaks
            return min(max(arg, x + 0.125 * w), y - 0.125 * w), "peak"
        near, c_next = self.ws.crossings_near(x, self.tol)
        if not near:                                 # re-search x on a shorter cell
            return 0.5 * (x + y), "halve"
        return min(x + 32 * self.tol, 0.5 * (x + self.tol + c_next), 0.5 * (x + y)), "past"

    def split(self) -> bool:
        """Split the cell of the largest bound; ``False`` (cell kept) if it cannot be."""
        item = heapq.heappop(self.heap)
        _, _, x, y, path, arg, cap = item
        m, how = self._split_point(x, y, arg, cap)
        if m is None or not (x + 2 * self.tol < m < y - 2 * self.tol):   # too narrow
            heapq.heappush(self.heap, item)
            return False
        if how == "peak":
            self.push(x, m, path)                    # P stays valid on the left part
            self.push(m, y, self.evaluate(m, y)[0])
        elif how == "halve":
            self.push(x, m, self.evaluate(x, m, sample=False)[0])
            self.push(m, y, self.evaluate(m, y)[0])
        else:                                        # just past a crossing at x
            path_m, Qm = self.evaluate(m, y)
            self.push(x, m, path, cap=Qm + self.lam * (m - x))   # no crossing in (x + tol, m]
            self.push(m, y, path_m)
        return True

    def outcome(self) -> _PairOutcome:
        top = -self.heap[0][0] if self.heap else 0.0
        upper = max(self.best[0], self.done_ub, top)
        ok = (not self.heap or top <= self.best[0] + self.eps) and not self.delicate
        return _PairOutcome(self.best[0], self.best[1], self.best[2], upper, ok)


def _settle_pair(ws: _Workspace, s: int, C: float, eps: float, lam: float, tol: float,
                 spans: list[tuple[float, float, bool, bool]], lat_x: np.ndarray,
                 max_evals: int) -> _PairOutcome:
    """Branch and bound for one pair on its strict spans (contracting frame).

    A cell ``[x, y]`` of a strict span is bounded by the supremum over the cell of
    ``max_{v ∈ P} min(U_v, C) − U_s`` (:func:`_k_path_bound`), ``P`` the minimax path at
    ``x`` to an equilibrium that stays reachable on the whole cell (:func:`_k_escape`):
    ``B(σ) ≤ max_{v ∈ P} U_v(σ)`` there, jumps of ``U_A`` included. Where ``P`` is the
    escape path of the whole cell the bound is the cell's exact supremum. Cells whose
    bound exceeds ``best + ε`` are split where their bound peaks, best bound first.

    A bound that peaks at the left end ``x`` means the escape just after ``x`` differs
    from the one at ``x``: the left end is re-searched on the shorter cell. When a
    crossing sits at ``x`` itself (within the tolerance ``tol`` of the breakpoints), the
    next sample goes just past it, at ``m``, and the sliver ``(x, m]`` holds no
    crossing, so there ``G`` is continuous and ``Q ≤ Q(m) + λ (m − x)``, ``λ`` (N) the
    largest slope of any vertex energy.

    ``lat_x``: shared lattice separations inside the pair's range, the first samples.
    Returns the best sampled quality and the upper bound of ``sup Q``; ``ok`` is False
    when the budget ``max_evals`` (escape searches) ran out, or a cell became too
    narrow to split.
    """
    search = _PairSearch(ws, s, C, eps, lam, tol)
    search.seed(spans, lat_x)
    while search.open(max_evals) and search.split():
        pass
    return search.outcome()


@dataclass(frozen=True)
class PlanResult:
    """Quality of every jaw pair, each within ε of its optimum, ranked (SI units).

    Attributes
    ----------
    pairs : ndarray, shape (P, 2)
        Jaw node pairs considered (after the filters), in ranking order (best first).
    jaw_xy : ndarray, shape (P, 2, 2)
        Rest coordinates of the two jaw nodes of each pair (m).
    sigma0, k, e_max, sigma_L : ndarray, shape (P,)
        Rest distance (m), stiffness (N/m), strain per unit distance change (1/m) and
        elastic-limit separation (m) of each pair.
    sigma_star : ndarray, shape (P,)
        Separation where ``quality`` is attained (m), NaN where it is 0; the exact ``σ*``
        for the pairs settled by the exact method.
    quality, U_A, U_L : ndarray, shape (P,)
        Q, release energy (``inf`` possible) and elastic margin at ``sigma_star`` (J).
        ``quality ≤ Q* ≤ quality_upper ≤ quality + epsilon`` for every pair.
    quality_upper : ndarray, shape (P,)
        Proven upper bound of the pair's optimum ``Q*`` (J).
    settled : ndarray of str, shape (P,)
        How each row was settled, one of :data:`SETTLED`.
    lattice_quality : ndarray, shape (P,)
        Best Q on the coarse shared lattice (J), a lower bound.
    exact : ndarray of bool, shape (P,)
        The pair's values come from the exact method.
    pulls : ndarray of bool, shape (P,)
        The jaw line leaves the part at a jaw (the jaw would have to pull).
    epsilon, lipschitz, step : float
        ε (J) of the guarantee, global λ (N) and step ξ (m) of the shared lattice.
    n_sigma : int
        Number of shared lattice values (one all-vertices sweep each).
    refined : list of GraspAnalysis
        The ``top`` pairs (without pulling pairs unless ``allow_pulling``), re-optimised
        with the exact method, best first.
    allow_pulling : bool
        Whether pulling pairs may enter ``refined``.
    n_evaluations : int
        Escape-level evaluations of the per-pair refinement.
    mode : str
    jaw_width : float
    timings : dict

    Examples
    --------
    >>> from deformclosure import demo_part, mesh_part
    >>> plan = plan_grasps(mesh_part(demo_part(max_area_mm2=20.0)), top=0)
    >>> row = plan.to_dict()["pairs"][0]                   # the best pair
    >>> (row["a"], row["b"]) == tuple(plan.pairs[0]), row["quality"] == float(plan.quality[0])
    (True, True)
    """

    pairs: np.ndarray
    sigma0: np.ndarray
    k: np.ndarray
    e_max: np.ndarray
    sigma_L: np.ndarray
    sigma_star: np.ndarray
    quality: np.ndarray
    U_A: np.ndarray
    U_L: np.ndarray
    pulls: np.ndarray
    lattice_quality: np.ndarray
    exact: np.ndarray
    epsilon: float
    lipschitz: float
    step: float
    n_sigma: int
    refined: list = field(default_factory=list)
    mode: str = "contracting"
    jaw_width: float = 0.0
    timings: dict = field(default_factory=dict)
    model: GraspModel | None = None
    quality_upper: np.ndarray | None = None
    settled: np.ndarray | None = None
    jaw_xy: np.ndarray | None = None
    allow_pulling: bool = False
    n_evaluations: int = 0

    def settled_counts(self) -> dict[str, int]:
        """Number of rows settled each way (keys of :data:`SETTLED`)."""
        s = self.settled if self.settled is not None else np.array([], dtype=str)
        return {key: int(np.sum(s == key)) for key in SETTLED}

    def to_dict(self) -> dict[str, Any]:
        """JSON report (SPEC §5 "Plan report"); SI units, infinities as ``None``."""
        def f(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        rows = []
        for i in range(len(self.pairs)):
            rows.append({
                "a": int(self.pairs[i, 0]), "b": int(self.pairs[i, 1]),
                "sigma_star": f(self.sigma_star[i]),
                "quality": float(self.quality[i]),
                "U_A": f(self.U_A[i]), "U_A_infinite": bool(np.isinf(self.U_A[i])),
                "U_L": f(self.U_L[i]),
                "sigma0": float(self.sigma0[i]), "k": float(self.k[i]),
                "sigma_L": float(self.sigma_L[i]), "e_max": float(self.e_max[i]),
                "pulls": bool(self.pulls[i]),
                "method": "exact" if self.exact[i] else "approx-lattice",
                "lattice_quality": float(self.lattice_quality[i]),
                "quality_upper": float(self.quality_upper[i]),
                "settled": str(self.settled[i]),
                "jaw_positions": self.jaw_xy[i].tolist(),
            })
        nodes = self.model.mesh.nodes if self.model is not None else None
        top = []
        for r in self.refined:
            d = r.to_dict()
            top.append({"a": int(r.jaws[0]), "b": int(r.jaws[1]),
                        **{k: d[k] for k in ("sigma_star", "quality", "U_A", "U_A_infinite",
                                             "U_L", "sigma_L", "sigma0", "k01", "e_max",
                                             "method", "attained")},
                        "pulls": bool(d["pulls"]),
                        "jaw_positions": (nodes[list(r.jaws)].tolist() if nodes is not None
                                          else d["jaw_positions"])})
        return {
            "model": "paper",
            "pairs": rows,
            "top": top,
            "epsilon": float(self.epsilon),
            "lipschitz": float(self.lipschitz),
            "step": float(self.step),
            "n_sigma": int(self.n_sigma),
            "mode": self.mode,
            "jaw_width": float(self.jaw_width),
            "method": "approx-lattice",
            "energy_model": "linear",
            "units": dict(SI_UNITS),
            "timings_s": dict(self.timings),
            "guarantee": {
                "epsilon": float(self.epsilon),
                "rows": "every row: quality <= Q* <= quality_upper <= quality + epsilon "
                        "(to rounding), Q* = the pair's optimal quality (the supremum of "
                        "the exact method)",
                "ranking": "rows sorted by quality: a pair ranked below another has "
                           "Q* at most epsilon above the other's Q*",
            },
            "settled_counts": self.settled_counts(),
            "allow_pulling": bool(self.allow_pulling),
            "top_excludes_pulling": not self.allow_pulling,
            "n_evaluations": int(self.n_evaluations),
        }


def pair_elastic_limits(model: GraspModel, pairs_idx: np.ndarray,
                        elastic_limit_strain: float, max_bytes: float = 4e9
                        ) -> tuple[np.ndarray, np.ndarray]:
    """``e_max`` (1/m) and ``σ_L`` (m) of many graph vertices at once.

    The strain of every element under a unit force at every loaded perimeter DOF is
    ``T = B K⁺ E_b`` (one block solve with the model's factorisation); a jaw pair's
    strain per unit distance change is ``Σ_j λ_j T_j e`` over its contact nodes
    (``λ = ±k`` for point jaws), maximised over the elements by a compiled kernel.
    ``σ_L`` follows by :func:`~deformclosure.grasp.elastic_limit.elastic_limit_separation`,
    the formula of the single-pair :func:`~deformclosure.grasp.elastic_limit.elastic_limit`.

    Parameters
    ----------
    model : GraspModel
    pairs_idx : ndarray of int
        Graph vertices (jaw pairs).
    elastic_limit_strain : float
        ``e_L`` (-).
    max_bytes : float
        Memory allowed for ``T`` (bytes); a larger request raises ``GraspError``.
    """
    mesh = model.mesh
    pairs = model.graph.pairs[pairs_idx]
    e = mesh.nodes[pairs[:, 1]] - mesh.nodes[pairs[:, 0]]
    sig0 = np.linalg.norm(e, axis=1)
    e /= sig0[:, None]
    counts, loaded, weight = _jaw_loads(model, pairs, pairs_idx)
    nodes_used, pos = np.unique(loaded, return_inverse=True)
    from ..limits import check_strain_responses

    check_strain_responses(len(nodes_used), mesh.n_nodes, mesh.n_triangles, max_bytes)  # before T
    T = _unit_force_strains(mesh, model.condensed, nodes_used)
    e_max = _max_pair_strains(T, model.jaw_width, np.concatenate([[0], np.cumsum(counts)]), pos,
                              weight, e)
    return e_max, elastic_limit_separation(sig0, e_max, elastic_limit_strain, model.mode)


def _jaw_loads(model: GraspModel, pairs: np.ndarray, pairs_idx: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pair, its number of loaded nodes; all loaded nodes, pair by pair; and their
    forces (N per m of approach, along the pair's unit direction): ``+k`` at ``a`` and
    ``−k`` at ``b`` for point jaws, the patch forces of wide jaws."""
    if model.jaw_width:
        node_sets, forces = _wide_forces(model, pairs)
        counts = np.array([len(J) for J in node_sets], dtype=np.int64)
        loaded = np.concatenate([np.asarray(J, dtype=np.int64) for J in node_sets])
        weight = np.concatenate([np.asarray(f, dtype=float) for f in forces])
        return counts, loaded, weight
    counts = np.full(len(pairs), 2, dtype=np.int64)
    k = model.stiffness.k[pairs_idx]
    return counts, pairs.ravel().astype(np.int64), np.column_stack([k, -k]).ravel()


def _unit_force_strains(mesh, cc, nodes_used: np.ndarray) -> np.ndarray:
    """``T[P, 3c + j, i]``: strain component ``j`` of element ``i`` under a unit force at
    node ``nodes_used[P]`` in direction ``c`` (1/N; component-major, so the kernels'
    inner loops run over elements)."""
    q = len(nodes_used)
    n2 = 2 * mesh.n_nodes
    E = np.zeros((n2, 2 * q))
    E[2 * nodes_used, 2 * np.arange(q)] = 1.0
    E[2 * nodes_used + 1, 2 * np.arange(q) + 1] = 1.0
    # Unit forces at single DOFs are not self-equilibrated; the pinned solve adds
    # reactions at the pins, but every jaw-pair combination below is self-equilibrated,
    # so the reactions cancel and the strains are exact.
    X = cc.solve(E)                                            # (2n, 2q)
    del E
    B, _ = element_b_matrices(mesh.nodes, mesh.triangles)      # (m, 3, 6)
    tri_dofs = np.empty((mesh.n_triangles, 6), dtype=np.int64)
    tri_dofs[:, 0::2] = 2 * mesh.triangles
    tri_dofs[:, 1::2] = 2 * mesh.triangles + 1
    T = np.einsum("mij,mjr->rim", B, X[tri_dofs]).reshape(q, 6, mesh.n_triangles)
    del X
    return np.ascontiguousarray(T)


def _max_pair_strains(T: np.ndarray, jaw_width: float, ptr: np.ndarray, pos: np.ndarray,
                      weight: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Largest element strain magnitude of every pair (1/m), by the compiled kernels on
    chunks of pairs in threads (they release the GIL)."""
    from ._kernels import max_strain_magnitude, max_strain_point_jaws

    ex, ey = np.ascontiguousarray(e[:, 0]), np.ascontiguousarray(e[:, 1])
    e_max = np.empty(len(e))
    bounds = np.linspace(0, len(e), 8 * _workers() + 1).astype(np.int64)
    if jaw_width:
        def chunk(i: int) -> None:
            max_strain_magnitude(T, ptr, pos, weight, ex, ey, bounds[i], bounds[i + 1], e_max)
    else:
        pa, pb = np.ascontiguousarray(pos[0::2]), np.ascontiguousarray(pos[1::2])
        kk = np.ascontiguousarray(weight[0::2])

        def chunk(i: int) -> None:
            max_strain_point_jaws(T, pa, pb, kk, ex, ey, bounds[i], bounds[i + 1], e_max)
    with ThreadPoolExecutor(_workers()) as pool:
        list(pool.map(chunk, range(len(bounds) - 1)))
    return e_max


def _wide_forces(model: GraspModel, pairs: np.ndarray):
    from ..grasp.pair_stiffness import wide_jaw_forces

    _, sets, lam = wide_jaw_forces(model.mesh, model.condensed, pairs, model.jaw_width)
    return np.array(sets, dtype=object), np.array(lam, dtype=object)


def lattice(lo: float, hi: float, step: float, max_size: int | None = None) -> np.ndarray:
    """The ε-grid ``σ_j = j·step`` (m) inside ``[lo, hi]`` (paper §4.7).

    Raises ``GraspError`` when it would hold more than ``max_size`` values.
    """
    j0 = math.ceil(lo / step - 1e-9)
    j1 = math.floor(hi / step + 1e-9)
    if max_size is not None and j1 - j0 + 1 > max_size:
        raise GraspError(f"the step {step:.3g} m needs {j1 - j0 + 1} lattice values of σ, more than "
                         f"{max_size}; use a larger eps")
    return np.arange(j0, j1 + 1) * step


def _region_mask(mesh, regions: Sequence[Any] | None) -> np.ndarray | None:
    """Which nodes lie in the union of ``regions`` (within the SPEC's touching tolerance),
    ``None`` without regions."""
    if not regions:
        return None
    import shapely
    from shapely.geometry import box

    geoms = []
    for r in regions:
        if isinstance(r, (tuple, list)) and len(r) == 4:
            x0, y0, x1, y1 = map(float, r)
            if not (x0 < x1 and y0 < y1):
                raise GraspError(f"region {r!r}: expected (xmin, ymin, xmax, ymax) with min < max")
            geoms.append(box(x0, y0, x1, y1))
        elif hasattr(r, "geom_type"):
            geoms.append(r)
        else:
            raise GraspError(f"region {r!r}: give (xmin, ymin, xmax, ymax) in m or a shapely geometry")
    union = shapely.union_all(geoms)
    return shapely.dwithin(shapely.points(mesh.nodes), union, touch_tolerance(mesh.diameter))


def _check_plan_options(eps: float | None, top: int, max_evaluations: int) -> None:
    if eps is not None and not (math.isfinite(eps) and eps > 0):
        raise GraspError(f"eps = {eps!r}: must be a finite energy > 0 in joules")
    if not (isinstance(top, (int, np.integer)) and top >= 0):
        raise GraspError(f"top = {top!r}: must be a whole number >= 0")
    if not (isinstance(max_evaluations, (int, np.integer)) and max_evaluations >= 1):
        raise GraspError(f"max_evaluations = {max_evaluations!r}: must be a whole number >= 1")


def _selected_pairs(mesh, model: GraspModel, separation_range: tuple[float, float] | None,
                    regions: Sequence[Any] | None) -> np.ndarray:
    """Graph vertices kept by the separation-range and region filters."""
    graph, sigma0 = model.graph, model.stiffness.sigma0
    sel = np.ones(graph.n_vertices, bool)
    if separation_range is not None:
        lo_r, hi_r = map(float, separation_range)
        if not (math.isfinite(lo_r) and not math.isnan(hi_r) and 0 <= lo_r <= hi_r):
            raise GraspError(f"separation range {separation_range!r}: need 0 <= min <= max (m)")
        sel &= (sigma0 >= lo_r) & (sigma0 <= hi_r)
    rm = _region_mask(mesh, regions)
    if rm is not None:
        sel &= rm[graph.pairs[:, 0]] & rm[graph.pairs[:, 1]]
    idx = np.flatnonzero(sel)
    if not len(idx):
        raise GraspError("no jaw pair is left after the separation-range and region filters; widen them")
    return idx


def _shared_lattice(mode: str, sigma0: np.ndarray, k: np.ndarray, sigma_L: np.ndarray,
                    idx: np.ndarray, eps: float | None, n_sigma: int, max_sigma: int
                    ) -> tuple[float, float, float, np.ndarray]:
    """``λ`` (N), ε (J), step ξ (m) and values of the coarse shared lattice (paper §4.7).

    λ bounds the slope of every vertex energy, so of ``U_A = U_w − U_s`` and of
    ``U_L``, over the whole range; ε defaults to about ``n_sigma`` lattice values.
    """
    if mode == "contracting":
        lo, hi = float(sigma_L.min()), float(sigma0[idx].max())
    else:
        lo, hi = float(sigma0[idx].min()), float(sigma_L.max())
    lam = lipschitz_constant(sigma0, k, hi, mode)
    span = max(hi - lo, 1e-300)
    if eps is None:
        eps = lam * span / max(int(n_sigma), 1)
    step = max(eps / lam, span / max(int(n_sigma), 1))     # coarse: ≤ n_sigma + 1 values
    return lam, eps, step, lattice(lo, hi, step, max_size=max_sigma)


@dataclass
class _Spans:
    """Step 1 of the plan, in the contracting frame ``x = sign·σ``: per selected pair
    (position ``i`` in ``idx``) its range ``[x_lo, x_hi]``, ``C = U_s(σ_L)`` (J) and
    tolerance, and its strict spans ``(a, b)`` (open ends ``ao``/``bo``) grouped by
    pair, with the workspace of the escape searches."""

    sign: float
    x_lo: np.ndarray
    x_hi: np.ndarray
    C: np.ndarray
    tol: float
    tols: np.ndarray
    ws: _Workspace
    span_i: np.ndarray
    a: np.ndarray
    b: np.ndarray
    ao: np.ndarray
    bo: np.ndarray

    @property
    def strict_pairs(self) -> np.ndarray:
        """Positions in ``idx`` of the pairs with a strict span (the others: Q ≡ 0)."""
        return np.unique(self.span_i)

    def of_pair(self, n: int) -> list[tuple[float, float, bool, bool]]:
        """The strict spans of the ``n``-th pair of :attr:`strict_pairs`."""
        i = self.strict_pairs[n]
        j0, j1 = np.searchsorted(self.span_i, [i, i + 1])
        return [(float(self.a[j]), float(self.b[j]), bool(self.ao[j]), bool(self.bo[j]))
                for j in range(j0, j1)]


def _strict_spans(graph, sigma0: np.ndarray, k: np.ndarray, sigma_L: np.ndarray,
                  idx: np.ndarray, mode: str) -> _Spans:
    """Step 1: where each selected pair is a strict local minimum (module docstring)."""
    V = graph.n_vertices
    sign = 1.0 if mode == "contracting" else -1.0
    x0 = sign * sigma0
    x_lo, x_hi = sign * sigma_L, x0[idx]                 # each pair's range [x_lo, x_hi]
    C = 0.5 * k[idx] * (x_hi - x_lo) ** 2                # U_s(σ_L) per pair (J)
    g_lo, g_hi = float(x_lo.min()), float(x_hi.max())
    tol = pc.RTOL * max(abs(g_lo), abs(g_hi), g_hi - g_lo, 1e-300)
    # Per pair, the exact method's tolerance: breakpoints closer than it are one.
    tols = pc.RTOL * np.maximum.reduce([np.abs(x_lo), np.abs(x_hi), x_hi - x_lo,
                                        np.full(len(idx), 1e-300)])
    cr_ptr, cr_x, _n = _crossing_lists(x0, k, graph.edges, g_lo - tol, g_hi + tol, V)
    ws = _Workspace(graph, x0, k, cr_ptr, cr_x, tol)
    cap = int(np.sum(cr_ptr[idx + 1] - cr_ptr[idx])) + len(idx)
    out_i = np.empty(cap, np.int64)
    out_a, out_b = np.empty(cap), np.empty(cap)
    out_ao, out_bo = np.empty(cap, np.bool_), np.empty(cap, np.bool_)
    n = _k_strict_spans(ws.indptr, ws.indices, ws.x0, ws.k, idx.astype(np.int64),
                        np.ascontiguousarray(x_lo), np.ascontiguousarray(x_hi),
                        cr_ptr, cr_x, tols, out_i, out_a, out_b, out_ao, out_bo)
    return _Spans(sign, x_lo, x_hi, C, tol, tols, ws, out_i[:n], out_a, out_b, out_ao, out_bo)


@dataclass
class _Rows:
    """The plan's values per selected pair (position in ``idx``): quality, σ*, U_A, U_L
    and upper bound (SI), how each was settled, and whether by the exact method."""

    Q: np.ndarray
    s_star: np.ndarray
    UA: np.ndarray
    UL: np.ndarray
    upper: np.ndarray
    settled: np.ndarray
    exact: np.ndarray

    @classmethod
    def zeros(cls, n: int) -> "_Rows":
        return cls(np.zeros(n), np.full(n, np.nan), np.zeros(n), np.zeros(n), np.zeros(n),
                   np.full(n, "zero", dtype=object), np.zeros(n, bool))

    def set_exact(self, i: int, r) -> None:
        """Row ``i`` takes the exact method's values (``r`` a SeparationResult)."""
        self.Q[i] = r.quality
        self.upper[i] = r.quality
        self.s_star[i] = np.nan if r.sigma_star is None else r.sigma_star
        self.UA[i] = math.inf if r.U_A_infinite else (0.0 if r.U_A is None else r.U_A)
        self.UL[i] = r.U_L
        self.settled[i] = "exact"
        self.exact[i] = True


def _lattice_sweep(graph, sigma0: np.ndarray, k: np.ndarray, sigma_L: np.ndarray,
                   idx: np.ndarray, mode: str, grid: np.ndarray,
                   progress: Callable[[int, int], None] | None, total_steps: int) -> _Rows:
    """Step 2: the best ``Q`` of every selected pair on the shared lattice (its σ, U_A,
    U_L), one union–find sweep of all vertices per lattice value."""
    best = _Rows.zeros(len(idx))
    UsL = 0.5 * k[idx] * (sigma0[idx] - sigma_L) ** 2
    range_lo, range_hi = (sigma_L, sigma0[idx]) if mode == "contracting" else (sigma0[idx], sigma_L)

    def sweep(sig: float) -> tuple[np.ndarray, np.ndarray]:
        U = vertex_energies(sig, sigma0, k, mode)
        return release_energies(U, graph)[idx], UsL - U[idx]

    # The sweeps of different σ are independent and their kernels release the GIL: run
    # them on threads, fold the results in lattice order (deterministic ties).
    workers = _workers()
    with ThreadPoolExecutor(workers) as pool:
        for lo_j in range(0, len(grid), 4 * workers):
            block = grid[lo_j: lo_j + 4 * workers]
            for j, (sig, (R, UL)) in enumerate(zip(block, pool.map(sweep, block)), start=lo_j):
                inside = (sig >= range_lo) & (sig <= range_hi)
                Q = np.where(inside, np.minimum(R, UL), -np.inf)
                better = Q > best.Q
                best.Q = np.where(better, Q, best.Q)
                best.s_star = np.where(better, sig, best.s_star)
                best.UA = np.where(better, R, best.UA)
                best.UL = np.where(better, UL, best.UL)
                if progress is not None:
                    progress(j + 1, total_steps)
    return best


def _settle_by_bounds(rows: _Rows, spans: _Spans, lat: _Rows, idx: np.ndarray, k: np.ndarray,
                      xg: np.ndarray, eps: float, lam: float, max_evaluations: int,
                      progress: Callable[[int, int], None] | None, done: int,
                      total_steps: int) -> list[int]:
    """Step 3: per-pair bounds on the strict spans (:func:`_settle_pair`); rows not better
    than the lattice keep its values. Returns the pairs left to the exact method."""
    fallback = []
    for n, i in enumerate(spans.strict_pairs):
        j0, j1 = np.searchsorted(xg, [spans.x_lo[i] - spans.tol, spans.x_hi[i] + spans.tol])
        res = _settle_pair(spans.ws, int(idx[i]), float(spans.C[i]), float(eps), lam,
                           float(spans.tols[i]), spans.of_pair(n), xg[j0:j1], int(max_evaluations))
        if res.ok:
            rows.settled[i] = "bounds"
            rows.upper[i] = max(res.upper, lat.Q[i])
            if res.Q > lat.Q[i] * (1.0 + 1e-12):
                rows.Q[i] = res.Q
                rows.s_star[i] = spans.sign * res.x
                Es = 0.5 * k[idx[i]] * max(spans.x_hi[i] - res.x, 0.0) ** 2
                rows.UA[i] = res.B - Es if math.isfinite(res.B) else math.inf
                rows.UL[i] = spans.C[i] - Es
            else:              # nothing better than the lattice: keep its row as it was
                rows.Q[i], rows.s_star[i] = lat.Q[i], lat.s_star[i]
                rows.UA[i], rows.UL[i] = lat.UA[i], lat.UL[i]
        else:
            fallback.append(i)
        if progress is not None:
            progress(done + n + 1, total_steps)
    return fallback


def _refine_top(mesh, model: GraspModel, idx: np.ndarray, rows: _Rows, top: int,
                allow_pulling: bool, mode: str, jaw_width: float) -> list[GraspAnalysis]:
    """The ``top`` pairs (not pulling, unless allowed) by the exact method, full reports;
    their rows take its values. Best first (stable: ties keep their order)."""
    pulls = model.pulls[idx]
    refined: list[GraspAnalysis] = []
    for i in np.argsort(-rows.Q, kind="stable"):
        if len(refined) >= int(top) or rows.Q[i] <= 0:
            break
        if pulls[i] and not allow_pulling:
            continue
        a, b = model.graph.pairs[idx[i]]
        r = optimize_separation(mesh, (int(a), int(b)), method="exact", mode=mode,
                                jaw_width=jaw_width, model=model)
        refined.append(r)
        rows.set_exact(i, r.separation)
    refined.sort(key=lambda r: -r.quality)
    return refined


def _settle_rows(mesh, model: GraspModel, idx: np.ndarray, sigma_L: np.ndarray, grid: np.ndarray,
                 eps: float, lam: float, mode: str, max_evaluations: int,
                 progress: Callable[[int, int], None] | None, t: dict
                 ) -> tuple[_Rows, _Rows, _Spans]:
    """Steps 1–3 of the module docstring: the rows of every selected pair, the lattice's
    best values, and the strict spans (timings into ``t``)."""
    graph, sigma0, k = model.graph, model.stiffness.sigma0, model.stiffness.k
    with _timed(t, "strict_spans"):               # step 1: strict spans, every pair
        spans = _strict_spans(graph, sigma0, k, sigma_L, idx, mode)
    total_steps = len(grid) + len(spans.strict_pairs)
    with _timed(t, "lattice_sweeps"):             # step 2: the coarse shared lattice
        lat = _lattice_sweep(graph, sigma0, k, sigma_L, idx, mode, grid, progress, total_steps)
    rows = _Rows.zeros(len(idx))
    with _timed(t, "settle_bounds"):              # step 3: per-pair bounds, else exact
        xg = np.sort(spans.sign * grid, kind="stable")
        fallback = _settle_by_bounds(rows, spans, lat, idx, k, xg, eps, lam, max_evaluations,
                                     progress, len(grid), total_steps)
    with _timed(t, "settle_exact"):
        for i in fallback:
            rows.set_exact(i, optimize_separation_arrays(sigma0, k, graph, int(idx[i]),
                                                         float(sigma_L[i]), mode=mode,
                                                         method="exact", n_curve=2))
    return rows, lat, spans


@contextmanager
def _timed(t: dict, key: str):
    """Record the seconds the block takes as ``t[key]``."""
    t0 = time.perf_counter()
    yield
    t[key] = time.perf_counter() - t0


def plan_grasps(mesh, K: sp.spmatrix | None = None, *, eps: float | None = None,
                mode: str = "contracting", jaw_width: float = 0.0,
                separation_range: tuple[float, float] | None = None,
                regions: Sequence[Any] | None = None, top: int = 10,
                n_sigma: int = 400, max_sigma: int = 200_000,
                progress: Callable[[int, int], None] | None = None,
                model: GraspModel | None = None, allow_pulling: bool = False,
                max_evaluations: int = 4000) -> PlanResult:
    """Rank every jaw pair of a part, each pair's quality within ε of its optimum:
    ``quality ≤ Q* ≤ quality_upper ≤ quality + ε`` on every row (module docstring).

    Parameters
    ----------
    mesh : Mesh
        Meshed part with material.
    K : sparse matrix, optional
        Stiffness (N/m); assembled if omitted.
    eps : float, optional
        ε (J). Default: about ``n_sigma`` shared lattice points over the range (reported).
    mode : {"contracting", "expanding"}
    jaw_width : float
        Jaw contact width (m).
    separation_range : (float, float), optional
        Keep pairs whose rest distance σ0 (m) lies in this range.
    regions : sequence, optional
        Keep pairs with both jaw nodes in these boxes ``(xmin, ymin, xmax, ymax)`` (m) or
        shapely geometries.
    top : int
        Number of best pairs refined with the exact method (``refined``).
    n_sigma, max_sigma : int
        Size of the coarse shared lattice (and the default ε); the largest accepted.
    progress : callable, optional
        ``progress(done, total)`` after each lattice value and each pair settled by bounds.
    model : GraspModel, optional
        Reuse a model from :func:`grasp_model`.
    allow_pulling : bool
        Let pairs flagged ``pulls`` (a jaw would have to pull) into ``refined``.
    max_evaluations : int
        Escape-level evaluations one pair may use before it is solved exactly instead.

    Returns
    -------
    PlanResult

    Raises
    ------
    GraspError
        Bad ε, range, regions, or no pair left after filtering.

    Examples
    --------
    >>> from deformclosure import demo_part, mesh_part
    >>> plan = plan_grasps(mesh_part(demo_part(max_area_mm2=20.0)), top=1)
    >>> bool(np.all(np.diff(plan.quality) <= 0)), len(plan.refined)      # best first
    (True, 1)
    """
    _check_plan_options(eps, top, max_evaluations)
    model = model if model is not None else grasp_model(mesh, K, mode=mode, jaw_width=jaw_width)
    t = dict(model.timings)
    idx = _selected_pairs(mesh, model, separation_range, regions)
    if mesh.material is None:
        raise GraspError("no material: the elastic-limit strain e_L is unknown")
    with _timed(t, "elastic_limits"):
        e_max, sigma_L = pair_elastic_limits(model, idx, mesh.material.elastic_limit_strain)
    sigma0, k = model.stiffness.sigma0, model.stiffness.k
    lam, eps, step, grid = _shared_lattice(mode, sigma0, k, sigma_L, idx, eps, n_sigma, max_sigma)
    rows, lat, spans = _settle_rows(mesh, model, idx, sigma_L, grid, eps, lam, mode,
                                    max_evaluations, progress, t)
    with _timed(t, "refine_exact"):
        refined = _refine_top(mesh, model, idx, rows, top, allow_pulling, mode, jaw_width)
    rank = np.argsort(-rows.Q, kind="stable")
    pairs = model.graph.pairs[idx[rank]]
    return PlanResult(
        pairs=pairs, sigma0=sigma0[idx[rank]], k=k[idx[rank]], e_max=e_max[rank],
        sigma_L=sigma_L[rank], sigma_star=rows.s_star[rank], quality=rows.Q[rank],
        U_A=rows.UA[rank], U_L=rows.UL[rank], pulls=model.pulls[idx][rank],
        lattice_quality=lat.Q[rank], exact=rows.exact[rank], epsilon=float(eps),
        lipschitz=lam, step=step, n_sigma=len(grid), refined=refined, mode=mode,
        jaw_width=float(jaw_width), timings=t, model=model, quality_upper=rows.upper[rank],
        settled=np.asarray(rows.settled[rank], dtype=str), jaw_xy=mesh.nodes[pairs],
        allow_pulling=bool(allow_pulling), n_evaluations=int(spans.ws.n_eval))
