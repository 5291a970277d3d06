"""Geometric helpers shared by parts, meshes, fingers and jaws: the one home of the
polygon area, the diameter and the SPEC's touching tolerance.

SPEC §3: contacts count as touching within ``1e-9`` × the part's diameter. Every module
takes that tolerance from :func:`touch_tolerance`, and the diameter from
:func:`point_set_diameter` of the part's outer boundary, so all agree to the bit.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["point_set_diameter", "signed_area", "touch_tolerance", "TOUCH_TOLERANCE",
           "is_finite_number"]

#: Contacts count as touching within this fraction of the part's diameter (SPEC §3).
TOUCH_TOLERANCE = 1e-9


def is_finite_number(value) -> bool:
    """Whether ``value`` is one finite real number (not a string, an array or a bool).

    Examples
    --------
    >>> is_finite_number(2.5), is_finite_number(True), is_finite_number(float("nan"))
    (True, False, False)
    """
    if isinstance(value, (bool, np.bool_)):
        return False
    try:
        return math.isfinite(value)
    except (TypeError, ValueError):
        return False


def touch_tolerance(diameter: float) -> float:
    """The SPEC §3 touching tolerance (m) of a part of ``diameter`` (m): ``1e-9 × diameter``.

    Examples
    --------
    >>> touch_tolerance(0.03)
    3e-11
    """
    return TOUCH_TOLERANCE * float(diameter)


def signed_area(ring: np.ndarray) -> float:
    """Signed area of a closed ring ``(n, 2)`` (shoelace formula; > 0 counter-clockwise).

    Examples
    --------
    >>> signed_area(np.array([[0, 0], [2, 0], [2, 1], [0, 1]]))
    2.0
    """
    r = np.asarray(ring, float)
    x, y = r[:, 0], r[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def point_set_diameter(points: np.ndarray) -> float:
    """Largest distance between two of ``points`` (shape ``(n, 2)``), in O(n log n).

    The diameter is attained between two vertices of the convex hull; rotating calipers
    visit each antipodal pair once (Shamos 1978), so a 20 000-vertex circle takes
    milliseconds instead of a 20 000² distance table.
    """
    P = np.asarray(points, float)
    if len(P) < 2:
        return 0.0
    if len(P) > 3:
        from scipy.spatial import ConvexHull, QhullError

        try:
            P = P[ConvexHull(P).vertices]          # counter-clockwise
        except QhullError:                       # collinear: the extreme pair along the line
            d = P - P[0]
            t = d @ (d[np.argmax((d**2).sum(1))] if np.any(d) else np.array([1.0, 0.0]))
            return float(np.linalg.norm(P[np.argmax(t)] - P[np.argmin(t)]))
    m = len(P)
    if m <= 3:
        d = P[:, None, :] - P[None, :, :]
        return float(np.sqrt((d**2).sum(-1)).max())

    def area2(a, b, c) -> float:
        return abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    best, j = 0.0, 1
    pts = P.tolist()
    for i in range(m):
        a, b = pts[i], pts[(i + 1) % m]
        while area2(a, b, pts[(j + 1) % m]) > area2(a, b, pts[j]):
            j = (j + 1) % m
        for q in (a, b):
            c = pts[j]
            best = max(best, (q[0] - c[0]) ** 2 + (q[1] - c[1]) ** 2)
    return float(np.sqrt(best))
