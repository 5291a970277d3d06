"""The release landscape of a two-pad grasp over grasp axes (SPEC §6).

The part moves relative to the gripper by sliding across the closing axis and turning:
the vertices of the landscape are grasp axes on a ``(θ, c)`` grid whose spacing follows
the part's size (``Δθ = π / n_angles``, ``Δc = D / n_offsets`` with ``D`` the diameter),
never the mesh; neighbours are grid neighbours, and ``θ`` is periodic with
``(θ + π, −c)`` the same axis. At a gripper separation ``σ`` every axis has the energy of
its own contact problem; the release energy ``U_A`` is the minimax barrier from the start
axis to another equilibrium (an axis whose energy no neighbour undercuts, e.g. one where
the pads miss the part), exactly as SPEC §4 defines it on the contact graph.

Energies are computed lazily, only for the axes a search reaches, and cached as whole
exact curves ``U(σ)``.

**Noise floor.** On an unstructured mesh the energy of an axis jitters as the axis moves
relative to the nodes; a continuum solution does not. Relative energy differences below
``noise`` are not resolved: a start axis is a strict minimum only if every neighbour is
higher by more than ``noise`` × its energy, and a barrier smaller than ``noise`` × its
height is none (:mod:`deformclosure.landscape.noise`, the rule of every landscape);
:mod:`.noise` measures it. The search is the shared
:func:`~deformclosure.landscape.search.minimax_escape`; this module holds only the
coordinates: the grid, its neighbours and the axis energies. Energy differences the mesh
cannot resolve are thus ties, and a tie is not a hold: like a translation along parallel
edges (SPEC §3), a neutral direction lets a frictionless part slide.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..landscape.noise import higher, resolved, twin_floor
from ..landscape.search import cut_level, minimax_escape
from .contact import GraspCurve, PadContact
from .geometry import GraspAxis, Pad

__all__ = ["AxisGrid", "Landscape", "Release"]


def _out_of_reach(sigma: float) -> float:
    """The energy of an axis the pads cannot reach (:meth:`Landscape.energy`)."""
    return math.inf


@dataclass(frozen=True)
class AxisGrid:
    """A ``(θ, c)`` grid of axes anchored at a start axis; ``c`` about ``origin``.

    Vertex ``(i, j)`` is the axis ``θ_i = angle0 + i Δθ``, ``c_j = offset0 + j Δc`` for
    ``0 ≤ i < n_angles`` and ``j_min ≤ j ≤ j_max``; ``Δc`` is chosen so that the grid is
    closed under ``(θ + π, −c)`` (``2·offset0/Δc`` is an integer ``wrap``).
    """

    angle0: float
    offset0: float
    d_angle: float
    d_offset: float
    n_angles: int
    j_min: int
    j_max: int
    wrap: int
    origin: tuple[float, float]

    @classmethod
    def around(cls, start: GraspAxis, reach: float, diameter: float, n_angles: int = 48,
               n_offsets: int = 50) -> "AxisGrid":
        """Grid through ``start`` covering offsets up to ``reach`` (m) from the origin."""
        dc = diameter / n_offsets
        wrap = int(round(2 * start.offset / dc))
        if wrap != 0:
            dc = 2 * start.offset / wrap
        j_max = int(math.ceil((reach - start.offset) / dc)) + 1
        j_min = -j_max - wrap
        return cls(start.angle, start.offset, math.pi / n_angles, dc, n_angles, j_min, j_max,
                   wrap, start.origin)

    @classmethod
    def over_part(cls, solver: PadContact, start: GraspAxis, pad: Pad, n_angles: int = 48,
                  n_offsets: int = 50) -> "AxisGrid":
        """Grid through ``start`` covering every axis on which ``pad`` can reach the part's
        outer ring: offsets up to the ring's farthest node from ``start.origin`` plus the
        pad's half span (m)."""
        mesh = solver.mesh
        ring = mesh.nodes[mesh.outer_loop]
        reach = float(np.linalg.norm(ring - np.asarray(start.origin), axis=1).max()) + pad.half_span
        return cls.around(start, reach, mesh.diameter, n_angles, n_offsets)

    @property
    def n_offsets(self) -> int:
        """Number of offsets per angle."""
        return self.j_max - self.j_min + 1

    @property
    def size(self) -> int:
        """Number of vertices."""
        return self.n_angles * self.n_offsets

    def vertex(self, i: int, j: int) -> int:
        """Vertex id of grid cell ``(i, j)``."""
        return i * self.n_offsets + (j - self.j_min)

    def cell(self, v: int) -> tuple[int, int]:
        """Grid cell ``(i, j)`` of vertex ``v``."""
        i, r = divmod(v, self.n_offsets)
        return i, r + self.j_min

    def axis(self, v: int) -> GraspAxis:
        """The grasp axis of vertex ``v``."""
        i, j = self.cell(v)
        return GraspAxis(self.angle0 + i * self.d_angle, self.offset0 + j * self.d_offset,
                         self.origin)

    def neighbours(self, v: int) -> list[int]:
        """Grid neighbours (±Δθ with the periodic wrap, ±Δc)."""
        i, j = self.cell(v)
        out = []
        if j > self.j_min:
            out.append(self.vertex(i, j - 1))
        if j < self.j_max:
            out.append(self.vertex(i, j + 1))
        for di in (-1, 1):
            ii = i + di
            jj = j
            if ii < 0:
                ii, jj = self.n_angles - 1, -j - self.wrap
            elif ii >= self.n_angles:
                ii, jj = 0, -j - self.wrap
            out.append(self.vertex(ii, jj))
        return out

    def start_neighbours(self, v: int) -> list[int]:
        """The neighbours of the start's strictness test (here all grid neighbours; a grid
        refined around saddles keeps the coarse ones, :mod:`.saddle_grid`)."""
        return self.neighbours(v)


@dataclass(frozen=True)
class Release:
    """Release of the start axis at one separation.

    Attributes
    ----------
    U_A : float
        Release energy (J); ``inf`` if no other equilibrium is reachable.
    strict : bool
        Whether the start is a strict minimum beyond the noise floor.
    saddle : int or None
        Vertex holding the barrier's maximum energy.
    path : list of int
        Minimax path, start first, ending at another equilibrium (empty if not strict).
    bounded : bool
        The search stopped once the barrier exceeded the ``cap`` it was given: ``U_A`` is
        then a lower bound (``> cap``), ``saddle`` None and ``path`` empty.
    lower : float or None
        On a sub-landscape asked for its ``cut_bound`` (:meth:`Landscape.release`): a lower
        bound (J) of the *full* grid's release energy; else None.
    """

    U_A: float
    strict: bool
    saddle: int | None
    path: list[int]
    bounded: bool = False
    lower: float | None = None


class Landscape:
    """Lazily evaluated grasp energies over an :class:`AxisGrid`.

    Parameters
    ----------
    solver : PadContact
    pad : Pad
    grid : AxisGrid
    sigma_end : float
        Separation (m) at the far end of every query (smallest σ; largest, expanding);
        curves are traced to it.
    hole : int, optional
        Expanding grasps: the hole the pads open in.
    known : dict, optional
        Curves already traced on this solver, grid spacing and ``sigma_end``, by vertex
        (shared between landscapes of one level, :func:`~deformclosure.pads.refine.
        solve_level`); curves traced here are added to it.
    """

    def __init__(self, solver: PadContact, pad: Pad, grid: AxisGrid, sigma_end: float,
                 hole: int | None = None, known: dict | None = None) -> None:
        self.solver, self.pad, self.grid, self.sigma_end = solver, pad, grid, sigma_end
        self.hole = hole
        self._known: dict[int, GraspCurve] = {} if known is None else known
        self._curves: dict[int, GraspCurve] = {}
        self.twin: Landscape | None = None
        self._measured: list[int] = []
        # caches of pure functions of a vertex (and σ, floor): the searches ask for the
        # same neighbours, energies and releases many times
        self._nbrs: dict[int, list[int]] = {}
        self._energy_at: dict[int, object] = {}
        self._releases: dict[tuple, Release] = {}
        self._noise: dict[tuple, float] = {}
        #: The :class:`~deformclosure.landscape.search.Escape` of the last search run.
        self.last_escape = None

    def measure_noise(self, most: int = 48) -> bool:
        """Solve axes visited so far on the twin realisation, at most ``most`` in all
        (spread evenly over the visit order); True if any was added."""
        done = set(self._measured)
        visited = list(self._curves)
        room = most - len(self._measured)
        if room <= 0:
            return False
        todo = [v for v in visited if v not in done]
        if len(todo) > room:
            todo = [todo[int(k)] for k in np.linspace(0, len(todo) - 1, room)]
        for v in todo:
            self.twin.curve(v)
        self._measured.extend(todo)
        return bool(todo)

    def noise(self, sigma: float) -> float:
        """Relative noise at ``sigma`` (m) from the axes measured on both realisations
        (:func:`~deformclosure.landscape.noise.twin_floor`: twice the 90th percentile of
        ``|U₁ − U₂| / max(U₁, U₂)``)."""
        if self.twin is None:
            return 0.0
        if not self._measured:
            self.measure_noise()
        key = (sigma, self.twin, len(self._measured))      # the measured axes only grow
        out = self._noise.get(key)
        if out is None:
            U1 = np.array([self.energy(v, sigma) for v in self._measured])
            U2 = np.array([self.twin.energy(v, sigma) for v in self._measured])
            out = self._noise[key] = twin_floor(U1, U2)
        return out

    def seed(self, v: int, curve: GraspCurve) -> None:
        """Use an already traced ``curve`` for vertex ``v`` (e.g. the start axis)."""
        self._curves[v] = curve
        self._energy_at.pop(v, None)
        self._releases.clear()
        self._noise.clear()

    def curve(self, v: int) -> GraspCurve:
        """The exact energy curve of vertex ``v`` (computed once)."""
        c = self._curves.get(v)
        if c is None:
            c = self._known.get(v)
            if c is None:
                c = self.solver.curve(self.grid.axis(v), self.pad, self.sigma_end, self.hole)
                self._known[v] = c
            self._curves[v] = c
        return c

    @property
    def n_evaluated(self) -> int:
        """Number of axes whose contact problem has been solved."""
        return len(self._curves)

    def energy(self, v: int, sigma: float, near: int | None = None) -> float:
        """Energy (J) of vertex ``v`` at separation ``sigma`` (m).

        Expanding grasps: an axis where the pads do not fit in the hole (or miss its
        centre) is out of reach — the hole's walls stop the pads — so its energy is ``inf``.
        ``near`` is the vertex the search reached ``v`` from: a curve that is solved
        iteratively (finite strain, SPEC §8, ``energy_near``) starts from its state there.
        """
        if near is not None and near in self._curves:
            c = self.curve(v)
            warm = getattr(c, "energy_near", None)
            if warm is not None:
                return warm(sigma, self._curves[near])
        f = self._energy_at.get(v)
        if f is None:
            c = self.curve(v)
            f = _out_of_reach if self.hole is not None and c.touch is None else c.energy_at
            self._energy_at[v] = f
        return f(sigma)

    def grid_changed(self) -> None:
        """Forget the cached neighbours and releases after the grid's neighbours changed
        (a grown sub-landscape, :class:`~deformclosure.pads.finite_strain_grasp.
        RestrictedGrid`); the solved curves stay."""
        self._nbrs.clear()
        self._releases.clear()

    def neighbours(self, v: int) -> list[int]:
        """Grid neighbours of vertex ``v`` (:meth:`AxisGrid.neighbours`, cached)."""
        out = self._nbrs.get(v)
        if out is None:
            out = self._nbrs[v] = self.grid.neighbours(v)
        return out

    def release(self, start: int, sigma: float, noise: float = 0.0,
                cap: float | None = None, cut_bound: bool = False) -> Release:
        """Minimax release from ``start`` at separation ``sigma`` (SPEC §4 on this grid).

        ``noise`` is the relative noise floor: two energies closer than ``noise`` × the
        larger are a tie. A start with zero energy holds nothing (``U_A = 0``, SPEC §7's
        released placement). The start must exceed no neighbour within it (else ``U_A = 0``),
        and a barrier within it of the start's energy is no barrier (``U_A = 0``).
        ``cap`` (J): only whether ``U_A`` exceeds it matters (e.g. ``Q = min(U_A, U_L)``
        with ``cap = U_L``): the search stops at that level and the result is
        :attr:`Release.bounded`. Computed once per ``(start, sigma, noise, cap)``; an
        uncapped result answers every cap.

        ``cut_bound`` (a sub-landscape only, :class:`~deformclosure.pads.
        finite_strain_grasp.RestrictedGrid`): the release on a sub-landscape is an upper
        bound of the full grid's (a path it finds is a path of the grid). A lower bound
        comes with it (:attr:`Release.lower`): the search settled, in increasing level,
        every vertex ``S`` it reached below its final level ``b`` (the barrier found,
        where it stopped, or ``∞`` when it ran out), and ``S`` holds no other
        equilibrium. A path of the full grid from the start to another equilibrium either
        stays in the sub-landscape — it climbs at least ``b`` — or leaves ``S`` by an edge
        ``v → w``, ``v ∈ S``, ``w ∉`` the sub-landscape, and climbs at least
        ``max(level(v), U(w))`` (``level(v)``: the minimax level at which the search
        reached ``v``). So the cut's vertices are solved and ``lower = min(b, min over
        the cut of max(level(v), U(w))) − U(start)``; an unreachable ``w`` (``U = ∞``)
        counts as ``level(v)`` (unreachable is not infinitely high). With an empty cut
        the sub-landscape is the start's whole component and ``lower = U_A``.
        """
        out = self._releases.get((start, sigma, noise, None, cut_bound))
        if out is None:
            key = (start, sigma, noise, cap, cut_bound)
            out = self._releases.get(key)
            if out is None:
                out = self._releases[key] = self._release(start, sigma, noise, cap, cut_bound)
        return out

    def _release(self, start: int, sigma: float, noise: float,
                 cap: float | None = None, cut_bound: bool = False) -> Release:
        g, nbrs = self.grid, self.neighbours
        E: dict[int, float] = {}

        def U(v: int, near: int | None = None) -> float:
            if v not in E:
                E[v] = self.energy(v, sigma, near)
            return E[v]

        Us = U(start)
        if Us <= 0.0 or not all(higher(U(w), Us, noise) for w in g.start_neighbours(start)):
            # Nothing squeezed (a released placement), or a neighbour within the noise.
            return Release(0.0, False, None, [])
        # A sub-landscape (``grid.full_neighbours``) confirms an equilibrium against the
        # neighbours it does not expand into: its target is then one of the full grid.
        full = getattr(g, "full_neighbours", None)
        confirm = None if full is None else (lambda v: all(U(v) <= U(w, v) for w in full(v)))
        esc = self.last_escape = minimax_escape(start, nbrs, U, stop_above=cap,  # SPEC §4
                                                confirm=confirm)
        lower = None
        if cut_bound and full is not None:
            lower = min(esc.barrier, cut_level(esc, full, U)) - Us
        if not esc.complete:
            return Release(esc.barrier - Us, True, None, [], bounded=True, lower=lower)
        if esc.target is None:
            return Release(math.inf, True, None, [], lower=lower)
        b = esc.barrier
        if not resolved(b - Us, b, noise):      # a barrier the mesh cannot resolve is a tie
            return Release(0.0, False, None, [], lower=None if lower is None else 0.0)
        return Release(b - Us, True, max(esc.path, key=U), esc.path, lower=lower)
