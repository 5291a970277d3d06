"""Optimal separation of a two-pad grasp: ``σ* = argmax min(U_A, U_L)`` (SPEC §6).

``U_A(σ)`` is the minimax barrier on the axis landscape (:mod:`.landscape`), ``U_L(σ) =
U(σ_L) − U(σ)`` with ``σ_L`` from the critical-distance strain (:mod:`.limit`). Every
vertex energy is an exact piecewise quadratic in σ, and σ* is found by the one σ*-search
over piecewise-quadratic curves, :func:`deformclosure.landscape.optimum.maximise_quality`
(closed form per piece, candidates checked by definition, bisection where the saddle
changes; ``U_A`` can jump there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GraspError
from ..landscape.noise import combined_floor
from .contact import GraspCurve, PadContact
from .geometry import GraspAxis, Pad
from ..landscape.optimum import maximise_quality
from .landscape import AxisGrid, Landscape, Release
from .noise import jitter_noise
from .saddle_grid import SaddleRefinedGrid
from .limit import (LINEAR_STRAIN_RANGE, PadLimit, elastic_limit_strain_of,
                    pad_elastic_limit, pad_strain_at)

__all__ = ["PadGraspResult", "optimize_pads", "UNITS", "check_counts", "mesh_is_blind",
           "boundary_spacing"]

UNITS = {"length": "m", "energy": "J", "stiffness": "N/m", "strain_per_length": "1/m",
         "angle": "rad", "force": "N"}


@dataclass(frozen=True, eq=False)
class PadGraspResult:
    """Optimal separation of one pad grasp (SPEC §6 report). SI units.

    Attributes
    ----------
    axis, pad : GraspAxis, Pad
    contacts : ndarray, shape (2, 2)
        Rest contact points of pads A and B (m).
    sigma0, sigma_L : float
        First-touch width and elastic-limit separation (m).
    sigma_star : float or None
        Optimal separation (m); ``None`` when ``Q ≡ 0``.
    quality, U_A, U_L : float
        At σ* (J); ``U_A`` may be ``inf``.
    noise : float
        Noise floor of the landscape at σ* (J; mid-range if not held): energy
        differences below it are not resolved on this mesh.
    noise_relative : float
        The same relative to the start axis' energy.
    limit : PadLimit
    curve : dict
        ``{"sigma", "U", "U_A", "U_L", "Q", "F"}`` samples for plotting (m, J, N;
        ``None`` = ∞).
    escape_path : list of GraspAxis
        Minimax escape at σ*, start first (empty if U_A is 0 or ∞).
    force : float or None
        The pads' axial force at σ* (N), ``None`` when ``Q ≡ 0`` (SPEC §6 "Grip force");
        ``curve["F"]`` holds it at every curve σ.
    stiffness : float or None
        Grip stiffness ``dF/dδ = −dF/dσ`` (N/m) at σ* (contracting; for an expanding
        grasp the growth of the force with the opening).
    n_axes : int
        Number of axes whose contact problem was solved.
    grid : AxisGrid or SaddleRefinedGrid
        The landscape's grid of axes (refined around earlier saddles when adaptive).
    saddle : GraspAxis or None
        The escape path's highest axis at σ* (``None`` without a finite barrier): where
        the next level refines the landscape.
    escape_vertices : tuple of int
        The escape path as vertices of ``grid`` (the finite-strain model re-solves them,
        SPEC §8).
    strain_at_sigma_star : float or None
        The strain measure of SPEC §6 at σ* (dimensionless); above
        :data:`~deformclosure.pads.limit.LINEAR_STRAIN_RANGE` a warning says that linear
        elasticity is outside its range (SPEC §8).
    """

    axis: GraspAxis
    pad: Pad
    contacts: np.ndarray
    sigma0: float
    sigma_L: float
    sigma_star: float | None
    quality: float
    U_A: float
    U_L: float
    noise: float
    noise_relative: float
    limit: PadLimit
    curve: dict
    escape_path: list
    n_axes: int
    grid: AxisGrid
    start_curve: GraspCurve = field(repr=False)
    n_nodes: int = 0
    e_L: float | None = None
    strain_at_sigma_star: float | None = None
    blind: bool = False
    unresolved: bool = False
    warnings: tuple[str, ...] = ()
    solver: PadContact | None = field(default=None, repr=False, compare=False)
    saddle: GraspAxis | None = None
    escape_vertices: tuple[int, ...] = ()

    @property
    def force(self) -> float | None:
        """The pads' axial force (N) at σ*, ``None`` when ``Q ≡ 0``."""
        return None if self.sigma_star is None else self.start_curve.axial_force(self.sigma_star)

    @property
    def stiffness(self) -> float | None:
        """Grip stiffness ``−dF/dσ`` (N/m) at σ*, ``None`` when ``Q ≡ 0``."""
        return (None if self.sigma_star is None
                else self.start_curve.axial_stiffness(self.sigma_star))

    def state_at(self, sigma: float, label: str):
        """Displacement (m) and nodal contact forces (N) of the start axis at separation
        ``sigma`` (m), as a :class:`deformclosure.fields.FieldState`."""
        from ..fields import FieldState

        from .geometry import placed_pads

        solver, curve = self.solver, self.start_curve
        n = solver.mesh.n_nodes
        forces = np.zeros((n, 2))
        if curve.path is None:
            return FieldState(label, np.zeros(2 * n), forces, sigma=float(sigma))
        delta = float(curve.delta(sigma))
        lam = curve.path.multipliers(delta)
        np.add.at(forces, curve.nodes, lam[:, None] * curve.normals)
        u = solver.displacement(solver.load_vector(curve, lam))
        pads = placed_pads(self.pad, self.axis, curve.touch, max(delta, 0.0),
                           solver.mesh.nodes, u, forces)
        return FieldState(label, u, forces, sigma=float(sigma), squeeze=delta, pads=pads)

    @property
    def resolves(self) -> bool:
        """Whether this mesh can decide a verdict on its own: the pads meet more than one
        node (not :func:`mesh_is_blind`) and the elements at the contacts are at most half
        the critical distance (SPEC §6: what the first level of a refinement guarantees;
        ``unresolved`` otherwise, with a warning)."""
        return not (self.blind or self.unresolved)

    @property
    def verdict(self) -> str:
        """``"held"`` iff quality > 0 on a mesh that resolves the answer (single mesh;
        ``--refine`` refines this, :attr:`resolves`); a barrier on a blind or coarser mesh
        is ``"undecided"``: measured, a 12 × 20 mm block between round-ended flat pads
        (convex: never held without friction) shows Q* 2.6 × its noise floor on its
        216-node mesh, whose contact elements are 1.5 mm against ℓ/2 = 0.23 mm."""
        if self.quality <= 0:
            return "not held"
        return "held" if self.resolves else "undecided"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready report (SPEC §6), SI; an infinite U_A is ``None`` + ``U_A_infinite``."""
        inf = math.isinf(self.U_A)
        return {
            "model": "pads",
            "pad": self.pad.to_dict(),
            "axis": self.axis.to_dict(),
            "contacts": self.contacts.tolist(),
            "sigma0": self.sigma0,
            "sigma_L": self.sigma_L,
            "sigma_star": self.sigma_star,
            "quality": self.quality,
            "U_A": None if inf else self.U_A,
            "U_A_infinite": inf,
            "U_L": self.U_L,
            "force": self.force,
            "stiffness": self.stiffness,
            "verdict": self.verdict,
            "noise_floor": self.noise,
            "noise_floor_relative": self.noise_relative,
            "critical_distance": self.limit.critical_distance,
            "e_L": self.e_L,
            "strain_at_sigma_star": self.strain_at_sigma_star,
            "elasticity": "linear",
            "mode": "expanding" if self.start_curve.expanding else "contracting",
            "warnings": list(self.warnings),
            "escape_path": [ax.to_dict() for ax in self.escape_path],
            "grid": _grid_dict(self.grid),
            "n_axes_solved": self.n_axes,
            "nodes": self.n_nodes,
            "energy_model": "linear",
            "curve": self.curve,
            "units": UNITS,
        }


def _grid_dict(grid) -> dict:
    """The report's ``grid``: spacing and counts, and the saddle refinement if any."""
    if hasattr(grid, "to_dict"):
        return grid.to_dict()
    return {"d_angle": grid.d_angle, "d_offset": grid.d_offset, "n_angles": grid.n_angles,
            "n_offsets": grid.n_offsets, "refinement": 1, "patches": 0, "patch_vertices": 0}


@dataclass
class _Eval:
    sigma: float
    release: Release
    UL: float

    @property
    def UA(self) -> float:
        return self.release.U_A

    @property
    def Q(self) -> float:
        return min(self.UA, self.UL)

    @property
    def key(self):
        r = self.release
        return (r.strict, r.saddle if r.strict and math.isfinite(r.U_A) else None,
                math.isinf(r.U_A))


def optimize_pads(mesh, axis: GraspAxis, pad: Pad, *, solver: PadContact | None = None,
                  twin: PadContact | None = None, hole: int | None = None,
                  twin_hole: int | None = None, n_angles: int = 48, n_offsets: int = 50,
                  n_samples: int = 48, n_curve: int = 120, noise: bool = True,
                  saddles: tuple[int, list] | None = None,
                  known: tuple[dict, dict] | None = None) -> PadGraspResult:
    """Optimal separation ``σ* = argmax min(U_A, U_L)`` of a two-pad grasp on ``axis``.

    Parameters
    ----------
    mesh : Mesh
        Nodes in m, with a material (``e_L``, optional ``critical_distance`` in m).
    axis : GraspAxis
        Start axis in the part frame (angle in rad, offset in m).
    pad : Pad
        Width and end radius in m.
    solver : PadContact, optional
        Reuse a factorisation of this mesh.
    twin : PadContact, optional
        The part meshed again (:func:`deformclosure.mesh.generate.twin_mesh`): the noise floor from its energies
        on the axes compared; without it, from the jitter under sub-cell moves of the axis.
    hole, twin_hole : int, optional
        Expanding grasp: the pads open inside this hole of ``mesh`` (of ``twin``),
        starting at the axis point nearest the hole's centroid; ``σ`` grows from ``σ0``.
    n_angles, n_offsets : int
        Landscape grid: ``Δθ = π/n_angles`` (rad), ``Δc = D/n_offsets`` (m, D = diameter).
    n_samples, n_curve : int
        σ samples that start the exact search, and of the plotted curve (each at least 2).
    noise : bool
        Measure and use the landscape's noise floor (see :mod:`.noise`).
    saddles : (int, list of GraspAxis), optional
        ``(factor, axes)``: refine the landscape grid ``factor`` times around these axes
        (:class:`~deformclosure.pads.saddle_grid.SaddleRefinedGrid`; the saddles of a
        coarser level).
    known : (dict, dict), optional
        Curves already traced on ``solver`` and on ``twin`` with this grid's spacing, by
        vertex (re-solves of one level share them); updated in place.

    Returns
    -------
    PadGraspResult
        σ0, σ_L, σ* in m; quality, U_A, U_L in J.

    Raises
    ------
    GraspError
        No material, a count out of range, or pads that miss the part on ``axis``.

    Examples
    --------
    Round 2 mm pads seated in the V-notches of the notched bar (about 1 s):

    >>> from deformclosure import mesh_part, notched_part
    >>> from deformclosure.pads import GraspAxis, Pad
    >>> mesh = mesh_part(notched_part(), max_area=1e-6)            # m²
    >>> res = optimize_pads(mesh, GraspAxis(1.5707963, -0.015), Pad(0.0, 2e-3),
    ...                     n_angles=8, n_offsets=8, noise=False)
    >>> round(res.sigma0 * 1e3, 3), res.verdict                    # mm
    (7.657, 'undecided')

    (one mesh whose contact elements exceed ℓ/2 decides nothing: :attr:`PadGraspResult.resolves`;
    ``pad_grasp`` refines to an accuracy and decides "held".)
    """
    e_L = elastic_limit_strain_of(mesh)
    check_counts(n_angles=n_angles, n_offsets=n_offsets, n_samples=(n_samples, 2),
                  n_curve=(n_curve, 2))
    solver = PadContact(mesh) if solver is None else solver
    start_curve = _start_curve(solver, GraspAxis(axis.angle, axis.offset, axis.origin), pad, hole)
    sigma0 = start_curve.sigma0
    limit = pad_elastic_limit(solver, start_curve, e_L)
    sigma_L = limit.sigma_L
    land, start_axis = _landscape(solver, axis, pad, start_curve, sigma_L, hole, n_angles,
                                  n_offsets, saddles, None if known is None else known[0])
    grid, s, Us = land.grid, land.grid.vertex(0, 0), start_curve.energy_at
    tau = (_noise_floor(land, start_axis, twin, twin_hole, None if known is None else known[1])
           if noise else (lambda sig: 0.0))
    U_sL = float(Us(sigma_L))
    sigma_star, e_star = _optimum(land, s, Us, U_sL, sigma_L, sigma0, tau, n_samples, noise)
    sig_n = sigma_star if sigma_star is not None else 0.5 * (sigma_L + sigma0)
    curve = _sample_curve(land, s, Us, U_sL, sigma_L, sigma0, tau, n_curve, sigma_star,
                          start_curve.axial_force)
    rel = e_star.release
    barrier = rel.strict and math.isfinite(rel.U_A) and sigma_star is not None
    path = [grid.axis(v) for v in rel.path] if barrier else []
    saddle = grid.axis(rel.saddle) if barrier and rel.saddle is not None else None
    contacts = np.array([start_curve.touch.contact_a, start_curve.touch.contact_b])
    strain = (None if sigma_star is None
              else pad_strain_at(solver, start_curve, sigma_star, limit.critical_distance))
    coarse = _contact_size_warnings(mesh, contacts, pad, limit.critical_distance)
    return PadGraspResult(
        axis=GraspAxis(axis.angle, axis.offset, axis.origin), pad=pad, contacts=contacts,
        sigma0=sigma0, sigma_L=sigma_L, sigma_star=sigma_star,
        quality=0.0 if sigma_star is None else e_star.Q,
        U_A=e_star.UA if sigma_star is not None else 0.0,
        U_L=e_star.UL if sigma_star is not None else 0.0,
        noise=tau(sig_n) * float(Us(sig_n)), noise_relative=tau(sig_n),
        limit=limit, curve=curve, escape_path=path, n_axes=land.n_evaluated, grid=grid,
        start_curve=start_curve, n_nodes=mesh.n_nodes, e_L=e_L,
        strain_at_sigma_star=strain, blind=mesh_is_blind(mesh, pad, hole),
        unresolved=bool(coarse), warnings=_resolution_warnings(mesh, pad, hole)
        + _range_warnings(strain) + coarse, solver=solver,
        saddle=saddle, escape_vertices=tuple(rel.path) if barrier else ())


def _landscape(solver: PadContact, axis: GraspAxis, pad: Pad, start_curve: GraspCurve,
               sigma_L: float, hole: int | None, n_angles: int, n_offsets: int,
               saddles: tuple[int, list] | None = None, known: dict | None = None
               ) -> tuple[Landscape, GraspAxis]:
    """The release landscape of ``axis`` traced to ``sigma_L`` (m), its start (vertex
    ``(0, 0)``) seeded with ``start_curve``, and the start axis re-anchored at the area
    centroid, so that the grid's wrap ``(θ + π, −c)`` is exact; refined around
    ``saddles`` = ``(factor, axes)`` when given."""
    start_axis = GraspAxis.at(axis.point, axis.angle, solver.centroid)
    grid = AxisGrid.over_part(solver, start_axis, pad, n_angles, n_offsets)
    if saddles is not None and saddles[0] > 1 and saddles[1]:
        grid = SaddleRefinedGrid.around(grid, saddles[0], saddles[1])
    land = Landscape(solver, pad, grid, sigma_L, hole, known)
    land.seed(grid.vertex(0, 0), start_curve)
    return land, start_axis


def _optimum(land: Landscape, s: int, Us, U_sL: float, sigma_L: float, sigma0: float, tau,
             n_samples: int, noise: bool) -> tuple[float | None, _Eval]:
    """``σ*`` (``None`` when ``Q ≡ 0``) and the evaluation there (at ``σ0`` without one).

    With a twin the noise floor grows as the search visits more axes: the search is
    repeated until every axis it compares has been measured on both realisations.
    """
    for _ in range(4):
        best, ev = _search_sigma_star(land, s, Us, U_sL, sigma_L, sigma0, tau, n_samples)
        if land.twin is None or not noise or not land.measure_noise():
            break
    sigma_star = None if best is None else best[1]
    return sigma_star, ev(sigma0 if sigma_star is None else sigma_star)


def check_counts(**counts) -> None:
    """Each ``name=value`` or ``name=(value, least)`` a whole number ≥ least (default 1)."""
    for name, spec in counts.items():
        value, least = spec if isinstance(spec, tuple) else (spec, 1)
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise GraspError(f"{name} = {value!r}: give a whole number >= {least}")


def _start_curve(solver: PadContact, ax0: GraspAxis, pad: Pad, hole: int | None) -> GraspCurve:
    """The start axis' curve: closed to σ = 0, or (expanding) opened to three times the
    rest width, or until the elastic limit; refused if the pads do not grip there."""
    if hole is None:
        start_curve = solver.curve(ax0, pad, 0.0)
    else:
        touch = solver.curve(ax0, pad, -np.inf, hole)
        start_curve = touch if touch.touch is None else solver.curve(ax0, pad, 3 * touch.sigma0, hole)
    if start_curve.touch is None:
        where = ("the pads miss the part on this axis; move the axis onto the part" if hole is None
                 else "the pads do not fit in the hole on this axis, or the axis misses its centre")
        raise GraspError(f"axis: {where}")
    if start_curve.path is None:
        raise GraspError("axis: no mesh node within the pads' reach at first touch; refine the "
                         "mesh (mesh.max_area) or use larger pads")
    return start_curve


def _noise_floor(land: Landscape, start: GraspAxis, twin: PadContact | None,
                 twin_hole: int | None, known: dict | None = None):
    """The relative noise floor ``tau(σ)`` of the landscape's start axis ``start``.

    Two views of the noise: the jitter under sub-cell moves of the start axis (the nodes'
    positions under the pads) and, with a twin, the spread between two mesh realisations
    over every axis the search compares (attached to ``land``). The larger counts.
    """
    grid, hole = land.grid, land.hole
    jitter = jitter_noise(land.solver, land.pad, start, grid.d_offset, grid.d_angle,
                          land.sigma_end, hole=hole)
    if twin is not None and (hole is None or twin_hole is not None):
        land.twin = Landscape(twin, land.pad, grid, land.sigma_end, twin_hole, known)
    return lambda sig: combined_floor(jitter(sig), land.noise(sig))


def _range_warnings(strain: float | None) -> tuple[str, ...]:
    """A warning when the strain at σ* is beyond small strain (SPEC §8)."""
    if strain is not None and strain > LINEAR_STRAIN_RANGE:
        return (f"the strain at sigma* is {strain:.3g} (> {LINEAR_STRAIN_RANGE}): linear "
                "elasticity is outside its range there, so sigma* and Q* are first-order "
                "estimates; rerun with --elasticity neo-hookean (SPEC §8)",)
    return ()


def boundary_spacing(mesh, hole: int | None = None) -> float:
    """Median distance (m) between neighbouring nodes of the outer loop (or of hole
    ``hole``)."""
    loop = mesh.outer_loop if hole is None else mesh.hole_loops[hole]
    P = mesh.nodes[loop]
    return float(np.median(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)))


def mesh_is_blind(mesh, pad: Pad, hole: int | None = None) -> bool:
    """Whether boundary nodes are farther apart than the pads' contact reach: the pads
    then meet one node or none, energies follow the nodes, and a barrier read off such a
    mesh is no evidence of holding (its verdict is "undecided" at best)."""
    return boundary_spacing(mesh, hole) > pad.reach


def contact_element_size(mesh, points: np.ndarray, radius: float) -> float:
    """Size ``h`` (m) of the largest element within ``radius`` (m) of ``points`` (m): the
    side of the equilateral triangle of its area."""
    c = mesh.nodes[mesh.triangles].mean(axis=1)
    d = np.min(np.linalg.norm(c[:, None, :] - np.asarray(points)[None], axis=2), axis=1)
    near = d <= radius
    area = float(mesh.areas[near].max()) if near.any() else float(mesh.areas.max())
    return math.sqrt(4.0 * area / math.sqrt(3.0))


def _contact_size_warnings(mesh, contacts: np.ndarray, pad: Pad, ell: float
                           ) -> tuple[str, ...]:
    """A warning when elements at the pads' contacts are larger than ``ℓ/2`` (SPEC §6:
    the first level of a refinement is never that coarse)."""
    h = contact_element_size(mesh, contacts, pad.half_span + 0.5 * ell)
    if h > 0.5 * ell * (1 + 1e-6):
        return (f"elements at the pads' contacts are {h:.3g} m, more than half the critical "
                f"distance ({0.5 * ell:.3g} m): this mesh does not resolve the answer; refine "
                "to an accuracy (--rtol, the default) rather than one mesh",)
    return ()


def _resolution_warnings(mesh, pad: Pad, hole: int | None) -> tuple[str, ...]:
    """A warning when boundary nodes are farther apart than the pad's contact reach: the
    pads then meet one node or none, and energies follow the nodes (a large noise floor)."""
    h = boundary_spacing(mesh, hole)
    if mesh_is_blind(mesh, pad, hole):
        return (f"boundary nodes are {h:.3g} m apart, more than the pads' contact reach "
                f"{pad.reach:.3g} m: refine the mesh (mesh.max_area) or use larger pads",)
    return ()


def _search_sigma_star(land: Landscape, s: int, Us, U_sL: float, sigma_L: float,
                       sigma0: float, tau, n_samples: int):
    """Exact ``argmax Q`` on ``[σ_L, σ0]`` by the one σ*-search
    (:func:`deformclosure.landscape.optimum.maximise_quality`) on this axis landscape;
    returns ``(best, ev)``: ``best`` is ``(Q*, σ*)`` or ``None`` when ``Q ≡ 0``, ``ev(σ)``
    evaluates by definition."""
    def evaluate(sig: float) -> _Eval:
        return _Eval(sig, land.release(s, sig, tau(sig)), U_sL - float(Us(sig)))

    def saddle_curve(w: int):
        c = land.curve(w)
        return c.energy_at, c.kinks()

    return maximise_quality(evaluate, Us, land.curve(s).kinks(), saddle_curve, U_sL,
                            sigma_L, sigma0, n_samples)


def _sample_curve(land, s, Us, U_sL, sigma_L, sigma0, tau, n, sigma_star, force) -> dict:
    """The plotted curve: ``sigma`` (m); ``U``, ``U_A``, ``U_L``, ``Q`` (J); ``F`` (N, the
    pads' axial force)."""
    sig = np.linspace(sigma_L, sigma0, n)
    if sigma_star is not None:
        sig = np.unique(np.append(sig, sigma_star))
    UA = [land.release(s, float(x), tau(float(x))).U_A for x in sig]
    U = np.array([Us(float(x)) for x in sig])
    UL = U_sL - U
    Q = np.minimum(np.array(UA), UL)

    def lst(a):
        return [None if not math.isfinite(float(v)) else float(v) for v in a]

    F = [force(float(x)) for x in sig]
    return {"sigma": lst(sig), "U": lst(U), "U_A": lst(UA), "U_L": lst(UL), "Q": lst(Q),
            "F": lst(F)}
