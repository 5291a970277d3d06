"""Coulomb pads (SPEC §9): the frictional squeeze of a grasp axis and its holding force
and torque, on the contact rows of :meth:`deformclosure.pads.contact.PadContact.curve`
and the event-driven solver :mod:`deformclosure.contact.friction`.

**Rows.** The frictionless curve's rows (nodes, pad, unit normals, the gaps along the
axis scaled to the normal) gain their tangents ``t = (−n_y, n_x)``; the compliance of
both directions is the same gauged ``Y`` (``W = D Y Dᵀ``, ``D = [N; T]``). The slip of a
row is the tangential displacement of the part's node relative to its pad: the pads move
only along the axis ``a`` (pad A fixed, pad B by ``−δ a``) and the part floats along it by
``t a``, so ``s = t_i · (u_i + t a + δ a [pad B])``.

**Gauge during the squeeze.** As in SPEC §6 the part's mean cross-axis displacement and
mean rotation are those of the axis and its axial float is an unknown. With friction the
pads' forces can have a net cross-axis resultant and a moment; the gauge then supplies
the opposite load (a uniform body force ``w_i/A`` per node across the axis and a couple
distributed like the mean-rotation row): the *gauge reaction* is the external force and
torque that keeps the part on the axis while it is squeezed (zero for a symmetric grasp;
:meth:`FrictionalCurve.gauge_reaction`).

**Holding force and torque.** At ``σ``, from the frictional state reached by the squeeze
(path-dependent), the cross-axis translation ``v`` and the rotation ``φ`` become free and
an external load with the gauge's distributions takes the gauge reaction's place. First
the gauge reaction ``P0`` is taken off incrementally (external load ``P0 → 0``: the part
in the gripper alone; if it slips out on the way it is not held, ``"unbalanced"``), then
the load ``α d`` is applied with ``d`` a unit cross-axis force (N) or a unit torque (N·m)
of either sign, the other component zero. The same event-driven solver follows ``α``
with the pads fixed until no finite rate exists (every row that could hold has reached
the cone: gross slip); ``hold`` is the external load there, ``{"force": [f−, f+] (N),
"torque": [t−, t+] (N·m)}`` with ``f− ≤ 0 ≤ f+`` — the load needed to dislodge the part
each way. A grasp the linearised kinematics never lets go of has ``±inf``: a block
between fixed flat pads jams under a torque (its diagonal is longer than the pad
separation), and a part pressed into round pads on both flanks of their apex is wedged
across the axis, friction or not — that resistance is geometric (leaving it is large
motion: the release landscape's question). ``hold["slide"]`` gives, for the same loads,
where every contact row first slides (the friction is exhausted) and
``hold["limited_by"]`` names what ends each entry (``"friction"``: gross slip as the last
row slides, the entry equals ``slide``; ``"geometry"``: load carried beyond that;
``"dynamic"``, ``"unbalanced"``, ``"budget"``; :meth:`FrictionalCurve.hold`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..contact.friction import (OPEN, SLIP_POS, STICK, FrictionPath, FrictionProblem, FrictionState,
                                trace_friction)
from ..contact.solve import ContactProblem
from ..errors import GraspError
from .contact import GraspCurve, PadContact

__all__ = ["FrictionalCurve", "LoadedGrasp", "frictional_grasp"]


@dataclass(frozen=True, eq=False)
class LoadedGrasp:
    """A frictional grasp under an external load with the gauge released.

    Attributes
    ----------
    state : FrictionState
        At the end of the loading (its ``y`` is ``[t, v, φ]``: axial float (m), cross-axis
        translation (m) and rotation (rad) of the part).
    path : FrictionPath
        The loading path in the load factor ``α`` (0 → 1 for :meth:`FrictionalCurve.loaded`).
    reached : bool
        Whether the load was reached before gross slip.
    """

    state: FrictionState
    path: FrictionPath
    reached: bool


@dataclass(frozen=True, eq=False)
class FrictionalCurve:
    """The frictional squeeze of one grasp axis (module docstring).

    Attributes
    ----------
    curve : GraspCurve
        The frictionless curve whose rows and range this follows.
    mu : float
        Coulomb coefficient.
    problem : FrictionProblem or None
        The squeeze problem in ``δ`` (rows of ``curve``); ``None`` if the pads miss.
    path : FrictionPath or None
        The exact stick/slip path in ``δ``; ``None`` at ``μ = 0`` (the frictionless
        ``curve.path`` is the answer, bit for bit) or when the pads miss.
    tangents : ndarray, shape (r, 2)
    arm : ndarray, shape (r, 2)
        Rest positions of the rows' nodes relative to the area centroid (m).
    gap_tol : float
        Gaps below this (m) count as closed.
    delta_max : float
        The squeeze (m) traced (the frictionless curve's range).
    """

    curve: GraspCurve
    mu: float
    problem: FrictionProblem | None
    path: FrictionPath | None
    tangents: np.ndarray
    arm: np.ndarray
    gap_tol: float
    delta_max: float
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    # ------------------------------------------------------------------ squeeze
    def _delta(self, sigma: float) -> float:
        c = self.curve
        if c.touch is None or c.path is None:
            raise GraspError("the pads do not squeeze the part on this axis")
        d = float(c.delta(sigma))
        hi = self.delta_max
        if d > hi * (1 + 1e-12):
            raise GraspError(f"sigma = {sigma!r} m: beyond the traced range "
                             f"(σ ≥ {float(c.sigma_at(hi))!r} m)")
        return min(d, hi)

    def _frictionless(self) -> bool:
        return self.path is None

    def state(self, sigma: float) -> FrictionState:
        """The frictional state at separation ``sigma`` (m) (``y = [t]``, the float)."""
        delta = self._delta(sigma)
        if self._frictionless():
            cp = self.curve.path
            lam = cp.multipliers(delta)
            if len(cp.delta) < 2 or delta <= cp.delta[0]:
                t = cp.t[0]
            else:
                i = int(cp.piece(np.array(delta)))
                w = (delta - cp.delta[i]) / (cp.delta[i + 1] - cp.delta[i])
                t = (1 - w) * cp.t[i] + w * cp.t[i + 1]
            mode = np.where(lam > 0, SLIP_POS, OPEN)
            return FrictionState(delta, lam, np.zeros_like(lam), np.array([t]),
                                 self._frictionless_slip(delta), mode)
        return self.path.state(delta)

    def _frictionless_slip(self, delta: float) -> np.ndarray:
        """Accumulated slip (m) on the frictionless path: the tangential motion of each
        row while it carries force."""
        cp, prob = self.curve.path, self.problem
        r = prob.rows
        out = np.zeros(r)
        for i in range(len(cp.delta) - 1):
            d0, d1 = cp.delta[i], min(cp.delta[i + 1], delta)
            if d1 <= d0:
                break
            z = np.zeros(r)
            s0 = prob.slips(d0, cp.lam[i], z, cp.t[i:i + 1])
            w = (d1 - d0) / (cp.delta[i + 1] - d0)
            lam1 = (1 - w) * cp.lam[i] + w * cp.lam[i + 1]
            t1 = (1 - w) * cp.t[i] + w * cp.t[i + 1]
            s1 = prob.slips(d1, lam1, z, np.array([t1]))
            on = (cp.lam[i] > 0) | (cp.lam[i + 1] > 0)
            out += np.where(on, s1 - s0, 0.0)
        return out

    def forces(self, sigma: float) -> tuple[np.ndarray, np.ndarray]:
        """Normal and tangential forces on the part (N), each shape (r,), at ``sigma`` (m)."""
        if self.problem is None:
            return np.zeros(0), np.zeros(0)
        st = self.state(sigma)
        return st.lam, st.tau

    def force_vectors(self, sigma: float) -> np.ndarray:
        """Contact forces on the part (N), shape (r, 2)."""
        lam, tau = self.forces(sigma)
        return lam[:, None] * self.curve.normals + tau[:, None] * self.tangents

    def slip(self, sigma: float) -> np.ndarray:
        """Accumulated slip (m, along each row's tangent) from first touch to ``sigma``."""
        if self.problem is None:
            return np.zeros(0)
        return self.state(sigma).slip

    def modes(self, sigma: float) -> np.ndarray:
        """Row modes on the piece at ``sigma`` (:data:`~deformclosure.contact.friction.OPEN`,
        ``STICK``, ``SLIP_POS``, ``SLIP_NEG``)."""
        return self.state(sigma).mode

    def kinks(self) -> np.ndarray:
        """Separations (m) of the breakpoints of the stick/slip path (contact, stick and
        slip events), from first touch on; the frictionless curve's at ``μ = 0``."""
        if self.problem is None or self._frictionless():
            return self.curve.kinks()
        return self.curve.sigma_at(self.path.p)

    def energy(self, sigma: float) -> float:
        """Elastic energy (J) at ``sigma`` (m); the frictionless curve's at ``μ = 0``."""
        if self.problem is None or self._frictionless():
            return float(self.curve.energy(sigma))
        c = self.curve
        if float(c.delta(sigma)) <= self.path.p[0]:
            return 0.0
        return self.path.energy(self._delta(sigma))

    def axial_force(self, sigma: float) -> float:
        """Squeezing force (N) of each pad along the axis at ``sigma`` (m)."""
        if self.problem is None:
            return 0.0
        if self._frictionless():
            return self.curve.axial_force(sigma)
        f = self.force_vectors(sigma)
        return float((f[self.curve.pad_of == 0] @ self.curve.axis.direction).sum())

    def pad_forces(self, sigma: float) -> tuple[float, float]:
        """Normal (axial) force (N) of pads A and B at ``sigma``."""
        f = self.force_vectors(sigma)
        a = self.curve.axis.direction
        on_a = self.curve.pad_of == 0
        return float((f[on_a] @ a).sum()), float(-(f[~on_a] @ a).sum())

    def gauge_reaction(self, sigma: float) -> tuple[float, float]:
        """The external cross-axis force (N) and torque (N·m) that keep the part on the
        axis during the squeeze (module docstring): minus the pads' resultant."""
        f = self.force_vectors(sigma)
        n = self.curve.axis.normal
        moment = float(np.sum(self.arm[:, 0] * f[:, 1] - self.arm[:, 1] * f[:, 0]))
        return -float((f @ n).sum()), -moment

    def penetration(self, pad_contact: PadContact) -> float:
        """Largest penetration (m, ≥ 0) of a boundary node that is not one of the rows
        into a pad at any breakpoint of the frictional path (gaps are linear on every
        piece, so the breakpoints decide). The rows are the frictionless curve's; friction
        changes the displacements, so a node it did not need could in principle close."""
        c = self.curve
        if self.problem is None or self._frictionless():
            return 0.0
        loop = next(lp for lp in pad_contact.mesh.loops if np.isin(c.nodes[0], lp))
        s, x = c.axis.coordinates(pad_contact.mesh.nodes[loop])
        d, slope = c.pad.profile(x)
        inside = np.isfinite(d)
        # the curve's own rest gaps (expanding: the ring behind a pad cannot touch it)
        rest_a, rest_b = pad_contact._rest_gaps(s, d, c.touch)
        far = 4.0 * float(self.path.p[-1]) + self.gap_tol
        check = np.flatnonzero(inside & ((rest_a <= far) | (rest_b <= far)))
        if len(check) == 0:
            return 0.0
        Y = pad_contact.Y
        pos_c = pad_contact.position(c.nodes)
        cd = np.column_stack([2 * pos_c, 2 * pos_c + 1]).ravel()
        pos_l = pad_contact.position(loop[check])
        ld = np.column_stack([2 * pos_l, 2 * pos_l + 1]).ravel()
        path = self.path
        F = (path.lam[:, :, None] * c.normals[None] + path.tau[:, :, None] * self.tangents[None])
        u = (F.reshape(len(path.p), -1) @ Y[np.ix_(cd, ld)]).reshape(len(path.p), len(check), 2)
        a, n = c.axis.direction, c.axis.normal
        ua, un = u @ a, u @ n
        sl = slope[check]
        D, t = path.p[:, None], path.y[:, :1]
        gA = rest_a[check] + ua + sl * un + t
        gB = rest_b[check] - D - ua + sl * un - t
        worst = 0.0
        for g, pad in ((gA, 0), (gB, 1)):
            rows = np.zeros(pad_contact.mesh.n_nodes, bool)
            rows[c.nodes[c.pad_of == pad]] = True
            other = ~rows[loop[check]] & np.isfinite(rest_a[check] if pad == 0 else rest_b[check])
            if other.any():
                worst = max(worst, float(-g[:, other].min()))
        return max(worst, 0.0)

    # ------------------------------------------------------------------ loading
    def loading_problem(self, sigma: float, direction: np.ndarray) -> tuple[FrictionProblem, FrictionState]:
        """The problem with the gauge released at ``sigma`` (m) and its start state: rigid
        motions ``y = [t, v, φ]`` (axial float, cross-axis translation, rotation about the
        area centroid; m, m, rad), external load ``P0 + α direction`` with ``P0`` the gauge
        reaction and ``direction = [force (N), torque (N·m)]`` per unit ``α``; the pads
        stay where the squeeze left them."""
        if self.problem is None:
            raise GraspError("the pads do not squeeze the part on this axis")
        prob = self.problem
        st = self.state(sigma)
        c = self.curve
        nrm, tan = c.normals, self.tangents
        a, nx = c.axis.direction, c.axis.normal
        cross = lambda v: self.arm[:, 0] * v[:, 1] - self.arm[:, 1] * v[:, 0]  # noqa: E731
        Bn = np.vstack([nrm @ a, nrm @ nx, cross(nrm)])
        Bt = np.vstack([tan @ a, tan @ nx, cross(tan)])
        # at fixed pads the gaps and slips no longer move with the parameter
        gap = prob.gap + st.p * prob.gap_rate
        lam, tau = st.lam, st.tau
        R0 = Bn @ lam + Bt @ tau                   # the pads' resultant (axial ≈ 0)
        R0[0] = 0.0
        mu = self.mu
        lp = FrictionProblem(prob.W, gap, np.zeros_like(gap), np.zeros_like(gap), Bn, Bt,
                             R0, -np.r_[0.0, direction], mu)
        y = np.r_[st.y[0], 0.0, 0.0]
        mode = st.mode.copy()
        if mu == 0:
            mode = np.where(lam > 0, SLIP_POS, OPEN)
        return lp, FrictionState(0.0, lam.copy(), tau.copy(), y, st.slip.copy(), mode)

    def loaded(self, sigma: float, force: float | None = None, torque: float | None = None
               ) -> LoadedGrasp:
        """The grasp at ``sigma`` (m) under an external cross-axis ``force`` (N) and
        ``torque`` (N·m) (default: the gauge reaction's, i.e. unchanged), applied
        incrementally from the squeezed state with the gauge released."""
        P0 = np.array(self.gauge_reaction(sigma))
        target = np.array([P0[0] if force is None else force, P0[1] if torque is None else torque])
        lp, st = self.loading_problem(sigma, target - P0)
        path = trace_friction(lp, st, 1.0, gap_tol=self.gap_tol)
        reached = bool(path.ok and path.p[-1] >= 1.0)
        return LoadedGrasp(path.state(float(path.p[-1])), path, reached)

    def _released(self, sigma: float, deadline: float | None = None):
        """The loading problem at ``sigma`` (m) and the state with the gauge released: the
        gauge reaction ``P0`` taken off incrementally (external load ``P0 → 0``).
        Returns ``(problem, state, ended)``: ``problem`` has its ``α = 0`` at zero external
        load, ``ended`` is ``None`` or why the release did not reach zero load
        (``"unbalanced"``: gross slip or no quasi-static rate on the way — the part is not
        held without the gauge; ``"budget"``: the deadline passed)."""
        P0 = np.array(self.gauge_reaction(sigma))
        lp, st = self.loading_problem(sigma, -P0)
        if P0.any():
            path = trace_friction(lp, st, 1.0, gap_tol=self.gap_tol, deadline=deadline)
            if path.stopped:
                return lp, st, "budget"
            if not (path.ok and not path.limit and path.p[-1] >= 1.0):
                return lp, st, "unbalanced"
            end = path.state(1.0)
            st = FrictionState(0.0, end.lam, end.tau, end.y, end.slip, end.mode)
        zero = dataclasses.replace(lp, load=lp.load + lp.load_rate,
                                   load_rate=np.zeros_like(lp.load_rate))
        return zero, st, None

    def hold_limit(self, sigma: float, direction: np.ndarray, *, deadline: float | None = None,
                   released=None) -> tuple[float, float, str]:
        """Load factors ``α`` (≥ 0) of the external load ``α direction`` (``direction =
        [force (N), torque (N·m)]``) applied after the gauge's release (zero external
        load; :meth:`hold`): before gross slip (``inf`` if none), where every contact row
        first slides (friction exhausted; ``≤`` the first), and what limits it:
        ``"friction"`` (gross slip as the last row slides), ``"dynamic"`` (the
        quasi-static path ends, no consistent stick/slip rate, before every row slides),
        ``"geometry"`` (the part carries load after every row slides, or for ever: wedged
        on the pads' curvature or jammed), ``"budget"`` (``deadline`` passed: both ``nan``) or ``"unbalanced"``
        (the part is not held at zero load: both 0)."""
        lp, st, ended = self._released(sigma, deadline) if released is None else released
        if ended == "unbalanced":
            return 0.0, 0.0, ended
        if ended == "budget":
            return float("nan"), float("nan"), ended
        d = np.asarray(direction, float)
        lp = dataclasses.replace(lp, load_rate=-np.r_[0.0, d])
        path = trace_friction(lp, st, np.inf, gap_tol=self.gap_tol, deadline=deadline)
        if path.stopped:
            return float("nan"), float("nan"), "budget"
        # No finite rate (gross slip), or no consistent stick/slip rate at all (the
        # quasi-static path ends in a dynamic slip, as in Klarbring's examples for large μ):
        # either way the grasp lets go beyond this load.
        limit = float(path.p[-1]) if (path.limit or not path.ok) else float("inf")
        slide = limit
        for i, mode in enumerate(path.mode):
            if (mode != OPEN).any() and not (mode == STICK).any():
                slide = float(path.p[i])
                break
        # load carried after every row slides is not friction's: the pads' curvature (or
        # a block's corners) resist — whether the linear path then ends in a dynamic slip
        # (far beyond small displacements, e.g. 47 kN on the L-shape's round pads) or never
        if limit > slide * (1 + 1e-9) + 1e-300 or not np.isfinite(limit):
            kind = "geometry"
        elif not path.ok:
            kind = "dynamic"
        else:
            kind = "friction"
        return limit, slide, kind

    def hold(self, sigma: float, *, deadline: float | None = None) -> dict:
        """Holding force and torque at ``sigma`` (m) (module docstring), the external load
        beyond which the part lets go, from zero external load (the gauge reaction
        released first): ``{"force": [f−, f+] (N), "torque": [t−, t+] (N·m), "slide":
        {"force", "torque"}, "limited_by": {"force": [k−, k+], "torque": [..]},
        "gauge_reaction": {"force" (N), "torque" (N·m)}, "stopped": None or why}`` with
        ``f− ≤ 0 ≤ f+`` (the force applied the negative way is negative), each a load in
        one direction with the other component zero. ``slide``: the loads at which every
        contact row first slides (the friction is exhausted); ``limited_by`` per entry:
        ``"friction"`` (gross slip: the entry equals ``slide``; for flat pads),
        ``"dynamic"`` (the quasi-static path ends there, before every row slides),
        ``"geometry"`` (wedged on the pads' curvature or jammed: the linear kinematics
        carries load beyond ``slide``, up to the entry, ``±inf`` if for ever — that resistance is geometric, its strength the
        release landscape's question, SPEC §6, §9), ``"unbalanced"`` (the squeeze's
        resultant cannot be carried once the gauge is released: 0, not held at zero load)
        or ``"budget"`` (``deadline``, a ``time.perf_counter()`` value, passed first:
        ``nan``; ``stopped`` says so)."""
        key = float(sigma)
        if key in self._cache:
            return self._cache[key]
        F0, M0 = self.gauge_reaction(sigma)
        out = {"force": [0.0, 0.0], "torque": [0.0, 0.0],
               "slide": {"force": [0.0, 0.0], "torque": [0.0, 0.0]},
               "limited_by": {"force": ["", ""], "torque": ["", ""]},
               "gauge_reaction": {"force": F0 + 0.0, "torque": M0 + 0.0}, "stopped": None}
        # every trace checks the deadline before its first piece: a passed deadline makes
        # the release and each loading "budget" at once
        released = self._released(sigma, deadline)
        for key2, j, d in (("force", 0, [-1.0, 0.0]), ("force", 1, [1.0, 0.0]),
                           ("torque", 0, [0.0, -1.0]), ("torque", 1, [0.0, 1.0])):
            lim, sl, kind = self.hold_limit(sigma, d, deadline=deadline, released=released)
            sign = -1.0 if j == 0 else 1.0
            out[key2][j] = sign * lim + 0.0
            out["slide"][key2][j] = sign * sl + 0.0
            out["limited_by"][key2][j] = kind
        if any(k == "budget" for v in out["limited_by"].values() for k in v):
            out["stopped"] = ("time budget (--max-seconds) spent before the holding loads "
                              "were traced to their limit")
        else:
            self._cache[key] = out          # a truncated hold is not kept
        return out


def _squeeze(pad_contact: PadContact, curve: GraspCurve, mu: float, delta_max: float, tol: float):
    """The squeeze problem on ``curve``'s rows and (``mu > 0``) its frictional path to
    ``delta_max`` (m); returns ``(problem, path, tangents, arms)``."""
    nodes, nrm, pad_of = curve.nodes, curve.normals, curve.pad_of
    tan = ContactProblem(np.zeros((len(nodes), len(nodes))), np.zeros(len(nodes)),
                         normals=nrm).tangents()
    axis, touch = curve.axis, curve.touch
    a = axis.direction
    s, x = axis.coordinates(pad_contact.mesh.nodes[nodes])
    d, _ = curve.pad.profile(x)
    e = nrm @ a                                    # = ±1/|∇g|: the rows' scaling
    inv = np.abs(e)
    g0 = np.where(pad_of == 0, s - touch.z_a + d, touch.z_b + d - s) * inv
    rate = pad_of * inv
    W = pad_contact.delassus(np.r_[nodes, nodes], np.vstack([nrm, tan]))
    # pad B moves by −δ a: the part's node moves by +δ a relative to it
    slip_rate = pad_of * (tan @ a)
    prob = FrictionProblem(W, g0, -rate, slip_rate, e[None, :], (tan @ a)[None, :],
                           np.zeros(1), np.zeros(1), mu)
    arm = pad_contact.mesh.nodes[nodes] - pad_contact.centroid
    if mu == 0:
        return prob, None, tan, arm
    # first touch on the nodes, as the frictionless path: translate until pad A touches,
    # squeeze until pad B does
    A, B = e > 0, e < 0
    t0 = -float(np.min(g0[A] / e[A]))
    d0 = float(np.min((g0[B] + e[B] * t0) / rate[B]))
    r = len(nodes)
    start = FrictionState(d0, np.zeros(r), np.zeros(r), np.array([t0]), np.zeros(r),
                          np.zeros(r, int))
    path = trace_friction(prob, start, delta_max, gap_tol=tol)
    if not path.ok or path.limit or path.p[-1] < delta_max * (1 - 1e-12):
        raise GraspError(f"friction = {mu!r}: the frictional squeeze has no quasi-static "
                         f"stick/slip solution beyond a squeeze of {path.p[-1]!r} m "
                         "(Coulomb friction this large need not have one); try a smaller friction")
    return prob, path, tan, arm


def frictional_grasp(pad_contact: PadContact, curve: GraspCurve, mu: float) -> FrictionalCurve:
    """The frictional squeeze of ``curve``'s axis with Coulomb coefficient ``mu`` over the
    curve's traced range (module docstring).

    At ``mu = 0`` the frictionless path of ``curve`` is used as it is (SPEC §9: §6
    exactly). With friction the rows are ``curve``'s; if the frictional path makes another
    boundary node enter a pad, the rows of the frictionless curve traced twice as far are
    taken instead (up to three times).

    Raises
    ------
    GraspError
        A friction coefficient that is not a finite number ≥ 0, or a squeeze without a
        quasi-static solution.

    Examples
    --------
    See ``docs/friction.md``.
    """
    if not (isinstance(mu, (int, float)) and np.isfinite(mu) and mu >= 0):
        raise GraspError(f"friction = {mu!r}: the Coulomb coefficient must be a finite number ≥ 0")
    mu = float(mu)
    tol = 1e-10 * pad_contact.diameter
    if curve.touch is None or curve.path is None:
        return FrictionalCurve(curve, mu, None, None, np.zeros((0, 2)), np.zeros((0, 2)), tol, 0.0)
    delta_max = float(curve.path.delta[-1])
    hole = None
    if curve.expanding:
        hole = next(k for k, lp in enumerate(pad_contact.mesh.hole_loops) if np.isin(curve.nodes[0], lp))
    rows, reach = curve, delta_max
    for _ in range(4):
        prob, path, tan, arm = _squeeze(pad_contact, rows, mu, delta_max, tol)
        fc = FrictionalCurve(rows, mu, prob, path, tan, arm, tol, delta_max)
        if mu == 0 or fc.penetration(pad_contact) <= tol + 1e-9 * delta_max:
            return fc
        reach *= 2.0
        rows = pad_contact.curve(curve.axis, curve.pad, curve.sigma_at(reach), hole)
    raise GraspError("the frictional squeeze makes boundary nodes enter a pad that the "
                     "contact rows do not hold; refine the mesh under the pads")
