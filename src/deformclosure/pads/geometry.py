"""Pads and grasp axes: the gripper's geometry in the part frame (SPEC §6).

A *pad* is a rigid capsule: a flat face of width ``W`` perpendicular to the closing axis
with rounded ends of radius ``ρ`` (``W = 0``: a round fingertip). Its front surface, seen
from the part, is a height function of the cross-axis coordinate ``x``::

    d(x) = 0                                   |x| ≤ W/2
    d(x) = ρ − sqrt(ρ² − (|x| − W/2)²)         W/2 < |x| < W/2 + ρ

and the pad cannot touch points with ``|x| ≥ W/2 + ρ``. Contact is *enforced* only where
the surface is at most :data:`FLANK_ANGLE` (75°) from the face, ``|x| < W/2 + ρ sin 75°``:
on the steeper flanks the gap, linearised along the axis, has slope ``d' → ∞`` and would
pin a node sideways as soon as the node comes within reach (a jump of the energy as the
axis moves, not a property of the pad); reaching there needs an indentation of
``ρ (1 − cos 75°) ≈ 0.74 ρ`` beyond the face. A *grasp axis* is a line in the
part frame: angle ``θ`` of the closing direction ``a = (cos θ, sin θ)`` and signed offset
``c`` of the line from the reference point along ``n = (−sin θ, cos θ)``. Pad A approaches
along ``+a`` from ``s = −∞`` and occupies ``s ≤ z_A − d(x)``; pad B approaches along
``−a`` and occupies ``s ≥ z_B + d(x)``; the separation is ``σ = z_B − z_A``.

The first touch of each pad with the part's outer ring is found exactly, edge by edge:
along an edge ``s`` is linear and ``d`` convex in the edge parameter, so the minimum of
``s + d(x)`` is at an end, at ``|x| = W/2``, or where the slope of ``d`` equals the edge's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..contact.bodies import FLANK_ANGLE, Capsule
from ..errors import GraspError
from ..geometry import is_finite_number, touch_tolerance

__all__ = ["Pad", "GraspAxis", "FirstTouch", "first_touch", "pad_outline", "pad_pair",
           "placed_pads", "face_shift", "pad_depth", "FLANK_ANGLE"]


@dataclass(frozen=True)
class Pad(Capsule):
    """A rigid pad: flat face of width ``width`` (m) with rounded ends of ``radius`` (m) —
    the capsule body of :class:`deformclosure.contact.bodies.Capsule` moving rigidly
    along a grasp axis (its profile, reach and flank rule live there).

    Examples
    --------
    >>> Pad(width=0.004, radius=0.001).half_span   # W/2 + ρ: the widest point it touches
    0.003
    """


@dataclass(frozen=True)
class GraspAxis:
    """A closing axis: angle ``angle`` (rad) and offset ``offset`` (m) from ``origin``.

    The axis is the line ``{p : n·(p − origin) = offset}`` traversed along
    ``a = (cos angle, sin angle)``. ``(angle + π, −offset)`` is the same line with the
    pads' roles exchanged.

    Examples
    --------
    >>> ax = GraspAxis.through([0.0, 0.01], [0.012, 0.01])   # across a 12 mm block, m
    >>> ax.angle, ax.offset
    (0.0, 0.01)
    """

    angle: float
    offset: float
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if not (is_finite_number(self.angle) and is_finite_number(self.offset)):
            raise GraspError(f"axis = ({self.angle!r} rad, {self.offset!r} m): the angle and "
                             "offset must be finite numbers")
        o = self.origin
        if not (isinstance(o, (tuple, list, np.ndarray)) and len(o) == 2
                and is_finite_number(o[0]) and is_finite_number(o[1])):
            raise GraspError(f"axis origin = {o!r}: give a point (x, y) in m")

    @classmethod
    def through(cls, p: np.ndarray, q: np.ndarray, origin=(0.0, 0.0)) -> "GraspAxis":
        """The axis through points ``p`` and ``q`` (m), closing direction ``p → q``."""
        p, q = np.asarray(p, float), np.asarray(q, float)
        d = q - p
        if not np.all(np.isfinite(d)) or np.hypot(*d) == 0:
            raise GraspError("--at: the two points must be distinct and finite")
        ang = float(np.arctan2(d[1], d[0]))
        return cls.at(p, ang, origin)

    @classmethod
    def at(cls, point: np.ndarray, angle: float, origin=(0.0, 0.0)) -> "GraspAxis":
        """The axis through ``point`` (m) with closing direction ``angle`` (rad)."""
        n = np.array([-np.sin(angle), np.cos(angle)])
        o = np.asarray(origin, float)
        return cls(float(angle), float(n @ (np.asarray(point, float) - o)), (float(o[0]), float(o[1])))

    @property
    def direction(self) -> np.ndarray:
        """Closing direction ``a`` (unit)."""
        return np.array([np.cos(self.angle), np.sin(self.angle)])

    @property
    def normal(self) -> np.ndarray:
        """Cross-axis direction ``n`` (unit)."""
        return np.array([-np.sin(self.angle), np.cos(self.angle)])

    @property
    def point(self) -> np.ndarray:
        """The axis' point nearest the origin (m)."""
        return np.asarray(self.origin) + self.offset * self.normal

    def coordinates(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Axial ``s`` and cross-axis ``x`` coordinates (m) of points ``P`` (k, 2)."""
        P = np.asarray(P, float) - np.asarray(self.origin)
        return P @ self.direction, P @ self.normal - self.offset

    def to_dict(self) -> dict:
        """``{"point": [x, y], "angle"}`` (m, rad)."""
        return {"point": [float(v) for v in self.point], "angle": float(self.angle)}


@dataclass(frozen=True)
class FirstTouch:
    """Where the pads first touch the part when closing along an axis (rest geometry).

    Contracting, pad A comes from ``−a`` and pad B from ``+a``. Expanding (pads opening
    inside a hole from a start point), pad A moves towards ``+a`` and pad B towards
    ``−a``; each has the same gap formula as its contracting namesake, so one contact
    solver serves both.

    Attributes
    ----------
    z_a, z_b : float
        Face positions (m, along the axis) of pads A and B at first touch.
    expanding : bool
        Whether the pads open inside a hole.
    contact_a, contact_b : ndarray, shape (2,)
        Rest contact points (m): the middle of the touching set of each pad.
    """

    z_a: float
    z_b: float
    contact_a: np.ndarray
    contact_b: np.ndarray
    expanding: bool = False

    @property
    def sigma0(self) -> float:
        """Closing (or, expanding, opening) width at first touch (m)."""
        return self.z_a - self.z_b if self.expanding else self.z_b - self.z_a


def _edge_minima(s0, s1, x0, x1, pad: Pad, tol: float):
    """Minimum of ``s + d(x)`` along each edge and the argmin points' ``(s, x)``."""
    ds, dx = s1 - s0, x1 - x0
    h, r = 0.5 * pad.width, pad.radius
    with np.errstate(divide="ignore", invalid="ignore"):
        m = -ds / dx                     # d'(x) at a stationary point of s + d
        xi = np.abs(m) * r / np.sqrt(1.0 + m * m)
        cand_x = np.stack([x0, x1, np.full_like(x0, -h), np.full_like(x0, h),
                           np.where(m > 0, h + xi, np.nan), np.where(m < 0, -h - xi, np.nan)], 1)
        tau = (cand_x - x0[:, None]) / dx[:, None]
    tau[:, :2] = [0.0, 1.0]
    vertical = np.abs(dx) <= tol
    tau[vertical, 2:] = np.nan
    ok = np.isfinite(tau) & (tau >= 0) & (tau <= 1)
    tau = np.where(ok, tau, 0.0)
    xs = x0[:, None] + tau * dx[:, None]
    ss = s0[:, None] + tau * ds[:, None]
    d, _ = pad.profile(xs, capped=False)
    f = np.where(ok, ss + d, np.inf)
    return f, ss, xs


def first_touch(ring: np.ndarray, axis: GraspAxis, pad: Pad,
                start: float | None = None) -> FirstTouch | None:
    """Exact first touch of both pads with a closed ring.

    Parameters
    ----------
    ring : ndarray, shape (k, 2)
        The part's outer ring (contracting) or the hole ring the pads open in (expanding),
        m, not closed.
    axis : GraspAxis
    pad : Pad
    start : float, optional
        Expanding grasps: the axial coordinate ``s`` (m) where the pads start, back to
        back, inside the hole. Pad A then meets the ring ahead of it (``s + d ≥ start``),
        pad B the ring behind it.

    Returns
    -------
    FirstTouch or None
        ``None`` when the pads miss the part (no boundary point within ``W/2 + ρ`` of the
        axis) or, expanding, when a pad does not fit in the hole at the start.
    """
    ring = np.asarray(ring, float)
    s, x = axis.coordinates(ring)
    s1, x1 = np.roll(s, -1), np.roll(x, -1)
    # SPEC §3's touching tolerance, on the ring's extent (no hull per axis).
    tol = touch_tolerance(float(np.ptp(ring, axis=0).max()))
    out = []
    for sign in (1.0, -1.0):   # pad A minimises s + d(x); pad B maximises s − d(x)
        f, ss, xs = _edge_minima(sign * s, sign * s1, x, x1, pad, tol)
        if start is not None:
            # Only the ring ahead of each pad; an edge that passes from behind the face to
            # ahead of it inside the pad's span means the pad does not fit at the start.
            front = sign * start - tol
            finite = np.isfinite(f)
            behind = (finite & (f < front)).any(axis=1)
            ahead = (finite & (f >= front)).any(axis=1)
            if np.any(behind & ahead):
                return None
            f = np.where(f >= front, f, np.inf)
        best = float(f.min())
        if not np.isfinite(best):
            return None
        near = f <= best + tol
        xs_t = xs[near]
        xm = 0.5 * (xs_t.min() + xs_t.max())
        sm = sign * best - sign * float(pad.profile(np.array([xm]), capped=False)[0][0])
        out.append((sign * best, np.asarray(axis.origin) + sm * axis.direction
                    + (xm + axis.offset) * axis.normal))
    (za, pa), (zb, pb) = out
    return FirstTouch(za, zb, pa, pb, start is not None)


def pad_outline(pad: Pad, axis: GraspAxis, z: float, side: int, depth: float,
                n: int = 24) -> np.ndarray:
    """Outline (m, part frame; one turn, the first point not repeated) of a pad whose face
    is at axial position ``z`` (m): the face and its rounded ends towards the part, and
    ``depth`` (m) of body behind them.

    ``side`` is +1 for pad A (occupies ``s ≤ z − d(x)``) and −1 for pad B
    (``s ≥ z + d(x)``). ``n`` points per rounded end.
    """
    a, nrm = axis.direction, axis.normal
    h, r = 0.5 * pad.width, pad.radius
    t = np.linspace(0.0, np.pi / 2, n)
    # (x, distance behind the face) of the face side, then the back edge
    right = np.column_stack([h + r * np.sin(t), r - r * np.cos(t)])
    prof = np.vstack([right[::-1] * [-1.0, 1.0], right])
    if h == 0.0:
        prof = np.delete(prof, n, axis=0)             # the two ends meet at x = 0
    back = np.array([[h + r, r + depth], [-h - r, r + depth]])
    x, sd = np.vstack([prof, back]).T
    o = np.asarray(axis.origin, float) + axis.offset * nrm
    return o[None] + x[:, None] * nrm[None] + (z - side * sd)[:, None] * a[None]


def pad_depth(pad: Pad, touch: FirstTouch) -> float:
    """How deep (m) a drawn or exported pad's body reaches behind its face:
    ``0.15 max(σ0, W/2 + ρ)``, a stub that keeps the pads near the part."""
    return 0.15 * max(touch.sigma0, pad.half_span)


def pad_pair(pad: Pad, axis: GraspAxis, touch: FirstTouch, z_a: float, z_b: float,
             depth: float) -> tuple[np.ndarray, np.ndarray]:
    """Outlines (m, as :func:`pad_outline`) of pad A with its face at ``z_a`` and pad B
    at ``z_b`` (m, along ``axis``), ``depth`` (m) of body behind each face — less between
    back-to-back pads opening in a hole (``touch.expanding``): at most 0.45 of the faces'
    distance, so the two bodies never overlap."""
    if touch.expanding:                     # back to back inside the hole
        depth = min(depth, 0.45 * max(z_a - z_b, 1e-12))
    return pad_outline(pad, axis, z_a, 1, depth), pad_outline(pad, axis, z_b, -1, depth)


def face_shift(pad: Pad, axis: GraspAxis, touch: FirstTouch, delta: float,
               nodes: np.ndarray, u: np.ndarray, forces: np.ndarray) -> float:
    """Common shift (m, along ``axis``) that puts both pads, each moved in by half the
    squeeze ``delta`` (m) from its first-touch face, on the part displaced by ``u``.

    The part floats, so its displacement has a gauge (SPEC §6) that may shift it along
    the axis against that split. The shift is the mean offset of the loaded nodes from
    the faces (a loaded node of pad A sits at ``s + a·u = z_A − d(x) − d'(x) n·u``, of
    pad B at ``s + a·u = z_B + d(x) + d'(x) n·u``: the model's gaps, linearised in ``u``;
    a node pushed along ``+a`` is pad A's), so the faces sit on the deformed part to first
    order in ``u``; 0 when nothing is loaded.

    Parameters
    ----------
    pad, axis, touch
        The gripper and its first touch (rest geometry).
    delta : float
        Squeeze (m), ≥ 0.
    nodes : ndarray, shape (n, 2)
        Rest positions (m).
    u, forces : ndarray, shape (n, 2) or (2n,)
        Node displacements (m) and contact forces on the nodes (N).
    """
    nodes = np.asarray(nodes, float)
    u = np.asarray(u, float).reshape(-1, 2)
    f = np.asarray(forces, float).reshape(-1, 2)
    za, zb = touch.z_a + 0.5 * delta, touch.z_b - 0.5 * delta
    a = axis.direction
    fa = f @ a
    scale = np.abs(fa).max() if len(fa) else 0.0
    loaded = np.abs(fa) > 1e-9 * scale if scale > 0 else np.zeros(len(fa), bool)
    if not loaded.any():
        return 0.0
    s, x = axis.coordinates(nodes[loaded])
    d, slope = pad.profile(x, capped=False)
    ok = np.isfinite(d) & np.isfinite(slope)
    # the model's gap, linearised in u (pads/contact.py): d(x) + d'(x) n·u
    d = np.where(ok, d + np.where(ok, slope, 0.0) * (u[loaded] @ axis.normal), 0.0)
    s = s + u[loaded] @ a
    face = np.where(fa[loaded] > 0, s + d - za, s - d - zb)
    return float(np.mean(face))


def placed_pads(pad: Pad, axis: GraspAxis, touch: FirstTouch, delta: float,
                nodes: np.ndarray, u: np.ndarray, forces: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Outlines (m) of pads A and B at squeeze ``delta`` (m), where they touch the part
    displaced by ``u``: each moved in by half the squeeze from its first-touch face
    position, both by :func:`face_shift` (whose parameters these are).

    Returns
    -------
    outline_a, outline_b : ndarray, shape (k, 2)
        As :func:`pad_pair`, :func:`pad_depth` deep.
    """
    shift = face_shift(pad, axis, touch, delta, nodes, u, forces)
    return pad_pair(pad, axis, touch, touch.z_a + 0.5 * delta + shift,
                    touch.z_b - 0.5 * delta + shift, pad_depth(pad, touch))
