"""Rigid bodies that touch the part: the fingers of ``check`` (point, disc, convex
polygon, half-plane; paper §3.2, SPEC §2) and the capsule shape of the pads (SPEC §6) —
one hierarchy for every contact model.

A *finger* is a rigid body held fixed in the plane. Every finger is a frozen dataclass in
SI units (metres) with a few vectorised geometric queries used by the D-obstacle tests,
the contact problem, the closure test and the compiled placement kernel (its
:meth:`Finger.kernel_encoding`). A *pad* is a rigid capsule (:class:`Capsule`: a flat
face of width ``W`` with rounded ends of radius ``ρ``) moving along a grasp axis; a disc
finger is the capsule of width 0 (:attr:`DiscFinger.shape`) and presses like a round pad,
so its contact reach — :data:`FLANK_ANGLE` from its axis — comes from the same shape.

The finger *file* (reading and writing finger sets) is :mod:`deformclosure.dspace.fingers`.

References
----------
K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure Grasps of Deformable
Parts", IJRR 24(11), 2005, §3.2 (fingers and D-obstacles).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar, Sequence

import numpy as np

from ..errors import FingerError, GraspError
from ..geometry import is_finite_number, signed_area

__all__ = [
    "Finger",
    "PointFinger",
    "DiscFinger",
    "PolygonFinger",
    "HalfPlaneFinger",
    "Capsule",
    "FLANK_ANGLE",
    "FINGER_TYPES",
    "as_fingers",
    "segment_distance",
]

#: Kind codes of the fingers in the compiled contact kernel
#: (:mod:`deformclosure.dspace.placement_energy`).
KERNEL_POINT, KERNEL_DISC, KERNEL_POLYGON, KERNEL_HALFPLANE = 0, 1, 2, 3


def _as_points(points: Any) -> np.ndarray:
    p = np.asarray(points, dtype=float)
    if p.shape[-1:] != (2,):
        raise FingerError(f"points: expected shape (..., 2), got {p.shape}; give [x, y] coordinates")
    return p


def segment_distance(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Distance from point(s) ``p`` to closed segments ``a-b`` (broadcast over ``...``)."""
    ab = b - a
    ap = p - a
    den = np.einsum("...j,...j->...", ab, ab)
    s = np.clip(np.einsum("...j,...j->...", ap, ab) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    d = ap - s[..., None] * ab
    return np.sqrt(np.einsum("...j,...j->...", d, d))


def _clip_hits(a: np.ndarray, b: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Cyrus-Beck: does closed segment ``a-b`` meet the open polygon ``{m_j . x < h_j}``?"""
    num = offsets - a @ normals.T  # (..., k)
    den = (b - a) @ normals.T
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = num / den
    upper = np.min(np.where(den > 0, ratio, np.inf), axis=-1)
    lower = np.max(np.where(den < 0, ratio, -np.inf), axis=-1)
    parallel_ok = np.all((den != 0) | (num > 0), axis=-1)
    return parallel_ok & (lower < upper) & (lower < 1.0) & (upper > 0.0)


def _translation_clear(H: np.ndarray, hn: np.ndarray, D: np.ndarray, P: np.ndarray, pn: np.ndarray,
                       tol: float) -> np.ndarray:
    """Separating axes: may the convex polygon ``H`` (outward edge normals ``hn``) translate
    to infinity along each direction of ``D (k, 2)`` without entering the convex polygon
    ``P`` (edge normals ``pn``; a point when ``P`` has one row)? Touching within ``tol``
    is allowed."""
    clear = np.ones(len(D), bool)
    for j, d in enumerate(D):
        axes = np.vstack([hn, pn, [[-d[1], d[0]]]])
        hp = H @ axes.T                       # (h, a)
        lo, hi = hp.min(axis=0), hp.max(axis=0)
        ad = axes @ d
        hi = np.where(ad > 1e-12, np.inf, hi)
        lo = np.where(ad < -1e-12, -np.inf, lo)
        fp = P @ axes.T
        flo, fhi = fp.min(axis=0), fp.max(axis=0)
        if not np.any((fhi <= lo + tol) | (flo >= hi - tol)):
            clear[j] = False
    return clear


class Finger(ABC):
    """Base class of the rigid finger bodies (all lengths in metres).

    Every kind answers the geometric questions the D-space modules ask of a finger, so
    no module needs to know which kind it holds:

    * :meth:`signed_distance` -- distance from the finger body, negative inside
      (for a point finger: the distance to the point, never negative);
    * :meth:`outward_normal` -- unit gradient of the signed distance (pointing from
      the finger towards the query point);
    * :meth:`segment_hits` -- which segments meet the open body eroded by a tolerance
      (the D-obstacle test, :mod:`.obstacles`);
    * :attr:`vertices` -- the corners of the body, ``(k, 2)`` (the point itself for a
      point finger, none for discs and half-planes), with :meth:`corner_edges` and
      :meth:`corner_normals` at a corner;
    * :meth:`round_centre` -- centre and radius of a circular boundary (discs);
    * :meth:`probe_point`, :meth:`reference_points`, :meth:`extent_points`,
      :meth:`depth_samples` -- representative points of the body;
    * :meth:`kernel_encoding` -- the kind code and parameters for the compiled contact
      kernel of :mod:`.placement_energy`;
    * :meth:`translation_clear` -- may a convex part translate away past the finger;
    * :meth:`plot` -- draw the body on matplotlib axes;
    * :attr:`radius_of_curvature` -- radius of curvature of the smooth part of the
      boundary (``0`` for a point, ``r`` for a disc, ``inf`` for flat faces).

    Examples
    --------
    >>> fingers = [PointFinger((0.0, 0.0)), DiscFinger((0.0, 0.0), 0.001)]
    >>> [float(f.signed_distance([0.003, 0.004])) for f in fingers]
    [0.005, 0.004]
    """

    type: ClassVar[str] = ""
    radius_of_curvature: ClassVar[float] = math.inf

    @property
    def vertices(self) -> np.ndarray:
        """Corners of the body ``(k, 2)`` (m)."""
        return np.zeros((0, 2))

    @property
    def has_interior(self) -> bool:
        """Whether the body has a non-empty interior (all fingers but the point)."""
        return True

    def check(self, where: str) -> None:
        """Refuse a finger built in code with non-finite numbers (:class:`FingerError`
        naming ``where``); kinds add their own conditions. The file reader checks the
        same before it builds a finger."""
        for name, value in vars(self).items():
            arr = np.asarray(value, dtype=float)
            if not np.all(np.isfinite(arr)):
                raise FingerError(f"{where}.{name}: must be finite, got {value!r}")

    @abstractmethod
    def signed_distance(self, points: Any) -> np.ndarray:
        """Distance (m) of ``points (..., 2)`` from the body, negative inside."""

    @abstractmethod
    def outward_normal(self, points: Any) -> np.ndarray:
        """Unit gradient of :meth:`signed_distance` at ``points (..., 2)``."""

    @abstractmethod
    def segment_hits(self, a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
        """Whether the closed segments ``a-b`` (arrays ``(..., 2)``) meet the open body
        eroded by ``tol`` (m): overlaps up to ``tol`` count as touching. Bool ``(...)``."""

    def probe_point(self) -> np.ndarray | None:
        """A point in the interior of the body (``None`` for a half-plane)."""
        return None

    def round_centre(self) -> tuple[np.ndarray, float] | None:
        """Centre (m) and radius (m) of the body's circular boundary, ``None`` when it has
        none. A boundary edge of the part touches it where the centre's distance to the
        edge's line equals the radius."""
        return None

    def reference_points(self) -> np.ndarray:
        """Points ``(k, 2)`` (m) that stand for the body when locating a set of fingers
        (their mean is the fingers' hub): the corners, else the centre or the boundary
        point of a half-plane."""
        return np.asarray(self.vertices, float).reshape(-1, 2)

    def extent_points(self) -> np.ndarray | None:
        """Points ``(k, 2)`` (m) whose bounding box contains the body; ``None`` when the
        body is unbounded (half-plane)."""
        return np.asarray(self.vertices, float).reshape(-1, 2)

    def depth_samples(self) -> np.ndarray:
        """Points ``(k, 2)`` (m) of the body whose depth in the part is measured
        (:func:`.placement.finger_depths`); none for a half-plane, which is measured by
        the boundary nodes it covers."""
        return np.zeros((0, 2))

    def corner_edges(self, k: int) -> list[np.ndarray]:
        """Vectors along the body's two edges leaving corner ``k`` (none for a point)."""
        return []

    def corner_normals(self, k: int) -> list[np.ndarray]:
        """Outward unit normals of the body's two faces at corner ``k`` (none for a point)."""
        return []

    @abstractmethod
    def kernel_encoding(self, axis: Any = (0.0, 0.0)) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """The finger for the compiled contact kernel: ``(code, params (6,), vertices
        (k, 2), normals (k, 2))``, ``code`` one of the ``KERNEL_*`` constants. ``axis``:
        a disc's pressing direction (unit, world frame); ignored by the other kinds."""

    def _outline(self) -> tuple[np.ndarray, np.ndarray]:
        """A convex polygon containing the body and its edge normals (separating axes)."""
        return np.asarray(self.vertices, float), np.zeros((0, 2))

    def translation_clear(self, H: np.ndarray, hn: np.ndarray, D: np.ndarray, tol: float) -> np.ndarray:
        """Whether the convex polygon ``H (h, 2)`` (outward unit edge normals ``hn``) may
        translate to infinity along each unit direction of ``D (k, 2)`` without entering
        the body (touching within ``tol`` m allowed). Bool ``(k,)``."""
        P, pn = self._outline()
        return _translation_clear(H, hn, D, P, pn, tol)

    def plot(self, ax: Any, *, scale: float = 1.0, bounds: Sequence[float] | None = None,
             **style: Any) -> np.ndarray:
        """Draw the body on matplotlib axes ``ax`` in plot units (``scale`` metres per
        unit); ``style`` goes to the patch. Returns the point (plot units) to label it at."""
        ax.add_patch(self._patch(scale, bounds, ax, **style))
        return self._label_point() / scale

    def _patch(self, scale: float, bounds: Sequence[float] | None, ax: Any, **style: Any) -> Any:
        from matplotlib.patches import Polygon

        return Polygon(self.vertices / scale, closed=True, **style)

    def _label_point(self) -> np.ndarray:
        return self.probe_point()

    @abstractmethod
    def to_dict(self, scale: float = 1.0) -> dict:
        """The finger-file entry, lengths divided by ``scale`` (m per file unit)."""

    def obstacle(self, where: str, axis: Any = (0.0, 0.0)) -> Any:
        """The finger as a body of the finite-strain contact solver (SPEC §8,
        :mod:`.large_deformation`: signed distance, unit gradient and curvature of points
        against it), same frame; ``axis``: a disc's pressing direction (it presses like a
        round pad on that axis, carried by the finger behind it). Kinds without one raise
        :class:`FingerError` naming ``where``: the solver's rows are boundary nodes
        against bodies, so a body must be smooth or meet the part with faces."""
        raise FingerError(f"{where}: a {self.type} finger has no finite-strain contact yet "
                          "(SPEC §8: boundary nodes against smooth bodies); use disc and "
                          "half-plane fingers, or --elasticity linear")


@dataclass(frozen=True)
class PointFinger(Finger):
    """A point finger at ``at`` (m). Its body has no interior: the part collides with
    it when the point lies strictly inside the part.

    Examples
    --------
    >>> PointFinger((0.0, 0.0)).signed_distance([[0.003, 0.004]])
    array([0.005])
    """

    at: tuple[float, float]
    type: ClassVar[str] = "point"
    radius_of_curvature: ClassVar[float] = 0.0

    @property
    def vertices(self) -> np.ndarray:
        return np.array([self.at], dtype=float)

    @property
    def has_interior(self) -> bool:
        return False

    def obstacle(self, where: str, axis: Any = (0.0, 0.0)) -> Any:
        raise FingerError(f"{where}: a point finger has no finite-strain contact (a point "
                          "force in 2-D makes an unbounded strain, SPEC §8); model the "
                          "fingertip as a disc, or use --elasticity linear")

    def signed_distance(self, points: Any) -> np.ndarray:
        return np.linalg.norm(_as_points(points) - np.asarray(self.at), axis=-1)

    def outward_normal(self, points: Any) -> np.ndarray:
        d = _as_points(points) - np.asarray(self.at)
        n = np.linalg.norm(d, axis=-1, keepdims=True)
        return np.divide(d, n, out=np.zeros_like(d), where=n > 0)

    def segment_hits(self, a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
        return np.zeros(np.shape(a)[:-1], dtype=bool)   # no interior to meet

    def probe_point(self) -> np.ndarray:
        return np.asarray(self.at, dtype=float)

    def depth_samples(self) -> np.ndarray:
        return np.asarray(self.vertices, dtype=float).reshape(-1, 2)

    def kernel_encoding(self, axis: Any = (0.0, 0.0)) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        par = np.zeros(6)
        par[:2] = self.at
        return KERNEL_POINT, par, np.zeros((0, 2)), np.zeros((0, 2))

    def plot(self, ax: Any, *, scale: float = 1.0, bounds: Sequence[float] | None = None,
             **style: Any) -> np.ndarray:
        """Draw the point as a black cross (``style`` is for bodies); returns it (plot units)."""
        p = np.asarray(self.at) / scale
        ax.plot(*p, marker="x", color="k", ms=8, mew=2, zorder=5)
        return p

    def to_dict(self, scale: float = 1.0) -> dict:
        return {"type": "point", "at": [self.at[0] / scale, self.at[1] / scale]}


@dataclass(frozen=True)
class DiscFinger(Finger):
    """A disc finger with ``center`` (m) and ``radius`` (m).

    Examples
    --------
    >>> disc = DiscFinger((0.0, 0.0), 0.01)
    >>> disc.signed_distance([[0.02, 0.0], [0.0, 0.0]]), disc.outward_normal([0.0, 0.02])
    (array([ 0.01, -0.01]), array([0., 1.]))
    """

    center: tuple[float, float]
    radius: float
    type: ClassVar[str] = "disc"

    @property
    def radius_of_curvature(self) -> float:  # type: ignore[override]
        return float(self.radius)

    @property
    def shape(self) -> "Capsule":
        """The disc as a capsule of width 0: the round pad it presses like (SPEC §6)."""
        return Capsule(0.0, float(self.radius))

    def check(self, where: str) -> None:
        super().check(where)
        if not self.radius > 0:
            raise FingerError(f"{where}.radius: must be > 0 (m), got {self.radius!r}")

    @property
    def vertices(self) -> np.ndarray:
        return np.zeros((0, 2))

    def signed_distance(self, points: Any) -> np.ndarray:
        return np.linalg.norm(_as_points(points) - np.asarray(self.center), axis=-1) - self.radius

    def outward_normal(self, points: Any) -> np.ndarray:
        d = _as_points(points) - np.asarray(self.center)
        # hypot, not norm: the squares of an offset of 1e-158 m underflow to subnormals
        n = np.hypot(d[..., 0], d[..., 1])[..., None]
        out = np.divide(d, n, out=np.zeros_like(d), where=n > 0)
        out[..., 0] = np.where(n[..., 0] > 0, out[..., 0], 1.0)
        return out

    def segment_hits(self, a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
        return segment_distance(a, b, self.probe_point()) < self.radius - tol

    def probe_point(self) -> np.ndarray:
        return np.asarray(self.center, dtype=float)

    def round_centre(self) -> tuple[np.ndarray, float]:
        return np.asarray(self.center), self.radius

    def reference_points(self) -> np.ndarray:
        return np.asarray([self.center])

    def extent_points(self) -> np.ndarray:
        c = np.asarray(self.center)
        return np.array([c - self.radius, c + self.radius])

    def depth_samples(self) -> np.ndarray:
        t = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
        c = np.asarray(self.center, dtype=float)
        ring = c + self.radius * np.c_[np.cos(t), np.sin(t)]
        inner = c + 0.5 * self.radius * np.c_[np.cos(t[::4]), np.sin(t[::4])]
        return np.vstack([c, inner, ring])

    def kernel_encoding(self, axis: Any = (0.0, 0.0)) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """Parameters ``(cx, cy, r, ax, ay, reach)``: the disc presses like a round pad
        (SPEC §6) along ``axis``; contact is enforced within ``reach = r sin 75°`` of it."""
        par = np.zeros(6)
        par[:3] = (*self.center, self.radius)
        par[3:5] = axis
        par[5] = self.shape.reach
        return KERNEL_DISC, par, np.zeros((0, 2)), np.zeros((0, 2))

    def obstacle(self, where: str, axis: Any = (0.0, 0.0)) -> Any:
        from .large_deformation import CapsuleObstacle

        a = np.asarray(axis, float)
        back = (float(-a[0]), float(-a[1])) if np.hypot(*a) > 0 else None
        c = (float(self.center[0]), float(self.center[1]))
        # the round front against the part's edges (edge rows), the flanks against its nodes
        return CapsuleObstacle(c, c, float(self.radius), back, front_by_edges=True)

    def _outline(self) -> tuple[np.ndarray, np.ndarray]:
        k = 16                                  # circumscribed 16-gon
        t = np.linspace(0, 2 * np.pi, k, endpoint=False)
        P = np.asarray(self.center) + (self.radius / np.cos(np.pi / k)) * np.c_[np.cos(t), np.sin(t)]
        return P, np.c_[np.cos(t + np.pi / k), np.sin(t + np.pi / k)]

    def _patch(self, scale: float, bounds: Sequence[float] | None, ax: Any, **style: Any) -> Any:
        from matplotlib.patches import Circle

        return Circle(np.asarray(self.center) / scale, self.radius / scale, **style)

    def to_dict(self, scale: float = 1.0) -> dict:
        return {
            "type": "disc",
            "center": [self.center[0] / scale, self.center[1] / scale],
            "radius": self.radius / scale,
        }


@dataclass(frozen=True)
class PolygonFinger(Finger):
    """A convex polygon finger; ``vertices`` (m) counter-clockwise, no repeated vertex.

    The body is ``{x : m_j . x <= h_j}`` with outward unit edge normals ``m_j``
    (:attr:`normals`) and offsets ``h_j`` (:attr:`offsets`).

    Examples
    --------
    >>> square = PolygonFinger(((0.0, 0.0), (0.01, 0.0), (0.01, 0.01), (0.0, 0.01)))
    >>> square.signed_distance([[0.005, 0.004], [0.013, 0.014]])
    array([-0.004,  0.005])
    """

    corners: tuple[tuple[float, float], ...]
    type: ClassVar[str] = "polygon"

    def check(self, where: str) -> None:
        super().check(where)
        v = np.asarray(self.corners, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3 or abs(signed_area(v)) <= 0:
            raise FingerError(f"{where}.corners: give at least 3 corners (m) enclosing an area")

    @property
    def vertices(self) -> np.ndarray:
        return np.array(self.corners, dtype=float)

    @property
    def normals(self) -> np.ndarray:
        v = self.vertices
        e = np.roll(v, -1, axis=0) - v
        m = np.stack([e[:, 1], -e[:, 0]], axis=1)
        return m / np.linalg.norm(m, axis=1, keepdims=True)

    @property
    def offsets(self) -> np.ndarray:
        return np.einsum("ij,ij->i", self.normals, self.vertices)

    def _closest(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closest boundary point and distance for points ``p (..., 2)``."""
        a = self.vertices
        b = np.roll(a, -1, axis=0)
        ab = b - a
        ap = p[..., None, :] - a
        s = np.clip(np.einsum("...kj,kj->...k", ap, ab) / np.einsum("kj,kj->k", ab, ab), 0, 1)
        foot = a + s[..., None] * ab
        dist = np.linalg.norm(p[..., None, :] - foot, axis=-1)
        k = np.argmin(dist, axis=-1)
        closest = np.take_along_axis(foot, k[..., None, None], axis=-2)[..., 0, :]
        return closest, np.take_along_axis(dist, k[..., None], axis=-1)[..., 0]

    def signed_distance(self, points: Any) -> np.ndarray:
        p = _as_points(points)
        depth = np.max(p @ self.normals.T - self.offsets, axis=-1)
        _, dist = self._closest(p)
        return np.where(depth > 0, dist, depth)

    def outward_normal(self, points: Any) -> np.ndarray:
        p = _as_points(points)
        lev = p @ self.normals.T - self.offsets
        face = self.normals[np.argmax(lev, axis=-1)]
        closest, dist = self._closest(p)
        d = p - closest
        radial = np.divide(d, dist[..., None], out=np.zeros_like(d), where=dist[..., None] > 0)
        use_radial = (np.max(lev, axis=-1) > 0) & (dist > 0)
        return np.where(use_radial[..., None], radial, face)

    def segment_hits(self, a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
        return _clip_hits(a, b, self.normals, self.offsets - tol)

    def probe_point(self) -> np.ndarray:
        return self.vertices.mean(axis=0)

    def depth_samples(self) -> np.ndarray:
        v = np.asarray(self.vertices, dtype=float)
        mid = 0.5 * (v + np.roll(v, -1, axis=0))
        return np.vstack([v, mid, v.mean(axis=0)])

    def corner_edges(self, k: int) -> list[np.ndarray]:
        c = self.vertices
        return [c[(k - 1) % len(c)] - c[k], c[(k + 1) % len(c)] - c[k]]

    def corner_normals(self, k: int) -> list[np.ndarray]:
        m = self.normals
        return [m[j] for j in ((k - 1) % len(m), k)]   # the faces ending and starting at k

    def kernel_encoding(self, axis: Any = (0.0, 0.0)) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        v = self.vertices
        par = np.zeros(6)
        par[:2] = v.mean(axis=0)
        return KERNEL_POLYGON, par, v, self.normals

    def _outline(self) -> tuple[np.ndarray, np.ndarray]:
        return self.vertices, self.normals

    def to_dict(self, scale: float = 1.0) -> dict:
        return {"type": "polygon", "vertices": (self.vertices / scale).tolist()}


@dataclass(frozen=True)
class HalfPlaneFinger(Finger):
    """A half-plane finger ``{x : (x - point) . normal <= 0}``; ``normal`` is a unit
    vector pointing out of the finger, towards the part.

    Examples
    --------
    >>> floor = HalfPlaneFinger((0.0, 0.0), (0.0, 1.0))
    >>> floor.signed_distance([[0.5, 0.002], [0.0, -0.001]])
    array([ 0.002, -0.001])
    """

    point: tuple[float, float]
    normal: tuple[float, float]
    type: ClassVar[str] = "halfplane"

    def check(self, where: str) -> None:
        super().check(where)
        if abs(float(np.hypot(*self.normal)) - 1.0) > 1e-9:
            raise FingerError(f"{where}.normal: must be a unit vector, got {self.normal!r}; "
                              "divide it by its length")

    @property
    def vertices(self) -> np.ndarray:
        return np.zeros((0, 2))

    def signed_distance(self, points: Any) -> np.ndarray:
        return (_as_points(points) - np.asarray(self.point)) @ np.asarray(self.normal)

    def outward_normal(self, points: Any) -> np.ndarray:
        p = _as_points(points)
        return np.broadcast_to(np.asarray(self.normal, dtype=float), p.shape).copy()

    def segment_hits(self, a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
        n = np.asarray(self.normal)
        p0 = np.asarray(self.point)
        return ((a - p0) @ n < -tol) | ((b - p0) @ n < -tol)

    def obstacle(self, where: str, axis: Any = (0.0, 0.0)) -> Any:
        from .large_deformation import HalfPlaneObstacle

        return HalfPlaneObstacle((float(self.point[0]), float(self.point[1])),
                                 (float(self.normal[0]), float(self.normal[1])))

    def reference_points(self) -> np.ndarray:
        return np.asarray([self.point])

    def extent_points(self) -> None:
        return None

    def kernel_encoding(self, axis: Any = (0.0, 0.0)) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        par = np.zeros(6)
        par[:4] = (*self.point, *self.normal)
        return KERNEL_HALFPLANE, par, np.zeros((0, 2)), np.zeros((0, 2))

    def translation_clear(self, H: np.ndarray, hn: np.ndarray, D: np.ndarray, tol: float) -> np.ndarray:
        """Clear when ``H`` is outside the half-plane (within ``tol``) and the direction
        does not point into it."""
        ok = float(self.signed_distance(H).min()) >= -tol
        return ok & (D @ np.asarray(self.normal) >= -1e-12)

    def _patch(self, scale: float, bounds: Sequence[float] | None, ax: Any, **style: Any) -> Any:
        """The half-plane clipped to a square four times the size of ``bounds`` (plot
        units; default the axes' limits)."""
        from matplotlib.patches import Polygon

        x0, x1, y0, y1 = bounds if bounds is not None else (*ax.get_xlim(), *ax.get_ylim())
        big = 4.0 * max(x1 - x0, y1 - y0)
        p = np.asarray(self.point) / scale
        n = np.asarray(self.normal)
        t = np.array([-n[1], n[0]])
        quad = np.array([p + big * t, p - big * t, p - big * t - big * n, p + big * t - big * n])
        return Polygon(quad, closed=True, **style)

    def _label_point(self) -> np.ndarray:
        return np.asarray(self.point)

    def to_dict(self, scale: float = 1.0) -> dict:
        return {
            "type": "halfplane",
            "point": [self.point[0] / scale, self.point[1] / scale],
            "normal": [float(self.normal[0]), float(self.normal[1])],
        }


FINGER_TYPES: dict[str, type[Finger]] = {
    "point": PointFinger,
    "disc": DiscFinger,
    "polygon": PolygonFinger,
    "halfplane": HalfPlaneFinger,
}



def as_fingers(fingers: Any, name: str = "fingers") -> tuple[Finger, ...]:
    """``fingers`` as a tuple of :class:`Finger`; :class:`FingerError` naming the entry
    that is not one.

    Examples
    --------
    >>> as_fingers([PointFinger((0.0, 0.0))])
    (PointFinger(at=(0.0, 0.0)),)
    """
    if isinstance(fingers, (Finger, str, bytes, dict)) or not hasattr(fingers, "__iter__"):
        raise FingerError(f"{name}: expected a sequence of fingers, got {type(fingers).__name__}; "
                          "pass a list such as [PointFinger((x, y)), ...]")
    out = tuple(fingers)
    for i, f in enumerate(out):
        if not isinstance(f, Finger):
            raise FingerError(f"{name}[{i}]: expected a Finger (PointFinger, DiscFinger, PolygonFinger or "
                              f"HalfPlaneFinger), got {type(f).__name__}; build fingers in code or read them "
                              "with load_fingers / fingers_from_dict")
        f.check(f"{name}[{i}]")
    return out


# --------------------------------------------------------------------------- capsule shape

#: Steepest surface angle (rad, from the face) where a round pad's — or a disc finger's —
#: contact is enforced (SPEC §6): on the steeper flanks the gap, linearised along the axis,
#: has slope ``d' → ∞`` and would pin a node sideways as soon as it comes within reach;
#: reaching there needs an indentation of ``ρ (1 − cos 75°) ≈ 0.74 ρ`` beyond the face.
FLANK_ANGLE = np.radians(75.0)


@dataclass(frozen=True)
class Capsule:
    """A rigid capsule shape: a flat face of width ``width`` (m) with rounded ends of
    radius ``radius`` (m) — the segment of width ``W`` swept by a disc of radius ``ρ``
    (``W = 0``: a disc). Seen from the part along its axis its front surface is a height
    function of the cross-axis coordinate ``x``::

        d(x) = 0                                   |x| ≤ W/2
        d(x) = ρ − sqrt(ρ² − (|x| − W/2)²)         W/2 < |x| < W/2 + ρ

    and it cannot touch points with ``|x| ≥ W/2 + ρ``; contact is enforced where the
    surface is at most :data:`FLANK_ANGLE` from the face.

    Examples
    --------
    >>> Capsule(width=0.004, radius=0.001).half_span   # W/2 + ρ: the widest point it touches
    0.003
    """

    width: float
    radius: float

    def __post_init__(self) -> None:
        if not (is_finite_number(self.width) and self.width >= 0):
            raise GraspError(f"pad width = {self.width!r}: must be a finite length >= 0 "
                             "(0 = round fingertip)")
        if not (is_finite_number(self.radius) and self.radius > 0):
            raise GraspError(f"pad radius = {self.radius!r}: must be a finite length > 0")

    @property
    def half_span(self) -> float:
        """Largest ``|x|`` (m) the shape can touch: ``W/2 + ρ``."""
        return 0.5 * self.width + self.radius

    @property
    def reach(self) -> float:
        """Largest ``|x|`` (m) where contact is enforced: ``W/2 + ρ sin(FLANK_ANGLE)``."""
        return 0.5 * self.width + self.radius * float(np.sin(FLANK_ANGLE))

    def profile(self, x: np.ndarray, capped: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Surface height ``d(x)`` (m) and slope ``d'(x)``; ``inf`` outside the shape.

        Parameters
        ----------
        x : ndarray
            Cross-axis coordinates relative to the axis (m).
        capped : bool
            Only the contact range ``|x| < reach`` (True) or the whole capsule
            ``|x| < W/2 + ρ`` (False, for the rest geometry).
        """
        x = np.asarray(x, float)
        xi = np.abs(x) - 0.5 * self.width
        inside = np.abs(x) < (self.reach if capped else self.half_span)
        xi_c = np.clip(xi, 0.0, self.radius)          # outside the shape the value is unused
        root = np.sqrt(np.clip(self.radius**2 - xi_c**2, 0.0, None))
        d = np.where(inside, self.radius - root, np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(inside & (xi > 0), np.sign(x) * xi_c / root, 0.0)
        return d, np.where(inside, slope, np.inf)

    def to_dict(self) -> dict[str, float]:
        """``{"width", "radius"}`` in m."""
        return {"width": float(self.width), "radius": float(self.radius)}
