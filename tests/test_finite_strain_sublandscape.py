"""The finite-strain model's sub-landscape (SPEC §8): the escape search on the linear
escape path's neighbourhood, grown where it runs out of vertices, against a brute-force
bottleneck on the full grid (threshold connectivity, written here independently of the
minimax search)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure.pads.finite_strain_grasp import RestrictedGrid, _allowed, grown_release
from deformclosure.pads.geometry import Pad
from deformclosure.pads.landscape import AxisGrid, Landscape


class _Curve:
    def __init__(self, energy: float) -> None:
        self.E, self.touch = energy, object()

    def energy_at(self, sigma: float) -> float:
        return self.E


class _TableSolver:
    """A landscape 'solver' whose axis energies are a table over the grid's vertices."""

    def __init__(self, grid: AxisGrid, table: np.ndarray) -> None:
        self.table = table
        self.ids = {(round(grid.axis(v).angle, 12), round(grid.axis(v).offset, 12)): v
                    for v in range(grid.size)}
        self.solved: set[int] = set()

    def curve(self, axis, pad, sigma_end=0.0, hole=None) -> _Curve:
        v = self.ids[(round(axis.angle, 12), round(axis.offset, 12))]
        self.solved.add(v)
        return _Curve(float(self.table[v]))


def _grid() -> AxisGrid:
    return AxisGrid(0.0, 0.0, math.pi / 6, 1e-3, 6, -4, 4, 0, (0.0, 0.0))


def brute_force_barrier(grid: AxisGrid, U: np.ndarray, start: int) -> float:
    """``U_A`` on the full grid: the least level ``L`` at which the start's component of
    ``{v : U(v) ≤ L}`` holds another vertex no neighbour undercuts (SPEC §4), minus
    ``U(start)``; ``inf`` when none."""
    nbrs = [grid.neighbours(v) for v in range(grid.size)]
    is_eq = [all(U[v] <= U[w] for w in nbrs[v]) for v in range(grid.size)]
    for L in sorted({float(x) for x in U if np.isfinite(x) and x >= U[start]}):
        seen, todo = {start}, [start]
        while todo:
            v = todo.pop()
            for w in nbrs[v]:
                if w not in seen and U[w] <= L:
                    seen.add(w)
                    todo.append(w)
        if any(v != start and is_eq[v] for v in seen):
            return L - U[start]
    return math.inf


def _table(seed: int, p_inf: float) -> tuple[AxisGrid, np.ndarray, int]:
    grid = _grid()
    rng = np.random.default_rng(seed)
    U = rng.uniform(1.0, 10.0, grid.size)
    U[rng.random(grid.size) < p_inf] = math.inf
    start = grid.vertex(0, 0)
    U[start] = 0.5                          # a strict minimum: every neighbour is higher
    return grid, U, start


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), p_inf=st.sampled_from([0.0, 0.15, 0.35]),
       path_len=st.integers(0, 4), exact_proxy=st.booleans())
def test_grown_sub_landscape_bounds_the_full_barrier_from_above(seed, p_inf, path_len,
                                                                exact_proxy):
    """From the start and a few vertices along one offset row (a stand-in for the linear
    escape path) and their neighbours, the grown search's barrier is at least the full
    grid's, finite whenever the full grid's is, its path a path of the full grid ending at
    an equilibrium of the full grid, and its barrier the largest energy on that path —
    whether the growth is steered by the energies themselves or by a random proxy."""
    grid, U, start = _table(seed, p_inf)
    proxy = U if exact_proxy else np.random.default_rng(seed + 1).random(grid.size)
    path = [grid.vertex(0, j) for j in range(1, path_len + 1)]
    solver = _TableSolver(grid, U)
    sub = RestrictedGrid(grid, _allowed(grid, start, path), most=grid.size)
    land = Landscape(solver, Pad(0.0, 1e-3), sub, 0.0)
    rel = grown_release(land, sub, start, 1.0, 0.0, lambda v, sig: proxy[v])
    ref = brute_force_barrier(grid, U, start)
    assert rel.strict
    assert rel.U_A >= ref - 1e-12
    if math.isfinite(ref):
        assert math.isfinite(rel.U_A)
    if math.isfinite(rel.U_A):
        p = rel.path
        assert p[0] == start and all(b in grid.neighbours(a) for a, b in zip(p, p[1:]))
        assert all(U[p[-1]] <= U[w] for w in grid.neighbours(p[-1]))
        assert max(U[v] for v in p) - U[start] == rel.U_A
        assert set(p) <= sub.allowed


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), p_inf=st.sampled_from([0.0, 0.2]))
def test_sub_landscape_of_the_whole_grid_is_the_full_search(seed, p_inf):
    """``allowed`` = every vertex: the same barrier as the brute force, exactly."""
    grid, U, start = _table(seed, p_inf)
    sub = RestrictedGrid(grid, set(range(grid.size)))
    land = Landscape(_TableSolver(grid, U), Pad(0.0, 1e-3), sub, 0.0)
    rel = grown_release(land, sub, start, 1.0, 0.0, lambda v, sig: U[v])
    assert rel.U_A == brute_force_barrier(grid, U, start)
    assert sub.n_grown == 0


def test_growth_opens_the_grid_where_the_search_was_heading():
    """A valley along offset row 0, walled by axes the pads cannot reach (inf), climbing
    beyond the allowed set, with the only equilibrium in a dip at its far end: the
    restricted search runs out of vertices, the grid grows along the valley one vertex at a
    time (steered by the energies themselves as the proxy), and the barrier is the
    valley's rim before the dip."""
    grid = _grid()
    U = np.full(grid.size, math.inf)
    for j in range(0, grid.j_max + 1):
        U[grid.vertex(0, j)] = 1.0 + j              # up the valley ...
    U[grid.vertex(0, grid.j_max - 1)] = 3.5
    U[grid.vertex(0, grid.j_max)] = 2.0             # ... into a dip at its end
    start = grid.vertex(0, 0)
    solver = _TableSolver(grid, U)
    sub = RestrictedGrid(grid, _allowed(grid, start, [grid.vertex(0, 1)]), most=grid.size)
    land = Landscape(solver, Pad(0.0, 1e-3), sub, 0.0)
    before = len(sub.allowed)
    rel = grown_release(land, sub, start, 1.0, 0.0, lambda v, sig: U[v])
    ref = brute_force_barrier(grid, U, start)
    assert rel.U_A == ref == 3.5 - 1.0
    assert rel.path == [grid.vertex(0, j) for j in range(grid.j_max + 1)]
    assert 0 < sub.n_grown == len(sub.allowed) - before
    assert len(solver.solved) < grid.size / 3


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), p_inf=st.sampled_from([0.0, 0.15, 0.35]),
       path_len=st.integers(0, 4), cap=st.sampled_from([None, 2.0, 5.0]))
def test_cut_bound_brackets_the_full_barrier(seed, p_inf, path_len, cap):
    """The sub-landscape's release (no growth) brackets the full grid's brute-force
    barrier: its ``lower`` (the cut around the settled set) from below, its ``U_A`` (a
    found path) from above — with or without a cap; the capped search's ``U_A`` is then
    itself a lower bound on the sub-landscape only, so ``lower`` is what bounds the full
    grid."""
    grid, U, start = _table(seed, p_inf)
    path = [grid.vertex(0, j) for j in range(1, path_len + 1)]
    allowed = _allowed(grid, start, path)
    sub = RestrictedGrid(grid, allowed, most=len(allowed))
    land = Landscape(_TableSolver(grid, U), Pad(0.0, 1e-3), sub, 0.0)
    rel = land.release(start, 1.0, 0.0, cap, cut_bound=True)
    ref = brute_force_barrier(grid, U, start)
    assert rel.strict and rel.lower is not None
    assert rel.lower <= ref + 1e-12
    if not rel.bounded:
        assert rel.U_A >= ref - 1e-12 and rel.lower <= rel.U_A
    else:
        assert rel.lower <= rel.U_A                      # the cap's level caps it too
    # without the cut bound the release is the same search, no lower bound
    plain = Landscape(_TableSolver(grid, U), Pad(0.0, 1e-3), sub, 0.0).release(start, 1.0, 0.0, cap)
    assert plain.lower is None and plain.U_A == rel.U_A


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), p_inf=st.sampled_from([0.0, 0.2]))
def test_cut_bound_of_the_whole_grid_is_the_barrier(seed, p_inf):
    """``allowed`` = every vertex: with every axis reachable the cut is empty and ``lower``
    is the barrier itself; an unreachable axis (``U = ∞``, never settled) stays in the cut
    and counts as the level it was reached at — unreachable is not infinitely high — so
    ``lower`` may then fall below the barrier, never above it."""
    grid, U, start = _table(seed, p_inf)
    sub = RestrictedGrid(grid, set(range(grid.size)))
    land = Landscape(_TableSolver(grid, U), Pad(0.0, 1e-3), sub, 0.0)
    rel = land.release(start, 1.0, 0.0, None, cut_bound=True)
    ref = brute_force_barrier(grid, U, start)
    assert rel.U_A == ref
    if p_inf == 0.0:
        assert rel.lower == ref
    else:
        assert rel.lower <= ref


def test_cut_bound_by_hand():
    """A valley along offset row 0 (energies 1, 2, 3, ... from the start), walls of 9
    elsewhere except one low axis, energy 1.5, beside the valley's second vertex and
    outside the allowed set: the search runs out (the sub-landscape holds no equilibrium),
    and the lower bound is the climb to that axis from the start: max(level 2, 1.5) − 1."""
    grid = _grid()
    U = np.full(grid.size, 9.0)
    for j in range(0, grid.j_max + 1):
        U[grid.vertex(0, j)] = 1.0 + j
    start = grid.vertex(0, 0)
    allowed = {grid.vertex(0, j) for j in range(0, 3)}
    beside = grid.vertex(1, 2)
    assert beside in grid.neighbours(grid.vertex(0, 1)) or beside in grid.neighbours(grid.vertex(0, 2))
    U[beside] = 1.5
    sub = RestrictedGrid(grid, allowed, most=len(allowed))
    land = Landscape(_TableSolver(grid, U), Pad(0.0, 1e-3), sub, 0.0)
    rel = land.release(start, 1.0, 0.0, None, cut_bound=True)
    assert math.isinf(rel.U_A)
    reach = min(U[v] for v in allowed if beside in grid.neighbours(v))   # level of v = U(v) here
    assert rel.lower == max(reach, 1.5) - 1.0
