"""D-obstacles and the free D-space ``D_free`` (paper §3.2, SPEC §2).

Configuration ``q`` is in the D-obstacle ``DA_i`` of finger ``i`` when the interior of
the deformed part meets the interior of the finger; touching is free. With the
tolerance ``tol`` (default ``1e-9`` x the part's diameter, SPEC §3) the finger is
eroded by ``tol`` first, so contact with overlap up to ``tol`` counts as touching.
A point finger has no interior: it collides when the point lies inside the deformed
part farther than ``tol`` from its boundary. ``D_free = D_T ∩ complement(∪ DA_i)``.

Method
------
For ``q`` in ``D_T`` the deformed part is the polygon with holes bounded by the
deformed boundary rings, so everything is computed from boundary edges (vectorised over
edges and configurations):

* the open (eroded) finger meets the part's interior iff some boundary edge meets the
  open finger -- half-plane: an edge end strictly inside; disc: the edge passes closer
  than ``r - tol`` to the centre; convex polygon: Cyrus-Beck clipping of the edge
  against the open polygon -- **or** no edge does and an interior point of the finger
  (centre / centroid / the point itself) lies inside the part (even-odd crossing rule);
* the crossing parity, "some edge hits" and the nearest-edge distance are reductions
  over edges, so a slice that moves one node recomputes only the two edges at that
  node (:mod:`.slices`).

Outside ``D_T`` the rings may overlap themselves and the result refers to the even-odd
region of the rings; ``D_free`` does not depend on it.

The contact rows (the linearised non-penetration conditions of :mod:`.equilibrium`
and :mod:`.closure`: gap, gradient, contact point, part feature) are built by the one
builder of every model, :mod:`deformclosure.contact.rows` (its §3 rule,
:data:`~deformclosure.contact.rows.EQUILIBRIUM_RULE`); their names are re-exported here.

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.2 (D-obstacles, ``D_free``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .energy import as_configurations
from .. import geometry
from ..errors import DeformClosureError
from ..geometry import TOUCH_TOLERANCE
from ..contact.bodies import Finger, segment_distance
from ..contact.rows import (CENTRE_EDGE, CONVEX, CORNER_EDGE, CORNER_NODE, DISC_EDGE, FEATURE_NAMES,  # noqa: F401
                            NODE_BODY, REFLEX, STRAIGHT, STRAIGHT_SINE, BoundaryModel, ContactRows,
                            contact_rows, finger_gaps, merge_rows, ray_crossings,
                            refresh_rows)
from .topology import DEFAULT_MIN_AREA_RATIO, in_dt, loop_edges

__all__ = [
    "TOUCH_TOLERANCE",
    "touch_tolerance",
    "in_dobstacle",
    "dobstacle_mask",
    "in_dfree",
    "boundary_gaps",
]

def touch_tolerance(mesh: Any) -> float:
    """Touching tolerance (m) of a mesh: :func:`deformclosure.geometry.touch_tolerance` of
    its diameter, ``1e-9`` x ``mesh.diameter`` (SPEC §3)."""
    return geometry.touch_tolerance(mesh.diameter)


def resolve_tolerance(mesh: Any, tol: float | None) -> float:
    """``tol`` (m) as a float, or the mesh's touching tolerance when ``None``.

    Raises
    ------
    DeformClosureError
        ``tol`` is not a finite number >= 0.
    """
    if tol is None:
        return touch_tolerance(mesh)
    return nonnegative(tol, "tol", "the touching tolerance in m", "or None for 1e-9 x the part's diameter")


def nonnegative(value: Any, name: str, what: str, alternative: str = "") -> float:
    """``value`` as a finite float >= 0; :class:`DeformClosureError` naming ``name`` and
    asking for ``what`` (``alternative``: what else may be given) otherwise."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        out = math.nan
    if not (math.isfinite(out) and out >= 0.0):
        raise DeformClosureError(f"{name} = {value!r:.60}: give {what} as a finite number >= 0"
                                 + (f", {alternative}" if alternative else ""))
    return out


# ----------------------------------------------------------------------------- kernels


@dataclass
class _Terms:
    """Per-configuration reductions over a set of boundary edges for one finger."""

    hit: np.ndarray  # bool: some edge meets the open (eroded) finger
    parity: np.ndarray  # bool: crossing parity of the finger's probe point
    mind: np.ndarray  # float: distance from the probe point to the nearest edge

    def combine(self, other: "_Terms") -> "_Terms":
        return _Terms(self.hit | other.hit, self.parity ^ other.parity, np.minimum(self.mind, other.mind))


def _edge_terms(finger: Finger, a: np.ndarray, b: np.ndarray, tol: float) -> _Terms:
    """Reductions over the edges axis (second to last) of segment arrays ``(..., E, 2)``.

    The crossing parity is that of the finger's probe point (none for a half-plane); the
    distance to the nearest edge matters only for a body without interior (a point)."""
    shape = a.shape[:-2]
    no = np.zeros(shape, dtype=bool)
    inf = np.full(shape, np.inf)
    if a.shape[-2] == 0:
        return _Terms(no, no.copy(), inf)
    hit = np.any(finger.segment_hits(a, b, tol), axis=-1)
    probe = finger.probe_point()
    if probe is None:
        return _Terms(hit, no, inf)
    parity = np.logical_xor.reduce(ray_crossings(a, b, probe), axis=-1)
    mind = inf if finger.has_interior else np.min(segment_distance(a, b, probe), axis=-1)
    return _Terms(hit, parity, mind)


def _collides(t: _Terms, tol: float) -> np.ndarray:
    """The open (eroded) finger meets the part's interior: some edge meets it, or its
    probe point is inside the part (for a point: farther than ``tol`` from the boundary;
    a body with interior has ``mind = inf``)."""
    return t.hit | (t.parity & (t.mind > tol))


def _obstacles(qb: np.ndarray, edges: np.ndarray, fingers: Sequence[Finger], tol: float) -> np.ndarray:
    a, b = qb[:, edges[:, 0]], qb[:, edges[:, 1]]
    out = np.zeros((len(qb), len(fingers)), dtype=bool)
    for i, f in enumerate(fingers):  # loop over the few fingers only
        out[:, i] = _collides(_edge_terms(f, a, b, tol), tol)
    return out


# ----------------------------------------------------------------------------- public API


def dobstacle_mask(mesh: Any, q: Any, fingers: Sequence[Finger], tol: float | None = None) -> np.ndarray:
    """Membership of ``q`` in every finger's D-obstacle ``DA_i``.

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        Configuration(s) (m), see :func:`deformclosure.dspace.energy.as_configurations`.
    fingers : sequence of Finger
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter``.

    Returns
    -------
    ndarray of bool, shape (n_fingers,) or (b, n_fingers)
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    tol = resolve_tolerance(mesh, tol)
    out = _obstacles(qb, loop_edges(mesh.loops), list(fingers), tol)
    return out if batched else out[0]


def in_dobstacle(mesh: Any, q: Any, finger: Finger, tol: float | None = None) -> bool | np.ndarray:
    """Whether ``q`` lies in the D-obstacle of one ``finger`` (bool or ``(b,)`` bool)."""
    m = dobstacle_mask(mesh, q, [finger], tol)
    return bool(m[0]) if m.ndim == 1 else m[:, 0]


def in_dfree(
    mesh: Any,
    q: Any,
    fingers: Sequence[Finger],
    tol: float | None = None,
    min_area_ratio: float = DEFAULT_MIN_AREA_RATIO,
) -> bool | np.ndarray:
    """Membership of ``q`` in ``D_free = D_T ∩ complement(∪ DA_i)`` (paper §3.2).

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        ``(n, 2)``/``(2n,)`` or a batch ``(b, n, 2)``/``(b, 2n)`` (m).
    fingers : sequence of Finger
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter``.
    min_area_ratio : float
        Minimum deformed/rest area of a triangle in ``D_T``.

    Returns
    -------
    bool or ndarray of bool, shape (b,)
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    ok = np.asarray(in_dt(mesh, qb, min_area_ratio=min_area_ratio))
    if len(fingers) and ok.any():
        idx = np.flatnonzero(ok)
        ok[idx] = ~np.any(dobstacle_mask(mesh, qb[idx], fingers, tol), axis=1)
    return ok if batched else bool(ok[0])


def boundary_gaps(mesh: Any, q: Any, finger: Finger) -> np.ndarray:
    """Signed distance (m) of every boundary node of configuration ``q`` from ``finger``
    (negative inside the finger; for a point finger the distance to the point)."""
    qb, _ = as_configurations(q, len(mesh.nodes))
    nodes = np.unique(loop_edges(mesh.loops)[:, 0])
    return finger.signed_distance(qb[0, nodes])
