"""The pads' moves on the release landscape with friction: the dissipation of a move
between neighbouring grasp axes and the release work ``U_A^μ`` (SPEC §9).

The vertices of the pads' landscape (:mod:`.landscape`) are grasp axes ``(θ, c)`` in the
part frame at a fixed separation σ. Moving from axis ``v`` to its neighbour ``w`` is a
rigid motion of the part relative to the gripper; the pads' contacts slip, and Coulomb
friction dissipates ``D(v, w) = μ Σ_r f_r |slip_r|`` over the contact rows ``r``. The
release work is then the least peak of ``U(v) − U(start) + D(path so far)`` over paths to
a release — an axis where no pad presses — found by the one search,
:func:`deformclosure.landscape.search.dissipative_escape`.

**The relative motion.** The gripper frame at axis ``v`` has its origin at the pads'
centre — the middle ``(z_A + z_B)/2`` of the first touch on the axis (SPEC §6's pads
squeeze symmetrically about it), :func:`gripper_centre` — and axes ``(a, n)``, the
closing and cross-axis directions: a part point ``p`` has gripper coordinates
``g_v(p) = R_vᵀ (p − C_v)``. At ``w`` the same point is at ``g_w(p)``; the part's motion
in the gripper frame is the rigid map ``g_v(p) ↦ g_w(p)``: a turn by ``ψ = θ_v − θ_w``
and a shift ``b = R_wᵀ (C_v − C_w)``. The line ``(θ + π, −c)`` is the line ``(θ, c)``
with the pads exchanged; of the two, the one turning by less than π/2 is the move (so a
grid needs at least 3 angles). An axis where the pads miss the part has no first touch:
its centre is taken as the foot of ``C_v`` on the line ``w``.

**The slip.** The move is taken as a turn about its fixed pole at a steady rate (a pure
shift when ``ψ = 0``). A contact stays at its point ``x`` of the gripper frame while the
part slides past it, with velocity ``ψ̇ J (x − Q)`` (``J``: the quarter turn, ``Q``: the
pole), so the slip along the pad's surface is ``slip = t · ψ J (x − Q)`` in closed form
(:func:`move_slip`), with ``t`` the row's tangent (the normal turned a quarter). Its
sign does not change during the move, so ``μ f |slip|`` is the move's dissipation exactly
for that motion: a shift ``Δc`` across flat pads slips ``Δc`` at every contact, a turn
``Δθ`` of a round part about its centre slips ``r Δθ`` (the displacement of the material
point that was in contact, projected on the tangent, is the same to first order:
``r sin Δθ``).

**Approximations.** (1) The slip comes from the *rigid* relative motion only: the part's
elastic deformation between the two axes' contact states does not enter, and the contact
points are the nodes' rest positions. (2) The forces are those of vertex ``v`` for the
whole move (the move's start; the frictionless normal forces of
:meth:`GraspCurve.forces` by default — :func:`release_work` takes any other, e.g.
frictional, normal forces as an argument). (3) Rows whose force is zero do not dissipate
(contacts that close during the move are not counted). The error of (1)–(3) shrinks with
the grid spacing: a move is one grid step (``Δθ = π/n_angles``, ``Δc = D/n_offsets``).
"""

from __future__ import annotations

import math
import time
from typing import Callable

import numpy as np

from ..errors import GraspError
from ..geometry import is_finite_number
from ..landscape.search import DissipativeEscape, dissipative_escape
from .contact import GraspCurve
from .geometry import GraspAxis
from .landscape import Landscape

__all__ = ["gripper_centre", "row_tangents", "move_slip", "move_dissipation",
           "contact_normal_forces", "is_released", "release_work", "OutOfTime"]


class OutOfTime(Exception):
    """A :func:`release_work` search passed its ``deadline`` (it is abandoned: no partial
    work is returned)."""


def gripper_centre(curve: GraspCurve) -> np.ndarray | None:
    """Centre of the pads (m, part frame) on ``curve``'s axis: the middle of the first
    touch, ``origin + ½ (z_A + z_B) a + c n``; ``None`` when the pads miss the part."""
    t = curve.touch
    if t is None:
        return None
    ax = curve.axis
    return np.asarray(ax.origin, float) + 0.5 * (t.z_a + t.z_b) * ax.direction + ax.offset * ax.normal


def row_tangents(normals: np.ndarray) -> np.ndarray:
    """Unit tangents (along the pad surface) of contact rows with unit ``normals`` (m, 2):
    the normals turned a quarter counter-clockwise."""
    normals = np.asarray(normals, float)
    return np.column_stack([-normals[:, 1], normals[:, 0]])


def _frame(axis: GraspAxis) -> np.ndarray:
    """``R = [a n]`` (columns): part-frame components of the gripper axes."""
    return np.column_stack([axis.direction, axis.normal])


def move_slip(points: np.ndarray, tangents: np.ndarray, axis_v: GraspAxis,
              centre_v: np.ndarray, axis_w: GraspAxis,
              centre_w: np.ndarray | None = None) -> np.ndarray:
    """Slip (m, signed) along each contact's tangent when the gripper's axis moves from
    ``axis_v`` to ``axis_w`` (both in the part frame), the part moving rigidly.

    Parameters
    ----------
    points : ndarray, shape (m, 2)
        Contact points (m, part frame) at ``axis_v``.
    tangents : ndarray, shape (m, 2)
        Unit tangents of the rows (part frame), e.g. :func:`row_tangents`.
    axis_v, axis_w : GraspAxis
        The move's start and end axes (of the same ``origin``).
    centre_v : ndarray, shape (2,)
        Pads' centre (m) on ``axis_v`` (:func:`gripper_centre`).
    centre_w : ndarray, shape (2,), optional
        Pads' centre on ``axis_w``; default (the pads miss the part there) the foot of
        ``centre_v`` on ``axis_w``.

    Returns
    -------
    ndarray, shape (m,)
        ``t · ψ J (x − Q)`` at each contact's gripper point ``x`` (module docstring); the
        shift ``t · b`` for a move without a turn.

    Examples
    --------
    A contact 5 mm ahead of the centre on the axis, flat pad (tangent across the axis):
    a shift of 1 mm across slips 1 mm, a turn of 0.01 rad slips 5 mm × 0.01.

    >>> p, t, o = np.array([[0.005, 0.0]]), np.array([[0.0, 1.0]]), np.zeros(2)
    >>> float(move_slip(p, t, GraspAxis(0.0, 0.0), o, GraspAxis(0.0, 0.001))[0])
    -0.001
    >>> round(float(move_slip(p, t, GraspAxis(0.0, 0.0), o, GraspAxis(0.01, 0.0), o)[0]), 12)
    -5e-05
    """
    points = np.asarray(points, float).reshape(-1, 2)
    tangents = np.asarray(tangents, float).reshape(-1, 2)
    Cv = np.asarray(centre_v, float)
    phi = math.remainder(axis_w.angle - axis_v.angle, 2.0 * math.pi)
    aw = axis_w
    if abs(phi) > 0.5 * math.pi:        # the same line with the pads exchanged turns less
        aw = GraspAxis(axis_w.angle + math.pi, -axis_w.offset, axis_w.origin)
        phi = math.remainder(aw.angle - axis_v.angle, 2.0 * math.pi)
    if centre_w is None:
        Cw = Cv + (aw.offset - aw.normal @ (Cv - np.asarray(aw.origin, float))) * aw.normal
    else:
        Cw = np.asarray(centre_w, float)
    Rv, Rw = _frame(axis_v), _frame(aw)
    psi = -phi                                  # the part's turn in the gripper frame
    b = Rw.T @ (Cv - Cw)                        # g_w = R(ψ) g_v + b
    x = (points - Cv) @ Rv                      # gripper coordinates at v
    t = tangents @ Rv
    # ψ J (x − Q) with (I − R(ψ)) Q = b: (I − R(ψ))⁻¹ = ½ I + ½ cot(ψ/2) J, so
    # ψ J Q = (ψ/2) J b − κ b, κ = (ψ/2) cot(ψ/2) → 1 as ψ → 0 (no pole: a pure shift).
    kappa = 1.0 if psi == 0.0 else (0.5 * psi) / math.tan(0.5 * psi)
    Jx = np.column_stack([-x[:, 1], x[:, 0]])
    Jb = np.array([-b[1], b[0]])
    s = psi * Jx - 0.5 * psi * Jb + kappa * b
    return np.einsum("ij,ij->i", t, s)


def move_dissipation(mu: float, normal_forces: np.ndarray, slip: np.ndarray) -> float:
    """Coulomb dissipation (J) of one move: ``μ Σ_r |f_r| |slip_r|``.

    Parameters
    ----------
    mu : float
        Friction coefficient (pad–part, ≥ 0).
    normal_forces : ndarray, shape (m,)
        Normal force (N) of each contact row during the move.
    slip : ndarray, shape (m,)
        Slip (m) of each row along its tangent (:func:`move_slip`).
    """
    return float(mu * np.sum(np.abs(np.asarray(normal_forces, float))
                             * np.abs(np.asarray(slip, float))))


def contact_normal_forces(curve: GraspCurve, sigma: float) -> np.ndarray:
    """Normal force (N) of each candidate row of ``curve`` at separation ``sigma`` (m): the
    component of :meth:`GraspCurve.forces` along the row normal (frictionless, SPEC §6)."""
    f = curve.forces(sigma)
    return np.einsum("ij,ij->i", f, curve.normals) if len(f) else np.zeros(0)


def is_released(curve: GraspCurve, sigma: float) -> bool:
    """Whether no pad presses on ``curve``'s axis at ``sigma`` (m): the pads miss the part,
    the separation is not below first touch (``σ ≥ σ0`` contracting, ``σ ≤ σ0``
    expanding: zero energy and zero force), or nothing is squeezed on this mesh."""
    if curve.touch is None or curve.path is None:
        return True
    return bool(curve.delta(sigma) <= 0.0)


def release_work(landscape: Landscape, start: int, sigma: float, mu: float, *,
                 normal_forces: Callable[[GraspCurve, float], np.ndarray] | None = None,
                 stop_above: float | None = None,
                 max_evaluations: int | None = None,
                 cache: dict | None = None,
                 deadline: float | None = None) -> DissipativeEscape:
    """Release work ``U_A^μ`` (J) from axis ``start`` at separation ``sigma`` (SPEC §9).

    The least, over paths on the landscape's grid to an axis where no pad presses
    (:func:`is_released`), of the largest work ``U(v) − U(start) + Σ D`` on the path, each
    move dissipating ``D(v, w) = μ Σ f_r |slip_r|`` (:func:`move_slip` with the forces at
    ``v``). No noise floor is applied (a start the pads do not squeeze is released: 0).

    Parameters
    ----------
    landscape : Landscape
        The pads' axis landscape (its energies, curves and grid neighbours).
    start : int
        Start vertex.
    sigma : float
        Separation (m), within the landscape's traced range.
    mu : float
        Friction coefficient (≥ 0); 0 gives the minimax barrier to a release.
    normal_forces : callable, optional
        ``normal_forces(curve, sigma)``: the normal force (N) of each candidate row of
        ``curve`` at ``sigma``; default :func:`contact_normal_forces` (frictionless).
    stop_above, max_evaluations : optional
        As in :func:`~deformclosure.landscape.search.dissipative_escape`.
    cache : dict, optional
        Keeps what does not depend on σ between calls on one landscape (a σ*-search asks
        many σ): each vertex's rows and centre, and each move's slips (the rows of a curve
        and the rigid move are the same at every σ; only the forces change).
    deadline : float, optional
        ``time.perf_counter()`` value after which the search is abandoned
        (:class:`OutOfTime` is raised; checked at every vertex energy).

    Returns
    -------
    DissipativeEscape
        ``work`` (J), the escape ``path`` of vertices and its ``dissipation`` (J).

    Raises
    ------
    GraspError
        ``mu`` is not a finite number ≥ 0.
    OutOfTime
        The ``deadline`` passed.
    """
    if not (is_finite_number(mu) and mu >= 0):
        raise GraspError(f"friction = {mu!r}: give a friction coefficient μ ≥ 0")
    forces_of = contact_normal_forces if normal_forces is None else normal_forces
    nodes = landscape.solver.mesh.nodes
    store = {} if cache is None else cache
    geometry = store.setdefault("rows", {})       # v -> (points, tangents, centre)
    slips = store.setdefault("slips", {})         # (v, w) -> slip of every row of v
    moves = store.setdefault("moves", {})         # v -> (neighbour -> k, |slip| (deg, m), M)
    rows_now: dict[int, np.ndarray | None] = {}   # v -> dissipation of each move at sigma

    def rows_of(v: int) -> tuple:
        """Points and tangents of every candidate row of ``v``, and its centre."""
        out = geometry.get(v)
        if out is None:
            c = landscape.curve(v)
            out = geometry[v] = (nodes[c.nodes], row_tangents(c.normals), gripper_centre(c))
        return out

    def moves_of(v: int) -> tuple:
        """The moves out of ``v``: each neighbour's place, the rows' |slip| per move and,
        for the frictionless forces, ``M = Λ |S|ᵀ`` at the curve's breakpoints (the forces
        are linear in the squeeze between them, so the dissipation of every move is too:
        ``μ M`` interpolated at σ, one vector per vertex and σ)."""
        out = moves.get(v)
        if out is None:
            P, T, Cv = rows_of(v)
            grid = landscape.grid
            nbrs = list(landscape.neighbours(v))
            S = np.empty((len(nbrs), len(P)))
            for k, w in enumerate(nbrs):
                sl = slips.get((v, w))
                if sl is None:
                    sl = slips[v, w] = move_slip(P, T, grid.axis(v), Cv, grid.axis(w),
                                                 gripper_centre(landscape.curve(w)))
                S[k] = sl
            S = np.abs(S)
            path = landscape.curve(v).path
            M = None if path is None else path.lam @ S.T
            out = moves[v] = ({w: k for k, w in enumerate(nbrs)}, S, M)
        return out

    def move_row(v: int) -> np.ndarray | None:
        """Dissipation (J) of every move out of ``v`` at ``sigma`` (``None``: no force)."""
        if v in rows_now:
            return rows_now[v]
        c = landscape.curve(v)
        row = None
        if c.path is not None:
            at, S, M = moves_of(v)
            if normal_forces is None:
                path = c.path
                delta = c.delta(sigma)
                if delta > path.delta[0] and len(path.delta) >= 2:
                    i = int(path.piece(np.array(delta)))
                    t = (delta - path.delta[i]) / (path.delta[i + 1] - path.delta[i])
                    row = mu * ((1 - t) * M[i] + t * M[i + 1])
            else:
                f = np.abs(np.asarray(forces_of(c, sigma), float))
                if f.any():
                    row = mu * (S @ f)
            if row is not None and not row.any():
                row = None
        rows_now[v] = row
        return row

    def dissipation(v: int, w: int) -> float:
        if mu == 0.0:
            return 0.0
        row = move_row(v)
        if row is None:
            return 0.0
        return float(row[moves_of(v)[0][w]])

    def energy(v: int, near) -> float:
        if deadline is not None and time.perf_counter() > deadline:
            raise OutOfTime(f"release work at sigma = {sigma:.6g} m")
        return landscape.energy(v, sigma)

    return dissipative_escape(start, landscape.neighbours, energy, dissipation,
                              lambda v, e: is_released(landscape.curve(v), sigma),
                              stop_above=stop_above, max_evaluations=max_evaluations)
