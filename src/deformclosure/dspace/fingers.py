"""Rigid finger bodies and the finger file (paper §3.2, SPEC §2 and §5).

A *finger* is a rigid body held fixed in the plane: a point, a disc, a convex polygon
or a half-plane. Every finger is a frozen dataclass in SI units (metres) with a few
vectorised geometric queries used by the D-obstacle tests (:mod:`.obstacles`), the
contact problem (:mod:`.equilibrium`) and the closure test (:mod:`.closure`).

Finger file
-----------
A JSON object with the length ``units`` (``"m"``, ``"mm"``, ``"cm"`` or ``"in"``) and a
non-empty list ``fingers``; every entry has a ``type`` and that type's fields only::

    {"units": "mm",
     "fingers": [
        {"type": "point",     "at": [x, y]},
        {"type": "disc",      "center": [x, y], "radius": r},
        {"type": "polygon",   "vertices": [[x, y], [x, y], [x, y], ...]},
        {"type": "halfplane", "point": [x, y], "normal": [nx, ny]}]}

A half-plane finger occupies the side its normal points *away* from,
``{x : (x - point) . normal <= 0}``; the normal points towards the part. Polygon
vertices may be given in either orientation (they are stored counter-clockwise) and
must form a convex polygon of positive area. Unknown fields, unknown types, non-finite
numbers, a non-positive radius, a zero normal or a non-convex polygon raise
:class:`deformclosure.errors.FingerError` with a one-line message that names the field
and says how to fix it.

References
----------
K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure Grasps of Deformable
Parts", IJRR 24(11), 2005, §3.2 (fingers and D-obstacles).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, Sequence, Union

import numpy as np

from ..errors import FingerError
from ..geometry import signed_area
from ..jsonfile import InputFile, as_source, read_json
from ..units import LENGTH_UNITS

__all__ = [
    "Finger",
    "PointFinger",
    "DiscFinger",
    "PolygonFinger",
    "HalfPlaneFinger",
    "FINGER_TYPES",
    "as_fingers",
    "load_fingers",
    "fingers_from_dict",
    "fingers_to_dict",
    "write_fingers",
]

#: Kind codes of the fingers in the compiled contact kernel (:mod:`.placement_energy`).
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
        n = np.linalg.norm(d, axis=-1, keepdims=True)
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
        from ..pads.geometry import FLANK_ANGLE

        par = np.zeros(6)
        par[:3] = (*self.center, self.radius)
        par[3:5] = axis
        par[5] = self.radius * np.sin(FLANK_ANGLE)
        return KERNEL_DISC, par, np.zeros((0, 2)), np.zeros((0, 2))

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


# --------------------------------------------------------------------------- file format

try:  # pydantic is a core dependency; keep the import local to this module.
    from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError
except ImportError as err:  # pragma: no cover
    raise ImportError("deformclosure.dspace.fingers needs pydantic>=2") from err

#: Largest coordinate or length magnitude accepted in a finger file (file units).
_MAX_LENGTH = 1e12


def _real(v: Any) -> float:
    """A JSON number, not a boolean or a string (which pydantic's lax mode would coerce)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"must be a number, got {v!r:.40}")
    if not (math.isfinite(v) and abs(v) <= _MAX_LENGTH):
        raise ValueError(f"must be a finite number of at most {_MAX_LENGTH:g} in magnitude")
    return float(v)


_Num = Annotated[float, BeforeValidator(_real)]
_Pt = tuple[_Num, _Num]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=False)


class _PointModel(_Model):
    type: Literal["point"]
    at: _Pt


class _DiscModel(_Model):
    type: Literal["disc"]
    center: _Pt
    radius: _Num


class _PolygonModel(_Model):
    type: Literal["polygon"]
    vertices: list[_Pt]


class _HalfPlaneModel(_Model):
    type: Literal["halfplane"]
    point: _Pt
    normal: _Pt


_FingerModel = Annotated[
    Union[_PointModel, _DiscModel, _PolygonModel, _HalfPlaneModel], Field(discriminator="type")
]


class _FingerFile(_Model):
    units: Literal["m", "mm", "cm", "in"]
    fingers: list[_FingerModel]


_FIELDS = {
    "point": "type, at",
    "disc": "type, center, radius",
    "polygon": "type, vertices",
    "halfplane": "type, point, normal",
}
_HINTS = {
    "units": 'give "units" as one of "m", "mm", "cm", "in"',
    "fingers": 'give "fingers" as a non-empty list of finger objects',
    "at": "give the point as [x, y]",
    "center": "give the centre as [x, y]",
    "radius": "give the radius as a positive number in the file's units",
    "vertices": "give the polygon as a list of [x, y] vertices",
    "point": "give a point on the boundary line as [x, y]",
    "normal": "give the normal as [nx, ny], pointing out of the finger towards the part",
    "type": "use one of point, disc, polygon, halfplane",
}


def _loc_str(loc: Sequence[Any]) -> tuple[str, str | None]:
    """Format a pydantic location like ``fingers[2].radius``; also return the field name."""
    parts = list(loc)
    # drop the discriminator tag pydantic inserts after the list index
    if len(parts) >= 3 and parts[0] == "fingers" and isinstance(parts[1], int) and parts[2] in _FIELDS:
        del parts[2]
    parts = [p for p in parts if p != "function-after"]
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else ("." if out else "") + str(p)
    field = next((str(p) for p in reversed(parts) if isinstance(p, str)), None)
    return out or "(top level)", field


def _message(err: ValidationError, source: str, raw: Any) -> str:
    errors = err.errors()
    rank = {"extra_forbidden": 0, "union_tag_invalid": 1, "union_tag_not_found": 1}
    e = min(errors, key=lambda x: rank.get(x["type"], 2))
    where, field = _loc_str(e["loc"])
    kind = e["type"]
    if kind in ("missing", "too_long", "too_short") and e["loc"] and isinstance(e["loc"][-1], int):
        where = where[: where.rfind("[")]
        return f"{source}: {where}: expected [x, y] with exactly 2 numbers"
    if kind in ("tuple_type", "list_type") and field in ("at", "center", "point", "normal", "vertices"):
        return f"{source}: {where}: expected a list; {_HINTS[field]}"
    if kind == "union_tag_invalid":
        tag = e.get("input", {}).get("type") if isinstance(e.get("input"), dict) else None
        return f"{source}: {where}.type: unknown finger type {tag!r}; use one of point, disc, polygon, halfplane"
    if kind == "union_tag_not_found":
        return f'{source}: {where}: missing "type"; use one of point, disc, polygon, halfplane'
    if kind == "extra_forbidden":
        ftype = _finger_type_at(raw, e["loc"])
        valid = _FIELDS.get(ftype, "units, fingers") if ftype else "units, fingers"
        what = f"a {ftype} finger" if ftype else "the finger file"
        return f"{source}: {where}: unknown field; valid fields for {what}: {valid}"
    if kind == "missing":
        ftype = _finger_type_at(raw, e["loc"])
        hint = _HINTS.get(field or "", "")
        if ftype:
            return f"{source}: {where}: missing; a {ftype} finger needs {_FIELDS[ftype]}"
        return f"{source}: {where}: missing; {hint}".rstrip("; ")
    if kind in ("model_type", "dict_type", "model_attributes_type"):
        hint = _HINTS.get(field or "", "see the finger file format in docs/dspace.md")
        return f"{source}: {where}: expected a JSON object; {hint}"
    if kind == "literal_error" and field == "units":
        return f"{source}: units: {e.get('input')!r} is not a length unit; {_HINTS['units']}"
    hint = _HINTS.get(field or "", "")
    msg = e["msg"].rstrip(".").removeprefix("Value error, ")
    return f"{source}: {where}: {msg}" + (f"; {hint}" if hint else "")


def _finger_type_at(raw: Any, loc: Sequence[Any]) -> str | None:
    if len(loc) >= 2 and loc[0] == "fingers" and isinstance(loc[1], int):
        try:
            t = raw["fingers"][loc[1]].get("type")
        except (KeyError, IndexError, TypeError, AttributeError):
            return None
        return t if t in _FIELDS else None
    return None


def _convex_ccw(vertices: np.ndarray, where: str) -> np.ndarray:
    """Validate a convex polygon, drop collinear vertices, return it counter-clockwise."""
    v = np.asarray(vertices, dtype=float)
    if len(v) < 3:
        raise FingerError(f"{where}.vertices: a polygon needs at least 3 vertices, got {len(v)}")
    scale = float(np.ptp(v, axis=0).max()) or 1.0
    e = np.roll(v, -1, axis=0) - v
    if np.any(np.linalg.norm(e, axis=1) <= 1e-12 * scale):
        raise FingerError(f"{where}.vertices: repeated vertex; list each corner once without closing the ring")
    area2 = float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))
    if abs(area2) <= 1e-12 * scale**2:
        raise FingerError(f"{where}.vertices: the polygon has zero area; give at least 3 non-collinear corners")
    if area2 < 0:
        v = v[::-1]
        e = np.roll(v, -1, axis=0) - v
    prev = np.roll(e, 1, axis=0)  # edge arriving at vertex i
    cross = prev[:, 0] * e[:, 1] - prev[:, 1] * e[:, 0]  # turn at vertex i
    lens = np.linalg.norm(e, axis=1) * np.linalg.norm(prev, axis=1)
    if np.any(cross < -1e-12 * lens):
        raise FingerError(
            f"{where}.vertices: the polygon is not convex; split it into convex fingers or use its convex hull"
        )
    # winding must be simple: total turning of a convex polygon is exactly 2*pi
    ang = np.arctan2(cross, np.einsum("ij,ij->i", prev, e))
    if abs(ang.sum() - 2 * np.pi) > 1e-6:
        raise FingerError(f"{where}.vertices: the polygon winds more than once; list the corners in order once")
    v = v[cross > 1e-12 * lens]  # drop collinear corners (they are face points)
    return v


def fingers_from_dict(data: Any, source: str = "fingers") -> tuple[Finger, ...]:
    """Build fingers from a finger-file dictionary (lengths converted to metres).

    Parameters
    ----------
    data : dict
        ``{"units": ..., "fingers": [...]}`` as described in the module docstring.
    source : str
        Name used at the start of error messages (usually the file name).

    Returns
    -------
    tuple of Finger
        In file order, SI units (m).

    Raises
    ------
    FingerError
        One-line message naming the offending field and the fix.

    Examples
    --------
    >>> fingers_from_dict({"units": "mm", "fingers": [{"type": "disc", "center": [0, 0], "radius": 2}]})
    (DiscFinger(center=(0.0, 0.0), radius=0.002),)
    """
    if not isinstance(data, dict):
        raise FingerError(f'{source}: expected a JSON object {{"units": ..., "fingers": [...]}}')
    try:
        model = _FingerFile.model_validate(data)
    except ValidationError as err:
        raise FingerError(_message(err, source, data)) from None
    if not model.fingers:
        raise FingerError(f"{source}: fingers: the list is empty; {_HINTS['fingers']}")
    f = LENGTH_UNITS[model.units]
    out: list[Finger] = []
    for i, m in enumerate(model.fingers):
        where = f"{source}: fingers[{i}]"
        if isinstance(m, _PointModel):
            out.append(PointFinger(at=(m.at[0] * f, m.at[1] * f)))
        elif isinstance(m, _DiscModel):
            if not m.radius > 0:
                raise FingerError(f"{where}.radius: must be > 0, got {m.radius:g}; {_HINTS['radius']}")
            out.append(DiscFinger(center=(m.center[0] * f, m.center[1] * f), radius=m.radius * f))
        elif isinstance(m, _PolygonModel):
            v = _convex_ccw(np.asarray(m.vertices, dtype=float) * f, where)
            out.append(PolygonFinger(corners=tuple((float(x), float(y)) for x, y in v)))
        else:
            n = np.asarray(m.normal, dtype=float)
            n = n / max(float(np.abs(n).max()), 1e-300)   # scale first: no overflow in the norm
            norm = float(np.linalg.norm(n))
            if not norm > 0 or not np.any(np.asarray(m.normal) != 0):
                raise FingerError(f"{where}.normal: must be non-zero; {_HINTS['normal']}")
            n = n / norm
            out.append(
                HalfPlaneFinger(point=(m.point[0] * f, m.point[1] * f), normal=(float(n[0]), float(n[1])))
            )
    return tuple(out)


def load_fingers(path: InputFile) -> tuple[Finger, ...]:
    """Read and validate a finger file (JSON); see the module docstring for the format.

    Parameters
    ----------
    path : str, Path or Source
        The finger file, or its bytes already read (:class:`deformclosure.jsonfile.Source`;
        messages then name ``Source.name``).

    Returns
    -------
    tuple of Finger
        SI units (m).

    Raises
    ------
    FingerError
        Unreadable file, invalid JSON or invalid content (one-line message).

    Examples
    --------
    >>> from deformclosure.jsonfile import Source
    >>> load_fingers(Source("f.json", b'{"units": "mm", "fingers": [{"type": "point", "at": [1, 2]}]}'))
    (PointFinger(at=(0.001, 0.002)),)
    """
    src = as_source(path, FingerError, "finger file")
    return fingers_from_dict(read_json(src, FingerError, "finger file"), source=src.name)


def fingers_to_dict(fingers: Sequence[Finger], units: str = "m") -> dict:
    """Inverse of :func:`fingers_from_dict`: a finger-file dictionary in ``units``."""
    if units not in LENGTH_UNITS:
        raise FingerError(f"units: {units!r} is not a length unit; {_HINTS['units']}")
    s = LENGTH_UNITS[units]
    return {"units": units, "fingers": [f.to_dict(s) for f in fingers]}


def write_fingers(fingers: Sequence[Finger], path: str | Path, units: str = "m") -> None:
    """Write a finger file (JSON) in ``units``, atomically."""
    from ..outputs import write_json

    write_json(path, fingers_to_dict(fingers, units), "finger file")
