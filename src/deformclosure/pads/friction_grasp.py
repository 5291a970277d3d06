"""A pad grasp with Coulomb friction (SPEC §9): ``Q = min(U_A^μ, U_L)`` on the levels of a
refined grasp, the holding loads at σ*, and the report's friction keys.

The frictionless refinement (:func:`~deformclosure.pads.refine.pad_grasp`) solves each
level's mesh, factorisation and axis grid; this module re-reads every level with
friction, on the *same* axis landscape (the same solver, grid, ``σ_L`` and start curve):

* **Release work** ``U_A^μ(σ)`` — :func:`deformclosure.pads.release_work.release_work`:
  the least peak of ``U(v) − U(start) + Σ D`` over paths to an axis where no pad presses,
  each move dissipating ``μ Σ f_n |slip|`` with the slip from the rigid relative motion
  of pads and part and the *frictional* normal forces of the move's start vertex
  (:func:`~deformclosure.pads.friction.frictional_grasp` of that vertex's curve; where
  the frictional squeeze of a vertex has no quasi-static solution, or needs more rows
  than the curve holds, its frictionless forces — counted in ``frictionless_vertices``).
  The frictional squeeze of every axis the search expands costs about 30 ms on a 216-node
  mesh against 3 ms for its frictionless curve, and a search expands thousands of axes,
  so by default the search's moves use the frictionless forces and the escape path found
  at σ* is re-evaluated with the frictional ones (``path_check``: its peak work and
  relative difference, 1.5 % on the README block); ``forces="frictional"`` runs the whole
  search on them.
  The vertex energies are the landscape's (frictionless) ones: the frictional squeeze of
  a block differs from it by 0.2 % in force at a 5 % squeeze and by 4.8 % at 23 %
  (friction restrains the faces' Poisson expansion, ``docs/friction.md``), and the
  state the part reaches at a *neighbouring* axis is the result of being moved there,
  which the rigid-move model does not follow.
* **σ\\*** — ``U_A^μ`` is known only by evaluation (a search per σ, not a piecewise
  quadratic), so σ* comes from the one sampled σ*-search,
  :func:`deformclosure.landscape.optimum.maximise_sampled`. Each evaluation stops its
  search once the work passes ``U_L(σ)``: then ``Q = U_L`` whatever the rest of it.
* **Error estimate, convergence, verdict** — every level becomes a copy of its
  :class:`~deformclosure.pads.optimize.PadGraspResult` with the frictional ``sigma_star``,
  ``quality``, ``U_A``, ``U_L``, escape path and noise floor (the level's relative floor
  times ``U(σ*)``), gathered in a :class:`~deformclosure.pads.refine.RefinedPadGrasp`:
  its one error estimate and verdict rule (SPEC §6) apply unchanged. The levels were
  refined for the frictionless answer (mesh and saddle patches); the frictional estimate
  is therefore honest but may not meet ``rtol`` (``converged: false`` says so).
* **Hold** at σ* of the finest level: :meth:`FrictionalCurve.hold` of the start axis.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GraspError
from ..landscape.optimum import maximise_sampled
from .friction import frictional_grasp
from .landscape import Landscape
from .optimize import PadGraspResult
from .refine import DEFAULT_MAX_SECONDS, DEFAULT_RTOL, RefinedPadGrasp
from .release_work import (OutOfTime, contact_normal_forces, gripper_centre, is_released,
                           move_dissipation, move_slip, release_work, row_tangents)

__all__ = ["check_friction", "check_friction_model", "FrictionalLevel", "frictional_level",
           "FrictionalGrasp", "FrictionalRefinement", "frictional_refined", "hold_to_dict",
           "HOLD_LIMITS",
           "SIGMA_SAMPLES"]

#: σ samples of the sampled σ*-search on ``[σ_L, σ0]`` (then halvings around the best).
SIGMA_SAMPLES = 12


def check_friction(mu: Any) -> float:
    """The Coulomb coefficient of ``--friction`` as a float; one-line error otherwise.

    >>> check_friction(0.5), check_friction(None)
    (0.5, 0.0)
    >>> check_friction(-1)
    Traceback (most recent call last):
    ...
    deformclosure.errors.GraspError: --friction = -1: give a Coulomb friction coefficient μ >= 0 (a finite number, e.g. 0.5; 0 = frictionless)
    """
    if mu is None:
        return 0.0
    if isinstance(mu, bool) or not isinstance(mu, (int, float, np.floating, np.integer)) \
            or not math.isfinite(float(mu)) or float(mu) < 0:
        raise GraspError(f"--friction = {mu!r}: give a Coulomb friction coefficient μ >= 0 "
                         "(a finite number, e.g. 0.5; 0 = frictionless)")
    return float(mu)


def check_friction_model(mu: float, elasticity: str | None) -> None:
    """Refuse friction (``mu > 0``) with a material law it is not built on (SPEC §9 is on
    the linear model; neo-Hookean pads are frictionless, SPEC §8)."""
    if mu > 0 and elasticity == "neo-hookean":
        raise GraspError("--friction with --elasticity neo-hookean (or material.model "
                         "neo-hookean): not yet supported (friction is built on the linear "
                         "model, SPEC §9); use --friction 0 or --elasticity linear")


@dataclass(frozen=True, eq=False)
class FrictionalLevel:
    """One level read with friction.

    Attributes
    ----------
    result : PadGraspResult
        The level with the frictional ``sigma_star`` (m), ``quality``, ``U_A``, ``U_L``
        (J), escape path and noise floor (J).
    frictionless : PadGraspResult
        The level as solved without friction.
    mu : float
    dissipation : float
        Dissipation (J) along the escape path at σ* (``nan`` without one).
    works : list of float
        Work (J) at each axis of the escape path (``U(v) − U(start)`` + dissipation so far).
    frictionless_vertices : int
        Axes whose frictional squeeze was asked for but could not be solved (their
        frictionless normal forces were used).
    expanded : int
        Axes whose frictional squeeze was asked for (the search's expanded axes with
        ``forces="frictional"``, else the escape path's and the start).
    forces : str
        The normal forces of the search's moves (``"frictionless"`` or ``"frictional"``).
    path_check : dict or None
        The escape path at σ* with every move's normal forces from the frictional squeeze
        of its start axis: ``{"work", "dissipation"}`` (J; the path's peak work is an upper
        bound of ``U_A^μ`` with those forces) and ``relative`` (its difference from
        ``U_A``).
    hold : dict or None
        :meth:`FrictionalCurve.hold` at σ* (N, N·m; may hold ``±inf``), if computed.
    hold_error : str or None
        Why ``hold`` is missing, if it is.
    stopped : str or None
        Why the level's reading stopped early (its time budget): σ* and Q* are then the
        best of the separations evaluated, and ``U_A_bound`` says whether ``U_A`` is only
        a lower bound (the search at σ* was cut short above ``U_L``: ``Q = U_L`` is exact).
    U_A_bound : bool
    seconds : float
        Time (s) the level's reading took.
    """

    result: PadGraspResult
    frictionless: PadGraspResult
    mu: float
    dissipation: float
    works: list
    frictionless_vertices: int
    expanded: int
    forces: str = "frictionless"
    path_check: dict | None = None
    hold: dict | None = None
    hold_error: str | None = None
    stopped: str | None = None
    U_A_bound: bool = False
    seconds: float = 0.0


def _hole_of(solver, curve) -> int | None:
    """The hole an expanding curve opens in (``None``: contracting)."""
    if not curve.expanding:
        return None
    return next(k for k, lp in enumerate(solver.mesh.hole_loops) if np.isin(curve.nodes[0], lp))


def frictional_level(res: PadGraspResult, mu: float, *, rtol: float | None = None,
                     n_samples: int = SIGMA_SAMPLES, hold: bool = False,
                     forces: str = "frictionless",
                     deadline: float | None = None) -> FrictionalLevel:
    """Re-read one solved level ``res`` with Coulomb coefficient ``mu`` (module docstring).

    Parameters
    ----------
    res : PadGraspResult
        A level solved by :func:`~deformclosure.pads.optimize.optimize_pads` (its solver,
        grid and start curve are reused).
    mu : float
        Coulomb coefficient, ``> 0`` (``0`` returns the level unchanged).
    rtol : float, optional
        Relative accuracy of Q* for the sampled σ*-search (default
        :data:`~deformclosure.pads.refine.DEFAULT_RTOL`).
    n_samples : int
        σ samples of the search.
    hold : bool
        Also compute the holding force and torque at σ*.
    forces : {"frictionless", "frictional"}
        The normal forces of the moves in the search: the landscape's frictionless ones
        (default: cheap), or each expanded axis' frictional squeeze (about 30 ms per axis
        on a 216-node mesh, thousands of axes). With ``hold`` (or ``"frictional"``) the
        escape path found at σ* is re-evaluated with the frictional forces
        (``path_check``).
    deadline : float, optional
        ``time.perf_counter()`` value after which no release-work search runs on (the
        one under way is abandoned): σ* is the best of the separations evaluated and the
        level says ``stopped``; the path check is skipped. The hold at σ* keeps to it
        too: loadings not finished by then are ``limited_by: "budget"`` (``None`` in the
        report) and the hold says ``stopped``.

    Returns
    -------
    FrictionalLevel
    """
    mu = check_friction(mu)
    t_begin = time.perf_counter()
    if forces not in ("frictionless", "frictional"):
        raise GraspError(f"forces = {forces!r}: choose one of frictionless, frictional")
    if mu == 0.0:
        return FrictionalLevel(res, res, 0.0, math.nan, [], 0, 0)
    solver, start_curve = res.solver, res.start_curve
    land = Landscape(solver, res.pad, res.grid, res.sigma_L, _hole_of(solver, start_curve))
    s = res.grid.vertex(0, 0)
    land.seed(s, start_curve)
    # id(curve) -> (curve, FrictionalCurve or None, index of each row of curve in its rows)
    frictional: dict[int, tuple] = {}
    fallback: set[int] = set()

    def frictional_curve(curve) -> tuple:
        key = id(curve)
        got = frictional.get(key)
        if got is None:
            rows = curve
            if curve is start_curve:
                # the start is traced to σ = 0 (full closure, where a stick/slip path
                # need not exist); the search and the hold need it only down to σ_L
                rows = solver.curve(curve.axis, curve.pad, res.sigma_L, land.hole)
            try:
                fc = frictional_grasp(solver, rows, mu)
            except GraspError:
                fc = None
            at = None
            if fc is not None:      # its rows may be re-taken (friction.py): match them
                index = {(int(n), int(q)): i for i, (n, q) in
                         enumerate(zip(fc.curve.nodes, fc.curve.pad_of))}
                at = np.array([index.get((int(n), int(q)), -1)
                               for n, q in zip(curve.nodes, curve.pad_of)], int)
            got = frictional[key] = (curve, fc, at)
        return got[1], got[2]

    def frictional_forces(curve, sigma: float) -> np.ndarray:
        if is_released(curve, sigma):
            return np.zeros(len(curve.nodes))
        fc, at = frictional_curve(curve)
        if fc is not None:
            lam = fc.forces(sigma)[0]
            out = np.where(at >= 0, lam[np.maximum(at, 0)], 0.0)
            # a force on a row the curve does not have would be lost: not comparable
            if out.sum() >= lam.sum() * (1 - 1e-9):
                return out
        fallback.add(id(curve))
        return contact_normal_forces(curve, sigma)

    Us = start_curve.energy_at
    U_sL = float(Us(res.sigma_L))
    cache: dict = {}                 # rows and slips, the same at every σ
    search_forces = frictional_forces if forces == "frictional" else None

    def work(sig: float, stop: float | None = None):
        return release_work(land, s, sig, mu, normal_forces=search_forces, stop_above=stop,
                            cache=cache, deadline=deadline)

    samples: list[tuple[float, float, float, bool]] = []     # (σ, U_A or bound, U_L, exact)
    searched: dict[float, object] = {}                        # σ -> its search

    def quality(sig: float) -> float:
        UL = U_sL - float(Us(sig))
        if UL <= 0.0:
            samples.append((sig, 0.0, UL, False))
            return 0.0
        esc = searched[sig] = work(sig, stop=UL)  # past U_L the rest cannot matter
        # a search stopped above U_L leaves a lower bound; a complete one without a
        # release: no way out (∞)
        ua = esc.work if (esc.released or not esc.complete) else math.inf
        samples.append((sig, ua, UL, esc.complete))
        return min(esc.work, UL)

    lo, hi = sorted((res.sigma_L, res.sigma0))
    rtol = DEFAULT_RTOL if rtol is None else rtol
    stopped, ua_bound = None, False
    try:
        best = maximise_sampled(quality, lo, hi, n_samples, rtol, 1e-4 * (hi - lo))
    except OutOfTime as err:
        stopped = (f"friction: time budget ran out in the sigma*-search ({err}; "
                   f"{len(samples)} separations evaluated)")
        ranked = sorted(((min(x[1], x[2]), x[0]) for x in samples), reverse=True)
        best = ranked[0] if ranked and ranked[0][0] > 0 else None
    if best is None:
        sigma_star, UA, UL, esc = None, 0.0, 0.0, None
        q = 0.0
    else:
        sigma_star = best[1]
        UL = U_sL - float(Us(sigma_star))
        esc = searched.get(sigma_star)
        if esc is None or not (esc.released or esc.complete):
            # the sample's search stopped above U_L (or there was none): the whole search
            # for U_A and the escape path (a search that released below U_L is this one:
            # the stop only cuts labels above it)
            try:
                esc = work(sigma_star)
            except OutOfTime:
                stopped = stopped or "friction: time budget ran out in the search for U_A at sigma*"
                ua_bound = True
        if ua_bound:
            # Q = U_L exactly (the work passes U_L before any release); U_A ≥ that bound
            UA = max(esc.work, UL) if esc is not None else UL
            esc = None
        else:
            UA = esc.work if esc.released else math.inf
        q = min(UA, UL)
    grid = res.grid
    path = list(esc.path) if esc is not None and esc.released else []
    saddle = None
    if path and len(path) > 1:
        saddle = grid.axis(path[int(np.argmax(esc.works))])
    noise = res.noise_relative * float(Us(sigma_star)) if sigma_star is not None else res.noise
    new = dataclasses.replace(
        res, sigma_star=sigma_star, quality=q, U_A=UA, U_L=UL, noise=noise,
        curve=_sampled_curve(samples, Us, start_curve.axial_force, res.curve),
        escape_path=[grid.axis(v) for v in path], saddle=saddle, escape_vertices=tuple(path),
        n_axes=land.n_evaluated)
    # the frictional squeezes of the path's axes cost more than the search on fine
    # meshes: checked where the hold is asked for (the finest level of a run)
    out_of_time = deadline is not None and time.perf_counter() > deadline
    check = (_path_check(land, path, sigma_star, mu, frictional_forces, cache)
             if path and (hold or forces == "frictional") and not out_of_time else None)
    if check is not None:
        check["relative"] = (check["work"] - UA) / UA if UA > 0 else None
    fails = len(fallback)
    out = FrictionalLevel(new, res, mu, esc.dissipation if path else math.nan,
                          list(esc.works) if path else [], fails, len(frictional), forces,
                          check, stopped=stopped, U_A_bound=ua_bound)
    if hold and sigma_star is not None:
        fc = frictional_curve(start_curve)[0]
        if fc is None:
            out = dataclasses.replace(out, hold_error="the frictional squeeze of the start "
                                      "axis has no quasi-static solution")
        else:
            try:
                out = dataclasses.replace(out, hold=fc.hold(sigma_star, deadline=deadline))
            except GraspError as err:
                out = dataclasses.replace(out, hold_error=str(err))
    return dataclasses.replace(out, seconds=time.perf_counter() - t_begin)


def _sampled_curve(samples: list, Us, force, frictionless: dict) -> dict:
    """The report's ``curve`` with friction: the σ*-search's samples in σ (m) — ``U``,
    ``U_A`` (the release work, J; where the search stopped above ``U_L`` a lower bound,
    ``U_A_bound`` true), ``U_L``, ``Q`` (J), ``F`` (N) — and the frictionless curve as
    ``frictionless``."""
    samples = sorted(samples)

    def num(v: float):
        return None if not math.isfinite(v) else float(v)

    return {"sigma": [x[0] for x in samples], "U": [float(Us(x[0])) for x in samples],
            "U_A": [num(x[1]) for x in samples], "U_A_bound": [not x[3] for x in samples],
            "U_L": [float(x[2]) for x in samples],
            "Q": [float(max(min(x[1], x[2]), 0.0)) for x in samples],
            "F": [float(force(x[0])) for x in samples], "frictionless": frictionless}


def _path_check(land: Landscape, path: list, sigma: float, mu: float, forces_of,
                cache: dict) -> dict:
    """The works along ``path`` at ``sigma`` with ``forces_of`` (frictional) normal forces
    (:class:`FrictionalLevel` ``path_check``); the moves' slips are the search's."""
    U0 = land.energy(path[0], sigma)
    works, d = [0.0], 0.0
    for v, w in zip(path[:-1], path[1:]):
        c = land.curve(v)
        f = np.asarray(forces_of(c, sigma), float)
        if f.any():
            slip = cache.get("slips", {}).get((v, w))
            if slip is None:
                slip = move_slip(land.solver.mesh.nodes[c.nodes], row_tangents(c.normals),
                                 land.grid.axis(v), gripper_centre(c), land.grid.axis(w),
                                 gripper_centre(land.curve(w)))
            d += move_dissipation(mu, f, slip)
        works.append(land.energy(w, sigma) - U0 + d)
    return {"work": max(works), "dissipation": d, "works": works}


#: What ends a holding-load entry (``hold["limited_by"]``) and what that means; a value
#: is reported only for ``"friction"``, ``"dynamic"`` and ``"unbalanced"``.
HOLD_LIMITS = {
    "friction": "gross slip as the last contact starts to slide (the value equals 'slide')",
    "dynamic": "the quasi-static stick/slip path ends (no consistent rate): the part lets "
               "go dynamically beyond the value",
    "geometry": "wedged or jammed: the part carries load after every contact slides (the "
                "pads' curvature, or a block's corners, resist in the small-displacement "
                "kinematics; leaving that is large motion, measured by the release work "
                "U_A); value null, 'slide' gives the load at which the friction is "
                "exhausted, 'geometric_limit' the small-displacement limit (null: none)",
    "unbalanced": "not held at zero external load: the squeeze's contact forces leave a "
                  "resultant ('gauge_reaction') that friction cannot carry once released",
    "budget": "not computed: the time budget (--max-seconds) was spent first",
}


def _num(x: float) -> float | None:
    """A finite float for JSON (``-0.0`` as ``0.0``), ``None`` for ``±inf``/``nan``."""
    return float(x) + 0.0 if math.isfinite(x) else None


def hold_to_dict(hold: dict | None, reason: str | None = None) -> dict[str, Any] | None:
    """The report's ``hold`` (valid JSON: no infinity, no ``-0.0``): ``force`` [N] and
    ``torque`` [N·m] pairs ``[−, +]`` from zero external load (``f− ≤ 0 ≤ f+``: the load
    that dislodges the part each way, :meth:`FrictionalCurve.hold`), each ``None`` unless
    friction (or the end of the quasi-static path) limits it, ``limited_by`` naming what
    does per entry (:data:`HOLD_LIMITS`), ``slide`` (the loads at which every contact
    slides: the friction exhausted, finite wherever friction is what holds),
    ``geometric_limit`` (the small-displacement limit of the geometric entries),
    ``gauge_reaction`` and a ``reason`` for every ``None``."""
    if hold is None:
        return None if reason is None else {"force": None, "torque": None, "slide": None,
                                            "limited_by": None, "reason": reason}
    kinds = hold["limited_by"]

    def value(key: str) -> list:
        return [_num(x) if k in ("friction", "dynamic", "unbalanced") else None
                for x, k in zip(hold[key], kinds[key])]

    def geometric(key: str) -> list:
        return [_num(x) if k == "geometry" else None for x, k in zip(hold[key], kinds[key])]

    used = sorted({k for v in kinds.values() for k in v},
                  key=list(HOLD_LIMITS).index)
    why = "; ".join(f"{k}: {HOLD_LIMITS[k]}" for k in used if k != "friction") or None
    if hold.get("stopped"):
        why = hold["stopped"] + ("" if why is None else "; " + why)
    pair = lambda v: [_num(x) for x in v]  # noqa: E731
    return {"force": value("force"), "torque": value("torque"),
            "limited_by": {"force": list(kinds["force"]), "torque": list(kinds["torque"])},
            "slide": {"force": pair(hold["slide"]["force"]),
                      "torque": pair(hold["slide"]["torque"])},
            "geometric_limit": {"force": geometric("force"), "torque": geometric("torque")},
            "gauge_reaction": {k: _num(v) for k, v in hold["gauge_reaction"].items()},
            "convention": "external load (force across the axis, torque about the area "
                          "centroid) from zero, applied one way at a time: [-, +] with "
                          "- <= 0 <= +",
            "reason": why, "units": {"force": "N", "torque": "N*m"}}


@dataclass(frozen=True, eq=False)
class FrictionalGrasp:
    """A refined pad grasp read with friction on every level.

    Attributes
    ----------
    refined : RefinedPadGrasp
        The frictional levels (their error estimate, convergence and verdict, SPEC §6).
    frictionless : RefinedPadGrasp
        The run as solved without friction.
    levels : list of FrictionalLevel
    mu : float
    budget : dict or None
        The friction stage's time budget: ``max_seconds``, ``seconds`` (s), ``stopped``
        (why it stopped early, or ``None``), ``levels_read`` of ``levels``.
    """

    refined: RefinedPadGrasp
    frictionless: RefinedPadGrasp
    levels: list = field(default_factory=list)
    mu: float = 0.0
    budget: dict | None = None

    @property
    def finest(self) -> FrictionalLevel:
        return self.levels[-1]

    def to_dict(self) -> dict[str, Any]:
        """The refined report (frictional values) plus ``friction``, ``hold``,
        ``dissipation``, ``release_work`` and the frictionless answer for comparison."""
        d = self.refined.to_dict()
        fin = self.finest
        d["friction"] = self.mu
        d["U_A_model"] = "release work with dissipation (SPEC §9)"
        d["hold"] = hold_to_dict(fin.hold, fin.hold_error)
        d["dissipation"] = None if not math.isfinite(fin.dissipation) else fin.dissipation
        check = fin.path_check
        d["release_work"] = {
            "forces": fin.forces, "works": fin.works,
            "path_check": None if check is None else
            {"forces": "frictional", "work": check["work"], "dissipation": check["dissipation"],
             "relative": check["relative"]},
            "frictional_axes": fin.expanded, "frictionless_fallback": fin.frictionless_vertices}
        if self.budget is not None:
            d["friction_stage"] = dict(self.budget, units={"max_seconds": "s", "seconds": "s"})
        if fin.U_A_bound:
            d["U_A_lower_bound"] = True
        fl = self.frictionless
        d["frictionless"] = {"sigma_star": fl.finest.sigma_star, "quality": fl.finest.quality,
                             "U_A": None if math.isinf(fl.finest.U_A) else fl.finest.U_A,
                             "verdict": fl.verdict}
        return d


class FrictionalRefinement(RefinedPadGrasp):
    """The frictional levels as a :class:`~deformclosure.pads.refine.RefinedPadGrasp`
    (the same error estimate and verdict rules), not converged when a level's reading ran
    out of its time budget (its σ* is then the best of the separations evaluated)."""

    @property
    def converged(self) -> bool:
        return super().converged and not (self.stopped or "").startswith("friction")


def frictional_refined(run: RefinedPadGrasp, mu: float, *, hold: bool = True,
                       n_samples: int = SIGMA_SAMPLES,
                       max_seconds: float | None = None) -> FrictionalGrasp:
    """Every level of ``run`` read with friction ``mu`` (module docstring); ``hold`` at σ*
    of the finest level.

    ``max_seconds`` is the friction stage's time budget (s; default
    :data:`~deformclosure.pads.refine.DEFAULT_MAX_SECONDS`, as the refinement's and the
    finite-strain stage's). When it runs out the level being read keeps the best
    separation it evaluated, the coarser levels are kept, the finer ones are not read
    (the refinement keeps as many frictional levels as were read), and the result says
    ``stopped`` — the report's ``stopped``, ``converged: false`` and its
    ``friction_stage`` entry."""
    mu = check_friction(mu)
    if mu == 0.0:
        raise GraspError("--friction: 0 is the frictionless run itself; give μ > 0")
    budget = DEFAULT_MAX_SECONDS if max_seconds is None else float(max_seconds)
    t0 = time.perf_counter()
    deadline = t0 + budget
    last = len(run.levels) - 1
    levels: list[FrictionalLevel] = []
    for k, r in enumerate(run.levels):
        lv = frictional_level(r, mu, rtol=run.rtol, n_samples=n_samples,
                              hold=hold and k == last, deadline=deadline)
        levels.append(lv)
        if lv.stopped:
            break
    stopped = next((lv.stopped for lv in levels if lv.stopped), None)
    if stopped is not None and len(levels) < len(run.levels):
        stopped += f"; {len(run.levels) - len(levels)} finer level(s) not read with friction"
        if hold:        # the hold belongs to the finest level read
            fin = levels[-1]
            levels[-1] = _with_hold(fin, mu, deadline)
    k = len(levels)
    refined = FrictionalRefinement(
        [lv.result for lv in levels], run.max_areas[:k], run.rtol, run.adaptive,
        stopped if stopped is not None else run.stopped, run.seconds[:k],
        [lv.result.saddle for lv in levels if lv.result.saddle is not None])
    return FrictionalGrasp(refined, run, levels, mu,
                           {"max_seconds": budget, "seconds": time.perf_counter() - t0,
                            "stopped": stopped,
                            "levels_read": k, "levels": len(run.levels)})


def _with_hold(lv: FrictionalLevel, mu: float, deadline: float | None = None) -> FrictionalLevel:
    """``lv`` with the hold at its σ* (the finest level read when the budget ran out;
    skipped, with the reason, when ``deadline`` has passed)."""
    res = lv.result
    if res.sigma_star is None:
        return lv
    if deadline is not None and time.perf_counter() > deadline:
        return dataclasses.replace(lv, hold_error="skipped: the time budget (--max-seconds) "
                                   "was spent before the holding loads")
    try:
        curve = res.solver.curve(res.start_curve.axis, res.start_curve.pad, res.sigma_L,
                                 _hole_of(res.solver, res.start_curve))
        return dataclasses.replace(lv, hold=frictional_grasp(res.solver, curve, mu)
                                   .hold(res.sigma_star, deadline=deadline))
    except GraspError as err:
        return dataclasses.replace(lv, hold_error=str(err))
