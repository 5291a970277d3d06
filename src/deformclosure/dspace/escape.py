"""Release energy ``U_A`` of a part among fixed fingers, and its escape path (SPEC §7).

The state of a frictionless part among fixed fingers is its placement ``g = (x, y, φ)``
(translation of the area centroid, m, and rotation about it, rad, relative to the part at
rest); every placement has the contact energy ``E(g)`` of
:class:`~deformclosure.dspace.placement_energy.PlacementEnergy`. ``U_A`` is the minimax
barrier of that 3-D landscape from the equilibrium ``g*`` to a *released* placement or to
another equilibrium — SPEC §4's definition on the contact graph, carried to placements:

1. **Equilibrium.** ``g*`` minimises ``E`` near the contact equilibrium of
   :func:`~deformclosure.dspace.equilibrium.equilibrium` (quasi-Newton on the exact
   generalised force ``dE/dg``). At rest (``E* = 0`` with touching fingers) it is a strict
   minimum iff the rigid part is in form closure (Thm 1; the rigid test of
   :mod:`.closure` decides, since a lattice cannot follow second-order motions);
   otherwise it is strict iff its *noise plateau* — the placements the search reaches
   without exceeding ``E*`` by more than the noise floor — stays within two lattice
   steps of it (a part that can slide or turn at no resolvable cost is not held).
2. **Landscape.** A lattice of placements centred on ``g*``: translation step
   ``h = min(D/48, ρ_min/2)`` (``D`` the part's diameter, ``ρ_min`` the smallest disc
   finger) and rotation step ``h / R`` (``R`` the largest distance of the boundary from
   the centroid) rounded to divide 2π; ``φ`` is periodic. Translations span the fingers'
   reach (their bounding box grown by ``R``); energies are computed lazily, only where the
   search goes, each contact problem warm-started from its parent's active set.
3. **Minimax.** Dijkstra on the bottleneck (the paper's §4.4 procedure) from ``g*``
   (:func:`deformclosure.landscape.search.minimax_escape`, the search of every model). A
   vertex is a target when it is *released* — no finger presses (``E = 0``) and the part
   can translate to infinity without entering a finger (tested on its convex hull) — or
   *another equilibrium* — ``E > 0`` beyond a barrier, all 26 neighbours higher beyond
   the noise floor (a dip the mesh cannot resolve is no equilibrium: on an unstructured
   mesh an uphill slope has such dips), and a continuous minimisation from it staying in
   its cell (a narrow valley running diagonally to the lattice makes false minima).
   ``U_A = max E on the path − E*``; ``U_A = ∞`` when no target is reachable through
   admissible placements inside the fingers' reach (a cage). A barrier within the noise
   floor of its height is none (``U_A = 0``). On zero-energy plateaus the search prefers
   placements farther from the fingers (ties only).
4. **Refinement near the saddle.** The path around its highest vertex is searched again
   on lattices with ``h/2``, ``h/4`` (boxes of ±3 fine steps about the saddle); the error
   estimate of ``U_A`` is the largest change under a halving plus the noise floor times
   the saddle energy.
5. **Noise floor.** As for pads (the rule is :mod:`deformclosure.landscape.noise`, shared
   by every model; the twin realisation :func:`deformclosure.mesh.generate.twin_mesh`): the jitter of ``E``
   under sub-cell moves of ``g*`` (residual of quadratic fits, each side of ``g*`` on its
   own — a kink at the minimum is no noise —, × 4, relative) and, when
   the part's geometry is known, a second mesh realisation (twin) compared on up to 48
   placements the search settled (× 2 the 90th percentile); the larger counts, and the
   search is repeated while it rises. At rest (``E* = 0``) only the twin can measure it.

``deform_closure`` is ``U_A > error`` at a strict minimum. At rest (``E* = 0``) with the
rigid part in form closure it is ``U_A > 0`` (Thm 1, SPEC §7): every exit then deforms the
part, the zero start energy is exact (no finger presses) and the noise floor, relative to
energies, bounds the value of ``U_A``, not whether it exists; the barrier is kept however
high the noise. A start that is *not* a strict minimum but from which every exit needs work
(``U_A > error``) is ``caged``: the part rattles among the fingers but cannot leave without
deforming.

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.3 (deform closure, ``U_A``) and
§4.4 (minimax release).
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import DeformClosureError
from ..limits import blas_threads
from ..landscape.noise import (JITTER_FACTOR, ROUND_OFF, higher, jitter_floor, quadratic_residual,
                               resolved, twin_floor)
from ..landscape.search import Escape, minimax_escape
from .fingers import Finger, as_fingers
from .placement_energy import PlacementEnergy, PlacementState

__all__ = ["PlacementGrid", "PlacementLandscape", "FingerRelease", "release_energy_fingers",
           "equilibrium_placement", "lattice_angle", "jitter_noise", "UNITS"]

UNITS = {"length": "m", "angle": "rad", "energy": "J", "force": "N", "stiffness": "N/m",
         "strain_per_length": "1/m"}

Key = tuple[int, int, int]


@dataclass(frozen=True)
class PlacementGrid:
    """Lattice of placements ``origin + ((i e₁ + j e₂) h, k h_φ) / scale``; ``k`` periodic.

    Keys are integer triples on the finest lattice (``scale`` subdivisions of a coarse
    step); the coarse lattice is every ``scale``-th of them. The translation axes
    ``e₁ = (cos α, sin α)``, ``e₂ = (−sin α, cos α)`` are attached to the part
    (:func:`lattice_angle`: its long principal axis at rest), so the lattice moves with
    part and fingers and ``U_A`` is invariant under a rigid motion of both (Thm 2).

    Attributes
    ----------
    origin : ndarray (3,)
        Placement at key (0, 0, 0) (m, m, rad).
    angle : float
        ``α`` (rad).
    h : float
        Coarse translation step (m).
    n_phi : int
        Coarse rotation steps per turn (``h_φ = 2π / n_phi``).
    scale : int
        Finest-lattice subdivisions per coarse step (a power of 2).
    lo, hi : tuple of int
        Translation bounds (finest-lattice units) of ``i`` and ``j``.
    """

    origin: np.ndarray
    h: float
    n_phi: int
    scale: int
    lo: tuple[int, int]
    hi: tuple[int, int]
    angle: float = 0.0

    @property
    def axes(self) -> np.ndarray:
        """``[e₁, e₂]`` as rows."""
        c, s = math.cos(self.angle), math.sin(self.angle)
        return np.array([[c, s], [-s, c]])

    @property
    def h_phi(self) -> float:
        """Coarse rotation step (rad)."""
        return 2.0 * math.pi / self.n_phi

    @property
    def period(self) -> int:
        """Rotation period in finest-lattice units."""
        return self.n_phi * self.scale

    def placement(self, key: Key) -> np.ndarray:
        """Placement (m, m, rad) of ``key``; φ in ``(−π, π]`` about the origin's."""
        i, j, k = key
        k = k % self.period
        if k > self.period // 2:
            k -= self.period
        c, s = math.cos(self.angle), math.sin(self.angle)
        u, v = i * self.h / self.scale, j * self.h / self.scale
        return self.origin + np.array([c * u - s * v, s * u + c * v, k * self.h_phi / self.scale])

    def norm(self, key: Key) -> Key:
        return (key[0], key[1], key[2] % self.period)

    def inside(self, key: Key) -> bool:
        return self.lo[0] <= key[0] <= self.hi[0] and self.lo[1] <= key[1] <= self.hi[1]

    def neighbours(self, key: Key, step: int) -> list[Key]:
        """The six lattice neighbours at ``step`` (finest units) inside the bounds."""
        i, j, k = key
        out = []
        for d in ((step, 0, 0), (-step, 0, 0), (0, step, 0), (0, -step, 0)):
            w = (i + d[0], j + d[1], k)
            if self.inside(w):
                out.append(w)
        out.append((i, j, (k + step) % self.period))
        out.append((i, j, (k - step) % self.period))
        return out

    def distance(self, a: Key, b: Key) -> int:
        """Chebyshev distance (finest units), periodic in ``k``."""
        dk = abs(a[2] - b[2]) % self.period
        return max(abs(a[0] - b[0]), abs(a[1] - b[1]), min(dk, self.period - dk))


class PlacementLandscape:
    """Lazily evaluated energies on a :class:`PlacementGrid`, with the minimax search.

    Parameters
    ----------
    energy : PlacementEnergy
    grid : PlacementGrid
    max_evaluations : int
        Budget of contact problems for the whole landscape.
    """

    def __init__(self, energy: PlacementEnergy, grid: PlacementGrid, max_evaluations: int = 200_000,
                 count: Callable[[int], None] | None = None):
        self.pe, self.grid = energy, grid
        self.max_evaluations = int(max_evaluations)
        self._count = count
        self._E: dict[Key, float] = {}
        self._act: dict[Key, np.ndarray] = {}
        self._esc: dict[Key, bool] = {}
        self._eq: dict[tuple, bool] = {}
        # the fingers' hub: on zero-energy plateaus the search prefers moving away from it
        self._hub = np.concatenate([f.reference_points() for f in energy.fingers]).mean(axis=0)
        self.twin: PlacementEnergy | None = None
        self._twin_E: dict[Key, float] = {}

    @property
    def n_evaluated(self) -> int:
        """Number of placements whose contact problem has been solved."""
        return len(self._E)

    def energy(self, key: Key, warm: Key | None = None) -> float:
        """Energy (J) of ``key`` (cached); ``warm``: a solved neighbour to warm-start from."""
        key = self.grid.norm(key)
        E = self._E.get(key)
        if E is None:
            E, act = self.pe.energy_and_active(self.grid.placement(key),
                                               None if warm is None else self._act.get(warm))
            self._E[key] = E
            self._act[key] = act
            if self._count is not None and len(self._E) % 100 == 0:
                self._count(len(self._E))
        return E

    def state(self, key: Key) -> PlacementState:
        """Full contact solution at ``key``."""
        return self.pe.energy(self.grid.placement(key), self._act.get(self.grid.norm(key)))

    def escapable(self, key: Key) -> bool:
        """Released: nothing presses and the part can leave (cached)."""
        key = self.grid.norm(key)
        v = self._esc.get(key)
        if v is None:
            v = self.energy(key) == 0.0 and self.pe.escapable(self.grid.placement(key),
                                                               angle0=self.grid.angle)
            self._esc[key] = v
        return v

    def _priority(self, key: Key) -> float:
        g = self.grid.placement(key)
        return -float(np.linalg.norm(self.pe.centroid + g[:2] - self._hub))

    def search(self, start: Key, step: int, noise: float, *, goal: Key | None = None,
               box: tuple[Key, int] | None = None, stop_above: float | None = None,
               allowed: set | None = None) -> Escape:
        """Minimax (bottleneck) path from ``start`` on the lattice of ``step``
        (:func:`~deformclosure.landscape.search.minimax_escape` on this lattice).

        With ``goal`` the path ends there; otherwise at the first target (released or
        another equilibrium beyond the relative noise floor ``noise``, module docstring).
        ``box = (centre, half_width)`` restricts the search; ``stop_above`` (J) stops once
        the barrier above the start exceeds it; ``allowed``, a set of keys, restricts
        where the search expands (a sub-landscape; its equilibria are still tested against
        every lattice neighbour). The result's ``plateau`` is the extent (finest units) of
        the start's noise plateau.
        """
        g = self.grid

        def nbrs(v: Key) -> list[Key]:
            out = [g.norm(w) for w in g.neighbours(v, step)]
            if box is not None:
                out = [w for w in out if g.distance(w, box[0]) <= box[1]]
            if allowed is not None:
                out = [w for w in out if w in allowed]
            return out

        return minimax_escape(
            g.norm(start), nbrs, lambda w, near: self.energy(w, warm=near),
            is_release=lambda v, Ev: Ev == 0.0 and self.escapable(v),
            goal=None if goal is None else g.norm(goal), noise=noise,
            confirm=lambda v: self.energy(v) > 0.0 and self.is_equilibrium(v, step, noise),
            stop_above=stop_above, max_evaluations=self.max_evaluations,
            evaluated=self.spent, priority=self._priority, distance=g.distance)

    def spent(self) -> int:
        """The budget count the search compares with ``max_evaluations``: the placements
        solved (a landscape with a time budget counts it spent past its deadline)."""
        return self.n_evaluated

    def is_equilibrium(self, v: Key, step: int, noise: float) -> bool:
        """Whether lattice vertex ``v`` (a minimum over its six axis neighbours) is an
        equilibrium: every one of its 26 neighbours is higher beyond the noise floor, and
        the continuous minimum of ``E`` from it stays in its cell with ``E > 0`` (a narrow
        valley running diagonally to the lattice makes false lattice minima)."""
        key = (self.grid.norm(v), step)
        if key in self._eq:
            return self._eq[key]
        g = self.grid
        Ev = self.energy(v)
        ok = True
        for di, dj, dk in itertools.product((-1, 0, 1), repeat=3):
            if (di, dj, dk) == (0, 0, 0):
                continue
            w = (v[0] + di * step, v[1] + dj * step, v[2] + dk * step)
            if g.inside(w) and not higher(self.energy(w, warm=v), Ev, max(noise, ROUND_OFF)):
                ok = False
                break
        ok = ok and self._stays_in_cell(v, step)
        self._eq[key] = ok
        return ok

    def _stays_in_cell(self, v: Key, step: int) -> bool:
        """Whether the continuous minimum of ``E`` from lattice vertex ``v`` stays in its
        cell (lattice spacing ``step``) with ``E > 0``: :meth:`is_equilibrium`'s last test."""
        g = self.grid
        h, hp = g.h * step / g.scale, g.h_phi * step / g.scale
        g0 = g.placement(v)
        gm = _minimise(self.pe, g0, h, hp)
        d = gm - g0
        u = g.axes @ d[:2] / h
        return bool(np.all(np.abs(u) <= 1.0) and abs(d[2]) <= hp and self.pe.energy(gm).energy > 0)

    # ---------------------------------------------------------------- noise
    def twin_noise(self, keys: Sequence[Key], floor: float, most: int = 48) -> float:
        """Relative noise from the twin realisation
        (:func:`~deformclosure.landscape.noise.twin_floor`: 2 × the 90th percentile of
        ``|E₁ − E₂| / max(E₁, E₂)``) over up to ``most`` of ``keys`` (the placements a
        search settled, i.e. below its barrier) with ``E ≥ floor`` (J)."""
        if self.twin is None:
            return 0.0
        keys = [k for k in keys if math.isfinite(self._E[k]) and self._E[k] >= floor and self._E[k] > 0]
        if not keys:
            return 0.0
        if len(keys) > most:
            keys = [keys[int(i)] for i in np.linspace(0, len(keys) - 1, most)]
        for k in keys:
            if k not in self._twin_E:
                self._twin_E[k] = self._twin_energy(k)
        keys = [k for k in self._twin_E if self._E[k] >= floor and math.isfinite(self._twin_E[k])]
        E1 = np.array([self._E[k] for k in keys])
        E2 = np.array([self._twin_E[k] for k in keys])
        return twin_floor(E1, E2)


    def _twin_energy(self, key: Key) -> float:
        """The twin realisation's energy (J) at ``key``."""
        return self.twin.energy(self.grid.placement(key)).energy


def jitter_noise(pe: PlacementEnergy, g: np.ndarray, h: float, h_phi: float, E0: float,
                 n: int = 9, factor: float = JITTER_FACTOR, angle: float = 0.0) -> float:
    """Relative noise: ``factor`` × the largest residual of quadratic fits of ``E`` along
    the lattice axes (``e₁``, ``e₂`` at ``angle``, and φ) over one cell about ``g``, over
    ``E0`` (:func:`~deformclosure.landscape.noise.jitter_floor`). Each side of ``g`` is
    fitted on its own: at a minimum held by corners or by contacts that open on one side
    the energy has a kink there, which is no noise."""
    if not E0 > 0:
        return 0.0
    n = 2 * (n // 2) + 1
    ts = np.linspace(-0.5, 0.5, n)
    m = n // 2
    projs = []
    for sl in (slice(0, m + 1), slice(m, n)):
        projs.append((sl, quadratic_residual(ts[sl])))
    worst = 0.0
    c, s = math.cos(angle), math.sin(angle)
    for step in (np.array([c * h, s * h, 0.0]), np.array([-s * h, c * h, 0.0]), np.array([0.0, 0.0, h_phi])):
        G = np.asarray(g, float)[None] + ts[:, None] * step[None]
        E, _ = pe.energies(G)
        if not np.all(np.isfinite(E)):
            continue
        for sl, proj in projs:
            worst = max(worst, float(np.abs(proj @ E[sl]).max()))
    return jitter_floor(worst, E0, factor)


# ----------------------------------------------------------------------------- result


@dataclass(frozen=True, eq=False)
class FingerRelease:
    """Release energy of a finger set (SPEC §7). SI units.

    Attributes
    ----------
    U_A : float
        Release energy (J): the minimax barrier from the equilibrium to a released
        placement or another equilibrium; ``inf`` if none is reachable (a cage); a lower
        bound when ``complete`` is False.
    U_A_error : float
        Error estimate of ``U_A`` (J): the largest change under a halving of the lattice
        near the saddle plus the noise floor at the saddle.
    deform_closure : bool
        Strict minimum and ``U_A > U_A_error``; at rest with the rigid part in form
        closure (``by_theorem1``), ``U_A > 0``.
    strict : bool
        The equilibrium is a strict local minimum (beyond the noise floor; at rest: the
        rigid form-closure test, Thm 1).
    caged : bool
        Not a strict minimum, yet leaving needs work (``U_A > U_A_error``).
    equilibrium : ndarray (3,)
        ``g*``: placement (m, m, rad) of the equilibrium.
    energy : float
        ``E(g*)`` (J, linear, this model).
    path : ndarray (k, 3)
        Escape path, placements from ``g*`` to the target (empty if ``U_A`` is ∞).
    path_energy : ndarray (k,)
        Energy (J) along it.
    saddle : int or None
        Index of the highest placement of the path.
    target : str or None
        ``"released"``, ``"equilibrium"`` or ``None``.
    noise_relative : float
        Relative noise floor.
    grid : PlacementGrid
    U_A_levels : list of float
        ``U_A`` on the coarse lattice and after each halving near the saddle.
    U_L : float
        Work (J) from the equilibrium to the elastic limit under proportional loading of
        the equilibrium's contact forces, ``E* ((e_L / e*)² − 1)``; ``inf`` at rest.
    quality : float
        ``min(U_A, U_L)`` (J) when held (deform closure), else 0.
    strain : float
        ``e*``: largest critical-distance-averaged strain magnitude at the equilibrium.
    saddle_strain : float or None
        The same at the saddle of the escape path.
    critical_distance : float
        ``ℓ`` (m).
    e_L : float or None
    n_evaluations : int
        Placements solved.
    complete : bool
        The search finished (not stopped by ``stop_above`` or the budget).
    seconds : float
    centroid : ndarray (2,)
        The point the placements turn about (the part's area centroid at rest, m).
    contact_forces, contact_points : ndarray (k, 2)
        Contact forces (N) at the equilibrium and their points on the part at rest (m),
        part frame.
    warnings : tuple of str
        E.g. point fingers pressing the part (their energies follow the mesh).
    by_theorem1 : bool
        At rest (``E* = 0``) with the rigid part in form closure: ``U_A > 0`` is certain
        (Thm 1), so ``deform_closure`` is ``U_A > 0`` and the noise floor does not zero
        ``U_A`` (SPEC §7).
    coarse_path : tuple of Key
        The coarse lattice's escape path (keys of :attr:`grid`), before the refinement
        near the saddle: the sub-landscape the finite-strain model re-solves
        (:mod:`.finite_strain_release`).
    twin_mesh : Mesh or None
        The second mesh realisation the noise floor was measured on (None without one):
        the finite-strain model measures its own floor on it.

    Examples
    --------
    Made by :func:`release_energy_fingers` (skipped: see there why):

    >>> rel = release_energy_fingers(mesh, fingers)                  # doctest: +SKIP
    >>> rel.U_A > rel.U_A_error, rel.target, rel.to_dict()["U_A"]     # doctest: +SKIP
    (True, 'released', 0.0037...)
    """

    U_A: float
    U_A_error: float
    deform_closure: bool
    strict: bool
    caged: bool
    equilibrium: np.ndarray
    energy: float
    path: np.ndarray
    path_energy: np.ndarray
    saddle: int | None
    target: str | None
    noise_relative: float
    grid: PlacementGrid
    U_A_levels: list
    U_L: float
    quality: float
    strain: float
    saddle_strain: float | None
    critical_distance: float
    e_L: float | None
    n_evaluations: int
    complete: bool
    seconds: float
    centroid: np.ndarray = field(default_factory=lambda: np.zeros(2))
    contact_forces: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    contact_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    warnings: tuple = ()
    by_theorem1: bool = False
    coarse_path: tuple = field(default=(), repr=False)
    twin_mesh: Any = field(default=None, repr=False)

    @property
    def U_A_infinite(self) -> bool:
        """Whether no release is reachable within the fingers' reach."""
        return math.isinf(self.U_A)

    def place(self, g: Any, points: Any) -> np.ndarray:
        """World coordinates (m) of part-frame ``points (k, 2)`` at placement ``g``."""
        g = np.asarray(g, float)
        c, s = math.cos(g[2]), math.sin(g[2])
        R = np.array([[c, -s], [s, c]])
        return (np.asarray(points, float) - self.centroid) @ R.T + self.centroid + g[:2]

    def to_dict(self) -> dict:
        """JSON-ready (SI); infinities are ``None`` with a ``*_infinite`` flag."""

        def num(v):
            return None if v is None or not math.isfinite(v) else float(v)

        return {
            "U_A": num(self.U_A),
            "U_A_infinite": bool(math.isinf(self.U_A)),
            "U_A_error": num(self.U_A_error),
            "deform_closure": bool(self.deform_closure),
            "strict_minimum": bool(self.strict),
            "caged": bool(self.caged),
            "quality": num(self.quality),
            "quality_infinite": bool(math.isinf(self.quality)),
            "U_L": num(self.U_L),
            "U_L_infinite": bool(math.isinf(self.U_L)),
            "escape_path": {
                "placements": self.path.tolist(),
                "energy": [num(e) for e in self.path_energy],
                "saddle": self.saddle,
                "target": self.target,
            },
            "release": {
                "equilibrium_placement": self.equilibrium.tolist(),
                "rotation_centre": self.centroid.tolist(),
                "equilibrium_energy": float(self.energy),
                "noise_floor_relative": float(self.noise_relative),
                "grid": {"d_translation": self.grid.h, "d_angle": self.grid.h_phi,
                         "refinements": int(round(math.log2(self.grid.scale))),
                         "U_A_levels": [num(u) for u in self.U_A_levels]},
                "strain_at_equilibrium": float(self.strain),
                "strain_at_saddle": num(self.saddle_strain),
                "critical_distance": float(self.critical_distance),
                "e_L": self.e_L,
                "placements_solved": int(self.n_evaluations),
                "complete": bool(self.complete),
                "energy_model": "linear",
                "warnings": list(self.warnings),
                "closure_rule": "thm1_at_rest" if self.by_theorem1 else "U_A_beyond_error",
                "seconds": float(self.seconds),
            },
        }


# ----------------------------------------------------------------------------- driver


def lattice_angle(mesh: Any) -> float:
    """Direction (rad) of the lattice's first translation axis, attached to the part: its
    principal axis of least area inertia (the long axis of a bar), or, when the two
    principal moments are within 1 % (a square, a disc), its first boundary edge."""
    x = np.asarray(mesh.nodes, float)
    tri = np.asarray(mesh.triangles)
    A = np.asarray(mesh.areas)
    c = (A[:, None] * x[tri].mean(axis=1)).sum(axis=0) / A.sum()
    P = x[tri] - c
    # second moments of each triangle about c: (A/12) (Σ p_i p_iᵀ + (Σ p_i)(Σ p_i)ᵀ)
    S = np.einsum("t,tij->ij", A / 12.0, np.einsum("tki,tkj->tij", P, P)
                  + np.einsum("ti,tj->tij", P.sum(axis=1), P.sum(axis=1)))
    w, V = np.linalg.eigh(S)
    if w[1] - w[0] <= 0.01 * w[1]:
        ring = x[mesh.outer_loop]
        e = ring[1] - ring[0]
        return float(math.atan2(e[1], e[0]))
    v = V[:, 1]                                    # the larger second moment ∑ p pᵀ: long axis
    if v[0] < 0 or (v[0] == 0 and v[1] < 0):
        v = -v
    return float(math.atan2(v[1], v[0]))


def _grid(pe: PlacementEnergy, g0: np.ndarray, n_translation: int, levels: int) -> PlacementGrid:
    """The lattice about ``g0`` (module docstring, step 2)."""
    D = pe.diameter
    rounds = [f.round_centre() for f in pe.fingers]
    radii = [rc[1] for rc in rounds if rc is not None]
    h = D / n_translation
    if radii:
        h = min(h, 0.5 * min(radii))
    R = pe.radius
    n_phi = int(math.ceil(2 * math.pi * R / h))
    scale = 2 ** int(levels)
    alpha = lattice_angle(pe.mesh)
    lo, hi = _translation_bounds(pe, g0, h, alpha)
    ilo = tuple(int(math.floor(v / h)) * scale for v in lo)
    ihi = tuple(int(math.ceil(v / h)) * scale for v in hi)
    return PlacementGrid(np.asarray(g0, float), float(h), n_phi, scale, ilo, ihi, float(alpha))


def _translation_bounds(pe: PlacementEnergy, g0: np.ndarray, h: float, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """Translation bounds (m, lattice frame at angle ``alpha``) about ``g0``: the bounded
    fingers' bounding box grown by the part's radius and two steps (at least ±2 steps);
    ±2 diameters when every finger is a half-plane."""
    R, D = pe.radius, pe.diameter
    c = pe.centroid + g0[:2]
    A = np.array([[math.cos(alpha), math.sin(alpha)], [-math.sin(alpha), math.cos(alpha)]])
    extents = [e for e in (f.extent_points() for f in pe.fingers) if e is not None]
    if not extents:
        return np.full(2, -2.0 * D), np.full(2, 2.0 * D)
    P = (np.concatenate(extents) - c) @ A.T                # lattice coordinates
    rounds = [rc for rc in (f.round_centre() for f in pe.fingers) if rc is not None]
    if rounds:                                             # disc corners in this frame
        P = np.vstack([P] + [((np.asarray(cc) - c) @ A.T) + r * np.array(sg)
                             for cc, r in rounds for sg in ((1, 1), (1, -1), (-1, 1), (-1, -1))])
    lo = P.min(axis=0) - R - 2 * h
    hi = P.max(axis=0) + R + 2 * h
    return np.minimum(lo, -2 * h), np.maximum(hi, 2 * h)


def equilibrium_placement(energy: PlacementEnergy, start: Any, h: float, h_phi: float) -> np.ndarray:
    """Local minimum ``g*`` (m, m, rad) of the contact energy near ``start``: BFGS on the
    exact generalised force, in coordinates scaled by the translation step ``h`` (m) and
    the rotation step ``h_phi`` (rad). A start where nothing presses is returned as is."""
    return _minimise(energy, np.asarray(start, float).reshape(3), h, h_phi)


def _minimise(pe: PlacementEnergy, g0: np.ndarray, h: float, h_phi: float) -> np.ndarray:
    """Local minimum of ``E`` near ``g0`` (BFGS on lattice-scaled coordinates)."""
    from scipy.optimize import minimize

    s0 = pe.energy(g0)
    if not (s0.energy > 0 and math.isfinite(s0.energy)):
        return np.asarray(g0, float)
    scale = np.array([h, h, h_phi])
    E0 = s0.energy
    warm = {"act": s0.active}

    def f(z):
        st = pe.energy(g0 + z * scale, warm["act"])
        if not math.isfinite(st.energy):
            return 1e6, np.zeros(3)
        warm["act"] = st.active
        return st.energy / E0, st.gradient * scale / E0

    res = minimize(f, np.zeros(3), jac=True, method="BFGS", options={"gtol": 1e-9, "maxiter": 200})
    z = res.x if res.fun <= 1.0 else np.zeros(3)
    return np.asarray(g0, float) + z * scale


def _strain(pe: PlacementEnergy, state: PlacementState, ell: float) -> float:
    from ..elasticity.critical_distance import averaged_strain_maximum
    from ..elasticity.strain import element_strains

    if len(state.forces) == 0:
        return 0.0
    u = pe.displacement(state)
    return float(averaged_strain_maximum(pe.mesh, element_strains(pe.mesh, u), ell))


def release_energy_fingers(mesh: Any, fingers: Sequence[Finger], *, part: Any = None, solver: Any = None,
                           start: Any = None, rigid_closed: bool | None = None, n_translation: int = 48,
                           levels: int = 2, noise: bool = True, twin: Any = None, stop_above: float | None = None,
                           max_evaluations: int = 200_000, progress: Callable[[str], None] | None = None,
                           count: Callable[[int], None] | None = None) -> FingerRelease:
    """Release energy ``U_A`` of a part held by fixed fingers, with its escape path.

    Parameters
    ----------
    mesh : Mesh
        The part at rest (m) with its material.
    fingers : sequence of Finger
        Fixed fingers (m), placed against the part at rest (touching or pre-squeezing).
    part : Part, optional
        The part's geometry: enables the twin-mesh noise floor (:func:`deformclosure.mesh.generate.twin_mesh`).
    solver : PadContact, optional
        Reuse a factorisation of ``mesh``.
    start : array_like (3,) or EquilibriumResult, optional
        Where to look for the equilibrium: a placement, or the contact equilibrium of
        :func:`~deformclosure.dspace.equilibrium.equilibrium` (its rigid motion); default
        the rest placement ``(0, 0, 0)``.
    rigid_closed : bool, optional
        Verdict of the rigid test (:func:`~deformclosure.dspace.closure.deform_closure`),
        used at rest (``E* = 0``, Thm 1); computed when needed and not given.
    n_translation : int
        Coarse translation step ``D / n_translation`` (at most half the smallest disc radius).
    levels : int
        Halvings of the lattice near the saddle.
    noise : bool
        Measure and use the noise floor.
    twin : PadContact, optional
        A second mesh realisation's solver (default: made from ``part`` when given).
    stop_above : float, optional
        Stop the search once the barrier exceeds this (J): enough to decide the verdict
        (``U_A`` is then a lower bound, ``complete`` False).
    max_evaluations : int
        Budget of contact problems.
    progress : callable, optional
        Receives one line per step (also logged on the package logger).
    count : callable, optional
        Receives the number of placements solved so far, every 100.

    Returns
    -------
    FingerRelease
        ``U_A`` (J) with its error, the verdict, the escape path (m, m, rad) and its
        energies (J), the elastic limit ``U_L`` (J) and the quality (J).

    Raises
    ------
    FingerError
        ``fingers`` is not a sequence of fingers.
    DeformClosureError
        A bad ``start``, lattice parameter or budget, or a finger reaching deeper into the
        part at the start than the model allows.

    Examples
    --------
    A 40 mm x 20 mm plate pinched by two discs at the middle of its long sides and
    stopped at its ends by two point fingers. Skipped as a doctest: the first call
    compiles the contact kernels (one to two minutes), and the search solves thousands
    of contact problems.

    >>> from deformclosure import Part, mesh_part
    >>> from deformclosure.dspace import DiscFinger, PointFinger, release_energy_fingers
    >>> plate = Part.from_dict({"units": "mm", "outer": [[0, 0], [40, 0], [40, 20], [0, 20]], "mesh": {
    ...     "max_area": 20}, "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "elastic_limit_strain": 0.5}})
    >>> fingers = [DiscFinger((0.02, -0.0049), 0.005), DiscFinger((0.02, 0.0249), 0.005),
    ...            PointFinger((0.0, 0.01)), PointFinger((0.04, 0.01))]
    >>> rel = release_energy_fingers(mesh_part(plate), fingers, n_translation=16, levels=1,
    ...                              noise=False)           # doctest: +SKIP
    >>> rel.U_A > 0, rel.deform_closure, rel.path.shape[1]  # doctest: +SKIP
    (True, True, 3)
    """
    fingers = as_fingers(fingers)
    _check_lattice(n_translation, levels, max_evaluations)
    with blas_threads():          # a loop over placements: small solves (limits.BLAS_THREADS)
        return _release(mesh, fingers, part=part, solver=solver, start=start, rigid_closed=rigid_closed,
                        n_translation=n_translation, levels=levels, noise=noise, twin=twin,
                        stop_above=stop_above, max_evaluations=max_evaluations,
                        say=_reporter(progress), count=count)


#: The lattice key of the equilibrium placement.
_ORIGIN: Key = (0, 0, 0)


def _reporter(progress: Callable[[str], None] | None) -> Callable[[str], None]:
    """A function that logs a line and passes it to ``progress``."""
    from ..log import logger

    def say(line: str) -> None:
        logger.info(line)
        if progress is not None:
            progress(line)

    return say


def _check_lattice(n_translation: Any, levels: Any, max_evaluations: Any) -> None:
    """Refuse lattice parameters and budgets that are not finite numbers in range."""
    for name, v, ok, want in (("n_translation", n_translation, lambda x: x > 0, "> 0"),
                              ("levels", levels, lambda x: x >= 0, ">= 0"),
                              ("max_evaluations", max_evaluations, lambda x: x >= 0, ">= 0")):
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                or not math.isfinite(v) or not ok(v):
            raise DeformClosureError(f"{name} = {v!r}: give a finite number {want}")


def _release(mesh: Any, fingers: tuple[Finger, ...], *, part: Any, solver: Any, start: Any,
             rigid_closed: bool | None, n_translation: int, levels: int, noise: bool, twin: Any,
             stop_above: float | None, max_evaluations: int, say: Callable[[str], None],
             count: Callable[[int], None] | None) -> FingerRelease:
    """:func:`release_energy_fingers` in its named steps (module docstring)."""
    t0 = time.perf_counter()
    pe = PlacementEnergy(mesh, fingers, solver=solver)
    g0 = _start_placement(pe, start)
    grid0 = _grid(pe, g0, n_translation, levels)
    gstar = _minimise(pe, g0, grid0.h, grid0.h_phi)
    grid = _grid(pe, gstar, n_translation, levels)
    land = PlacementLandscape(pe, grid, max_evaluations, count)
    Es = land.energy(_ORIGIN)
    say(f"equilibrium placement ({gstar[0]:.4g} m, {gstar[1]:.4g} m, {gstar[2]:.4g} rad), "
        f"E = {Es:.6g} J; lattice h = {grid.h:.3g} m, {grid.n_phi} angles")
    tau = _start_noise(land, gstar, Es, noise, twin, part)
    start_state = land.state(_ORIGIN)
    strict = _strict_at_rest(pe, gstar, Es, rigid_closed, mesh, fingers)
    res, tau = _minimax(land, Es, tau, stop_above)
    if strict is None:
        # strict beyond the noise: the placements within the noise floor of the start's
        # energy (its plateau) stay within two lattice steps of it
        strict = res.plateau <= 2 * grid.scale
    say(f"coarse search: {land.n_evaluated} placements, barrier {res.barrier - Es:.6g} J, "
        f"target {res.target}")
    path, levels_U = _refine(land, res, levels, Es, tau)
    # at rest a touching form-closed set cannot leave without deforming the part (Thm 1):
    # its barrier exists whatever the (relative) noise floor; otherwise U_A must exceed
    # its error (SPEC §7)
    thm1 = bool(Es == 0.0 and strict)
    Ep, U_A, U_err = _barrier(land, res, path, levels_U, Es, tau, exists=thm1)
    held = U_A > 0.0 if thm1 else U_A > U_err
    deform = bool(strict and held)
    saddle = int(np.argmax(Ep)) if len(Ep) else None
    ell, e_star, e_sad, e_L, U_L = _elastic_limit(mesh, pe, land, start_state, path, saddle, Es)
    say(f"U_A = {U_A:.6g} J ± {U_err:.3g} J; {land.n_evaluated} placements solved")
    return FingerRelease(
        U_A=float(U_A), U_A_error=float(U_err), deform_closure=deform, strict=bool(strict),
        caged=bool((not strict) and held), equilibrium=gstar, energy=float(Es),
        path=np.array([grid.placement(k) for k in path]).reshape(-1, 3), path_energy=Ep, saddle=saddle,
        target=res.target, noise_relative=float(tau), grid=grid, U_A_levels=levels_U, U_L=float(U_L),
        quality=float(min(U_A, U_L) if deform else 0.0), strain=e_star, saddle_strain=e_sad,
        critical_distance=float(ell), e_L=e_L, n_evaluations=land.n_evaluated, complete=bool(res.complete),
        seconds=time.perf_counter() - t0, centroid=pe.centroid.copy(), contact_forces=start_state.forces,
        contact_points=start_state.points, warnings=_point_finger_notes(start_state, fingers, Es),
        by_theorem1=thm1, coarse_path=tuple(res.path),
        twin_mesh=None if land.twin is None else land.twin.mesh)


def _start_placement(pe: PlacementEnergy, start: Any) -> np.ndarray:
    """The placement ``(x, y, φ)`` where the search for the equilibrium starts; refused
    when a finger reaches deeper into the part there than the model allows."""
    if start is None:
        g0 = np.zeros(3)
    elif hasattr(start, "translation"):
        g0 = np.r_[np.asarray(start.translation, float), float(start.rotation)]
    else:
        try:
            g0 = np.asarray(start, float).reshape(3)
        except (TypeError, ValueError):
            g0 = np.full(3, np.nan)
    if not np.all(np.isfinite(g0)):
        raise DeformClosureError(f"start = {start!r:.60}: give a placement [x, y, phi] (m, m, rad), an "
                                 "EquilibriumResult or None for the rest placement")
    if not math.isfinite(pe.energy(g0).energy):
        raise DeformClosureError(
            "fingers: at the start placement a finger reaches deeper into the part than the "
            f"model allows ({pe.depth_limit:.3g} m, half the largest inscribed radius) or cuts "
            "through it; place the fingers against the part, touching or slightly overlapping it")
    return g0


def _start_noise(land: PlacementLandscape, gstar: np.ndarray, Es: float, noise: bool, twin: Any,
                 part: Any) -> float:
    """The jitter noise floor at the equilibrium; with ``noise``, also the twin mesh
    realisation of the landscape (given, or made from ``part``)."""
    pe, grid = land.pe, land.grid
    tau = 0.0
    if noise and Es > 0:
        tau = jitter_noise(pe, gstar, grid.h, grid.h_phi, Es, angle=grid.angle)
    if noise:
        if twin is None and part is not None:
            from ..contact.compliance import BoundaryCompliance
            from ..mesh.generate import twin_mesh

            twin = BoundaryCompliance.placement_gauge(twin_mesh(part))
        if twin is not None:
            land.twin = PlacementEnergy(twin.mesh, pe.fingers, solver=twin, centroid=pe.centroid,
                                        disc_axes_=pe.disc_axes)
    return tau


def _strict_at_rest(pe: PlacementEnergy, gstar: np.ndarray, Es: float, rigid_closed: bool | None, mesh: Any,
                    fingers: Sequence[Finger]) -> bool | None:
    """At rest (``E* = 0``) the equilibrium is strict iff a finger touches and the rigid
    part is in form closure (Thm 1); ``None`` otherwise (decided from the noise plateau)."""
    if Es != 0.0:
        return None
    if not _touching(pe, gstar):
        return False
    if rigid_closed is None:
        from .closure import deform_closure

        rigid_closed = deform_closure(mesh, fingers).deform_closure
    return bool(rigid_closed)


def _minimax(land: PlacementLandscape, Es: float, tau: float, stop_above: float | None,
             start: Key = _ORIGIN) -> tuple[Escape, float]:
    """The coarse minimax search from ``start``, repeated while the noise floor measured
    by the twin on the placements it settled rises. Returns the search and the floor."""
    for _ in range(4):
        res = land.search(start, land.grid.scale, tau, stop_above=stop_above)
        if land.twin is None:
            break
        new = land.twin_noise(res.settled, 0.5 * Es)
        if new <= tau:
            break
        tau = new
    return res, tau


def _refine(land: PlacementLandscape, res: Escape, levels: int, Es: float, tau: float) -> tuple[list, list]:
    """The path searched again near its saddle on lattices halved ``levels`` times (boxes
    of ±3 fine steps). Returns the path and ``U_A`` after each level."""
    grid = land.grid
    path = res.path
    levels_U = [res.barrier - Es]
    if not (res.complete and res.target is not None and math.isfinite(res.barrier) and len(path) > 1):
        return path, levels_U
    for lev in range(1, int(levels) + 1):
        step = grid.scale >> lev
        Ep = [land.energy(k) for k in path]
        si = int(np.argmax(Ep))
        if Ep[si] <= Es:
            levels_U.append(levels_U[-1])
            continue
        half = 3 * step
        c = path[si]
        i_in = si
        while i_in > 0 and grid.distance(path[i_in - 1], c) <= half:
            i_in -= 1
        i_out = si
        while i_out < len(path) - 1 and grid.distance(path[i_out + 1], c) <= half:
            i_out += 1
        loc = land.search(path[i_in], step, tau, goal=path[i_out], box=(c, half))
        if loc.target == "goal":
            path = path[:i_in] + loc.path + path[i_out + 1:]
        levels_U.append(max(land.energy(k) for k in path) - Es)
    return path, levels_U


def _barrier(land: PlacementLandscape, res: Escape, path: list, levels_U: list, Es: float,
             tau: float, exists: bool = False) -> tuple[np.ndarray, float, float]:
    """Energy along the path, ``U_A`` and its error estimate (module docstring, 3-5);
    ``exists``: the barrier is known to exist (at rest, Thm 1), so the noise floor does not
    make it none."""
    Ep = np.array([land.energy(k) for k in path]) if path else np.zeros(0)
    barrier = float(Ep.max()) if len(Ep) else (math.inf if res.complete else res.barrier)
    if res.complete and res.target is None:
        barrier = math.inf
    if not res.complete:
        barrier = max(res.barrier, barrier if math.isfinite(barrier) else -math.inf)
    U_A = barrier - Es
    if math.isfinite(U_A) and not resolved(U_A, barrier, tau) and not exists:
        U_A = 0.0                                     # a barrier within the noise is none
    fin = [u for u in levels_U if math.isfinite(u)]
    grid_err = max((abs(a - b) for a, b in zip(fin[:-1], fin[1:])), default=0.0)
    U_err = grid_err + (tau * barrier if math.isfinite(barrier) else 0.0)
    return Ep, U_A, U_err


def _elastic_limit(mesh: Any, pe: PlacementEnergy, land: PlacementLandscape, start_state: PlacementState,
                   path: list, saddle: int | None, Es: float) -> tuple:
    """Critical distance ``ℓ`` (m), averaged strains at the equilibrium and the saddle,
    ``e_L`` and ``U_L`` (J): the elastic limit over the critical distance."""
    from ..elasticity.critical_distance import critical_distance_of
    from ..landscape.limit import energy_to_limit_from_rest

    ell = critical_distance_of(mesh)
    e_star = _strain(pe, start_state, ell)
    e_sad = _strain(pe, land.state(path[saddle]), ell) if saddle is not None else None
    mat = getattr(mesh, "material", None)
    e_L = None if mat is None else float(mat.elastic_limit_strain)
    # the one elastic-limit rule: the state loaded proportionally from rest
    U_L = math.inf if e_L is None else energy_to_limit_from_rest(Es, e_star, e_L)
    return ell, e_star, e_sad, e_L, U_L


def _point_finger_notes(start_state: PlacementState, fingers: Sequence[Finger], Es: float) -> tuple[str, ...]:
    """A warning when fingers without interior (points) press the part."""
    points = sorted({int(i) for i in start_state.fingers if not fingers[int(i)].has_interior})
    if Es > 0 and points:
        return (f"point fingers {points} press the part: a point force in 2-D has no finite "
                "stiffness, so the energies and U_A follow the mesh; refine it or model the "
                "fingertips as discs",)
    return ()


def _touching(pe: PlacementEnergy, g: np.ndarray) -> bool:
    """Whether some finger touches the part at placement ``g`` (within 10 × tol)."""
    from .placement_energy import _scan

    z = _scan(np.asarray(g, float), 10.0 * pe.tol, True, *pe._args(), pe._cap)
    return bool(z[0] > 0 and np.min(z[11][:z[0]]) <= 10.0 * pe.tol)
