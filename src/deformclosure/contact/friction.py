"""Quasi-static 2-D Coulomb friction on the contact core: the exact event-driven
stick/slip path of a linear contact problem in one load parameter (SPEC §9).

Every contact row ``i`` has a unit normal ``n_i`` and tangent ``t_i`` (the rows of
:class:`~deformclosure.contact.solve.ContactProblem` and its
:meth:`~deformclosure.contact.solve.ContactProblem.tangents`), a normal force
``λ_i ≥ 0`` and a tangential force ``τ_i`` on the part (N). With the gauged boundary
compliance ``Y`` (:mod:`.compliance`) the compliance of the rows in both directions is
``W = D Y Dᵀ`` (m/N) with ``D = [N; T]``, and with the load parameter ``p`` (the squeeze
``δ``, or an external load factor) the gaps and the slips are linear::

    g = g0 + p ġ0 + W_nn λ + W_nt τ + B_nᵀ y        (m)
    s =      p ṡ0 + W_tn λ + W_tt τ + B_tᵀ y        (m, tangential motion of the part's
                                                    node relative to the pad)
    B_n λ + B_t τ = l0 + p l̇                       (balance of the free rigid motions y)

Coulomb (two-sided linear cone in 2-D), complementary in the *rates* ``(·)˙ = d/dp``:
a row is open (``λ = τ = 0``, ``g ≥ 0``), sticks (``g = 0``, ``ṡ = 0``,
``|τ| ≤ μ λ``) or slips in direction ``σ = ±1`` (``g = 0``, ``τ = −μ λ σ``,
``σ ṡ ≥ 0``). Within a fixed assignment of these modes every rate solves one linear
system, so the solution is *exactly piecewise linear* in ``p`` and the elastic energy
``½ [λ; τ]ᵀ W [λ; τ]`` exactly piecewise quadratic — the frictional analogue of the
parametric active set of :mod:`.path`.

**Scheme (event-driven, exact breakpoints).** At a breakpoint the rows on a boundary of
their mode (a closed gap without force, a force about to vanish, a force on the cone) are
*candidates*; their modes for the next piece solve the rate problem — the same
complementarity on the rates: ``λ̇ ⊥ ġ`` for a touching row, ``σ ṡ ≥ 0 ⊥ μ λ̇ + σ τ̇ ≥ 0``
for a row on the cone, ``|τ̇| ≤ μ λ̇`` with the slip opposite for a row touching without
force — found by principal pivoting on the modes (flip every violated row, then one at a
time, as :mod:`.lcp`). The piece ends at the first event: a gap closes, a normal force
reaches 0, a sticking force reaches the cone. There the event row is put exactly on its
boundary and the rate problem is solved again. A mode system that is singular means no
finite rate exists: with the gauge released (holding loads) that is gross slip, the limit
load.

The rate problem of non-associated friction need not have a unique solution for large
``μ`` (Klarbring's examples); the pivoting then takes the first consistent modes it
reaches and :func:`trace_friction` reports ``ok = False`` when it finds none.

References
----------
A. Klarbring, "Examples of non-uniqueness and non-existence of solutions to quasistatic
contact problems with friction", Ingenieur-Archiv 60 (1990). Y.-B. Jia, F. Guo, H. Lin,
"Grasping deformable planar objects: squeeze, stick/slip analysis, and energy-based
optimalities", IJRR 33(6), 2014 (event-driven stick/slip on a linear FEM part).
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dgecon, dgetrf, dgetrs

__all__ = ["FrictionProblem", "FrictionState", "FrictionPath", "trace_friction",
           "OPEN", "STICK", "SLIP_POS", "SLIP_NEG"]

#: Row modes. ``SLIP_POS``: the part's node slips along ``+t`` (``τ = −μ λ``);
#: ``SLIP_NEG`` along ``−t`` (``τ = +μ λ``).
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3

# Relative tolerances of the event detection (values of the order of rounding of the
# piecewise-linear quantities; every event row is snapped exactly onto its boundary).
_REL = 1e-10
# Singular values below this (relative, of the equilibrated mode system) are dropped, and a
# residual above _RESIDUAL (relative) means the mode system has no solution (no finite rate).
_RCOND = 1e-12
_RESIDUAL = 1e-8


@dataclass(frozen=True, eq=False)
class FrictionProblem:
    """A linear frictional contact problem in one load parameter ``p`` (module docstring).

    Attributes
    ----------
    W : ndarray, shape (2r, 2r)
        Compliance (m/N) of the rows' normal then tangential directions, symmetric.
    gap, gap_rate : ndarray, shape (r,)
        Gaps at ``p = 0`` and zero force (m) and their rate ``dg/dp`` (m per unit p).
    slip_rate : ndarray, shape (r,)
        Tangential motion of the part's node relative to the pad per unit ``p`` at
        fixed forces (m per unit p).
    Bn, Bt : ndarray, shape (k, r)
        Balance rows: the normal and tangential components of each free rigid motion at
        each row (the multipliers ``y`` are those motions).
    load, load_rate : ndarray, shape (k,)
        ``B_n λ + B_t τ = load + p load_rate`` (N or N·m: minus the external load).
    mu : float
        Coulomb coefficient (≥ 0).
    """

    W: np.ndarray
    gap: np.ndarray
    gap_rate: np.ndarray
    slip_rate: np.ndarray
    Bn: np.ndarray
    Bt: np.ndarray
    load: np.ndarray
    load_rate: np.ndarray
    mu: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.mu) and self.mu >= 0):
            raise ValueError(f"friction = {self.mu!r}: the Coulomb coefficient must be a finite number ≥ 0")

    @property
    def rows(self) -> int:
        return len(self.gap)

    def gaps(self, p: float, lam: np.ndarray, tau: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Gaps (m) at parameter ``p`` and forces ``lam, tau`` (N), rigid motions ``y``."""
        r = self.rows
        return (self.gap + p * self.gap_rate + self.W[:r, :r] @ lam + self.W[:r, r:] @ tau
                + self.Bn.T @ y)

    def slips(self, p: float, lam: np.ndarray, tau: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Tangential positions (m) of the part's nodes relative to the pads (their change
        is the slip)."""
        r = self.rows
        return p * self.slip_rate + self.W[r:, :r] @ lam + self.W[r:, r:] @ tau + self.Bt.T @ y


@dataclass(frozen=True, eq=False)
class FrictionState:
    """The frictional state at one value ``p`` of the load parameter.

    Attributes
    ----------
    p : float
    lam, tau : ndarray, shape (r,)
        Normal and tangential forces on the part (N).
    y : ndarray, shape (k,)
        Rigid motions (m, rad) of the balance rows.
    slip : ndarray, shape (r,)
        Accumulated slip (m) of each row while in contact (signed, along ``t``).
    mode : ndarray of int, shape (r,)
        Mode of each row on the piece ending here (``OPEN``, ``STICK``, ``SLIP_POS``,
        ``SLIP_NEG``).
    """

    p: float
    lam: np.ndarray
    tau: np.ndarray
    y: np.ndarray
    slip: np.ndarray
    mode: np.ndarray


@dataclass(frozen=True, eq=False)
class FrictionPath:
    """Exact piecewise-linear frictional path: states at the breakpoints, linear between.

    Attributes
    ----------
    p : ndarray, shape (K,)
        Breakpoints of the load parameter, increasing.
    lam, tau : ndarray, shape (K, r)
        Normal and tangential forces (N) at the breakpoints.
    y : ndarray, shape (K, k)
        Rigid motions at the breakpoints.
    slip : ndarray, shape (K, r)
        Accumulated slip (m) at the breakpoints.
    mode : ndarray of int, shape (K − 1, r)
        Modes on each piece.
    energy_coef : ndarray, shape (K − 1, 3)
        ``U = c0 + c1 h + c2 h²`` (J) on piece ``i``, ``h = p − p[i]``.
    limit : bool
        Whether the path ended because no finite rate exists (gross slip: the load
        parameter cannot grow beyond ``p[-1]``).
    ok : bool
        False when no consistent modes exist (the quasi-static path ends there).
    stopped : bool
        True when the tracing stopped at its ``deadline`` (:func:`trace_friction`) before
        ``p_end``, a limit or an end of the quasi-static path.
    """

    p: np.ndarray
    lam: np.ndarray
    tau: np.ndarray
    y: np.ndarray
    slip: np.ndarray
    mode: np.ndarray
    energy_coef: np.ndarray
    limit: bool = False
    ok: bool = True
    stopped: bool = False

    def piece(self, p: float) -> int:
        """Index of the piece holding ``p`` (clipped to the traced range)."""
        i = int(np.searchsorted(self.p, p, side="right")) - 1
        return min(max(i, 0), max(len(self.p) - 2, 0))

    def state(self, p: float) -> FrictionState:
        """The state at ``p`` (linear interpolation on its piece; ``p`` within range)."""
        if len(self.p) < 2 or p <= self.p[0]:
            return FrictionState(float(self.p[0]), self.lam[0].copy(), self.tau[0].copy(),
                                 self.y[0].copy(), self.slip[0].copy(),
                                 self.mode[0].copy() if len(self.mode) else
                                 np.zeros(self.lam.shape[1], int))
        i = self.piece(p)
        w = (p - self.p[i]) / (self.p[i + 1] - self.p[i])
        f = lambda A: (1 - w) * A[i] + w * A[i + 1]  # noqa: E731
        return FrictionState(float(p), f(self.lam), f(self.tau), f(self.y), f(self.slip),
                             self.mode[i].copy())

    def energy(self, p: float) -> float:
        """Elastic energy (J) at ``p``."""
        if len(self.p) < 2:
            return 0.0
        i = self.piece(p)
        h = p - self.p[i]
        c0, c1, c2 = self.energy_coef[i]
        return float(c0 + h * (c1 + h * c2))


def _rate_system(prob: FrictionProblem, J: np.ndarray, mode: np.ndarray):
    """Matrix and right side of the rate equations on the contact rows ``J`` (module
    docstring); unknowns ``[λ̇_J, τ̇_J, ẏ]``."""
    r, k = prob.rows, len(prob.load)
    nj = len(J)
    W = prob.W
    mu = prob.mu
    n = 2 * nj + k
    A = np.zeros((n, n))
    rhs = np.zeros(n)
    Jt = J + r
    # normal rows: ġ = 0
    A[:nj, :nj] = W[np.ix_(J, J)]
    A[:nj, nj:2 * nj] = W[np.ix_(J, Jt)]
    A[:nj, 2 * nj:] = prob.Bn[:, J].T
    rhs[:nj] = -prob.gap_rate[J]
    # tangential rows: ṡ = 0 (stick) or τ̇ + μ σ λ̇ = 0 (slip)
    mj = mode[J]
    st = np.flatnonzero(mj == STICK)
    sl = np.flatnonzero(mj != STICK)
    rows = nj + st
    A[rows, :nj] = W[np.ix_(Jt[st], J)]
    A[rows, nj:2 * nj] = W[np.ix_(Jt[st], Jt)]
    A[rows, 2 * nj:] = prob.Bt[:, J[st]].T
    rhs[rows] = -prob.slip_rate[J[st]]
    A[nj + sl, nj + sl] = 1.0
    A[nj + sl, sl] = mu * np.where(mj[sl] == SLIP_POS, 1.0, -1.0)
    # balance rows
    A[2 * nj:, :nj] = prob.Bn[:, J]
    A[2 * nj:, nj:2 * nj] = prob.Bt[:, J]
    rhs[2 * nj:] = prob.load_rate
    return A, rhs


def _solve_rates(prob: FrictionProblem, mode: np.ndarray):
    """Rates ``(λ̇, τ̇, ẏ)`` of the modes, or ``None`` if the mode system is singular."""
    r, k = prob.rows, len(prob.load)
    J = np.flatnonzero(mode != OPEN)
    A, rhs = _rate_system(prob, J, mode)
    if len(rhs) == 0:
        return np.zeros(r), np.zeros(r), np.zeros(k)
    # Column/row equilibration: compliances (m/N) and unit coefficients mix.
    s = 1.0 / np.sqrt(np.maximum(np.abs(A).max(axis=1), 1e-300))
    c = 1.0 / np.maximum(np.abs(A * s[:, None]).max(axis=0), 1e-300)
    As = A * s[:, None] * c[None, :]
    # The rates are linear in the right-hand side: solve for a unit one, so the residual
    # tests below neither underflow nor overflow (a 1e-200 N load squares to zero).
    b_scale = np.abs(rhs).max(initial=0.0)
    if b_scale == 0.0:
        return np.zeros(r), np.zeros(r), np.zeros(k)
    b = (rhs / b_scale) * s
    x = None
    # LU with LAPACK's condition estimate; a (numerically) singular system goes to the
    # least-norm solve below
    lu, piv, info = dgetrf(As)
    if info == 0:
        rcond, _ = dgecon(lu, np.abs(As).sum(axis=0).max(), norm="1")
        if rcond > _RCOND:
            x, _ = dgetrs(lu, piv, b)
            if not (np.all(np.isfinite(x)) and np.linalg.norm(As @ x - b)
                    <= _RESIDUAL * max(np.linalg.norm(b), 1e-300)):
                x = None
    if x is None:
        # A rigid motion the modes leave free (a frictionless pad's sliding direction) is
        # harmless when the equations are consistent: the least-norm rate. Inconsistent
        # equations mean no finite rate exists.
        x = np.linalg.lstsq(As, b, rcond=_RCOND)[0]
        if not (np.all(np.isfinite(x))
                and np.linalg.norm(As @ x - b) <= _RESIDUAL * max(np.linalg.norm(b), 1e-300)):
            return None
    x = x * (c * b_scale)
    nj = len(J)
    dlam, dtau = np.zeros(r), np.zeros(r)
    dlam[J], dtau[J] = x[:nj], x[nj:2 * nj]
    return dlam, dtau, x[2 * nj:]


def _candidates(prob: FrictionProblem, st: FrictionState, g: np.ndarray, tols):
    """Rows on a boundary of their mode: touching (open, gap closed), releasing (in
    contact without force), on the cone; and the slip mode a row on the cone can take."""
    mu = prob.mu
    gtol, ftol = tols
    contact = st.mode != OPEN
    touching = (~contact) & (g <= gtol)
    releasing = contact & (st.lam <= ftol)
    on_cone = (contact & ~releasing & (mu * st.lam - np.abs(st.tau) <= ftol * max(mu, 1e-300))
               & (mu > 0))
    # a row on the cone slips (if at all) in the direction its force opposes
    cone_dir = np.where(st.tau < 0, SLIP_POS, SLIP_NEG)
    return touching, releasing, on_cone, cone_dir


def _violations(prob: FrictionProblem, mode: np.ndarray, rates, cands):
    """Rows whose modes contradict their rates (``bad``) and the mode each would take
    (``new``): the rate complementarity of the module docstring on the candidates."""
    mu = prob.mu
    r = prob.rows
    touching, releasing, on_cone, cone_dir = cands
    free = touching | releasing
    dlam, dtau, dy = rates
    dg = prob.gap_rate + prob.W[:r, :r] @ dlam + prob.W[:r, r:] @ dtau + prob.Bn.T @ dy
    ds = prob.slip_rate + prob.W[r:, :r] @ dlam + prob.W[r:, r:] @ dtau + prob.Bt.T @ dy
    ls = max(np.abs(dlam).max(initial=0.0), np.abs(dtau).max(initial=0.0), 1e-300)
    gs = max(np.abs(dg).max(initial=0.0), np.abs(ds).max(initial=0.0),
             np.abs(prob.gap_rate).max(initial=0.0), np.abs(prob.slip_rate).max(initial=0.0),
             1e-300)
    bad = np.zeros(r, bool)
    new = mode.copy()
    # touching / releasing rows: λ̇ ⊥ ġ
    v = free & (mode == OPEN) & (dg < -_REL * gs)
    bad |= v
    new[v] = STICK if mu > 0 else SLIP_POS
    v = free & (mode != OPEN) & (dlam < -_REL * ls)
    bad |= v
    new[v] = OPEN
    if mu > 0:
        slipping = (mode == SLIP_POS) | (mode == SLIP_NEG)
        sg = np.where(mode == SLIP_POS, 1.0, -1.0)
        # rows without force in contact: |τ̇| ≤ μ λ̇ when sticking, σ ṡ ≥ 0 when slipping
        v = free & ~bad & (mode == STICK) & (np.abs(dtau) > mu * dlam + _REL * ls)
        bad |= v
        new[v] = np.where(dtau[v] < 0, SLIP_POS, SLIP_NEG)
        v = free & ~bad & slipping & (sg * ds < -_REL * gs)
        bad |= v
        new[v] = STICK
        # rows on the cone: stick needs μ λ̇ + σ τ̇ ≥ 0, slip needs σ ṡ ≥ 0
        sc = np.where(cone_dir == SLIP_POS, 1.0, -1.0)
        v = on_cone & (mode == STICK) & (mu * dlam + sc * dtau < -_REL * ls)
        bad |= v
        new[v] = cone_dir[v]
        v = on_cone & slipping & (sg * ds < -_REL * gs)
        bad |= v
        new[v] = STICK
    return bad, new


#: Largest number of candidate mode combinations tried one by one when pivoting fails.
_ENUMERATE = 4096


def _choose_modes(prob, st: FrictionState, cands):
    """Modes and rates of the next piece: principal pivoting on the candidates' modes,
    then (if it cycles) every combination of the candidates' modes up to
    :data:`_ENUMERATE` of them.

    Returns ``(mode, rates)``; ``rates`` is ``None`` when the mode system is singular
    (no finite rate: gross slip) and ``mode`` is ``None`` when no consistent modes exist
    (or, beyond the enumeration limit, none was found).

    Notes
    -----
    The pivoting control is that of :func:`deformclosure.contact.lcp.bpp_kernel` (Júdice
    and Pires' block pivots while the number of violations falls, a backup count, then
    Murty's single pivot). It is not shared with it on purpose: that kernel is compiled
    for the placement energy's inner loop and solves a symmetric positive-definite LCP in
    ``λ`` alone, where block pivoting provably terminates; here each row has four modes
    (open, stick, slip ±), the rate system is non-symmetric (friction couples ``τ̇`` to
    ``λ̇``), pivoting can cycle, so the enumeration behind it is part of the method.
    """
    mu = prob.mu
    touching, releasing, on_cone, cone_dir = cands
    mode = st.mode.copy()
    contact = mode != OPEN
    free = touching | releasing            # rows without force: open, or contact in any mode
    # first guess for a touching row: in contact (the pivoting opens it if it pulls)
    mode[touching] = STICK
    if mu == 0:
        # frictionless rows: τ ≡ 0, "slip" with zero force and no condition on the slip
        mode[mode != OPEN] = SLIP_POS
    else:
        inside = contact & ~on_cone & ~releasing
        mode[inside] = STICK               # strictly inside the cone: sticks
        keep = on_cone & (mode != STICK)
        mode[keep] = cone_dir[keep]
    r = prob.rows
    nflip_best, backup = r + 1, 3
    seen = set()
    singular = None
    for _ in range(10 * r + 50):
        rates = _solve_rates(prob, mode)
        if rates is None:
            singular = mode
            break
        bad, new = _violations(prob, mode, rates, cands)
        nbad = int(bad.sum())
        if nbad == 0:
            return mode, rates
        key = mode.tobytes()
        if nbad < nflip_best:
            nflip_best, backup = nbad, 3
            full = True
        elif backup > 0:
            backup -= 1
            full = True
        else:
            full = False
        seen.add(key)
        if full and new.tobytes() not in seen:
            mode = new
        else:
            i = int(np.flatnonzero(bad)[-1])       # one at a time (Murty's rule)
            mode = mode.copy()
            mode[i] = new[i]
    # Pivoting cycled or met a singular system: try every combination of the candidates'
    # modes (few rows are on a boundary at once). A consistent regular one wins; else a
    # singular one means no finite rate; else none exists.
    idx = np.flatnonzero(free | on_cone)
    if mu == 0:
        choices = [(OPEN, SLIP_POS) for _ in idx]
    else:
        choices = [(OPEN, STICK, SLIP_POS, SLIP_NEG) if free[i] else (STICK, int(cone_dir[i]))
                   for i in idx]
    if np.prod([len(c) for c in choices], dtype=float) <= _ENUMERATE:
        base = mode.copy()
        for combo in itertools.product(*choices):
            trial = base.copy()
            trial[idx] = combo
            rates = _solve_rates(prob, trial)
            if rates is None:
                singular = trial
                continue
            if not _violations(prob, trial, rates, cands)[0].any():
                return trial, rates
    if singular is not None:
        return singular, None
    return None, None


def trace_friction(prob: FrictionProblem, start: FrictionState, p_end: float, *,
                   gap_tol: float, max_pieces: int = 20000,
                   deadline: float | None = None) -> FrictionPath:
    """Follow the frictional path of ``prob`` from ``start`` to ``p_end`` (module docstring).

    Parameters
    ----------
    prob : FrictionProblem
    start : FrictionState
        A consistent state (e.g. first touch: every force zero, every mode ``OPEN``).
    p_end : float
        Last parameter value (may be ``inf``: trace to the limit).
    gap_tol : float
        Gaps below this (m) count as closed.
    max_pieces : int
        Most pieces traced.
    deadline : float, optional
        ``time.perf_counter()`` value after which no further piece is traced (the path
        ends at its last breakpoint with ``stopped = True``).

    Returns
    -------
    FrictionPath
        ``limit`` is True when the path ended at a mode system without solution (no
        finite rate: with free rigid motions, gross slip);
        ``p[-1] = inf`` never occurs: a final piece without events and ``p_end = inf``
        ends with ``limit = False`` at the last breakpoint (no finite limit).

    Examples
    --------
    One node pressed into a pad (its gap closes at 1 m per unit ``p``) that also drags it
    sideways (1 m per unit ``p``), unit compliances (m/N), ``μ = 0.5``: sticking would need
    ``|τ| = λ``, so it slips from the start, ``τ = −μ λ``, and slips by half the drag:

    >>> prob = FrictionProblem(np.eye(2), np.zeros(1), -np.ones(1), np.ones(1),
    ...                        np.zeros((0, 1)), np.zeros((0, 1)), np.zeros(0), np.zeros(0), 0.5)
    >>> start = FrictionState(0.0, np.zeros(1), np.zeros(1), np.zeros(0), np.zeros(1),
    ...                       np.zeros(1, int))
    >>> path = trace_friction(prob, start, 1.0, gap_tol=1e-12)
    >>> path.lam[-1].tolist(), path.tau[-1].tolist(), path.slip[-1].tolist(), path.mode.tolist()
    ([1.0], [-0.5], [0.5], [[2]])
    """
    r, k = prob.rows, len(prob.load)
    mu = prob.mu
    P, L, T, Yv, S, M = [start.p], [start.lam.copy()], [start.tau.copy()], [start.y.copy()], \
        [start.slip.copy()], []
    st = start
    limit, ok, stopped = False, True, False
    for _ in range(max_pieces):
        if st.p >= p_end:
            break
        if deadline is not None and time.perf_counter() > deadline:
            stopped = True
            break
        g = prob.gaps(st.p, st.lam, st.tau, st.y)
        lam_scale = max(np.abs(st.lam).max(initial=0.0), 1e-300)
        cands = _candidates(prob, st, g, (gap_tol, 1e-12 * lam_scale))
        touching, releasing, on_cone, _ = cands
        mode, rates = _choose_modes(prob, st, cands)
        if mode is None:
            ok = False
            break
        if rates is None:
            limit = True
            break
        dlam, dtau, dy = rates
        dg = prob.gap_rate + prob.W[:r, :r] @ dlam + prob.W[:r, r:] @ dtau + prob.Bn.T @ dy
        ds = prob.slip_rate + prob.W[r:, :r] @ dlam + prob.W[r:, r:] @ dtau + prob.Bt.T @ dy
        # next event
        h = p_end - st.p
        ev, kind = -1, ""
        contact = mode != OPEN
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            # rows on a boundary were decided by the pivoting: no event of theirs at h = 0
            ho = np.where(~contact & ~touching & (dg < 0), np.maximum(g, 0.0) / -dg, np.inf)
            hl = np.where(contact & ~releasing & (dlam < 0), st.lam / -dlam, np.inf)
            stick = (mode == STICK) & ~releasing
            hc = np.full(r, np.inf)
            if mu > 0:
                # a sticking row on the cone was decided there: only its other side counts
                side = np.where(cands[3] == SLIP_POS, 1.0, -1.0)
                for sc in (1.0, -1.0):
                    val = mu * st.lam + sc * st.tau
                    rate = mu * dlam + sc * dtau
                    live = stick & (rate < 0) & ~(on_cone & (side == sc))
                    hc = np.minimum(hc, np.where(live, np.maximum(val, 0.0) / -rate, np.inf))
        for arr, name in ((ho, "touch"), (hl, "release"), (hc, "cone")):
            i = int(np.argmin(arr))
            if arr[i] < h:
                h, ev, kind = float(arr[i]), i, name
        if not np.isfinite(h):
            break                                   # no event ahead, no limit: unbounded
        lam = st.lam + h * dlam
        tau = st.tau + h * dtau
        y = st.y + h * dy
        slip = st.slip + h * np.where(contact, ds, 0.0)
        lam = np.where(contact, np.maximum(lam, 0.0), 0.0)
        tau = np.where(contact, tau, 0.0)
        # snap the event row onto its boundary; slipping rows exactly on the cone
        if kind == "release":
            lam[ev], tau[ev] = 0.0, 0.0
        slipping = (mode == SLIP_POS) | (mode == SLIP_NEG)
        tau = np.where(slipping, -mu * lam * np.where(mode == SLIP_POS, 1.0, -1.0), tau)
        if kind == "cone":
            tau[ev] = np.sign(tau[ev]) * mu * lam[ev] if tau[ev] != 0 else tau[ev]
        pnew = st.p + h
        if h > 0:
            P.append(pnew)
            L.append(lam)
            T.append(tau)
            Yv.append(y)
            S.append(slip)
            M.append(mode)
        else:
            # a zero-length piece only changes the modes
            L[-1], T[-1] = lam, tau
        st = FrictionState(pnew, lam, tau, y, slip, mode)
    P = np.array(P)
    Lm, Tm = np.array(L), np.array(T)
    X = np.hstack([Lm, Tm])
    if len(P) > 1:
        dX = np.diff(X, axis=0) / np.diff(P)[:, None]
        WX = X[:-1] @ prob.W
        c0 = 0.5 * np.einsum("ij,ij->i", WX, X[:-1])
        c1 = np.einsum("ij,ij->i", WX, dX)
        c2 = 0.5 * np.einsum("ij,jk,ik->i", dX, prob.W, dX)
        coef = np.column_stack([c0, c1, c2])
        modes = np.array(M)
    else:
        coef = np.zeros((0, 3))
        modes = np.zeros((0, r), int)
    return FrictionPath(P, Lm, Tm, np.array(Yv).reshape(len(P), k), np.array(S), modes, coef,
                        limit, ok, stopped)

