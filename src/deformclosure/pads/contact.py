"""Frictionless contact of two rigid pads with an elastic part, on the condensed boundary
compliance (SPEC §6).

At a fixed grasp axis the part's mean rotation and mean translation are those of the axis
(the gauge of :class:`deformclosure.contact.compliance.BoundaryCompliance`, SPEC §6) and
it floats along the axis: the contact problem carries the float ``t`` as its own unknown.
The energy of a load ``f`` on the part so constrained is ``½ fᵀ Y f`` with the gauged
boundary compliance ``Y``.

Gaps are measured along the axis to the pad's surface ``d(x)`` (see
:mod:`deformclosure.pads.geometry`) and linearised in the part's displacement only:
``g_A = s − z_A + d(x) + (a + d'(x) n)·u``, ``g_B = z_B + d(x) − s + (−a + d'(x) n)·u``, so
each contact force is along the pad's normal there. The pad positions enter additively,
hence the energy is exactly piecewise quadratic in the separation σ.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..contact.compliance import BoundaryCompliance
from ..contact.path import ContactPath
from ..contact.solve import ContactProblem, trace_contact
from ..geometry import touch_tolerance
from ..limits import blas_threads
from .geometry import FirstTouch, GraspAxis, Pad, first_touch

__all__ = ["PadContact", "GraspCurve", "hole_containing"]


def hole_containing(mesh, point) -> int | None:
    """Index (into ``mesh.hole_loops``) of the hole containing ``point`` (m), or None."""
    import shapely

    for k, lp in enumerate(mesh.hole_loops):
        if shapely.contains_xy(shapely.Polygon(mesh.nodes[lp]), float(point[0]), float(point[1])):
            return k
    return None


@dataclass(frozen=True)
class GraspCurve:
    """Energy of one grasp axis as an exact piecewise quadratic in the separation σ.

    Attributes
    ----------
    axis : GraspAxis
    pad : Pad
    touch : FirstTouch or None
        ``None`` when the pads miss the part (energy 0 at every σ).
    nodes : ndarray of int, shape (m,)
        Candidate contact nodes (a node may appear once per pad).
    pad_of : ndarray of int, shape (m,)
        0 for pad A, 1 for pad B.
    normals : ndarray, shape (m, 2)
        Unit contact normals (direction of each contact force on the part).
    path : ContactPath
        Normal-force magnitudes (N) against the squeeze ``δ = σ0 − σ``.
    """

    axis: GraspAxis
    pad: Pad
    touch: FirstTouch | None
    nodes: np.ndarray
    pad_of: np.ndarray
    normals: np.ndarray
    path: ContactPath | None
    _fast: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # σ0 and the squeeze's sign for the scalar fast path (a landscape evaluates ~10⁵
        # energies; σ0 is a property of the touch)
        t = self.touch
        object.__setattr__(self, "_fast", (None if t is None else t.sigma0, t is not None and t.expanding))

    @property
    def sigma0(self) -> float:
        """Closing (opening) width at first touch (m); ``nan`` if the pads miss the part."""
        return self.touch.sigma0 if self.touch is not None else float("nan")

    @property
    def expanding(self) -> bool:
        """Whether the pads open inside a hole (squeeze ``δ = σ − σ0``)."""
        return self.touch is not None and self.touch.expanding

    def delta(self, sigma):
        """Squeeze ``δ`` (m) at separation ``sigma``: ``σ0 − σ``, or ``σ − σ0`` expanding."""
        return (sigma - self.touch.sigma0) if self.touch.expanding else (self.touch.sigma0 - sigma)

    def sigma_at(self, delta):
        """Separation (m) at squeeze ``delta`` (m)."""
        return (self.touch.sigma0 + delta) if self.touch.expanding else (self.touch.sigma0 - delta)

    @property
    def sigma_end(self) -> float:
        """Far end (m) of the traced range (smallest σ, or largest when expanding)."""
        if self.path is None:
            return -np.inf if self.touch is None else self.sigma0
        return self.sigma_at(float(self.path.delta[-1]))

    def energy(self, sigma: np.ndarray | float) -> np.ndarray:
        """Energy (J) at separations ``sigma`` (m)."""
        sigma = np.asarray(sigma, float)
        if sigma.ndim == 0:
            # one separation: the scalar path (the same arithmetic, 30 times faster)
            return np.asarray(self.energy_at(float(sigma)))
        if self.path is None:
            return np.zeros_like(sigma)
        return self.path.energy(self.delta(sigma))

    def energy_at(self, sigma: float) -> float:
        """Energy (J) at one separation ``sigma`` (m) (scalar fast path of :meth:`energy`)."""
        path = self.path
        if path is None:
            return 0.0
        s0, expanding = self._fast
        return path.energy_at((sigma - s0) if expanding else (s0 - sigma))

    def kinks(self) -> np.ndarray:
        """Separations (m) where the active contact set changes, from first touch on."""
        if self.path is None:
            return np.zeros(0)
        return self.sigma_at(self.path.delta)

    def forces(self, sigma: float) -> np.ndarray:
        """Contact forces on the part (N), shape (m, 2), at separation ``sigma`` (m)."""
        if self.path is None:
            return np.zeros((0, 2))
        lam = self.path.multipliers(self.delta(sigma))
        return lam[:, None] * self.normals

    def axial_force(self, sigma: float) -> float:
        """Squeezing force (N) of each pad along the axis at ``sigma`` (m)."""
        if self.path is None:
            return 0.0
        lam = self.path.multipliers(self.delta(sigma))
        on_a = self.pad_of == 0
        return float(lam[on_a] @ (self.normals[on_a] @ self.axis.direction))

    def axial_stiffness(self, sigma: float) -> float:
        """Grip stiffness ``dF/dδ`` (N/m) at ``sigma`` (m): how fast the pad force grows
        with the squeeze ``δ`` (``−dF/dσ`` for a contracting grasp, SPEC §6).

        The force is piecewise linear in ``δ``; at a breakpoint the slope of the piece
        beyond it (towards more squeeze) is taken, 0 before first touch.
        """
        path = self.path
        if path is None or len(path.delta) < 2:
            return 0.0
        delta = self.delta(sigma)
        if delta < path.delta[0]:
            return 0.0
        i = int(path.piece(np.array(delta)))
        on_a = self.pad_of == 0
        c = self.normals[on_a] @ self.axis.direction
        dlam = (path.lam[i + 1] - path.lam[i]) / (path.delta[i + 1] - path.delta[i])
        return float(dlam[on_a] @ c)


class PadContact(BoundaryCompliance):
    """One factorisation of a part's stiffness in the axis gauge of SPEC §6
    (:meth:`BoundaryCompliance.axis_gauge`); grasp energies for any axis and pad.

    It also keeps the mesh's strain data, built on first use: the element
    strain-displacement matrices, and (with the mesh) the critical-distance averages of
    each ``ℓ`` (:func:`~deformclosure.elasticity.critical_distance.disc_average`) — a plan
    evaluates the elastic limit of hundreds of axes on the same mesh.

    Parameters
    ----------
    mesh : Mesh
    K : sparse matrix, optional
        Stiffness (N/m); default the mesh's CST stiffness.
    """

    def __init__(self, mesh, K: sp.spmatrix | None = None) -> None:
        super().__init__(mesh, K)
        self._ring = mesh.nodes[mesh.outer_loop]

    def load_vector(self, curve: GraspCurve, lam: np.ndarray) -> np.ndarray:  # type: ignore[override]
        """Global load vector (N), shape (2n,), of multipliers ``lam`` on ``curve``'s contacts."""
        return super().load_vector(curve.nodes, lam[:, None] * curve.normals)

    def hole_start(self, axis: GraspAxis, hole: int) -> float | None:
        """Expanding grasps: axial coordinate (m) where the pads start in hole ``hole`` —
        the axis point nearest the hole's centroid — or ``None`` if it is not inside."""
        import shapely

        poly = shapely.Polygon(self.mesh.nodes[self.mesh.hole_loops[hole]])
        c = np.array(poly.centroid.coords[0])       # of the polygon: mesh-independent
        s0 = float((c - np.asarray(axis.origin)) @ axis.direction)
        p = np.asarray(axis.origin) + s0 * axis.direction + axis.offset * axis.normal
        if not shapely.contains_xy(poly, p[0], p[1]):
            return None
        return s0

    def curve(self, axis: GraspAxis, pad: Pad, sigma_end: float,
              hole: int | None = None) -> GraspCurve:
        """The exact energy curve of ``axis`` from first touch to ``sigma_end`` (m).

        Contracting (``hole=None``): the pads close from outside, ``σ`` down to
        ``sigma_end``. Expanding: the pads open from inside hole ``hole`` (index into
        ``mesh.hole_loops``), ``σ`` up to ``sigma_end``.
        """
        with blas_threads():      # one axis of many: small dense steps (limits.BLAS_THREADS)
            return self._curve(axis, pad, sigma_end, hole)

    def _curve(self, axis: GraspAxis, pad: Pad, sigma_end: float,
               hole: int | None) -> GraspCurve:
        empty = GraspCurve(axis, pad, None, np.zeros(0, int), np.zeros(0, int),
                           np.zeros((0, 2)), None)
        if hole is None:
            loop = self.mesh.outer_loop
            touch = first_touch(self._ring, axis, pad)
        else:
            loop = self.mesh.hole_loops[hole]
            start = self.hole_start(axis, hole)
            touch = None if start is None else first_touch(self.mesh.nodes[loop], axis, pad, start)
        if touch is None:
            return empty
        delta_max = max((sigma_end - touch.sigma0) if touch.expanding
                        else (touch.sigma0 - sigma_end), 0.0)
        s, x = axis.coordinates(self.mesh.nodes[loop])
        d, slope = pad.profile(x)
        inside = np.isfinite(d)
        a, n = axis.direction, axis.normal
        gA, gB = self._rest_gaps(s, d, touch)
        tol = 1e-10 * self.diameter
        # Contacts that could close within the squeeze; verified afterwards.
        cutoff = 2.0 * delta_max + tol
        for _ in range(6):
            selA = np.flatnonzero(inside & (gA <= cutoff))
            selB = np.flatnonzero(inside & (gB <= cutoff))
            nodes = np.concatenate([loop[selA], loop[selB]])
            pad_of = np.concatenate([np.zeros(len(selA), int), np.ones(len(selB), int)])
            sl = np.concatenate([slope[selA], slope[selB]])
            sgn = np.where(pad_of == 0, 1.0, -1.0)
            grad = sgn[:, None] * a[None, :] + sl[:, None] * n[None, :]
            # Rows scaled to unit gradient: multipliers become normal-force magnitudes (N)
            # and steep pad flanks (d' → ∞ at |x| → W/2 + ρ) stay well conditioned.
            norm = np.hypot(grad[:, 0], grad[:, 1])
            normals = grad / norm[:, None]
            g0 = np.concatenate([gA[selA], gB[selB]]) / norm
            W = self.delassus(nodes, normals)
            problem = ContactProblem(W, g0, balance=(sgn / norm)[None, :], rate=pad_of / norm,
                                     normals=normals)
            path = trace_contact(problem, delta_max, gap_tol=tol)
            if not np.isfinite(path.delta[0]):
                # A pad grazes the part between boundary nodes (no node within its reach):
                # nothing to squeeze on this mesh.
                return GraspCurve(axis, pad, touch, nodes, pad_of, normals, None)
            curve = GraspCurve(axis, pad, touch, nodes, pad_of, normals, path)
            missed = self._penetrations(curve, loop, s, d, slope, inside, touch, tol)
            if missed <= cutoff:
                return curve
            cutoff = 2.0 * missed
        return curve

    def _rest_gaps(self, s: np.ndarray, d: np.ndarray, touch: FirstTouch
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Rest gaps (m) of ring points at axial ``s`` to pads A and B at first touch (``d``:
        the pad surface at their cross-axis coordinates). Expanding, a pad can touch only
        the ring ahead of it: points behind it (beyond the touching tolerance) get ``inf``."""
        gA = s - touch.z_a + d
        gB = touch.z_b + d - s
        if touch.expanding:
            behind = -touch_tolerance(self.diameter)
            gA = np.where(gA >= behind, gA, np.inf)
            gB = np.where(gB >= behind, gB, np.inf)
        return gA, gB

    def _penetrations(self, curve: GraspCurve, loop, s, d, slope, inside, touch, tol) -> float:
        """Largest rest gap (m) of an excluded node that the traced path makes penetrate.

        Gaps are linear in the squeeze on every piece, so checking the breakpoints is exact.
        """
        path = curve.path
        if path is None or len(path.delta) < 2:
            return 0.0
        cand = np.zeros(self.mesh.n_nodes, bool)
        # Nodes whose rest gap exceeds four times the squeeze cannot close: boundary
        # displacements stay of the order of the squeeze.
        far = 4.0 * float(path.delta[-1]) + tol
        ga, gb = self._rest_gaps(s, d, touch)
        check = np.flatnonzero(inside & ((ga <= far) | (gb <= far)))
        if len(check) == 0:
            return 0.0
        pos_c = self.cc.position(curve.nodes)
        cd = np.column_stack([2 * pos_c, 2 * pos_c + 1]).ravel()
        pos_l = self.cc.position(loop[check])
        ld = np.column_stack([2 * pos_l, 2 * pos_l + 1]).ravel()
        Fc = (path.lam[:, :, None] * curve.normals[None]).reshape(len(path.delta), -1)
        u = (Fc @ self.Y[np.ix_(cd, ld)]).reshape(len(path.delta), len(check), 2)
        a, n = curve.axis.direction, curve.axis.normal
        ua, un = u @ a, u @ n
        slc = slope[check]
        D = path.delta[:, None]
        t = path.t[:, None]
        rest_a = ga[check]
        rest_b = gb[check]
        gA = rest_a + ua + slc * un + t
        gB = rest_b - D - ua + slc * un - t
        worst = 0.0
        for g, rest, p in ((gA, rest_a, 0), (gB, rest_b, 1)):
            cand[:] = False
            cand[curve.nodes[curve.pad_of == p]] = True
            bad = ~cand[loop[check]] & (g.min(axis=0) < -tol) & np.isfinite(rest)
            if bad.any():
                worst = max(worst, float(rest[bad].max()))
        return worst
