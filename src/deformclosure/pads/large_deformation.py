"""The pads model at finite strain: a neo-Hookean part between rigid capsule pads with the
exact contact geometry (SPEC §8).

On a grasp axis the pads are the capsules of SPEC §6 (:class:`.geometry.Pad`) at their
positions along the axis; a boundary node's gap is the exact signed distance of its
*current* position to each capsule, so the part may slide around a round pad and touch its
flanks at any squeeze (no flank cap). The part's gauge is SPEC §6's: its mean cross-axis
displacement and its mean rotation ω are zero, and it floats along the axis. The squeeze is
followed from first touch by :func:`deformclosure.contact.large_deformation.follow_squeeze`
(Newton with an active set, steps halved where needed, a squeeze it cannot reach reported).

A :class:`FiniteStrainCurve` is the energy of one axis against the separation ``σ``: no
longer piecewise quadratic, it is solved at the separations asked for, each from the
nearest converged state on the same axis (frictionless elasticity is path-independent, so
any converged neighbour is a valid start). :class:`FiniteStrainPads` makes them; it has the
``curve`` method of :class:`.contact.PadContact`, so the release landscape of SPEC §6
(:class:`.landscape.Landscape`) and its one minimax search run on it unchanged.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from ..contact.compliance import gauge_functionals
from ..contact.large_deformation import (CapsuleObstacle, ContactState, FiniteStrainContact,
                                         follow_squeeze)
from ..elasticity.critical_distance import averaged_strain_magnitude, critical_distance_of
from ..elasticity.finite_strain import averaged_stretch_magnitudes, law_strain_maximum
from ..elasticity.linear_energy import LinearEnergy
from ..elasticity.neohookean import material_law
from .geometry import FirstTouch, GraspAxis, Pad, first_touch

__all__ = ["FiniteStrainPads", "FiniteStrainCurve", "material_law"]

#: Squeeze steps (fraction of the first-touch width σ0) of the first trace of an axis.
STEP_FRACTION = 1.0 / 16.0


class FiniteStrainCurve:
    """Energy, force and strain of one grasp axis at finite strain, solved on demand.

    Attributes
    ----------
    axis : GraspAxis
    pad : Pad
    touch : FirstTouch or None
        ``None`` when the pads miss the part (energy 0 at every σ).
    delta0 : float
        Squeeze (m) at which both pads touch a node (energy 0 before it).
    delta_failed : float or None
        Smallest squeeze (m) found unreachable (Newton failed after every halving), or None.
    """

    def __init__(self, owner: "FiniteStrainPads", axis: GraspAxis, pad: Pad,
                 touch: FirstTouch | None) -> None:
        self.owner, self.axis, self.pad, self.touch = owner, axis, pad, touch
        self.delta_failed: float | None = None
        self._deltas: list[float] = []
        self._states: list[ContactState] = []
        self.n_solves = 0
        if touch is None:
            self.delta0 = math.inf
            return
        mesh = owner.mesh
        loop = mesh.outer_loop
        s, x = axis.coordinates(mesh.nodes[loop])
        d, _ = pad.profile(x, capped=False)
        ok = np.isfinite(d)
        if not ok.any():
            self.touch = None
            self.delta0 = math.inf
            return
        gA = s - touch.z_a + d
        gB = touch.z_b + d - s
        self._gA, self._gB = float(gA[ok].min()), float(gB[ok].min())
        self.delta0 = max(self._gA + self._gB, 0.0)
        a, n = axis.direction, axis.normal
        rows = [(loop, 0), (loop, 1)]
        G = gauge_functionals(mesh)
        gauge = np.vstack([n[0] * G[0] + n[1] * G[1], G[2]])
        self.problem = FiniteStrainContact(owner.law, mesh.nodes, rows, gauge, mesh.diameter,
                                           mesh.triangles)
        self._a, self._n = a, n
        self._on_a = self.problem.body == 0

    # ---------------------------------------------------------------- geometry
    @property
    def sigma0(self) -> float:
        """First-touch width (m); ``nan`` if the pads miss the part."""
        return self.touch.sigma0 if self.touch is not None else float("nan")

    @property
    def expanding(self) -> bool:
        return False

    def delta(self, sigma: float) -> float:
        """Squeeze ``σ0 − σ`` (m)."""
        return self.touch.sigma0 - sigma

    def sigma_at(self, delta: float) -> float:
        """Separation (m) at squeeze ``delta`` (m)."""
        return self.touch.sigma0 - delta

    def faces_at(self, delta: float) -> tuple[float, float]:
        """Axial positions (m) of the faces of pads A and B at squeeze ``delta`` (m): each
        moved in by half the squeeze beyond the first node contact (the part floats, so
        the split is free); the part's displacements are in this frame."""
        t = self.touch
        half = 0.5 * (delta - self.delta0)
        return t.z_a + self._gA + half, t.z_b - self._gB - half

    def bodies_at(self, delta: float) -> list[CapsuleObstacle]:
        """The two pads' capsules at squeeze ``delta`` (m): both have moved in by half the
        squeeze beyond the first node contact (the part floats, so the split is free)."""
        ax, pad = self.axis, self.pad
        zA, zB = self.faces_at(delta)
        o = np.asarray(ax.origin, float)
        a, n = self._a, self._n
        w = 0.5 * pad.width
        out = []
        # each pad is carried by its finger: the strip behind it (SPEC §6: the pads come
        # from outside along the axis), so a part wrapping round a pad meets its flanks
        for s, back in ((zA - pad.radius, -a), (zB + pad.radius, a)):
            p = o + s * a + (ax.offset - w) * n
            q = o + s * a + (ax.offset + w) * n
            out.append(CapsuleObstacle((float(p[0]), float(p[1])), (float(q[0]), float(q[1])),
                                       pad.radius, (float(back[0]), float(back[1]))))
        return out

    # ---------------------------------------------------------------- solving
    def state(self, delta: float) -> ContactState | None:
        """The converged state at squeeze ``delta`` (m); ``None`` before first contact
        (no load) or beyond the reachable squeeze."""
        if self.touch is None or delta <= self.delta0:
            return None
        if self.delta_failed is not None and delta >= self.delta_failed:
            return None
        k = bisect.bisect_left(self._deltas, delta)
        if k < len(self._deltas) and self._deltas[k] == delta:
            return self._states[k]
        step = STEP_FRACTION * self.touch.sigma0
        direct = self._direct(k, delta, step)
        if direct is not None:
            return direct
        if k > 0:
            start, d_start = self._states[k - 1], self._deltas[k - 1]
        else:
            start, d_start = None, self.delta0
        targets = list(np.arange(d_start + step, delta, step)) + [delta]
        path = follow_squeeze(self.problem, self.bodies_at, targets, start, d_start)
        self.n_solves += path.n_solves
        for d, st in zip(path.delta, path.states):
            j = bisect.bisect_left(self._deltas, float(d))
            if j < len(self._deltas) and self._deltas[j] == float(d):
                continue
            self._deltas.insert(j, float(d))
            self._states.insert(j, st)
        if not path.reached:
            self.delta_failed = (path.delta_failed if self.delta_failed is None
                                 else min(self.delta_failed, path.delta_failed))
            return None
        return path.states[-1]

    def energy_near(self, sigma: float, other: "FiniteStrainCurve") -> float:
        """:meth:`energy_at`, started (when this axis has no state yet) from ``other``'s
        converged state at the same ``sigma``: a neighbouring axis of the landscape holds
        the part in nearly the same shape, so one Newton solve replaces the trace from
        first touch (the trace remains the fallback)."""
        if self.touch is None or other.touch is None or self._states:
            return self.energy_at(sigma)
        d = self.delta(sigma)
        d_other = other.delta(sigma)
        if d <= self.delta0 or d_other <= other.delta0:
            return self.energy_at(sigma)
        seed = other.state(d_other)
        if seed is None:
            return self.energy_at(sigma)
        trial = self.problem.solve(self.bodies_at(d), seed.u, seed.lam, seed.mu)
        self.n_solves += 1
        if trial.converged:
            self._deltas.append(float(d))
            self._states.append(trial)
            return trial.energy
        return self.energy_at(sigma)

    def _direct(self, k: int, delta: float, step: float) -> ContactState | None:
        """One Newton solve at ``delta`` from the states beside it (interpolated between the
        two neighbours, or extrapolated from the two below by at most one of their
        spacings), when the nearest is within a step; ``None`` (the caller traces instead)
        when there is none, it fails, or its energy is not between its neighbours'."""
        D, S = self._deltas, self._states
        if k == 0 or delta - D[k - 1] > step:
            return None
        lo = S[k - 1]
        if k < len(D):
            w = (delta - D[k - 1]) / (D[k] - D[k - 1])
            u0, l0 = lo.u + w * (S[k].u - lo.u), lo.lam + w * (S[k].lam - lo.lam)
        elif k >= 2 and D[k - 1] - D[k - 2] > 0:
            w = min((delta - D[k - 1]) / (D[k - 1] - D[k - 2]), 1.0)
            u0, l0 = lo.u + w * (lo.u - S[k - 2].u), lo.lam + w * (lo.lam - S[k - 2].lam)
        else:
            u0, l0 = lo.u, lo.lam
        trial = self.problem.solve(self.bodies_at(delta), u0, np.maximum(l0, 0.0), lo.mu)
        self.n_solves += 1
        if not trial.converged or not self._monotone(k, trial.energy):
            return None
        self._deltas.insert(k, float(delta))
        self._states.insert(k, trial)
        return trial

    def _monotone(self, k: int, energy: float) -> bool:
        """Whether an energy at a squeeze between states ``k − 1`` and ``k`` keeps ``U(δ)``
        non-decreasing (the pads only push: ``dU/dδ = F ≥ 0``), with a round-off margin. A
        converged state that breaks it is another equilibrium branch (e.g. the part
        wrapped round a pad from a wild start), not the squeeze's."""
        S = self._states
        tol = 1e-9 * max(abs(energy), 1e-300)
        if k > 0 and energy < S[k - 1].energy - tol:
            return False
        if k < len(S) and energy > S[k].energy + tol:
            return False
        return True

    def energy_at(self, sigma: float) -> float:
        """Stored energy (J) at separation ``sigma`` (m); ``inf`` beyond the reachable
        squeeze (the pads cannot close that far on this model)."""
        if self.touch is None:
            return 0.0
        d = self.delta(sigma)
        if d <= self.delta0:
            return 0.0
        st = self.state(d)
        return math.inf if st is None else st.energy

    def energy(self, sigma) -> np.ndarray:
        """Energies (J) at separations ``sigma`` (m)."""
        return np.array([self.energy_at(float(s)) for s in np.atleast_1d(sigma)])

    def axial_force(self, sigma: float) -> float:
        """Each pad's squeezing force (N) along the axis at ``sigma`` (m); ``nan`` beyond
        the reachable squeeze."""
        if self.touch is None or self.delta(sigma) <= self.delta0:
            return 0.0
        st = self.state(self.delta(sigma))
        if st is None:
            return math.nan
        on = self._on_a
        return float(st.lam[on] @ (st.normals[on] @ self._a))

    def displacement(self, sigma: float) -> np.ndarray:
        """Displacement (m), shape (2n,), at ``sigma`` (zero before contact)."""
        if self.touch is None or self.delta(sigma) <= self.delta0:
            return np.zeros(2 * self.owner.mesh.n_nodes)
        st = self.state(self.delta(sigma))
        if st is None:
            raise ValueError("separation beyond the reachable squeeze")
        return st.u

    def strain(self, sigma: float, ell: float | None = None) -> float:
        """SPEC §8's strain measure (critical-distance-averaged C, ``max |λᵢ − 1|``) at
        ``sigma`` (m); ``inf`` beyond the reachable squeeze."""
        if self.touch is None or self.delta(sigma) <= self.delta0:
            return 0.0
        st = self.state(self.delta(sigma))
        if st is None:
            return math.inf
        mesh = self.owner.mesh
        ell = critical_distance_of(mesh) if ell is None else ell
        return law_strain_maximum(mesh, self.owner.law, st.u, ell)

    def strain_field(self, sigma: float, ell: float | None = None) -> np.ndarray:
        """Per element, the averaged strain magnitude (m/m) whose maximum is
        :meth:`strain` at ``sigma`` (m): SPEC §8's stretch measure, or §6's for the
        small-strain law; zeros before contact; ``ValueError`` beyond the reachable
        squeeze."""
        mesh = self.owner.mesh
        if self.touch is None or self.delta(sigma) <= self.delta0:
            return np.zeros(len(mesh.triangles))
        st = self.state(self.delta(sigma))
        if st is None:
            raise ValueError("separation beyond the reachable squeeze")
        ell = critical_distance_of(mesh) if ell is None else ell
        law = self.owner.law
        if isinstance(law, LinearEnergy):
            return averaged_strain_magnitude(mesh, law.small_strains(st.u), ell)
        return averaged_stretch_magnitudes(mesh, law.right_cauchy_green(st.u), ell)

    def kinks(self) -> np.ndarray:
        """No exact breakpoints: the curve is smooth between contact events."""
        return np.zeros(0)


@dataclass
class FiniteStrainLimit:
    """Elastic limit of one axis at finite strain (SPEC §8).

    Attributes
    ----------
    sigma_L : float
        Separation (m) where the strain reaches ``e_L`` (located to ``tol``), or the
        smallest reachable separation traced when it is not reached.
    reached : bool
        Whether ``e_L`` was reached before the squeeze became unreachable.
    critical_distance : float
    """

    sigma_L: float
    reached: bool
    critical_distance: float


class FiniteStrainPads:
    """Finite-strain grasp curves of one mesh (the ``curve`` interface of
    :class:`.contact.PadContact`).

    Parameters
    ----------
    mesh : Mesh
    elasticity : {"neo-hookean", "linear"}
        The material law; ``"linear"`` is the small-strain energy with the exact gap
        (a check of the solver against SPEC §6).
    """

    def __init__(self, mesh, elasticity: str = "neo-hookean") -> None:
        self.mesh = mesh
        self.elasticity = elasticity
        self.law = material_law(mesh, elasticity)
        self.diameter = mesh.diameter
        self._ring = mesh.nodes[mesh.outer_loop]

    def curve(self, axis: GraspAxis, pad: Pad, sigma_end: float = 0.0,
              hole: int | None = None) -> FiniteStrainCurve:
        """The (lazily solved) curve of ``axis``; contracting grasps only."""
        if hole is not None:
            from ..errors import GraspError
            raise GraspError("--elasticity neo-hookean: expanding grasps (pads opening in a "
                             "hole) are not supported yet; use --elasticity linear")
        return FiniteStrainCurve(self, axis, pad, first_touch(self._ring, axis, pad))

    def elastic_limit(self, curve: FiniteStrainCurve, e_L: float, ell: float | None = None,
                      rtol: float = 1e-3) -> FiniteStrainLimit:
        """``σ_L`` of ``curve``: the first squeeze where the strain measure reaches
        ``e_L``, bracketed on steps of :data:`STEP_FRACTION` σ0 and bisected to
        ``rtol`` σ0."""
        ell = critical_distance_of(self.mesh) if ell is None else ell
        sigma0 = curve.sigma0
        step = STEP_FRACTION * sigma0
        tol = rtol * sigma0
        top = sigma0 * (1 - 1e-9)                  # σ = 0: the pads meet
        lo, hi = curve.delta0, None
        # bracket: the first step whose strain reaches e_L, or that cannot be reached
        d = lo
        while d < top:
            d = min(d + step, top)
            e = curve.strain(curve.sigma_at(d), ell)
            if not math.isfinite(e) or e >= e_L:
                hi = d
                break
            lo = d
        if hi is None:                             # e_L not reached up to σ = 0
            return FiniteStrainLimit(curve.sigma_at(lo), False, ell)
        # bisect: a reachable point below e_L raises lo; one at or above e_L, or one the
        # solver cannot reach, lowers hi (an unreachable squeeze must not hide a crossing)
        crossed = math.isfinite(curve.strain(curve.sigma_at(hi), ell))
        while hi - lo > tol:
            mid = 0.5 * (lo + hi)
            em = curve.strain(curve.sigma_at(mid), ell)
            if math.isfinite(em) and em < e_L:
                lo = mid
            else:
                hi, crossed = mid, math.isfinite(em)
        if crossed:
            return FiniteStrainLimit(curve.sigma_at(hi), True, ell)
        return FiniteStrainLimit(curve.sigma_at(lo), False, ell)
