"""Pad grasps under mesh refinement: convergence table, Richardson error, verdict (SPEC §6).

``--refine N`` solves the same grasp on ``N`` meshes, the triangle area quartered each
time (``h`` halved). From the last three qualities ``Q₁, Q₂, Q₃`` the observed order is
``p = log₂(|Q₁ − Q₂| / |Q₂ − Q₃|)`` (clipped to [0.5, 4]) and the Richardson extrapolation
``Q∞ = Q₃ + (Q₃ − Q₂)/(2^p − 1)``; the error estimate is ``|Q∞ − Q₃|``, the same for σ*.
With two meshes ``p = 1`` is assumed (the rate of the CST energy under a point-like contact
singularity is about 1, and p = 1 is the cautious choice among the rates seen).

Verdict: ``"held"`` when the finest quality exceeds its error estimate; ``"not held"``
when the finest mesh has no barrier (``Q = 0``) and the extrapolation does not bring one
back (``Q∞ ≤ 0``); otherwise ``"undecided"``: the release energy is within its error of 0.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import GraspError
from ..log import done
from ..mesh import mesh_part
from ..mesh.generate import default_max_area
from .contact import PadContact, hole_containing
from .geometry import GraspAxis, Pad
from ..mesh.generate import twin_mesh
from .optimize import PadGraspResult, optimize_pads

__all__ = ["RefinedPadGrasp", "richardson", "pad_grasp"]

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


@dataclass(frozen=True, eq=False)
class RefinedPadGrasp:
    """A pad grasp solved on a refinement sequence; the finest result is the answer."""

    levels: list[PadGraspResult]
    max_areas: list[float]

    @property
    def finest(self) -> PadGraspResult:
        """The result on the finest mesh."""
        return self.levels[-1]

    def error_estimate(self) -> dict[str, float | None]:
        """Richardson error estimates of quality (J) and σ* (m)."""
        if len(self.levels) < 2:
            return {"quality": None, "sigma_star": None}
        Q = [r.quality for r in self.levels]
        _, eQ, _ = richardson(Q)
        S = [r.sigma_star for r in self.levels]
        eS = richardson(S)[1] if all(s is not None for s in S) else None
        return {"quality": eQ, "sigma_star": eS}

    @property
    def verdict(self) -> str:
        """``"held"``, ``"not held"`` or ``"undecided"`` (module docstring)."""
        fine = self.finest
        if len(self.levels) < 2:
            return fine.verdict
        Q = [r.quality for r in self.levels]
        ext, err, _ = richardson(Q)
        if fine.quality > err and fine.quality > 0:
            return "undecided" if fine.blind else "held"   # a blind mesh is no evidence
        if fine.quality == 0 and ext <= 0:
            return "not held"
        return "undecided"

    def to_dict(self) -> dict[str, Any]:
        """The finest report plus ``error_estimate``, ``convergence`` and the verdict."""
        d = self.finest.to_dict()
        if len(self.levels) > 1:
            d["error_estimate"] = self.error_estimate()
            d["convergence"] = [
                {"max_area": a, "nodes": r.n_nodes, "sigma_star": r.sigma_star,
                 "quality": r.quality, "U_A": None if math.isinf(r.U_A) else r.U_A,
                 "sigma0": r.sigma0, "sigma_L": r.sigma_L, "force": r.force}
                for a, r in zip(self.max_areas, self.levels)]
            d["verdict"] = self.verdict
        return d


def pad_grasp(part, axis: GraspAxis, pad: Pad, *, mesh=None, refine: int = 1,
              twin: bool = True, expanding_from=None, progress=None,
              max_area: float | None = None, **options) -> RefinedPadGrasp:
    """Optimal separation of a pad grasp, on one mesh or a refinement sequence.

    Parameters
    ----------
    part : Part or None
        The part (needed for ``refine > 1`` and for the twin realisation).
    axis : GraspAxis
        Start axis in the part frame (angle in rad, offset in m).
    pad : Pad
        Width and end radius in m.
    mesh : Mesh, optional
        The first mesh (default: the part meshed with its own settings).
    refine : int
        Number of meshes (``max_area`` quartered each time), 1 to 5.
    twin : bool
        Measure the noise floor on a second mesh realisation (needs ``part``).
    expanding_from : array_like, optional
        Expanding grasp: a point (m) inside the hole the pads open in.
    progress : callable, optional
        Called with ``(level, n_levels)`` before each level.
    max_area : float, optional
        Largest triangle area (m²) of the first level (default the part's own); each
        further level quarters it. ``mesh``, when given, must be that first level.
    **options
        Passed to :func:`optimize_pads`: ``n_angles``, ``n_offsets``, ``n_samples``,
        ``n_curve``, ``noise``.

    Returns
    -------
    RefinedPadGrasp
        One :class:`PadGraspResult` per mesh (σ in m, energies in J), the finest last,
        with the Richardson error estimate and the verdict.

    Raises
    ------
    GraspError
        A bad ``refine``, ``axis``, ``pad`` or option, no part or mesh, a point not in a
        hole, or any refusal of :func:`optimize_pads`.

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
    ('held', 7.657)
    """
    _check_request(part, axis, pad, refine, options)
    if mesh is None:
        if part is None:
            raise GraspError("part: give a part or a mesh")
        mesh = mesh_part(part, max_area=max_area)
    if max_area is not None:
        base = float(max_area)
    else:
        base = default_max_area(part) if part is not None else float(mesh.areas.max())
    levels, areas = [], []
    for k in range(refine):
        if progress is not None:
            progress(k, refine)
        area = base / 4.0**k
        m = mesh if k == 0 else mesh_part(part, max_area=area)
        tw = PadContact(twin_mesh(part, max_area=area)) if (twin and part is not None) else None
        holes = {} if expanding_from is None else _holes(m, tw, expanding_from)
        t0 = time.perf_counter()
        levels.append(optimize_pads(m, axis, pad, twin=tw, **holes, **options))
        areas.append(area)
        done("mesh %d of %d (%d nodes): Q* = %.6g J, %d grasp axes solved", t0,
             k + 1, refine, m.n_nodes, levels[-1].quality, levels[-1].n_axes)
    return RefinedPadGrasp(levels, areas)


def _check_request(part, axis, pad, refine, options: dict) -> None:
    """Refuse a bad ``refine``, ``axis``, ``pad`` or option of :func:`pad_grasp`."""
    if isinstance(refine, bool) or not (isinstance(refine, int) and 1 <= refine <= 5):
        raise GraspError(f"--refine = {refine!r}: give a whole number of meshes from 1 to 5")
    if not isinstance(axis, GraspAxis):
        raise GraspError(f"axis = {axis!r}: give a GraspAxis (angle in rad, offset in m)")
    if not isinstance(pad, Pad):
        raise GraspError(f"pad = {pad!r}: give a Pad (width and radius in m)")
    unknown = sorted(set(options) - _OPTIONS)
    if unknown:
        raise GraspError(f"{unknown[0]}: not an option of a pad grasp; use "
                         f"{', '.join(sorted(_OPTIONS))}")
    if part is None and refine > 1:
        raise GraspError("--refine: needs a part file (a mesh file cannot be re-meshed)")


def _holes(mesh, twin: PadContact | None, point) -> dict:
    """``hole`` and ``twin_hole`` of an expanding grasp: the holes of ``mesh`` and of the
    twin's mesh that contain ``point`` (m)."""
    hole = hole_containing(mesh, point)
    if hole is None:
        raise GraspError("--expanding: the axis point is not inside a hole of the part; "
                         "give --at points on a hole's boundary or an --axis point in it")
    return {"hole": hole, "twin_hole": None if twin is None else hole_containing(twin.mesh, point)}
