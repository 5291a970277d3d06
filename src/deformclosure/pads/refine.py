"""Pad grasps refined to a stated accuracy: levels, error estimates, verdict (SPEC §6
"Accuracy by default").

A pad grasp has two discretisations: the mesh (h) and the release landscape's grid of
axes. Each level refines both — the mesh (uniformly, ``h`` halved, with ``--refine N``;
adaptively by default, :mod:`.adapt`) and the landscape around the saddles found so far
(:mod:`.saddle_grid`, the grid there ``2^k`` times finer at level ``k``) — so one sequence
of levels carries the error of both.

**Error estimate.** From the values ``X₁ … X_k`` of ``quality``, ``U_A`` and ``sigma_star``
on the levels, the Richardson estimate of :func:`richardson` (observed order from three
levels, ``p = 1`` from two), never less than the last change ``|X_k − X_{k−1}|``: a
sequence that does not shrink monotonically gets no credit for it. σ*, the argmax of
``Q``, moves further than its own level changes show when the curves move: its
estimate is at least ``(e_Q + e_{U(σ_L)}) / |F|`` (``F`` the pad force, the slope of
``U_L``; ``U(σ_L)`` its level). The estimate is a
claim about the next level; the tests check that it brackets a much finer answer.

**Refinement to ``rtol``** (default 0.05): levels are added until the estimate of Q* and of
U_A is at most ``rtol`` times its value (a grasp with no barrier on two levels in a row
has nothing left to resolve), or until the budget ends it — ``max_seconds`` (the next
level's time predicted from the last two) or the memory limits of the pads model; the
report then says ``converged: false``.

**Verdict** (SPEC §6): ``"held"`` when U_A minus its error exceeds the noise floor (on a
mesh that resolves the pads, :func:`~deformclosure.pads.optimize.mesh_is_blind`);
``"not held"`` when U_A plus its error is within the noise floor (no barrier, or none
beyond the error); otherwise ``"undecided"``. A single mesh has no estimate: its verdict
is the mesh's own, ``"held"`` only where that mesh resolves the answer (the pads meet
several nodes and the contact elements are at most ℓ/2,
:attr:`~deformclosure.pads.optimize.PadGraspResult.resolves`), else ``"undecided"``.
"""

from __future__ import annotations

import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import DeformClosureError, GraspError
from ..limits import usable_cpus
from ..log import done
from ..mesh import mesh_part
from ..mesh.generate import default_max_area, twin_mesh
from ..mesh.sizing import Sizing
from .adapt import first_sizing, next_sizing
from .contact import PadContact, hole_containing
from .geometry import GraspAxis, Pad
from .optimize import PadGraspResult, optimize_pads

__all__ = ["RefinedPadGrasp", "richardson", "pad_grasp", "level_error", "check_accuracy",
           "DEFAULT_RTOL", "DEFAULT_MAX_SECONDS", "solve_level"]

#: Keyword options :func:`pad_grasp` passes on to :func:`optimize_pads`.
_OPTIONS = frozenset({"n_angles", "n_offsets", "n_samples", "n_curve", "noise"})


def richardson(values: list[float]) -> tuple[float, float, float | None]:
    """Extrapolated value, error estimate and observed order from a halving sequence.

    Parameters
    ----------
    values : list of float
        Values on successively refined meshes (h halving), coarsest first.

    Returns
    -------
    (extrapolated, error, order)
        ``order`` is ``None`` with fewer than three values (then ``p = 1``) or when the
        differences do not shrink monotonically (then ``p = 0.5``, a wide error).
    """
    try:
        v = [float(x) for x in values]
    except (TypeError, ValueError):
        raise GraspError(f"values = {values!r}: give a list of numbers") from None
    if not v:
        raise GraspError("values: give at least one value")
    if len(v) < 2:
        return v[-1], math.nan, None
    if len(v) == 2:
        p, order = 1.0, None
    else:
        d1, d2 = v[-3] - v[-2], v[-2] - v[-1]
        if d2 == 0:
            return v[-1], 0.0, math.inf
        ratio = abs(d1 / d2)
        if ratio <= 1:
            p, order = 0.5, None
        else:
            p = order = float(np.clip(math.log2(ratio), 0.5, 4.0))
    ext = v[-1] + (v[-1] - v[-2]) / (2.0**p - 1.0)
    return ext, abs(ext - v[-1]), order


#: Default relative accuracy of ``quality`` and ``U_A`` (``--rtol``).
DEFAULT_RTOL = 0.05

#: Default time budget (s) of a refinement (``--max-seconds``).
DEFAULT_MAX_SECONDS = 120.0

#: Most levels a refinement solves.
MAX_LEVELS = 6


def level_error(values: list[float]) -> float | None:
    """Error estimate of the last of ``values`` (module docstring); ``None`` with one
    value, ``inf`` when the last two differ in being infinite."""
    if len(values) < 2:
        return None
    v = [float(x) for x in values]
    if math.isinf(v[-1]) or math.isinf(v[-2]):
        return 0.0 if v[-1] == v[-2] else math.inf
    tail = v[-3:] if len(v) >= 3 and math.isfinite(v[-3]) else v[-2:]
    return max(richardson(tail)[1], abs(v[-1] - v[-2]))


@dataclass(frozen=True, eq=False)
class RefinedPadGrasp:
    """A pad grasp solved on a sequence of levels; the finest result is the answer.

    Attributes
    ----------
    levels : list of PadGraspResult
        Coarsest first.
    max_areas : list of float
        Largest triangle area (m²) of each level's mesh.
    rtol : float or None
        The accuracy asked for (``None``: a fixed number of levels, ``--refine``).
    converged : bool
        Whether the estimates of Q* and U_A met ``rtol`` (with ``--refine``: the default
        rtol) before the levels or the budget ran out.
    adaptive : bool
        Whether the meshes were refined adaptively.
    stopped : str or None
        Why refinement ended before converging (time, memory, levels).
    seconds : list of float
        Time (s) of each level.
    saddles : list of GraspAxis
        Every saddle the levels refined the landscape around.
    """

    levels: list[PadGraspResult]
    max_areas: list[float]
    rtol: float | None = None
    adaptive: bool = False
    stopped: str | None = None
    seconds: list[float] = field(default_factory=list)
    saddles: list = field(default_factory=list)

    @property
    def finest(self) -> PadGraspResult:
        """The result on the finest level."""
        return self.levels[-1]

    def _values(self, key: str) -> list[float]:
        if key == "U_A":
            return [r.U_A for r in self.levels]
        if key == "quality":
            return [r.quality for r in self.levels]
        return [r.sigma_star for r in self.levels]

    def error_estimate(self) -> dict[str, float | None]:
        """Error estimates of ``quality`` (J), ``U_A`` (J) and ``sigma_star`` (m)."""
        if len(self.levels) < 2:
            return {"quality": None, "U_A": None, "sigma_star": None}
        S = self._values("sigma_star")
        if all(s is None for s in S[-2:]):
            eS = 0.0
        elif any(s is None for s in S[-2:]):
            eS = None                     # a barrier on one level only: σ* is not located
        else:
            tail = S[-3:] if len(S) >= 3 and S[-3] is not None else S[-2:]
            eS = level_error(tail)
        eQ = level_error(self._values("quality"))
        eUL = level_error([r.start_curve.energy_at(r.sigma_L) for r in self.levels])
        force = self.finest.force
        if eS is not None and eQ is not None and eUL is not None and force \
                and math.isfinite(eQ + eUL):
            # σ* sits where Q = min(U_A, U_L) peaks; U_L's slope there is the pad force
            # (dU_L/dσ = −dU/dσ = F). Errors eQ in the curve that limits and eUL in U_L's
            # level U(σ_L) move the peak by up to (eQ + eUL) / |F| (at a crossing the two
            # slopes have opposite signs, so the shift is never more)
            eS = max(eS, (eQ + eUL) / abs(force))
        return {"quality": eQ, "U_A": level_error(self._values("U_A")), "sigma_star": eS}

    @property
    def converged(self) -> bool:
        """Whether Q* and U_A are within ``rtol`` (default :data:`DEFAULT_RTOL`)."""
        if len(self.levels) < 2:
            return False
        return _within(self.error_estimate(), self.finest,
                       DEFAULT_RTOL if self.rtol is None else self.rtol)

    @property
    def verdict(self) -> str:
        """``"held"``, ``"not held"`` or ``"undecided"`` (module docstring)."""
        fine = self.finest
        if len(self.levels) < 2:
            # one mesh asked for as such keeps its own verdict; a refinement cut short
            # after one level has no bounds to decide anything
            return fine.verdict if self.rtol is None else "undecided"
        e = self.error_estimate()
        ua, eua = fine.U_A, e["U_A"]
        floor = fine.noise
        if math.isinf(ua):
            return "held" if eua == 0.0 and not fine.blind and fine.quality > 0 else "undecided"
        if fine.quality > 0 and ua - eua > floor and not fine.blind:
            return "held"
        if ua + eua <= floor:
            return "not held"
        return "undecided"

    def to_dict(self) -> dict[str, Any]:
        """The finest report plus ``error_estimate``, ``converged``, ``convergence`` and the
        verdict."""
        d = self.finest.to_dict()
        d["error_estimate"] = self.error_estimate()
        d["converged"] = self.converged
        d["rtol"] = self.rtol
        d["refinement"] = ("adaptive" if self.adaptive else "uniform") if len(self.levels) > 1 \
            else "none"
        if self.stopped:
            d["stopped"] = self.stopped
        d["convergence"] = self.convergence()
        d["verdict"] = self.verdict
        return d

    def convergence(self) -> list[dict[str, Any]]:
        """The report's ``convergence`` rows, one per level (SI): ``level``, ``nodes``,
        ``grid``, ``sigma_star``, ``quality``, ``U_A`` (``None`` if infinite),
        ``U_A_infinite``, ``max_area``, ``sigma0``, ``sigma_L``, ``force``,
        ``n_axes_solved``."""
        return [
            {"level": k, "nodes": r.n_nodes, "grid": r.to_dict()["grid"],
             "sigma_star": r.sigma_star, "quality": r.quality,
             "U_A": None if math.isinf(r.U_A) else r.U_A, "U_A_infinite": math.isinf(r.U_A),
             "max_area": a, "sigma0": r.sigma0, "sigma_L": r.sigma_L, "force": r.force,
             "n_axes_solved": r.n_axes}
            for k, (a, r) in enumerate(zip(self.max_areas, self.levels))]


def _within(err: dict, fine: PadGraspResult, rtol: float) -> bool:
    """Whether the estimates of quality and U_A are within ``rtol`` of their values."""
    for key, value in (("quality", fine.quality), ("U_A", fine.U_A)):
        e = err[key]
        if e is None or math.isnan(e):
            return False
        if math.isinf(value):
            if e != 0.0:
                return False
            continue
        if e > rtol * abs(value):
            return False
    return True


def pad_grasp(part, axis: GraspAxis, pad: Pad, *, mesh=None, refine: int | None = None,
              rtol: float | None = None, max_seconds: float | None = None,
              adaptive: bool = True, twin: bool = True, expanding_from=None, progress=None,
              max_area: float | None = None, **options) -> RefinedPadGrasp:
    """Optimal separation of a pad grasp: on one mesh, on ``refine`` uniform levels, or
    refined until ``rtol`` is met (module docstring).

    Parameters
    ----------
    part : Part or None
        The part (needed to refine and for the twin realisation).
    axis : GraspAxis
        Start axis in the part frame (angle in rad, offset in m).
    pad : Pad
        Width and end radius in m.
    mesh : Mesh, optional
        The first mesh of a single or uniform run (default: the part meshed with its own
        settings); an adaptive run makes its own first level.
    refine : int, optional
        Number of uniform levels (``max_area`` quartered each time), 1 to 5; exclusive
        with ``rtol``. Neither given: one mesh.
    rtol : float, optional
        Relative accuracy of Q* and U_A to refine to, in (0, 1) (``--rtol``).
    max_seconds : float, optional
        Time budget (s) of an ``rtol`` run (default :data:`DEFAULT_MAX_SECONDS`).
    adaptive : bool
        With ``rtol``: refine the mesh where the error indicator is largest (default)
        rather than everywhere.
    twin : bool
        Measure the noise floor on a second mesh realisation (needs ``part``).
    expanding_from : array_like, optional
        Expanding grasp: a point (m) inside the hole the pads open in.
    progress : callable, optional
        Called with ``(level, n_levels)`` before each level (``n_levels`` the most
        levels of the run).
    max_area : float, optional
        Largest triangle area (m²) of the first level (default the part's own).
    **options
        Passed to :func:`optimize_pads`: ``n_angles``, ``n_offsets``, ``n_samples``,
        ``n_curve``, ``noise``.

    Returns
    -------
    RefinedPadGrasp
        One :class:`PadGraspResult` per level (σ in m, energies in J), the finest last,
        with the error estimates and the verdict.

    Raises
    ------
    GraspError
        A bad ``refine``, ``rtol``, ``max_seconds``, ``axis``, ``pad`` or option, no part
        or mesh, a point not in a hole, or any refusal of :func:`optimize_pads`.

    Examples
    --------
    Round 2 mm pads in the notches of the notched bar, one coarse mesh (about 1 s):

    >>> import math
    >>> from deformclosure import mesh_part, notched_part
    >>> from deformclosure.pads import GraspAxis, Pad
    >>> part = notched_part()
    >>> res = pad_grasp(part, GraspAxis(math.pi / 2, -0.015), Pad(0.0, 2e-3),
    ...                 mesh=mesh_part(part, max_area=1e-6), twin=False,
    ...                 n_angles=8, n_offsets=8, noise=False)
    >>> res.verdict, round(res.finest.sigma0 * 1e3, 3)              # mm
    ('undecided', 7.657)

    (one mesh has no error estimate, and this one does not resolve the contacts: its own
    verdict, ``"undecided"``; without ``mesh`` it refines to ``rtol`` and decides.)
    """
    _check_request(part, axis, pad, refine, rtol, max_seconds, options)
    if rtol is not None and part is not None:
        return _to_rtol(part, axis, pad, float(rtol), adaptive,
                        DEFAULT_MAX_SECONDS if max_seconds is None else float(max_seconds),
                        twin, expanding_from, progress, max_area, options)
    if mesh is None:
        if part is None:
            raise GraspError("part: give a part or a mesh")
        mesh = mesh_part(part, max_area=max_area)
    if max_area is not None:
        base = float(max_area)
    else:
        base = default_max_area(part) if part is not None else float(mesh.areas.max())
    n = 1 if refine is None else refine
    levels, areas, seconds = [], [], []
    saddles: list[GraspAxis] = []
    for k in range(n):
        if progress is not None:
            progress(k, n)
        area = base / 4.0**k
        t0 = time.perf_counter()
        m = mesh if k == 0 else mesh_part(part, max_area=area)
        tw = twin_mesh(part, max_area=area) if (twin and part is not None) else None
        levels.append(solve_level(m, tw, axis, pad, k, saddles, expanding_from, options))
        areas.append(area)
        seconds.append(time.perf_counter() - t0)
        _log_level(t0, k, n, levels[-1])
    return RefinedPadGrasp(levels, areas, None, False, None, seconds, saddles)


def solve_level(mesh, twin_m, axis: GraspAxis, pad: Pad, k: int, saddles: list,
                 expanding_from, options: dict, most: int = 4,
                 known: dict | None = None) -> PadGraspResult:
    """Level ``k``: the grasp on ``mesh`` (twin ``twin_m``), its landscape refined ``2^k``
    times around ``saddles`` (the earlier levels' saddles, to which this one's is added).

    Refining around a saddle can raise its pass (a coarse grid may cut a ridge between
    its vertices) so that the escape goes over another, still coarse pass; the level is
    solved again with that saddle refined too, until the escape's saddle lies in a
    refined patch (at most ``most`` solves). ``known``, if given (empty), is filled with
    the curves the level traced over all its solves: ``{grid factor: (mesh's curves by
    vertex, twin's)}`` (:func:`traced_axes` counts them)."""
    solver, tw = build_solvers(mesh, twin_m)   # one factorisation each
    holes = {} if expanding_from is None else _holes(mesh, tw, expanding_from)
    known = {} if known is None else known
    for _ in range(most):
        refined = (2**k, list(saddles)) if k > 0 and saddles else None
        res = optimize_pads(mesh, axis, pad, solver=solver, twin=tw, saddles=refined,
                            known=known.setdefault(1 if refined is None else 2**k, ({}, {})),
                            **holes, **options)
        solver = res.solver
        if res.saddle is None:
            return res
        inside = k > 0 and getattr(res.grid, "contains", lambda ax: False)(res.saddle)
        if not inside:
            saddles.append(res.saddle)
        if k == 0 or inside:
            return res
    return res


def build_solvers(mesh, twin_m) -> tuple[PadContact, PadContact | None]:
    """The level's solver and its twin's (``twin_m`` may be ``None``), built side by side
    when two CPUs are free to this process: the sparse factorisation and the dense
    inverse of each release the GIL (at 80 000 nodes the two builds are ~12 s of a 25 s
    ``optimize`` one after the other). The memory estimate counts both builds' transients
    at once (``limits.estimate_model_bytes``, ``condensing``)."""
    if twin_m is None or usable_cpus() < 2:
        return PadContact(mesh), None if twin_m is None else PadContact(twin_m)
    with ThreadPoolExecutor(1, thread_name_prefix="deformclosure-twin") as pool:
        twin = pool.submit(PadContact, twin_m)
        solver = PadContact(mesh)
        return solver, twin.result()


def traced_axes(known: dict) -> int:
    """Axes whose curves on the level's own mesh :func:`solve_level` traced (``known``)."""
    return sum(len(curves) for curves, _ in known.values())


def _log_level(t0: float, k: int, n: int, res: PadGraspResult) -> None:
    done("level %d of at most %d (%d nodes): Q* = %.6g J, %d grasp axes solved", t0,
         k + 1, n, res.n_nodes, res.quality, res.n_axes)


def _to_rtol(part, axis: GraspAxis, pad: Pad, rtol: float, adaptive: bool,
             max_seconds: float, twin: bool, expanding_from, progress, max_area,
             options: dict) -> RefinedPadGrasp:
    """Levels until the estimates of Q* and U_A are within ``rtol`` (module docstring)."""
    from ..limits import holding, kept_bytes
    from .size_limits import WITH_TWIN, check_pads_size, estimate_pads_bytes, level_axes

    t_start = time.perf_counter()
    base = float(max_area) if max_area is not None else default_max_area(part)
    hole_ring = None
    if expanding_from is not None:
        probe = mesh_part(part, max_area=base)
        h = hole_containing(probe, expanding_from)
        hole_ring = None if h is None else probe.nodes[probe.hole_loops[h]]
    sizing = first_sizing(part, axis, pad, base, hole_ring) if adaptive else Sizing(base)
    levels, areas, seconds, saddles = [], [], [], []
    stopped = None
    held = 0.0          # the solvers and curves of the levels so far, which the run keeps
    grid = (options.get("n_angles", 48), options.get("n_offsets", 50))
    for k in range(MAX_LEVELS):
        if progress is not None:
            progress(k, MAX_LEVELS)
        t0 = time.perf_counter()
        try:
            mesh = mesh_part(part, max_area=sizing.default, sizing=sizing)
            n_axes = level_axes(*grid, k, len(saddles))
            with holding(held):
                check_pads_size(mesh, solvers=WITH_TWIN if twin else 1, refine=1,
                                n_axes=n_axes)
        except DeformClosureError as err:
            if not levels:
                raise
            stopped = f"memory or size limit at level {k + 1}: {err}"
            break
        tw = twin_mesh(part, max_area=sizing.default, sizing=sizing) if twin else None
        known: dict = {}
        levels.append(solve_level(mesh, tw, axis, pad, k, saddles, expanding_from, options,
                                  known=known))
        # the run keeps the level's solver; the curves the level traced are freed but the
        # heap they took stays resident (the larger of their number and the estimate's:
        # the latter also covers the path kernels loaded at the first curve); its twin
        # goes with the level (measured: benchmarks/bench_memory.py)
        held += kept_bytes(estimate_pads_bytes(mesh, solvers=1,
                                               n_axes=max(n_axes, traced_axes(known))))
        areas.append(float(mesh.areas.max()))
        seconds.append(time.perf_counter() - t0)
        _log_level(t0, k, MAX_LEVELS, levels[-1])
        run = RefinedPadGrasp(levels, areas, rtol, adaptive, None, seconds, saddles)
        if run.converged:
            return run
        if k + 1 == MAX_LEVELS:
            stopped = f"{MAX_LEVELS} levels solved"
            break
        # the next level's time: the last growth, else a prior (an adaptive level adds
        # about half the elements again, a uniform one four times as many)
        prior = 2.5 if adaptive else 4.0
        growth = seconds[-1] / seconds[-2] if len(seconds) > 1 and seconds[-2] > 0 else prior
        predicted = seconds[-1] * min(max(growth, 1.5), 16.0)
        if time.perf_counter() - t_start + predicted > max_seconds:
            stopped = (f"time budget: level {k + 2} would take about {predicted:.0f} s, beyond "
                       f"--max-seconds {max_seconds:g}")
            break
        sizing = next_sizing(levels[-1], sizing) if adaptive else Sizing(sizing.default / 4.0)
    return RefinedPadGrasp(levels, areas, rtol, adaptive, stopped, seconds, saddles)


def check_accuracy(rtol, max_seconds) -> None:
    """Refuse an ``rtol`` outside (0, 1) or a ``max_seconds`` that is not a time > 0
    (``None``: the default)."""
    if rtol is not None:
        if isinstance(rtol, bool) or not isinstance(rtol, (int, float)) \
                or not (math.isfinite(rtol) and 0 < rtol < 1):
            raise GraspError(f"--rtol = {rtol!r}: give a relative accuracy between 0 and 1 "
                             "(e.g. 0.05)")
    if max_seconds is not None:
        if isinstance(max_seconds, bool) or not isinstance(max_seconds, (int, float)) \
                or not (math.isfinite(max_seconds) and max_seconds > 0):
            raise GraspError(f"--max-seconds = {max_seconds!r}: give a time budget in "
                             "seconds > 0")


def check_refine(refine) -> None:
    """Refuse a ``--refine`` that is not a whole number of meshes from 1 to 5
    (``None``: not given)."""
    if refine is not None and (isinstance(refine, bool) or not (isinstance(refine, int)
                                                                and 1 <= refine <= 5)):
        raise GraspError(f"--refine = {refine!r}: give a whole number of meshes from 1 to 5")


def _check_request(part, axis, pad, refine, rtol, max_seconds, options: dict) -> None:
    """Refuse a bad ``refine``, ``rtol``, ``max_seconds``, ``axis``, ``pad`` or option of
    :func:`pad_grasp`."""
    if refine is not None and rtol is not None:
        raise GraspError("--refine and --rtol: give one (--refine N solves N uniform levels; "
                         "--rtol R refines until the error estimate is within R)")
    check_refine(refine)
    check_accuracy(rtol, max_seconds)
    if not isinstance(axis, GraspAxis):
        raise GraspError(f"axis = {axis!r}: give a GraspAxis (angle in rad, offset in m)")
    if not isinstance(pad, Pad):
        raise GraspError(f"pad = {pad!r}: give a Pad (width and radius in m)")
    unknown = sorted(set(options) - _OPTIONS)
    if unknown:
        raise GraspError(f"{unknown[0]}: not an option of a pad grasp; use "
                         f"{', '.join(sorted(_OPTIONS))}")
    if part is None and refine is not None and refine > 1:
        raise GraspError("--refine: needs a part file (a mesh file cannot be re-meshed)")


def _holes(mesh, twin: PadContact | None, point) -> dict:
    """``hole`` and ``twin_hole`` of an expanding grasp: the holes of ``mesh`` and of the
    twin's mesh that contain ``point`` (m)."""
    hole = hole_containing(mesh, point)
    if hole is None:
        raise GraspError("--expanding: the axis point is not inside a hole of the part; "
                         "give --at points on a hole's boundary or an --axis point in it")
    return {"hole": hole, "twin_hole": None if twin is None else hole_containing(twin.mesh, point)}
